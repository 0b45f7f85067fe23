//! Frames on the wire for the master: one [`PacketLink`] on the segment's interface, frames
//! built in a fixed buffer, replies matched to requests by the datagram index, our own echo and
//! foreign frames dropped, and every lost, late and unmatched frame counted. Nothing here
//! allocates after [`Link::open`].

use std::time::{Duration, Instant};

use super::error::EcError;
use crate::proto::ecat::datagram::DatagramHeader;
use crate::proto::ecat::frame::{ETHERTYPE, Frame, FrameBuilder, MAX_FRAME_LEN, MacAddr};
use crate::transport::PacketLink;

/// Frame counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkCounters {
    /// Frames sent.
    pub sent: u64,
    /// Replies used.
    pub received: u64,
    /// Frames whose reply did not come before the deadline.
    pub lost: u64,
    /// Replies that came after their deadline (found later and dropped).
    pub late: u64,
    /// Returned frames with an index nothing waits for.
    pub unmatched: u64,
    /// Our own frames seen again (source = our address), dropped.
    pub echo: u64,
    /// Frames from another sender, dropped.
    pub foreign: u64,
    /// Returned frames that did not decode.
    pub corrupt: u64,
}

const GIVEN_UP: usize = 32;

/// The master's side of the wire.
#[derive(Debug)]
pub struct Link {
    socket: PacketLink,
    source: MacAddr,
    tx: Box<[u8; MAX_FRAME_LEN]>,
    rx: Box<[u8; MAX_FRAME_LEN + 64]>,
    rx_len: usize,
    next_index: u8,
    given_up: [Option<u8>; GIVEN_UP],
    given_up_next: usize,
    counters: LinkCounters,
    spin: Duration,
}

impl Link {
    /// Opens the raw socket on `interface`; frames leave from `source`.
    pub fn open(interface: &str, source: MacAddr) -> Result<Self, EcError> {
        let socket = PacketLink::open(interface, ETHERTYPE).map_err(|e| EcError::io(&e))?;
        Ok(Self {
            socket,
            source,
            tx: Box::new([0; MAX_FRAME_LEN]),
            rx: Box::new([0; MAX_FRAME_LEN + 64]),
            rx_len: 0,
            next_index: 0,
            given_up: [None; GIVEN_UP],
            given_up_next: 0,
            counters: LinkCounters::default(),
            spin: Duration::ZERO,
        })
    }

    /// Polls the socket without sleeping for up to `spin` after each send before it sleeps in
    /// the kernel: a reply that comes within that time is taken without a scheduler wake-up
    /// (tens of µs on a PC). Costs CPU time; 0 never spins.
    pub fn set_spin(&mut self, spin: Duration) {
        self.spin = spin;
    }

    /// The interface.
    pub fn interface(&self) -> &str {
        self.socket.interface()
    }

    /// Counts so far.
    pub fn counters(&self) -> LinkCounters {
        self.counters
    }

    /// A fresh datagram index for the next frame.
    pub fn next_index(&mut self) -> u8 {
        let i = self.next_index;
        self.next_index = self.next_index.wrapping_add(1);
        i
    }

    /// A frame builder over the send buffer.
    pub fn builder(&mut self) -> Result<FrameBuilder<'_>, EcError> {
        FrameBuilder::new(&mut self.tx[..], self.source).map_err(EcError::Frame)
    }

    /// The send buffer (to fill in datagram data after `builder`).
    pub fn tx_mut(&mut self) -> &mut [u8] {
        &mut self.tx[..]
    }

    /// Sends the first `len` bytes of the send buffer.
    pub fn send(&mut self, len: usize) -> Result<(), EcError> {
        self.socket
            .send(&self.tx[..len])
            .map_err(|e| EcError::io(&e))?;
        self.counters.sent += 1;
        Ok(())
    }

    /// Waits for the reply to the frame whose first datagram carries `index`, until
    /// `deadline`. On success the reply is in [`reply`](Self::reply). Echoes, foreign frames,
    /// late and unmatched replies on the way are dropped and counted; `Ok(false)` means the
    /// deadline passed (the frame is counted lost and its index remembered, so a late reply is
    /// recognised).
    pub fn receive(&mut self, index: u8, deadline: Instant) -> Result<bool, EcError> {
        let returned = self.source.forwarded();
        let spin_until = Instant::now() + self.spin;
        loop {
            let mut got = None;
            while got.is_none() && Instant::now() < spin_until.min(deadline) {
                got = self
                    .socket
                    .try_recv(&mut self.rx[..])
                    .map_err(|e| EcError::io(&e))?;
                if got.is_none() {
                    std::hint::spin_loop();
                }
            }
            let got = match got {
                Some(n) => Some(n),
                None => self
                    .socket
                    .recv_until(&mut self.rx[..], deadline)
                    .map_err(|e| EcError::io(&e))?,
            };
            let n = match got {
                Some(n) => n.min(self.rx.len()),
                None => {
                    self.counters.lost += 1;
                    self.given_up[self.given_up_next] = Some(index);
                    self.given_up_next = (self.given_up_next + 1) % GIVEN_UP;
                    return Ok(false);
                }
            };
            if n < 14 {
                self.counters.corrupt += 1;
                continue;
            }
            let bytes = &self.rx[..n];
            let src = MacAddr([bytes[6], bytes[7], bytes[8], bytes[9], bytes[10], bytes[11]]);
            if src == self.source {
                self.counters.echo += 1;
                continue;
            }
            if src != returned {
                self.counters.foreign += 1;
                continue;
            }
            let first = match Frame::decode(bytes) {
                Ok(f) => f
                    .datagrams()
                    .next()
                    .and_then(Result::ok)
                    .map(|d| d.header.index),
                Err(_) => None,
            };
            let Some(got) = first else {
                self.counters.corrupt += 1;
                continue;
            };
            if got == index {
                self.counters.received += 1;
                self.rx_len = n;
                return Ok(true);
            }
            if let Some(slot) = self.given_up.iter_mut().find(|s| **s == Some(got)) {
                *slot = None;
                self.counters.late += 1;
            } else {
                self.counters.unmatched += 1;
            }
        }
    }

    /// The last reply frame.
    pub fn reply(&self) -> &[u8] {
        &self.rx[..self.rx_len]
    }

    /// One datagram, sent and answered: `data` goes out and the reply's data comes back into
    /// it. Returns the working counter.
    pub fn transact(
        &mut self,
        header: DatagramHeader,
        data: &mut [u8],
        timeout: Duration,
    ) -> Result<u16, EcError> {
        let index = self.next_index();
        let mut h = header;
        h.index = index;
        let len = {
            let mut b = self.builder()?;
            b.push(h, data).map_err(EcError::Frame)?;
            b.finish()
        };
        self.send(len)?;
        if !self.receive(index, Instant::now() + timeout)? {
            return Err(EcError::Timeout {
                what: "a datagram",
                waited_us: timeout.as_micros() as u64,
            });
        }
        let frame = Frame::decode(self.reply()).map_err(EcError::Frame)?;
        let d = frame
            .datagrams()
            .next()
            .and_then(Result::ok)
            .ok_or(EcError::Reply("no datagram"))?;
        if d.header.cmd != h.cmd || d.data.len() != data.len() {
            return Err(EcError::Reply("the reply's command or length differs"));
        }
        data.copy_from_slice(d.data);
        Ok(d.wkc)
    }

    /// Drops every frame waiting in the socket (before a fresh start).
    pub fn drain(&mut self) -> Result<usize, EcError> {
        self.socket
            .drain(&mut self.rx[..])
            .map_err(|e| EcError::io(&e))
    }
}
