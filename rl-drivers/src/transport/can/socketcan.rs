//! Linux SocketCAN, raw (`CAN_RAW`): a non-blocking socket bound to one interface, with
//! receive filters, error frames enabled (they arrive as frames with the ERR flag and are
//! counted), CAN FD when asked, and the kernel's receive timestamps (`SO_TIMESTAMPNS`).
//!
//! Through `libc` rather than the `socketcan` crate: the few calls needed (socket, bind,
//! setsockopt, write, recvmsg) are simple; `recvmsg` with a control message is how the kernel
//! hands out its receive timestamp; the waits reuse this crate's `ppoll` deadline; and it adds
//! no dependency tree (socketcan 4 pulls netlink crates). All `unsafe` is in the private `sys`
//! module below, each block with its SAFETY argument.
//!
//! Machines without `AF_CAN` (containers, this project's CI) get `EAFNOSUPPORT` from
//! [`SocketCan::open`]; [`is_available`] tells tests to skip.

use std::io;
use std::os::fd::{AsFd, OwnedFd};
use std::time::Instant;

use super::{CanTransport, Received, RxQueue, TransportCounters};
use crate::proto::can::Frame;
use crate::proto::can::IdOrder;
use crate::proto::can::fd::CANFD_FRAME_LEN;
use crate::proto::can::frame::CAN_FRAME_LEN;
use crate::transport::{Readiness, wait};

/// A receive filter: a frame passes when `received_id & mask == id & mask` (`canid_t` values,
/// flags included; see `can(7)`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CanFilter {
    /// The identifier to match.
    pub id: u32,
    /// Which bits must match.
    pub mask: u32,
}

/// The OS error a kernel without CAN sockets gives (`EAFNOSUPPORT`).
pub const EAFNOSUPPORT: i32 = libc::EAFNOSUPPORT;

/// What a user does when the kernel has no CAN sockets (`EAFNOSUPPORT`, os error 97).
pub const NO_AF_CAN: &str = "this kernel offers no CAN sockets (AF_CAN): load the modules \
     (`modprobe can-raw`), run outside a container that hides them, or reach the bus through a \
     CAN-to-Ethernet gateway (cannelloni+udp://HOST:PORT)";

/// Whether this machine's kernel offers `AF_CAN` sockets (`false`: no module, a container).
pub fn is_available() -> bool {
    sys::socket().is_ok()
}

/// A raw SocketCAN socket.
#[derive(Debug)]
pub struct SocketCan {
    fd: OwnedFd,
    pending: Vec<Frame>,
    rx: RxQueue,
    counters: TransportCounters,
}

impl SocketCan {
    /// Opens `interface` (`can0`), with `filters` (none: every frame) and CAN FD frames if
    /// `fd_frames`.
    /// A kernel without CAN sockets is `Unsupported` ([`NO_AF_CAN`] says what to do), an
    /// unknown interface `NotFound`.
    pub fn open(interface: &str, filters: &[CanFilter], fd_frames: bool) -> io::Result<Self> {
        let fd = sys::socket().map_err(|e| {
            if e.raw_os_error() == Some(libc::EAFNOSUPPORT) {
                io::Error::new(io::ErrorKind::Unsupported, format!("{NO_AF_CAN} ({e})"))
            } else {
                e
            }
        })?;
        let index = sys::interface_index(interface)?;
        sys::set_error_filter(&fd, crate::proto::can::frame::EFF_MASK)?;
        if !filters.is_empty() {
            sys::set_filters(&fd, filters)?;
        }
        if fd_frames {
            sys::set_fd_frames(&fd)?;
        }
        crate::transport::timestamp::enable(fd.as_fd())?;
        sys::bind(&fd, index)?;
        Ok(Self {
            fd,
            pending: Vec::with_capacity(256),
            rx: RxQueue::new(),
            counters: TransportCounters::default(),
        })
    }
}

