//! A TCP connection with bounded waits: connect with a timeout, then non-blocking reads and
//! writes that wait at most until a deadline (an expired deadline is `ErrorKind::TimedOut`).

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::os::fd::{AsFd, BorrowedFd};
use std::time::{Duration, Instant};

use socket2::{Domain, Protocol, Socket, Type};

use super::{Readiness, wait};

/// A connected, non-blocking TCP stream.
#[derive(Debug)]
pub struct TcpLink {
    stream: TcpStream,
    peer: SocketAddr,
}

/// An expired deadline. Built from the kind alone, which allocates nothing (an
/// `io::Error::new` with a message allocates three times).
fn timed_out() -> io::Error {
    io::Error::from(io::ErrorKind::TimedOut)
}

impl AsFd for TcpLink {
    fn as_fd(&self) -> BorrowedFd<'_> {
        self.stream.as_fd()
    }
}

impl TcpLink {
    /// Connects to `peer` within `timeout` (Nagle off: commands are small and latency matters).
    pub fn connect(peer: SocketAddr, timeout: Duration) -> io::Result<Self> {
        let socket = Socket::new(Domain::for_address(peer), Type::STREAM, Some(Protocol::TCP))?;
        socket.connect_timeout(&peer.into(), timeout)?;
        socket.set_nonblocking(true)?;
        socket.set_tcp_nodelay(true)?;
        Ok(Self {
            stream: socket.into(),
            peer,
        })
    }

    /// Wraps an accepted stream (used by the fakes).
    pub fn from_stream(stream: TcpStream) -> io::Result<Self> {
        stream.set_nonblocking(true)?;
        stream.set_nodelay(true)?;
        let peer = stream.peer_addr()?;
        Ok(Self { stream, peer })
    }

    /// The connected peer.
    pub fn peer(&self) -> SocketAddr {
        self.peer
    }

    /// Writes all of `bytes` before `deadline`.
    pub fn send_all(&mut self, mut bytes: &[u8], deadline: Instant) -> io::Result<()> {
        while !bytes.is_empty() {
            match self.stream.write(bytes) {
                Ok(0) => return Err(io::Error::from(io::ErrorKind::WriteZero)),
                Ok(n) => bytes = &bytes[n..],
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    if !wait(self.stream.as_fd(), Readiness::Writable, deadline)? {
                        return Err(timed_out());
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }

    /// Reads what is available without waiting: `Ok(None)` if nothing, `Ok(Some(0))` if the
    /// peer closed the connection. `buf` must not be empty (a read into nothing would look
    /// like a closed connection).
    pub fn try_recv(&mut self, buf: &mut [u8]) -> io::Result<Option<usize>> {
        if buf.is_empty() {
            return Err(io::Error::from(io::ErrorKind::InvalidInput));
        }
        loop {
            match self.stream.read(buf) {
                Ok(n) => return Ok(Some(n)),
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(None),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }

    /// Reads at least one byte before `deadline` (`Ok(0)` means the peer closed; an expired
    /// deadline is `ErrorKind::TimedOut`, made without allocating). `buf` must not be empty.
    pub fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        if buf.is_empty() {
            return Err(io::Error::from(io::ErrorKind::InvalidInput));
        }
        loop {
            if let Some(n) = self.try_recv(buf)? {
                return Ok(n);
            }
            if !wait(self.stream.as_fd(), Readiness::Readable, deadline)? {
                return Err(timed_out());
            }
        }
    }
}
