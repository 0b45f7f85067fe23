//! Socket transports (std): non-blocking sockets where every wait is bounded by a deadline.

pub mod can;
pub mod packet;
pub mod tcp;
pub mod timestamp;
pub mod udp;

use std::io;
use std::os::fd::BorrowedFd;
use std::time::Instant;

use nix::poll::{PollFd, PollFlags, ppoll};
use nix::sys::time::TimeSpec;

pub use packet::{PacketCounters, PacketLink};
pub use tcp::TcpLink;
pub use udp::{UdpCounters, UdpLink};

/// Which readiness to wait for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Readiness {
    Readable,
    Writable,
}

/// Waits until `fd` is ready or `deadline` passes; `Ok(false)` means the deadline passed.
/// Uses `ppoll` for a nanosecond-resolution timeout; allocates nothing.
pub(crate) fn wait(
    fd: BorrowedFd<'_>,
    readiness: Readiness,
    deadline: Instant,
) -> io::Result<bool> {
    let events = match readiness {
        Readiness::Readable => PollFlags::POLLIN,
        Readiness::Writable => PollFlags::POLLOUT,
    };
    loop {
        let now = Instant::now();
        if now >= deadline {
            return Ok(false);
        }
        let timeout = TimeSpec::from_duration(deadline - now);
        let mut fds = [PollFd::new(fd, events)];
        match ppoll(&mut fds, Some(timeout), None) {
            Ok(0) => continue,
            Ok(_) => return Ok(true),
            Err(nix::errno::Errno::EINTR) => continue,
            Err(e) => return Err(io::Error::from(e)),
        }
    }
}
