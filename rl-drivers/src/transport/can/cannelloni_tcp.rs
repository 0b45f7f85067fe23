//! cannelloni over TCP (protocol version 1): after connecting, each side sends the 12-byte
//! banner `CANNELLONIv1`; then frames flow back to back in both directions, no header, no
//! delimiter ([`StreamDecoder`]). A frame that does not decode breaks the stream (there is
//! nothing to resynchronise on): it is counted and the link reports `InvalidData`.
//!
//! A master [`connect`](CannelloniTcp::connect)s; a fake or a test peer
//! [`Listener::accept`]s. Every wait — connect, banner, write, read — is bounded.

use std::io;
use std::net::{SocketAddr, TcpListener};
use std::os::fd::AsFd;
use std::time::{Duration, Instant};

use super::{CanTransport, Received, RxQueue, TransportCounters};
use crate::proto::can::Frame;
use crate::proto::can::cannelloni::{self, MAX_FRAME_LEN, StreamDecoder, TCP_BANNER};
use crate::transport::{Readiness, TcpLink, wait};

/// Bytes queued for one flush at most.
pub const TX_CAPACITY: usize = 8192;

/// A cannelloni TCP connection.
#[derive(Debug)]
pub struct CannelloniTcp {
    link: TcpLink,
    tx: Vec<u8>,
    tx_frames: u64,
    decoder: StreamDecoder,
    rx_buf: [u8; 2048],
    rx: RxQueue,
    counters: TransportCounters,
    broken: bool,
}

fn timed_out(what: &str) -> io::Error {
    io::Error::new(
        io::ErrorKind::TimedOut,
        format!("cannelloni TCP: {what} timed out"),
    )
}

impl CannelloniTcp {
    /// Connects to `addr` and exchanges banners, all within `timeout`.
    pub fn connect(addr: SocketAddr, timeout: Duration) -> io::Result<Self> {
        let deadline = Instant::now() + timeout;
        let link = TcpLink::connect(addr, timeout)?;
        Self::handshake(link, deadline)
    }

    fn handshake(mut link: TcpLink, deadline: Instant) -> io::Result<Self> {
        link.send_all(TCP_BANNER, deadline)?;
        let mut banner = [0u8; 12];
        let mut got = 0;
        while got < banner.len() {
            let n = link.recv(&mut banner[got..], deadline).map_err(|e| {
                if e.kind() == io::ErrorKind::TimedOut {
                    timed_out("banner")
                } else {
                    e
                }
            })?;
            if n == 0 {
                return Err(io::Error::new(
                    io::ErrorKind::UnexpectedEof,
                    "cannelloni TCP: the peer closed before its banner",
                ));
            }
            got += n;
        }
        if &banner != TCP_BANNER {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!(
                    "cannelloni TCP: the peer's banner is {:?}, not CANNELLONIv1",
                    String::from_utf8_lossy(&banner)
                ),
            ));
        }
        Ok(Self {
            link,
            tx: Vec::with_capacity(TX_CAPACITY),
            tx_frames: 0,
            decoder: StreamDecoder::new(),
            rx_buf: [0; 2048],
            rx: RxQueue::new(),
            counters: TransportCounters::default(),
            broken: false,
        })
    }

    /// The peer's address.
    pub fn peer(&self) -> SocketAddr {
        self.link.peer()
    }

    fn check(&self) -> io::Result<()> {
        if self.broken {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                "cannelloni TCP: the stream carried an invalid frame; reconnect",
            ));
        }
        Ok(())
    }
}

impl CanTransport for CannelloniTcp {
    fn send(&mut self, frame: &Frame) -> io::Result<()> {
        self.check()?;
        let mut b = [0u8; MAX_FRAME_LEN];
        let n = cannelloni::encode_frame(frame, &mut b).unwrap_or(0);
        if self.tx.len() + n > TX_CAPACITY {
            return Err(io::Error::new(
                io::ErrorKind::WouldBlock,
                "cannelloni TCP: send queue full",
            ));
        }
        self.tx.extend_from_slice(&b[..n]);
        self.tx_frames += 1;
        Ok(())
    }

    fn flush(&mut self, deadline: Instant) -> io::Result<()> {
        self.check()?;
        if self.tx.is_empty() {
            return Ok(());
        }
        let r = self.link.send_all(&self.tx, deadline);
        self.tx.clear();
        r?;
        self.counters.frames_sent += self.tx_frames;
        self.tx_frames = 0;
        Ok(())
    }

    fn recv(&mut self, deadline: Instant) -> io::Result<Option<Received>> {
        loop {
            if let Some(r) = self.rx.pop() {
                return Ok(Some(r));
            }
            self.check()?;
            match self.link.try_recv(&mut self.rx_buf)? {
                Some(0) => {
                    return Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "cannelloni TCP: the peer closed the connection",
                    ));
                }
                Some(n) => {
                    let (rx, counters) = (&mut self.rx, &mut self.counters);
                    let r = self.decoder.feed(&self.rx_buf[..n], |frame| {
                        counters.frames_received += 1;
                        rx.push(Received {
                            frame,
                            timestamp: None,
                        });
                    });
                    if r.is_err() {
                        self.counters.corrupt += 1;
                        self.broken = true;
                    }
                }
                None => {
                    if !wait(self.link.as_fd(), Readiness::Readable, deadline)? {
                        return Ok(None);
                    }
                }
            }
        }
    }

    fn counters(&self) -> TransportCounters {
        let mut c = self.counters;
        c.overruns = self.rx.overruns;
        c
    }
}

