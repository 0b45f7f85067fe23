//! The two channels of a session (std): the TCP command channel, which assembles answers from
//! the byte stream into a buffer whose capacity is fixed while a motion runs, and the UDP state
//! channel, which hears only the robot (its address, and from the first state on its port) and
//! counts everything else.

use std::io;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, UdpSocket};
use std::os::fd::AsFd;
use std::time::{Duration, Instant};

use super::command::{COMMAND_LEN, RobotCommand};
use super::message::{HEADER_LEN, Header, MAX_REQUEST_LEN, MessageError, Request, Status};
use super::state::STATE_LEN;
use crate::transport::{Readiness, TcpLink, wait};

/// Largest answer accepted at all (a URDF of a few hundred kB at most).
pub(crate) const MAX_ANSWER_LEN: usize = 16 << 20;
/// Bytes the answer buffer holds from the start: enough for the FR3's URDF (10.5 kB) and every
/// other answer, so it does not grow while a motion runs.
pub(crate) const ANSWER_BUFFER: usize = 64 << 10;

/// One answer taken from the stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Answer {
    pub(crate) header: Header,
    pub(crate) status: Status,
}

/// What went wrong on a channel.
#[derive(Debug)]
pub(crate) enum LinkError {
    Io(io::Error),
    Closed,
    Message(MessageError),
}

impl From<io::Error> for LinkError {
    fn from(e: io::Error) -> Self {
        Self::Io(e)
    }
}

/// The TCP command channel.
#[derive(Debug)]
pub(crate) struct CommandChannel {
    link: TcpLink,
    /// The assembly buffer, all of it initialised; `filled` bytes of it hold data.
    rx: Vec<u8>,
    filled: usize,
    next_id: u32,
    /// Whether `rx` may grow (outside a motion).
    pub(crate) may_grow: bool,
}

impl CommandChannel {
    pub(crate) fn connect(peer: SocketAddr, timeout: Duration) -> io::Result<Self> {
        Ok(Self {
            link: TcpLink::connect(peer, timeout)?,
            rx: vec![0; ANSWER_BUFFER],
            filled: 0,
            next_id: 0,
            may_grow: true,
        })
    }

    /// Sends `request`; returns its command id.
    pub(crate) fn send(&mut self, request: &Request, deadline: Instant) -> Result<u32, LinkError> {
        let mut buf = [0u8; MAX_REQUEST_LEN];
        let id = self.next_id;
        let n = request.encode(id, &mut buf).map_err(LinkError::Message)?;
        self.link.send_all(&buf[..n], deadline)?;
        self.next_id = self.next_id.wrapping_add(1);
        Ok(id)
    }

    /// Reads what the socket holds without waiting and hands every complete answer to
    /// `on_answer` with the bytes after its status byte. Allocates nothing unless an answer
    /// outgrows the buffer, which is refused while `may_grow` is off.
    pub(crate) fn poll(
        &mut self,
        mut on_answer: impl FnMut(Answer, &[u8]),
    ) -> Result<(), LinkError> {
        loop {
            if self.filled == self.rx.len() {
                if !self.may_grow {
                    return Err(LinkError::Message(MessageError::BadSize {
                        size: u32::try_from(self.filled + 1).unwrap_or(u32::MAX),
                        max: self.rx.len(),
                    }));
                }
                let grown = (self.rx.len() * 2).min(MAX_ANSWER_LEN + HEADER_LEN);
                self.rx.resize(grown, 0);
            }
            let n = match self.link.try_recv(&mut self.rx[self.filled..]) {
                Ok(Some(0)) => return Err(LinkError::Closed),
                Ok(Some(n)) => n,
                Ok(None) => 0,
                Err(e) => return Err(LinkError::Io(e)),
            };
            self.filled += n;
            self.take_answers(&mut on_answer)?;
            if n == 0 {
                return Ok(());
            }
        }
    }

    /// Splits complete answers off the front of the buffer.
    fn take_answers(&mut self, on_answer: &mut impl FnMut(Answer, &[u8])) -> Result<(), LinkError> {
        let mut at = 0;
        while self.filled - at >= HEADER_LEN {
            let header = Header::decode(&self.rx[at..self.filled], MAX_ANSWER_LEN)
                .map_err(LinkError::Message)?;
            let size = header.size as usize;
            if size > self.rx.len() && !self.may_grow {
                return Err(LinkError::Message(MessageError::BadSize {
                    size: header.size,
                    max: self.rx.len(),
                }));
            }
            if self.filled - at < size {
                break;
            }
            if size < HEADER_LEN + 1 {
                return Err(LinkError::Message(MessageError::TooShort {
                    what: "answer",
                    needed: HEADER_LEN + 1,
                    got: size,
                }));
            }
            let status = Status::decode(header.command, self.rx[at + HEADER_LEN])
                .map_err(LinkError::Message)?;
            on_answer(
                Answer { header, status },
                &self.rx[at + HEADER_LEN + 1..at + size],
            );
            at += size;
        }
        self.rx.copy_within(at..self.filled, 0);
        self.filled -= at;
        Ok(())
    }

