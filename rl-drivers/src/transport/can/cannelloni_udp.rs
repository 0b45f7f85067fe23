//! cannelloni over UDP: every [`flush`](CanTransport::flush) sends the frames queued since the
//! last one as one version 2 datagram (never the cannelloni tool's 100 ms batching: a control
//! loop flushes once per cycle). Received datagrams are checked — from the peer, version 2,
//! DATA, every frame valid — or dropped whole and counted; gaps in the sequence numbers are
//! counted as lost datagrams. Each frame carries the kernel's receive time of its datagram
//! (`SO_TIMESTAMPNS`, [`timestamp`]), as on SocketCAN.
//!
//! A master [`connect`](CannelloniUdp::connect)s to a fixed peer: datagrams from any other
//! address are rejected. A fake [`serve`](CannelloniUdp::serve)s on a bound address and takes
//! the first sender of a valid datagram as its peer, as a cannelloni gateway has one remote
//! (the tool checks the peer's address unless told not to): datagrams from any other address
//! are rejected and counted while the peer is active, and a new sender is taken only after
//! the peer has been silent for [`PEER_HOLD`] (a master that was restarted on a new port).

use std::io;
use std::net::{SocketAddr, UdpSocket};
use std::os::fd::AsFd;
use std::time::{Duration, Instant};

use socket2::{Domain, Protocol, Socket, Type};

use super::{CanTransport, Received, RxQueue, TransportCounters};
use crate::proto::can::Frame;
use crate::proto::can::cannelloni::{self, HEADER_LEN};
use crate::transport::{Readiness, timestamp, wait};

/// Bytes of one datagram at most (an Ethernet MTU's UDP payload).
pub const MAX_DATAGRAM: usize = 1472;

/// How long a serving endpoint keeps its peer after the peer's last datagram: until then a
/// datagram from another address is rejected. A running master sends every cycle (a few ms);
/// a quarter of a second of silence means it has ended, and the next master is taken.
pub const PEER_HOLD: Duration = Duration::from_millis(250);

/// A cannelloni UDP endpoint.
#[derive(Debug)]
pub struct CannelloniUdp {
    socket: UdpSocket,
    timestamps: bool,
    peer: Option<SocketAddr>,
    follow_sender: bool,
    /// When the peer's last valid datagram came (a serving endpoint).
    peer_heard: Option<Instant>,
    tx: [u8; MAX_DATAGRAM],
    tx_len: usize,
    tx_count: u16,
    seq: u8,
    last_seq_in: Option<u8>,
    rx_buf: [u8; 4096],
    rx: RxQueue,
    counters: TransportCounters,
}

/// A bound non-blocking socket, and whether the kernel gives receive timestamps on it (Linux
/// does; an emulator such as qemu-user may refuse the option: the frames then carry none).
fn bind(local: SocketAddr) -> io::Result<(UdpSocket, bool)> {
    let socket = Socket::new(Domain::for_address(local), Type::DGRAM, Some(Protocol::UDP))?;
    socket.set_nonblocking(true)?;
    socket.bind(&local.into())?;
    let timestamps = timestamp::enable(socket.as_fd()).is_ok();
    Ok((socket.into(), timestamps))
}

impl CannelloniUdp {
    /// A master's endpoint: bound to `local`, exchanging datagrams with `peer` only.
    pub fn connect(peer: SocketAddr, local: SocketAddr) -> io::Result<Self> {
        Ok(Self::with(bind(local)?, Some(peer), false))
    }

    /// A fake's endpoint: bound to `local`, taking the first sender of a valid datagram as its
    /// peer and rejecting others while that peer is active (heard within [`PEER_HOLD`]).
    pub fn serve(local: SocketAddr) -> io::Result<Self> {
        Ok(Self::with(bind(local)?, None, true))
    }

    fn with(
        (socket, timestamps): (UdpSocket, bool),
        peer: Option<SocketAddr>,
        follow_sender: bool,
    ) -> Self {
        Self {
            socket,
            timestamps,
            peer,
            follow_sender,
            peer_heard: None,
            tx: [0; MAX_DATAGRAM],
            tx_len: 0,
            tx_count: 0,
            seq: 0,
            last_seq_in: None,
            rx_buf: [0; 4096],
            rx: RxQueue::new(),
            counters: TransportCounters::default(),
        }
    }

    /// The bound address.
    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// Whether received frames carry the kernel's receive timestamp (Linux gives them; an
    /// emulator may not).
    pub fn has_timestamps(&self) -> bool {
        self.timestamps
    }

