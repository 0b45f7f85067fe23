//! CAN transports: one trait ([`CanTransport`]), non-blocking, every wait bounded by a
//! deadline, over which the CANopen master and the fake drives exchange [`Frame`]s:
//!
//! - [`socketcan`]: a Linux SocketCAN raw socket (`socketcan://can0`);
//! - [`cannelloni_udp`]: cannelloni version 2 datagrams, one per [`flush`] (`cannelloni+udp://`);
//! - [`cannelloni_tcp`]: the cannelloni version 1 TCP stream (`cannelloni+tcp://`);
//! - [`bus`]: an in-process bus for unit tests;
//! - [`record`]: a transport that also writes every frame to a pcap (SocketCAN link type 227,
//!   for Wireshark) and a candump log (for can-utils);
//! - [`replay`]: a recorded bus (candump log) played back to a device, which is checked against
//!   the recording frame by frame.
//!
//! [`flush`]: CanTransport::flush

pub mod bus;
pub mod cannelloni_tcp;
pub mod cannelloni_udp;
pub mod record;
pub mod replay;
pub mod socketcan;

use std::fmt;
use std::io;
use std::net::{SocketAddr, ToSocketAddrs};
use std::time::{Duration, Instant};

use crate::proto::can::Frame;

/// A frame as received.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Received {
    /// The frame.
    pub frame: Frame,
    /// The kernel's receive time since the Unix epoch, where the transport has one
    /// (SocketCAN); `None` otherwise.
    pub timestamp: Option<Duration>,
}

/// What a transport has seen below the frames: what it refused and why.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TransportCounters {
    /// Frames sent.
    pub frames_sent: u64,
    /// Frames received and handed on.
    pub frames_received: u64,
    /// Datagrams or connections from another peer than the configured one, dropped.
    pub rejected: u64,
    /// Datagrams or stream bytes that did not decode, dropped.
    pub corrupt: u64,
    /// Datagrams missing by their sequence numbers (cannelloni UDP).
    pub sequence_gaps: u64,
    /// Frames dropped because the receive queue was full.
    pub overruns: u64,
    /// SocketCAN error frames received.
    pub error_frames: u64,
}

impl core::ops::AddAssign for TransportCounters {
    /// Adds another link's counts (those of a link closed since, for totals that survive it).
    fn add_assign(&mut self, n: Self) {
        self.frames_sent += n.frames_sent;
        self.frames_received += n.frames_received;
        self.rejected += n.rejected;
        self.corrupt += n.corrupt;
        self.sequence_gaps += n.sequence_gaps;
        self.overruns += n.overruns;
        self.error_frames += n.error_frames;
    }
}

/// A CAN link: frames out (queued, then flushed once per cycle) and in.
pub trait CanTransport: Send {
    /// Queues a frame for the next [`flush`](Self::flush); never waits.
    fn send(&mut self, frame: &Frame) -> io::Result<()>;
    /// Writes the queued frames (cannelloni UDP: as one datagram), waiting at most until
    /// `deadline`.
    fn flush(&mut self, deadline: Instant) -> io::Result<()>;
    /// The next received frame, waiting at most until `deadline` (`Ok(None)` when it passed;
    /// a deadline in the past only takes what is already there).
    fn recv(&mut self, deadline: Instant) -> io::Result<Option<Received>>;
    /// The counts so far.
    fn counters(&self) -> TransportCounters;
}

impl<T: CanTransport + ?Sized> CanTransport for Box<T> {
    fn send(&mut self, frame: &Frame) -> io::Result<()> {
        (**self).send(frame)
    }

    fn flush(&mut self, deadline: Instant) -> io::Result<()> {
        (**self).flush(deadline)
    }

    fn recv(&mut self, deadline: Instant) -> io::Result<Option<Received>> {
        (**self).recv(deadline)
    }

    fn counters(&self) -> TransportCounters {
        (**self).counters()
    }
}

/// Where a CAN link goes, parsed from a device address.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CanAddress {
    /// `socketcan://IFACE`.
    SocketCan {
        /// Interface name (`can0`).
        interface: String,
    },
    /// `cannelloni+udp://HOST:PORT[?local=ADDR:PORT]`: datagrams to `remote`, from `local`
    /// (default 127.0.0.1:0 for a loopback peer, else 0.0.0.0:0). A fake that serves binds
    /// `remote` and answers whoever sent first.
    CannelloniUdp {
        /// The peer.
        remote: SocketAddr,
        /// The local address to bind.
        local: SocketAddr,
    },
    /// `cannelloni+tcp://HOST:PORT[?listen]`: connect to `addr`, or listen on it.
    CannelloniTcp {
        /// The address.
        addr: SocketAddr,
        /// Whether to listen (and accept one peer) instead of connecting.
        listen: bool,
    },
}

/// Why an address is not a CAN address.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AddressError(pub String);

impl fmt::Display for AddressError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for AddressError {}

fn resolve(host_port: &str) -> Result<SocketAddr, AddressError> {
    if let Ok(a) = host_port.parse::<SocketAddr>() {
        return Ok(a);
    }
    host_port
        .to_socket_addrs()
        .map_err(|e| AddressError(format!("cannot resolve `{host_port}` (HOST:PORT): {e}")))?
        .next()
        .ok_or_else(|| AddressError(format!("`{host_port}` has no address")))
}

