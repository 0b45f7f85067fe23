//! The RTDE connection: a TCP stream, a fixed receive buffer split into packages, and bounded
//! waits. Receiving and sending allocate nothing.

use std::io;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

use crate::proto::rtde::{HEADER_LEN, Header, Message, RtdeError, split};
use crate::transport::TcpLink;

/// Bytes the receive buffer holds (a data package of our recipe is about 500).
const RX: usize = 16 * 1024;

/// Why the link failed.
#[derive(Debug)]
pub(crate) enum LinkError {
    /// The socket failed or timed out.
    Io(io::Error),
    /// The controller closed the connection.
    Closed,
    /// A package did not decode.
    Rtde(RtdeError),
}

/// A package in the receive buffer: its header and where its payload lies.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Package {
    pub header: Header,
    start: usize,
    end: usize,
}

/// An RTDE connection.
#[derive(Debug)]
pub(crate) struct RtdeLink {
    tcp: TcpLink,
    rx: Box<[u8; RX]>,
    /// Bytes read and not yet consumed: `rx[head..tail]`.
    head: usize,
    tail: usize,
    pub version: u16,
    tx: Box<[u8; 4096]>,
}

impl RtdeLink {
    pub(crate) fn connect(addr: SocketAddr, timeout: Duration) -> io::Result<Self> {
        Ok(Self {
            tcp: TcpLink::connect(addr, timeout)?,
            rx: Box::new([0; RX]),
            head: 0,
            tail: 0,
            version: 1,
            tx: Box::new([0; 4096]),
        })
    }

    /// Sends one message before `deadline`.
    pub(crate) fn send(&mut self, m: &Message<'_>, deadline: Instant) -> Result<(), LinkError> {
        let n = m
            .encode(self.version, &mut self.tx[..])
            .map_err(LinkError::Rtde)?;
        self.tcp
            .send_all(&self.tx[..n], deadline)
            .map_err(LinkError::Io)
    }

    /// The payload of a package returned by [`next`](Self::next).
    pub(crate) fn payload(&self, p: &Package) -> &[u8] {
        &self.rx[p.start..p.end]
    }

    /// Reads what is there without waiting; `Ok(false)`: nothing.
    fn fill(&mut self) -> Result<bool, LinkError> {
        if self.head > 0 && self.tail == RX {
            self.rx.copy_within(self.head..self.tail, 0);
            self.tail -= self.head;
            self.head = 0;
        }
        if self.tail == RX {
            // A package larger than the buffer: the stream cannot go on.
            return Err(LinkError::Rtde(RtdeError::TooLong {
                what: "package",
                expected: RX,
                got: RX + 1,
            }));
        }
        match self.tcp.try_recv(&mut self.rx[self.tail..]) {
            Ok(Some(0)) => Err(LinkError::Closed),
            Ok(Some(n)) => {
                self.tail += n;
                Ok(true)
            }
            Ok(None) => Ok(false),
            Err(e) => Err(LinkError::Io(e)),
        }
    }

    /// The next complete package, waiting for it until `deadline` (`Ok(None)`: none came).
    /// Its payload stays in the buffer until the next call.
    pub(crate) fn next(&mut self, deadline: Instant) -> Result<Option<Package>, LinkError> {
        if self.head == self.tail {
            self.head = 0;
            self.tail = 0;
        }
        loop {
            if let Some((h, payload, _)) =
                split(&self.rx[self.head..self.tail]).map_err(LinkError::Rtde)?
            {
                let start = self.head + HEADER_LEN;
                let p = Package {
                    header: h,
                    start,
                    end: start + payload.len(),
                };
                self.head = p.end;
                return Ok(Some(p));
            }
            if self.fill()? {
                continue;
            }
            if Instant::now() >= deadline {
                return Ok(None);
            }
            let fd = std::os::fd::AsFd::as_fd(&self.tcp);
            if !crate::transport::wait(fd, crate::transport::Readiness::Readable, deadline)
                .map_err(LinkError::Io)?
            {
                return Ok(None);
            }
        }
    }
}