    /// Waits until the socket is readable or `deadline` passes.
    pub(crate) fn wait(&self, deadline: Instant) -> io::Result<bool> {
        wait(self.link.as_fd(), Readiness::Readable, deadline)
    }
}

/// The UDP state channel.
#[derive(Debug)]
pub(crate) struct StateChannel {
    socket: UdpSocket,
    robot: IpAddr,
    /// The robot's address and port, learned from its first state.
    peer: Option<SocketAddr>,
    tx: [u8; COMMAND_LEN],
    /// Datagrams from anyone but the robot, dropped.
    pub(crate) foreign: u64,
    /// Datagrams from the robot of the wrong length.
    pub(crate) wrong_length: u64,
}

impl StateChannel {
    /// Binds `local` (an unspecified address becomes the one that routes to `robot`).
    pub(crate) fn bind(mut local: SocketAddr, robot: IpAddr) -> io::Result<Self> {
        if local.ip().is_unspecified() {
            local.set_ip(route_ip(robot)?);
        }
        let socket = UdpSocket::bind(local)?;
        socket.set_nonblocking(true)?;
        Ok(Self {
            socket,
            robot,
            peer: None,
            tx: [0; COMMAND_LEN],
            foreign: 0,
            wrong_length: 0,
        })
    }

    pub(crate) fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    pub(crate) fn peer(&self) -> Option<SocketAddr> {
        self.peer
    }

    /// Takes one pending state datagram, if any, into `buf` without waiting: only from the
    /// robot (its address; once known, its port), exactly [`STATE_LEN`] bytes. Others are
    /// dropped and counted, at most until `deadline`.
    pub(crate) fn try_recv(
        &mut self,
        buf: &mut [u8; STATE_LEN + 1],
        deadline: Instant,
    ) -> io::Result<bool> {
        loop {
            match self.socket.recv_from(buf) {
                Ok((n, from)) => {
                    // A robot on loopback is heard from any loopback source: a simulator that
                    // binds its UDP socket to the wildcard (franky-sim) sends from 127.0.0.1
                    // whatever address it serves on. The port is checked from the first state on.
                    let ours = match self.peer {
                        Some(p) => from == p,
                        None => {
                            from.ip() == self.robot
                                || (self.robot.is_loopback() && from.ip().is_loopback())
                        }
                    };
                    if !ours {
                        self.foreign += 1;
                    } else if n != STATE_LEN {
                        self.wrong_length += 1;
                    } else {
                        self.peer.get_or_insert(from);
                        return Ok(true);
                    }
                    if Instant::now() >= deadline {
                        return Ok(false);
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(false),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }

    /// Waits for a state until `deadline` (`Ok(false)`: none came).
    pub(crate) fn recv_until(
        &mut self,
        buf: &mut [u8; STATE_LEN + 1],
        deadline: Instant,
    ) -> io::Result<bool> {
        loop {
            if self.try_recv(buf, deadline)? {
                return Ok(true);
            }
            if !wait(self.socket.as_fd(), Readiness::Readable, deadline)? {
                return Ok(false);
            }
        }
    }

    /// Sends `command` to the robot (known from its first state).
    pub(crate) fn send(&mut self, command: &RobotCommand) -> io::Result<()> {
        let peer = self.peer.ok_or(io::ErrorKind::NotConnected)?;
        command.encode(&mut self.tx);
        let n = self.socket.send_to(&self.tx, peer)?;
        if n == COMMAND_LEN {
            Ok(())
        } else {
            Err(io::ErrorKind::WriteZero.into())
        }
    }
}

/// The local address of the route to `robot`.
pub(crate) fn route_ip(robot: IpAddr) -> io::Result<IpAddr> {
    let any = match robot {
        IpAddr::V4(_) => IpAddr::V4(Ipv4Addr::UNSPECIFIED),
        IpAddr::V6(_) => IpAddr::V6(Ipv6Addr::UNSPECIFIED),
    };
    let probe = UdpSocket::bind((any, 0))?;
    probe.connect((robot, 9))?;
    Ok(probe.local_addr()?.ip())
}