    /// The peer (for a serving endpoint: the sender it took, once one has sent).
    pub fn peer(&self) -> Option<SocketAddr> {
        self.peer
    }

    /// Sends the queued frames as one datagram (nothing if none are queued).
    fn send_datagram(&mut self) -> io::Result<()> {
        if self.tx_count == 0 {
            return Ok(());
        }
        let count = self.tx_count;
        self.tx[..3].copy_from_slice(&[cannelloni::UDP_VERSION, 0, self.seq]);
        self.tx[3..5].copy_from_slice(&count.to_be_bytes());
        self.seq = self.seq.wrapping_add(1);
        self.tx_count = 0;
        let len = self.tx_len;
        self.tx_len = 0;
        let Some(peer) = self.peer else {
            // Nobody to talk to yet: the frames are dropped (a serving fake answers requests).
            return Ok(());
        };
        let n = self.socket.send_to(&self.tx[..len], peer)?;
        if n != len {
            return Err(io::Error::new(
                io::ErrorKind::WriteZero,
                "datagram sent partially",
            ));
        }
        self.counters.frames_sent += u64::from(count);
        Ok(())
    }

    fn take_datagram(&mut self, n: usize, from: SocketAddr, at: Option<Duration>) {
        let now = Instant::now();
        match self.peer {
            Some(p) if p == from => {}
            // A serving endpoint's peer is taken while it is active: a bus carries one master's
            // frames, not every sender's.
            Some(_)
                if self.follow_sender
                    && self
                        .peer_heard
                        .is_some_and(|t| now.duration_since(t) < PEER_HOLD) =>
            {
                self.counters.rejected += 1;
                return;
            }
            _ if self.follow_sender => {}
            _ => {
                self.counters.rejected += 1;
                return;
            }
        }
        let bytes = &self.rx_buf[..n];
        let Ok((header, frames)) = cannelloni::read_datagram(bytes) else {
            self.counters.corrupt += 1;
            return;
        };
        // Check every frame before using any: a datagram is taken whole or not at all.
        if frames.clone().any(|f| f.is_err()) {
            self.counters.corrupt += 1;
            return;
        }
        if self.follow_sender {
            if self.peer != Some(from) {
                self.last_seq_in = None;
            }
            self.peer = Some(from);
            self.peer_heard = Some(now);
        }
        if let Some(last) = self.last_seq_in {
            let gap = header.seq.wrapping_sub(last.wrapping_add(1));
            self.counters.sequence_gaps += u64::from(gap.min(127));
        }
        self.last_seq_in = Some(header.seq);
        for frame in frames.flatten() {
            self.counters.frames_received += 1;
            self.rx.push(Received {
                frame,
                timestamp: at,
            });
        }
    }
}

impl CanTransport for CannelloniUdp {
    fn send(&mut self, frame: &Frame) -> io::Result<()> {
        if self.tx_count == 0 {
            self.tx_len = HEADER_LEN;
        }
        if self.tx_len + cannelloni::encoded_len(frame) > MAX_DATAGRAM || self.tx_count == u16::MAX
        {
            // Full: what is there goes out as one datagram, this frame starts the next.
            self.send_datagram()?;
            self.tx_len = HEADER_LEN;
        }
        let written = cannelloni::encode_frame(frame, &mut self.tx[self.tx_len..])
            .ok_or_else(|| io::Error::other("frame does not fit a datagram"))?;
        self.tx_len += written;
        self.tx_count += 1;
        Ok(())
    }

    fn flush(&mut self, _deadline: Instant) -> io::Result<()> {
        self.send_datagram()
    }