impl CanAddress {
    /// Parses `socketcan://IFACE`, `cannelloni+udp://HOST:PORT[?local=ADDR:PORT]` or
    /// `cannelloni+tcp://HOST:PORT[?listen]`.
    pub fn parse(text: &str) -> Result<Self, AddressError> {
        if let Some(iface) = text.strip_prefix("socketcan://") {
            if iface.is_empty() || iface.len() > 15 || iface.contains(['/', ' ', '?']) {
                return Err(AddressError(format!(
                    "`{text}`: an interface name of 1 to 15 characters is expected"
                )));
            }
            return Ok(CanAddress::SocketCan {
                interface: iface.to_owned(),
            });
        }
        let split = |rest: &str| match rest.split_once('?') {
            Some((a, q)) => (a.to_owned(), Some(q.to_owned())),
            None => (rest.to_owned(), None),
        };
        if let Some(rest) = text.strip_prefix("cannelloni+udp://") {
            let (addr, query) = split(rest);
            let remote = resolve(&addr)?;
            let local = match query.as_deref() {
                None => default_local(remote),
                Some(q) => match q.strip_prefix("local=") {
                    Some(l) => resolve(l)?,
                    None => {
                        return Err(AddressError(format!(
                            "`{text}`: unknown option `{q}` (expected ?local=ADDR:PORT)"
                        )));
                    }
                },
            };
            return Ok(CanAddress::CannelloniUdp { remote, local });
        }
        if let Some(rest) = text.strip_prefix("cannelloni+tcp://") {
            let (addr, query) = split(rest);
            let listen = match query.as_deref() {
                None => false,
                Some("listen") => true,
                Some(q) => {
                    return Err(AddressError(format!(
                        "`{text}`: unknown option `{q}` (expected ?listen)"
                    )));
                }
            };
            return Ok(CanAddress::CannelloniTcp {
                addr: resolve(&addr)?,
                listen,
            });
        }
        Err(AddressError(format!(
            "`{text}`: expected socketcan://IFACE, cannelloni+udp://HOST:PORT or \
             cannelloni+tcp://HOST:PORT"
        )))
    }

    /// Opens the link as a master (connects; a listening TCP address waits at most
    /// `timeout` for its peer).
    pub fn open(&self, timeout: Duration) -> io::Result<Box<dyn CanTransport>> {
        Ok(match self {
            CanAddress::SocketCan { interface } => {
                Box::new(socketcan::SocketCan::open(interface, &[], false)?)
            }
            CanAddress::CannelloniUdp { remote, local } => {
                Box::new(cannelloni_udp::CannelloniUdp::connect(*remote, *local)?)
            }
            CanAddress::CannelloniTcp {
                addr,
                listen: false,
            } => Box::new(cannelloni_tcp::CannelloniTcp::connect(*addr, timeout)?),
            CanAddress::CannelloniTcp { addr, listen: true } => {
                let listener = cannelloni_tcp::Listener::bind(*addr)?;
                Box::new(listener.accept(Instant::now() + timeout)?)
            }
        })
    }
}

impl fmt::Display for CanAddress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CanAddress::SocketCan { interface } => write!(f, "socketcan://{interface}"),
            CanAddress::CannelloniUdp { remote, .. } => write!(f, "cannelloni+udp://{remote}"),
            CanAddress::CannelloniTcp { addr, listen } => {
                write!(
                    f,
                    "cannelloni+tcp://{addr}{}",
                    if *listen { "?listen" } else { "" }
                )
            }
        }
    }
}

/// 127.0.0.1:0 towards a loopback peer, any address otherwise (the route decides).
pub fn default_local(remote: SocketAddr) -> SocketAddr {
    use std::net::{IpAddr, Ipv4Addr, Ipv6Addr};
    match remote.ip() {
        ip if ip.is_loopback() => SocketAddr::new(ip, 0),
        IpAddr::V6(_) => SocketAddr::new(IpAddr::V6(Ipv6Addr::UNSPECIFIED), 0),
        IpAddr::V4(_) => SocketAddr::new(IpAddr::V4(Ipv4Addr::UNSPECIFIED), 0),
    }
}

/// A fixed-capacity queue of received frames (no allocation after construction).
#[derive(Debug)]
pub(crate) struct RxQueue {
    items: heapless::Deque<Received, 512>,
    pub(crate) overruns: u64,
}

impl RxQueue {
    pub(crate) const fn new() -> Self {
        Self {
            items: heapless::Deque::new(),
            overruns: 0,
        }
    }

    pub(crate) fn push(&mut self, r: Received) {
        if self.items.push_back(r).is_err() {
            self.overruns += 1;
        }
    }

    pub(crate) fn pop(&mut self) -> Option<Received> {
        self.items.pop_front()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_parse_and_bind_loopback_by_default() {
        assert_eq!(
            CanAddress::parse("socketcan://can0"),
            Ok(CanAddress::SocketCan {
                interface: "can0".into()
            })
        );
        assert_eq!(
            CanAddress::parse("cannelloni+udp://127.0.0.1:20000"),
            Ok(CanAddress::CannelloniUdp {
                remote: "127.0.0.1:20000".parse().unwrap(),
                local: "127.0.0.1:0".parse().unwrap()
            })
        );
        assert_eq!(
            CanAddress::parse("cannelloni+udp://127.0.0.1:20000?local=127.0.0.1:20001"),
            Ok(CanAddress::CannelloniUdp {
                remote: "127.0.0.1:20000".parse().unwrap(),
                local: "127.0.0.1:20001".parse().unwrap()
            })
        );
        assert_eq!(
            CanAddress::parse("cannelloni+tcp://127.0.0.1:20000?listen"),
            Ok(CanAddress::CannelloniTcp {
                addr: "127.0.0.1:20000".parse().unwrap(),
                listen: true
            })
        );
        for bad in [
            "socketcan://",
            "socketcan://a_very_long_interface_name",
            "cannelloni+udp://nohost",
            "cannelloni+udp://127.0.0.1:1?remote=x",
            "cannelloni+tcp://127.0.0.1:1?serve",
            "can://x",
        ] {
            assert!(CanAddress::parse(bad).is_err(), "{bad}");
        }
    }
}
