//! A UDP link to one peer: a non-blocking, unconnected socket that accepts datagrams only from
//! the configured peer. Anything else is dropped and counted (the kernel's own filter of a
//! connected socket would hide it). Where the kernel gives them (`SO_TIMESTAMPNS`, see
//! [`timestamp`]), each received datagram's kernel receive time is kept
//! ([`UdpLink::received_at`]): the caller can tell how long a reply waited in the socket.

use std::io;
use std::net::{SocketAddr, UdpSocket};
use std::os::fd::AsFd;
use std::time::{Duration, Instant};

use socket2::{Domain, Protocol, Socket, Type};

use super::{Readiness, timestamp, wait};

/// Datagram counts of a [`UdpLink`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UdpCounters {
    /// Datagrams sent.
    pub sent: u64,
    /// Datagrams received from the peer.
    pub received: u64,
    /// Datagrams from any other address, dropped.
    pub foreign: u64,
}

/// A UDP socket bound locally that exchanges datagrams with one peer.
#[derive(Debug)]
pub struct UdpLink {
    socket: UdpSocket,
    peer: SocketAddr,
    counters: UdpCounters,
    /// The kernel's receive time of the datagram last returned, where it gives one.
    received_at: Option<Duration>,
}

impl UdpLink {
    /// Binds a non-blocking socket to `local` (port 0 for an ephemeral one) for talking to `peer`.
    pub fn bind(local: SocketAddr, peer: SocketAddr) -> io::Result<Self> {
        let socket = Socket::new(Domain::for_address(local), Type::DGRAM, Some(Protocol::UDP))?;
        socket.set_nonblocking(true)?;
        socket.bind(&local.into())?;
        // Best effort: an emulator such as qemu-user may refuse the option; the datagrams then
        // carry no receive time.
        let _ = timestamp::enable(socket.as_fd());
        Ok(Self {
            socket: socket.into(),
            peer,
            counters: UdpCounters::default(),
            received_at: None,
        })
    }

    /// The local address (with the port the system chose).
    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// The only address replies are accepted from.
    pub fn peer(&self) -> SocketAddr {
        self.peer
    }

    /// Counts so far.
    pub fn counters(&self) -> UdpCounters {
        self.counters
    }

    /// The kernel's receive time (`CLOCK_REALTIME`, compare with
    /// [`timestamp::since_epoch`]) of the datagram the last successful receive returned;
    /// `None` where the kernel gives no timestamps.
    pub fn received_at(&self) -> Option<Duration> {
        self.received_at
    }

    /// Sends one datagram to the peer without blocking.
    pub fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        let n = self.socket.send_to(bytes, self.peer)?;
        if n != bytes.len() {
            return Err(io::Error::new(
                io::ErrorKind::WriteZero,
                "datagram sent partially",
            ));
        }
        self.counters.sent += 1;
        Ok(())
    }

    /// Receives one pending datagram from the peer, if any, without waiting. Foreign datagrams
    /// are dropped and counted — but only until `deadline`: a flood of them cannot hold the
    /// caller past it (`Ok(None)` then, with the rest left queued). Returns the datagram's
    /// length (datagrams longer than `buf` are cut).
    pub fn try_recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<Option<usize>> {
        loop {
            match timestamp::recv(self.socket.as_fd(), buf) {
                Ok((n, Some(from), at)) if from == self.peer => {
                    self.counters.received += 1;
                    self.received_at = at;
                    return Ok(Some(n));
                }
                Ok(_) => {
                    self.counters.foreign += 1;
                    if Instant::now() >= deadline {
                        return Ok(None);
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(None),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }

    /// Waits until a datagram from the peer arrives or `deadline` passes (`Ok(None)`); foreign
    /// datagrams on the way are dropped and counted.
    pub fn recv_until(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<Option<usize>> {
        loop {
            if let Some(n) = self.try_recv(buf, deadline)? {
                return Ok(Some(n));
            }
            if !wait(self.socket.as_fd(), Readiness::Readable, deadline)? {
                return Ok(None);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn only_the_peer_is_heard_and_others_are_counted() {
        let any: SocketAddr = "127.0.0.1:0".parse().unwrap();
        let peer = UdpSocket::bind(any).unwrap();
        let stranger = UdpSocket::bind(any).unwrap();
        let mut link = UdpLink::bind(any, peer.local_addr().unwrap()).unwrap();
        let me = link.local_addr().unwrap();
        stranger.send_to(b"spoof", me).unwrap();
        peer.send_to(b"real", me).unwrap();
        let mut buf = [0u8; 16];
        let deadline = Instant::now() + Duration::from_secs(2);
        assert_eq!(link.recv_until(&mut buf, deadline).unwrap(), Some(4));
        assert_eq!(&buf[..4], b"real");
        assert_eq!(link.counters().foreign, 1);
        // The datagram carries the kernel's receive time: before now, and recent.
        match link.received_at() {
            Some(at) => {
                let now = timestamp::since_epoch();
                assert!(
                    at <= now && now - at < Duration::from_secs(2),
                    "{at:?} vs {now:?}"
                );
            }
            None => println!(
                "SKIPPED the timestamp check: this kernel or emulator refuses SO_TIMESTAMPNS"
            ),
        }
        let start = Instant::now();
        let short = start + Duration::from_millis(20);
        assert_eq!(link.recv_until(&mut buf, short).unwrap(), None);
        assert!(start.elapsed() >= Duration::from_millis(20));
    }

    #[test]
    fn a_flood_of_foreign_datagrams_stops_at_the_deadline() {
        let any: SocketAddr = "127.0.0.1:0".parse().unwrap();
        let peer = UdpSocket::bind(any).unwrap();
        let stranger = UdpSocket::bind(any).unwrap();
        let mut link = UdpLink::bind(any, peer.local_addr().unwrap()).unwrap();
        let me = link.local_addr().unwrap();
        for _ in 0..200 {
            stranger.send_to(b"flood", me).unwrap();
        }
        let mut buf = [0u8; 16];
        // A deadline already passed: one foreign datagram is read, then the call returns.
        let past = Instant::now();
        assert_eq!(link.try_recv(&mut buf, past).unwrap(), None);
        assert_eq!(link.counters().foreign, 1);
        // With time left, the whole flood is drained and counted.
        let later = Instant::now() + Duration::from_secs(5);
        assert_eq!(link.try_recv(&mut buf, later).unwrap(), None);
        assert_eq!(link.counters().foreign, 200);
    }
}