/// Time a peer that has connected gets for the banners, whatever the deadline the caller gave
/// for waiting for a peer: a caller that polls with short deadlines (a fake's worker turn) must
/// not drop a peer in the middle of its handshake.
pub const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(1);

/// A listening socket that accepts cannelloni TCP peers.
#[derive(Debug)]
pub struct Listener {
    listener: TcpListener,
}

impl Listener {
    /// Listens on `addr` (non-blocking).
    pub fn bind(addr: SocketAddr) -> io::Result<Self> {
        let listener = TcpListener::bind(addr)?;
        listener.set_nonblocking(true)?;
        Ok(Self { listener })
    }

    /// The bound address.
    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.listener.local_addr()
    }

    /// Waits at most until `deadline` for a peer, then exchanges banners with it within
    /// [`HANDSHAKE_TIMEOUT`] (or until `deadline`, if that is later).
    pub fn accept(&self, deadline: Instant) -> io::Result<CannelloniTcp> {
        loop {
            match self.listener.accept() {
                Ok((stream, _)) => {
                    let link = TcpLink::from_stream(stream)?;
                    let handshake = deadline.max(Instant::now() + HANDSHAKE_TIMEOUT);
                    return CannelloniTcp::handshake(link, handshake);
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    if !wait(self.listener.as_fd(), Readiness::Readable, deadline)? {
                        return Err(timed_out("waiting for a peer"));
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read, Write};
    use std::net::TcpStream;

    #[test]
    fn banner_then_frames_both_ways() {
        let l = Listener::bind("127.0.0.1:0".parse().unwrap()).unwrap();
        let addr = l.local_addr().unwrap();
        let t = std::thread::spawn(move || {
            let mut s = TcpStream::connect(addr).unwrap();
            s.write_all(b"CANNELLONIv1").unwrap();
            let mut banner = [0u8; 12];
            s.read_exact(&mut banner).unwrap();
            assert_eq!(&banner, b"CANNELLONIv1");
            // Two frames written in odd pieces.
            let bytes = [0, 0, 7, 1, 1, 0x7F, 0, 0, 1, 0x81, 2, 0xAA, 0xBB];
            s.write_all(&bytes[..3]).unwrap();
            std::thread::sleep(Duration::from_millis(20));
            s.write_all(&bytes[3..]).unwrap();
            let mut back = [0u8; 6];
            s.read_exact(&mut back).unwrap();
            back
        });
        let deadline = Instant::now() + Duration::from_secs(2);
        let mut link = l.accept(deadline).unwrap();
        let a = link.recv(deadline).unwrap().unwrap().frame;
        let b = link.recv(deadline).unwrap().unwrap().frame;
        assert_eq!((a.standard_id(), a.bytes()), (Some(0x701), &[0x7F][..]));
        assert_eq!(
            (b.standard_id(), b.bytes()),
            (Some(0x181), &[0xAA, 0xBB][..])
        );
        link.send(&Frame::standard(0x000, &[1]).unwrap()).unwrap();
        link.flush(deadline).unwrap();
        assert_eq!(t.join().unwrap(), [0, 0, 0, 0, 1, 1]);
        let e = link.recv(deadline).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::UnexpectedEof);
    }

    /// A peer whose banner comes after the deadline for waiting for a peer is still accepted:
    /// the deadline bounds the wait for a connection, not the handshake (a fake polling in short
    /// turns once dropped a master this way, which saw the connection close at open).
    #[test]
    fn a_peer_accepted_at_the_end_of_a_short_wait_gets_time_for_its_banner() {
        let l = Listener::bind("127.0.0.1:0".parse().unwrap()).unwrap();
        let addr = l.local_addr().unwrap();
        let t = std::thread::spawn(move || {
            let mut s = TcpStream::connect(addr).unwrap();
            std::thread::sleep(Duration::from_millis(50));
            s.write_all(TCP_BANNER).unwrap();
            let mut banner = [0u8; 12];
            s.read_exact(&mut banner).unwrap();
            banner
        });
        // The connection waits in the backlog; the wait for a peer is 2 ms, the banner 50 ms late.
        std::thread::sleep(Duration::from_millis(20));
        l.accept(Instant::now() + Duration::from_millis(2))
            .expect("accepted despite the late banner");
        assert_eq!(&t.join().unwrap(), TCP_BANNER);
    }

    #[test]
    fn a_wrong_banner_is_refused_and_a_silent_peer_times_out() {
        let l = Listener::bind("127.0.0.1:0".parse().unwrap()).unwrap();
        let addr = l.local_addr().unwrap();
        let t = std::thread::spawn(move || {
            let mut s = TcpStream::connect(addr).unwrap();
            s.write_all(b"HELLOWORLD!!").unwrap();
            std::thread::sleep(Duration::from_millis(100));
        });
        let e = l
            .accept(Instant::now() + Duration::from_secs(2))
            .unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        t.join().unwrap();
        let start = Instant::now();
        let e = l.accept(start + Duration::from_millis(30)).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::TimedOut);
    }
}
