//! A raw Ethernet link: an `AF_PACKET` socket bound to one named interface and one EtherType,
//! non-blocking, every wait bounded by a deadline (EtherCAT runs on plain Ethernet frames, below
//! IP). Opening it needs root or the capability `CAP_NET_RAW` ([`PERMISSION_REMEDY`] says how).
//!
//! A packet socket does not receive the frames it sent itself, but it receives frames other
//! sockets on the host send through the same interface; the caller filters by source address.
//!
//! This file holds all of rl-drivers' `unsafe` code for raw sockets: each block calls one
//! system call on a valid descriptor with buffers that outlive the call.

use std::ffi::CString;
use std::io;
use std::mem::{size_of, zeroed};
use std::os::fd::{AsFd, AsRawFd, FromRawFd, OwnedFd};
use std::time::Instant;

use super::{Readiness, wait};

/// What a user does when opening the socket is not permitted.
pub const PERMISSION_REMEDY: &str = "raw Ethernet needs root or CAP_NET_RAW: run as root, or \
     grant the binary the capability once with `sudo setcap cap_net_raw,cap_net_admin+ep <path>`";

/// Whether `e` is the refusal [`PERMISSION_REMEDY`] explains (EPERM or EACCES).
pub fn is_permission_error(e: &io::Error) -> bool {
    e.kind() == io::ErrorKind::PermissionDenied
        || matches!(e.raw_os_error(), Some(libc::EPERM | libc::EACCES))
}

/// Frame counts of a [`PacketLink`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PacketCounters {
    /// Frames sent.
    pub sent: u64,
    /// Frames received (of the bound EtherType, from anyone).
    pub received: u64,
}

/// An `AF_PACKET` socket on one interface for one EtherType.
#[derive(Debug)]
pub struct PacketLink {
    fd: OwnedFd,
    interface: String,
    index: i32,
    mac: [u8; 6],
    counters: PacketCounters,
}