    fn recv(&mut self, deadline: Instant) -> io::Result<Option<Received>> {
        loop {
            if let Some(r) = self.rx.pop() {
                return Ok(Some(r));
            }
            match timestamp::recv(self.socket.as_fd(), &mut self.rx_buf) {
                Ok((n, Some(from), at)) => self.take_datagram(n, from, at),
                Ok((_, None, _)) => self.counters.rejected += 1,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    if !wait(self.socket.as_fd(), Readiness::Readable, deadline)? {
                        return Ok(None);
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) if e.kind() == io::ErrorKind::ConnectionRefused => {
                    // An ICMP port unreachable from an earlier send: the peer is not there
                    // (yet). Not a frame; keep listening.
                }
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_serving_endpoint_keeps_its_peer_while_it_is_active() {
        let any: SocketAddr = "127.0.0.1:0".parse().unwrap();
        let mut fake = CannelloniUdp::serve(any).unwrap();
        let to = fake.local_addr().unwrap();
        let master = UdpSocket::bind(any).unwrap();
        let stranger = UdpSocket::bind(any).unwrap();
        // One SYNC frame in a version 2 DATA datagram.
        let sync = [2, 0, 0, 0, 1, 0, 0, 0, 0x80, 0];
        let soon = || Instant::now() + Duration::from_millis(200);
        master.send_to(&sync, to).unwrap();
        assert!(fake.recv(soon()).unwrap().is_some());
        assert_eq!(fake.peer(), Some(master.local_addr().unwrap()));
        // A stranger's frames are not delivered, and the answers still go to the master.
        stranger.send_to(&sync, to).unwrap();
        assert!(fake.recv(soon()).unwrap().is_none());
        assert_eq!(fake.counters().rejected, 1);
        assert_eq!(fake.peer(), Some(master.local_addr().unwrap()));
        // Once the master has been silent for the hold time, a new one is taken (a restart).
        std::thread::sleep(PEER_HOLD + Duration::from_millis(50));
        stranger.send_to(&sync, to).unwrap();
        assert!(fake.recv(soon()).unwrap().is_some());
        assert_eq!(fake.peer(), Some(stranger.local_addr().unwrap()));
    }

    #[test]
    fn one_datagram_per_flush_and_only_the_peer_is_heard() {
        let any: SocketAddr = "127.0.0.1:0".parse().unwrap();
        let mut fake = CannelloniUdp::serve(any).unwrap();
        let mut master = CannelloniUdp::connect(fake.local_addr().unwrap(), any).unwrap();
        let raw = UdpSocket::bind(any).unwrap();
        raw.connect(fake.local_addr().unwrap()).unwrap();
        master.send(&Frame::standard(0x080, &[]).unwrap()).unwrap();
        master
            .send(&Frame::standard(0x201, &[0x0F, 0, 0, 0x10, 0, 0]).unwrap())
            .unwrap();
        master.flush(Instant::now()).unwrap();
        // The fake receives the reference's datagram (checked byte for byte by reading it raw).
        let soon = Instant::now() + Duration::from_secs(1);
        let a = fake.recv(soon).unwrap().unwrap();
        let b = fake.recv(soon).unwrap().unwrap();
        assert_eq!(
            (a.frame.standard_id(), b.frame.standard_id()),
            (Some(0x080), Some(0x201))
        );
        assert_eq!(fake.peer(), Some(master.local_addr().unwrap()));
        // Both frames carry the kernel's receive time of their datagram: before now, and not
        // before the send.
        if fake.has_timestamps() {
            let (ta, tb) = (a.timestamp.unwrap(), b.timestamp.unwrap());
            assert_eq!(ta, tb);
            let now = timestamp::since_epoch();
            assert!(
                ta <= now && now - ta < Duration::from_secs(1),
                "{ta:?} vs {now:?}"
            );
        } else {
            assert_eq!((a.timestamp, b.timestamp), (None, None));
            println!("SKIPPED the timestamp check: this kernel or emulator refuses SO_TIMESTAMPNS");
        }
        // The fake answers; a stranger's datagram to the master is rejected.
        let stranger = UdpSocket::bind(any).unwrap();
        stranger
            .send_to(
                &[2, 0, 0, 0, 1, 0, 0, 1, 0x81, 1, 5],
                master.local_addr().unwrap(),
            )
            .unwrap();
        fake.send(&Frame::standard(0x181, &[1, 2]).unwrap())
            .unwrap();
        fake.flush(Instant::now()).unwrap();
        let r = master.recv(soon).unwrap().unwrap();
        assert_eq!(r.frame.standard_id(), Some(0x181));
        assert_eq!(
            master
                .recv(Instant::now() + Duration::from_millis(20))
                .unwrap(),
            None
        );
        assert_eq!(master.counters().rejected, 1);
        // A bad datagram is dropped whole and counted; a skipped sequence number is a gap (from
        // another sender, once the master has been silent for the hold time).
        std::thread::sleep(PEER_HOLD);
        raw.send(&[3, 0, 0, 0, 0]).unwrap();
        raw.send(&[2, 0, 9, 0, 1, 0, 0, 1, 0x81, 9]).unwrap();
        assert_eq!(
            fake.recv(Instant::now() + Duration::from_millis(50))
                .unwrap(),
            None
        );
        assert_eq!(fake.counters().corrupt, 2);
        raw.send(&[2, 0, 9, 0, 0]).unwrap();
        raw.send(&[2, 0, 12, 0, 1, 0, 0, 1, 0x81, 0]).unwrap();
        assert!(fake.recv(soon).unwrap().is_some());
        assert_eq!(fake.counters().sequence_gaps, 2);
    }
}