impl CanTransport for SocketCan {
    fn send(&mut self, frame: &Frame) -> io::Result<()> {
        if self.pending.len() == self.pending.capacity() {
            return Err(io::Error::new(
                io::ErrorKind::WouldBlock,
                "SocketCAN: send queue full",
            ));
        }
        self.pending.push(*frame);
        Ok(())
    }

    fn flush(&mut self, deadline: Instant) -> io::Result<()> {
        let mut buf = [0u8; CANFD_FRAME_LEN];
        let mut sent = 0;
        let result = loop {
            let Some(frame) = self.pending.get(sent) else {
                break Ok(());
            };
            let n = frame
                .write_socketcan(&mut buf, IdOrder::Host)
                .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e.to_string()))?;
            match sys::write(&self.fd, &buf[..n]) {
                Ok(_) => {
                    sent += 1;
                    self.counters.frames_sent += 1;
                }
                // The interface's queue is full (ENOBUFS) or the socket would block.
                Err(e) if matches!(e.raw_os_error(), Some(libc::ENOBUFS | libc::EAGAIN)) => {
                    if Instant::now() >= deadline {
                        break Err(io::Error::new(
                            io::ErrorKind::TimedOut,
                            "SocketCAN: transmit queue full",
                        ));
                    }
                    wait(self.fd.as_fd(), Readiness::Writable, deadline)?;
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => break Err(e),
            }
        };
        self.pending.clear();
        result
    }

    fn recv(&mut self, deadline: Instant) -> io::Result<Option<Received>> {
        loop {
            if let Some(r) = self.rx.pop() {
                return Ok(Some(r));
            }
            let mut buf = [0u8; CANFD_FRAME_LEN];
            match crate::transport::timestamp::recv(self.fd.as_fd(), &mut buf) {
                Ok((n, _, timestamp)) => {
                    let frame = match n {
                        CAN_FRAME_LEN | CANFD_FRAME_LEN => {
                            Frame::read_socketcan(&buf[..n], IdOrder::Host)
                        }
                        _ => {
                            self.counters.corrupt += 1;
                            continue;
                        }
                    };
                    match frame {
                        Ok(frame) => {
                            if frame.is_error_frame() {
                                self.counters.error_frames += 1;
                            }
                            self.counters.frames_received += 1;
                            self.rx.push(Received { frame, timestamp });
                        }
                        Err(_) => self.counters.corrupt += 1,
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    if !wait(self.fd.as_fd(), Readiness::Readable, deadline)? {
                        return Ok(None);
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }

    fn counters(&self) -> TransportCounters {
        let mut c = self.counters;
        c.overruns = self.rx.overruns;
        c
    }
}

/// The system calls, each `unsafe` block with its argument.
mod sys {
    use std::ffi::CString;
    use std::io;
    use std::mem::{size_of, zeroed};
    use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};

    use super::CanFilter;

    fn check(r: libc::c_int) -> io::Result<libc::c_int> {
        if r < 0 {
            Err(io::Error::last_os_error())
        } else {
            Ok(r)
        }
    }

    pub(super) fn socket() -> io::Result<OwnedFd> {
        // SAFETY: socket(2) takes no pointers; a non-negative result is a new descriptor that
        // nothing else owns, so `OwnedFd` may take it.
        unsafe {
            let fd = check(libc::socket(
                libc::AF_CAN,
                libc::SOCK_RAW | libc::SOCK_NONBLOCK | libc::SOCK_CLOEXEC,
                libc::CAN_RAW,
            ))?;
            Ok(OwnedFd::from_raw_fd(fd))
        }
    }

    pub(super) fn interface_index(name: &str) -> io::Result<libc::c_int> {
        let c = CString::new(name).map_err(|_| io::Error::from(io::ErrorKind::InvalidInput))?;
        // SAFETY: `c` is a NUL-terminated string that lives across the call.
        let index = unsafe { libc::if_nametoindex(c.as_ptr()) };
        if index == 0 {
            return Err(io::Error::new(
                io::ErrorKind::NotFound,
                format!("SocketCAN: no interface `{name}`"),
            ));
        }
        Ok(index as libc::c_int)
    }

    fn setsockopt<T>(
        fd: &OwnedFd,
        level: libc::c_int,
        name: libc::c_int,
        value: &[T],
    ) -> io::Result<()> {
        // SAFETY: `value` points to `size_of_val(value)` initialised bytes that live across
        // the call; the kernel only reads them.
        unsafe {
            check(libc::setsockopt(
                fd.as_raw_fd(),
                level,
                name,
                value.as_ptr().cast(),
                std::mem::size_of_val(value) as libc::socklen_t,
            ))?;
        }
        Ok(())
    }

    pub(super) fn set_error_filter(fd: &OwnedFd, mask: u32) -> io::Result<()> {
        setsockopt(fd, libc::SOL_CAN_RAW, libc::CAN_RAW_ERR_FILTER, &[mask])
    }

    pub(super) fn set_filters(fd: &OwnedFd, filters: &[CanFilter]) -> io::Result<()> {
        let raw: Vec<libc::can_filter> = filters
            .iter()
            .map(|f| libc::can_filter {
                can_id: f.id,
                can_mask: f.mask,
            })
            .collect();
        setsockopt(fd, libc::SOL_CAN_RAW, libc::CAN_RAW_FILTER, &raw)
    }

    pub(super) fn set_fd_frames(fd: &OwnedFd) -> io::Result<()> {
        setsockopt(
            fd,
            libc::SOL_CAN_RAW,
            libc::CAN_RAW_FD_FRAMES,
            &[1 as libc::c_int],
        )
    }

    pub(super) fn bind(fd: &OwnedFd, index: libc::c_int) -> io::Result<()> {
        // SAFETY: an all-zero `sockaddr_can` is a valid value (plain integers and a union of
        // integers); the fields that matter are set below.
        let mut addr: libc::sockaddr_can = unsafe { zeroed() };
        addr.can_family = libc::AF_CAN as libc::sa_family_t;
        addr.can_ifindex = index;
        // SAFETY: `addr` is a valid `sockaddr_can` of the length given, alive for the call.
        unsafe {
            check(libc::bind(
                fd.as_raw_fd(),
                (&raw const addr).cast(),
                size_of::<libc::sockaddr_can>() as libc::socklen_t,
            ))?;
        }
        Ok(())
    }

    pub(super) fn write(fd: &OwnedFd, bytes: &[u8]) -> io::Result<usize> {
        // SAFETY: `bytes` is valid for reads of its length during the call.
        let n = unsafe { libc::write(fd.as_raw_fd(), bytes.as_ptr().cast(), bytes.len()) };
        if n < 0 {
            Err(io::Error::last_os_error())
        } else {
            Ok(n as usize)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// Needs a `vcan0` (`ip link add vcan0 type vcan; ip link set up vcan0`); otherwise prints
    /// SKIPPED and passes.
    #[test]
    fn frames_cross_a_virtual_can_interface() {
        if !is_available() {
            println!("SKIPPED: this kernel has no AF_CAN sockets (no can module or a container)");
            return;
        }
        let Ok(mut a) = SocketCan::open("vcan0", &[], false) else {
            println!("SKIPPED: no vcan0 interface (ip link add vcan0 type vcan)");
            return;
        };
        let mut b = SocketCan::open(
            "vcan0",
            &[CanFilter {
                id: 0x181,
                mask: 0x7FF,
            }],
            false,
        )
        .unwrap();
        a.send(&Frame::standard(0x100, &[1]).unwrap()).unwrap();
        a.send(&Frame::standard(0x181, &[2, 3]).unwrap()).unwrap();
        a.flush(Instant::now() + Duration::from_millis(100))
            .unwrap();
        let r = b
            .recv(Instant::now() + Duration::from_secs(1))
            .unwrap()
            .unwrap();
        assert_eq!(
            r.frame.standard_id(),
            Some(0x181),
            "the filter passes only 0x181"
        );
        assert!(r.timestamp.is_some(), "kernel timestamp");
    }
}