impl PacketLink {
    /// Opens a non-blocking raw socket on `interface` for frames of `ethertype`.
    /// `PermissionDenied` without root or `CAP_NET_RAW` ([`PERMISSION_REMEDY`]); `NotFound` for
    /// an unknown interface.
    pub fn open(interface: &str, ethertype: u16) -> io::Result<Self> {
        let name = CString::new(interface).map_err(|_| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                "interface name with a NUL byte",
            )
        })?;
        if interface.is_empty() || interface.len() >= libc::IFNAMSIZ {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("interface name {interface:?}: 1 to 15 bytes"),
            ));
        }
        let protocol = ethertype.to_be();
        // SAFETY: socket() takes plain integers and returns a new descriptor or -1.
        let raw = unsafe {
            libc::socket(
                libc::AF_PACKET,
                libc::SOCK_RAW | libc::SOCK_NONBLOCK | libc::SOCK_CLOEXEC,
                i32::from(protocol),
            )
        };
        if raw < 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: `raw` is a descriptor socket() just returned and nothing else owns.
        let fd = unsafe { OwnedFd::from_raw_fd(raw) };
        // SAFETY: `name` is a NUL-terminated string that lives across the call.
        let index = unsafe { libc::if_nametoindex(name.as_ptr()) };
        if index == 0 {
            return Err(io::Error::new(
                io::ErrorKind::NotFound,
                format!("no network interface named {interface:?}"),
            ));
        }
        let index = i32::try_from(index)
            .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "interface index"))?;
        // SAFETY: sockaddr_ll is a plain C struct for which all-zero bytes are a valid value.
        let mut sll: libc::sockaddr_ll = unsafe { zeroed() };
        sll.sll_family = libc::AF_PACKET as u16;
        sll.sll_protocol = protocol;
        sll.sll_ifindex = index;
        // SAFETY: `sll` is a valid sockaddr_ll of the length passed, alive across the call.
        let rc = unsafe {
            libc::bind(
                fd.as_raw_fd(),
                (&raw const sll).cast::<libc::sockaddr>(),
                size_of::<libc::sockaddr_ll>() as libc::socklen_t,
            )
        };
        if rc != 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: ifreq is a plain C struct (a name and a union); all-zero bytes are valid.
        let mut ifr: libc::ifreq = unsafe { zeroed() };
        for (d, s) in ifr.ifr_name.iter_mut().zip(name.as_bytes()) {
            *d = *s as libc::c_char;
        }
        // SAFETY: SIOCGIFHWADDR reads the name from and writes the address into `ifr`, a valid
        // ifreq alive across the call.
        let rc = unsafe { libc::ioctl(fd.as_raw_fd(), libc::SIOCGIFHWADDR, &raw mut ifr) };
        if rc != 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: after SIOCGIFHWADDR the union holds `ifru_hwaddr`.
        let hw = unsafe { ifr.ifr_ifru.ifru_hwaddr };
        let mut mac = [0u8; 6];
        for (d, s) in mac.iter_mut().zip(hw.sa_data.iter()) {
            *d = *s as u8;
        }
        Ok(Self {
            fd,
            interface: interface.to_owned(),
            index,
            mac,
            counters: PacketCounters::default(),
        })
    }

    /// The interface's name.
    pub fn interface(&self) -> &str {
        &self.interface
    }

    /// The interface's index.
    pub fn index(&self) -> i32 {
        self.index
    }

    /// The interface's hardware address.
    pub fn hardware_address(&self) -> [u8; 6] {
        self.mac
    }

    /// Counts so far.
    pub fn counters(&self) -> PacketCounters {
        self.counters
    }

    /// Sends one whole Ethernet frame (without FCS) without blocking.
    pub fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        loop {
            // SAFETY: `frame` is a valid buffer of the length passed, alive across the call.
            let n = unsafe {
                libc::send(
                    self.fd.as_raw_fd(),
                    frame.as_ptr().cast(),
                    frame.len(),
                    libc::MSG_DONTWAIT,
                )
            };
            if n >= 0 {
                if n as usize != frame.len() {
                    return Err(io::Error::new(
                        io::ErrorKind::WriteZero,
                        "frame sent partially",
                    ));
                }
                self.counters.sent += 1;
                return Ok(());
            }
            let e = io::Error::last_os_error();
            if e.kind() != io::ErrorKind::Interrupted {
                return Err(e);
            }
        }
    }

    /// Receives one pending frame, if any, without waiting; returns its length (frames longer
    /// than `buf` are cut).
    pub fn try_recv(&mut self, buf: &mut [u8]) -> io::Result<Option<usize>> {
        loop {
            // SAFETY: `buf` is a valid writable buffer of the length passed.
            let n = unsafe {
                libc::recv(
                    self.fd.as_raw_fd(),
                    buf.as_mut_ptr().cast(),
                    buf.len(),
                    libc::MSG_DONTWAIT,
                )
            };
            if n >= 0 {
                self.counters.received += 1;
                return Ok(Some(n as usize));
            }
            let e = io::Error::last_os_error();
            match e.kind() {
                io::ErrorKind::WouldBlock => return Ok(None),
                io::ErrorKind::Interrupted => {}
                _ => return Err(e),
            }
        }
    }

    /// Waits until a frame arrives or `deadline` passes (`Ok(None)`). Polls first, then reads:
    /// right after a send the reply cannot be there yet, so this saves the `recv` that would
    /// fail (two system calls per reply instead of three; `ppoll` returns at once when a frame
    /// is already waiting).
    pub fn recv_until(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<Option<usize>> {
        loop {
            if !wait(self.fd.as_fd(), Readiness::Readable, deadline)? {
                // One last look: a frame that came exactly at the deadline is not lost.
                return self.try_recv(buf);
            }
            if let Some(n) = self.try_recv(buf)? {
                return Ok(Some(n));
            }
        }
    }

    /// Drops every pending frame; returns how many.
    pub fn drain(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let mut n = 0;
        while self.try_recv(buf)?.is_some() {
            n += 1;
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_names_and_missing_interfaces_are_typed() {
        let e = PacketLink::open("", 0x88A4).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        let e = PacketLink::open("a-name-far-too-long-for-linux", 0x88A4).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        match PacketLink::open("rl-no-such-if", 0x88A4) {
            // Without privileges the socket itself is refused first.
            Err(e) if is_permission_error(&e) => println!("SKIPPED: not root ({e})"),
            Err(e) => assert_eq!(e.kind(), io::ErrorKind::NotFound, "{e}"),
            Ok(_) => panic!("opened a socket on a missing interface"),
        }
    }
}
