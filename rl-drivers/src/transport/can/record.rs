//! Recording: a transport that passes every frame on and also writes it, as sent and as
//! received, to a pcap file with the SocketCAN link type (227, `can_id` in network byte order,
//! as libpcap writes it — Wireshark's CANopen dissector decodes it) and/or a candump log
//! (`candump -l` format; opens in can-utils' `canplayer` and `log2asc`).
//!
//! For tests and tools, not the real-time path: the files are written through buffered
//! writers.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use pcap_file::pcap::{PcapHeader, PcapPacket, PcapWriter};
use pcap_file::{DataLink, Endianness};

use super::{CanTransport, Received, TransportCounters};
use crate::proto::can::candump::{self, Timestamp};
use crate::proto::can::fd::CANFD_FRAME_LEN;
use crate::proto::can::{Frame, IdOrder};

/// A buffered file the pcap writer writes through and the log can flush.
#[derive(Clone)]
struct SharedFile(Arc<Mutex<BufWriter<File>>>);

impl SharedFile {
    fn lock(&self) -> std::sync::MutexGuard<'_, BufWriter<File>> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }
}

impl Write for SharedFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.lock().write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.lock().flush()
    }
}

/// Writes frames to a pcap file (link type 227).
pub struct PcapLog {
    writer: PcapWriter<SharedFile>,
    file: SharedFile,
}

impl std::fmt::Debug for PcapLog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PcapLog")
    }
}

fn pcap_error(e: pcap_file::PcapError) -> io::Error {
    io::Error::other(e.to_string())
}

impl PcapLog {
    /// Creates `path`.
    pub fn create(path: &Path) -> io::Result<Self> {
        let file = SharedFile(Arc::new(Mutex::new(BufWriter::new(File::create(path)?))));
        let header = PcapHeader {
            datalink: DataLink::CAN_SOCKETCAN,
            endianness: Endianness::native(),
            ..PcapHeader::default()
        };
        Ok(Self {
            writer: PcapWriter::with_header(file.clone(), header).map_err(pcap_error)?,
            file,
        })
    }

    /// Appends a frame seen at `time` (since the Unix epoch).
    pub fn write(&mut self, time: std::time::Duration, frame: &Frame) -> io::Result<()> {
        let mut buf = [0u8; CANFD_FRAME_LEN];
        let n = frame
            .write_socketcan(&mut buf, IdOrder::Network)
            .map_err(|e| io::Error::other(e.to_string()))?;
        self.writer
            .write_packet(&PcapPacket::new(time, n as u32, &buf[..n]))
            .map_err(pcap_error)?;
        Ok(())
    }

    /// Flushes the file.
    pub fn flush(&mut self) -> io::Result<()> {
        self.file.flush()
    }
}

/// Writes frames as candump log lines.
#[derive(Debug)]
pub struct CandumpLog {
    writer: BufWriter<File>,
    interface: String,
    line: String,
}

impl CandumpLog {
    /// Creates `path`; lines name `interface`.
    pub fn create(path: &Path, interface: &str) -> io::Result<Self> {
        Ok(Self {
            writer: BufWriter::new(File::create(path)?),
            interface: interface.to_owned(),
            line: String::with_capacity(64),
        })
    }

    /// Appends a frame seen at `time`.
    pub fn write(&mut self, time: std::time::Duration, frame: &Frame) -> io::Result<()> {
        self.line.clear();
        candump::write_line(
            &mut self.line,
            Timestamp::from_duration(time),
            &self.interface,
            frame,
        )
        .map_err(|_| io::Error::other("formatting a candump line"))?;
        self.writer.write_all(self.line.as_bytes())
    }

    /// Flushes the file.
    pub fn flush(&mut self) -> io::Result<()> {
        self.writer.flush()
    }
}

/// A transport that records everything it sends and receives.
#[derive(Debug)]
pub struct Recording<T> {
    inner: T,
    pcap: Option<PcapLog>,
    candump: Option<CandumpLog>,
    pending: Vec<Frame>,
}

impl<T: CanTransport> Recording<T> {
    /// Wraps `inner`, writing to the logs given.
    pub fn new(inner: T, pcap: Option<PcapLog>, candump: Option<CandumpLog>) -> Self {
        Self {
            inner,
            pcap,
            candump,
            pending: Vec::with_capacity(256),
        }
    }

    /// The wrapped transport.
    pub fn inner(&self) -> &T {
        &self.inner
    }

    fn log(&mut self, time: std::time::Duration, frame: &Frame) -> io::Result<()> {
        if let Some(p) = &mut self.pcap {
            p.write(time, frame)?;
        }
        if let Some(c) = &mut self.candump {
            c.write(time, frame)?;
        }
        Ok(())
    }

    /// Flushes the log files.
    pub fn flush_logs(&mut self) -> io::Result<()> {
        if let Some(p) = &mut self.pcap {
            p.flush()?;
        }
        if let Some(c) = &mut self.candump {
            c.flush()?;
        }
        Ok(())
    }
}

fn now() -> std::time::Duration {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default()
}

impl<T> Drop for Recording<T> {
    fn drop(&mut self) {
        if let Some(p) = &mut self.pcap {
            let _ = p.flush();
        }
        if let Some(c) = &mut self.candump {
            let _ = c.flush();
        }
    }
}

impl<T: CanTransport> CanTransport for Recording<T> {
    fn send(&mut self, frame: &Frame) -> io::Result<()> {
        self.inner.send(frame)?;
        self.pending.push(*frame);
        Ok(())
    }

    fn flush(&mut self, deadline: Instant) -> io::Result<()> {
        self.inner.flush(deadline)?;
        let t = now();
        let pending = std::mem::take(&mut self.pending);
        for f in &pending {
            self.log(t, f)?;
        }
        self.pending = pending;
        self.pending.clear();
        Ok(())
    }

    fn recv(&mut self, deadline: Instant) -> io::Result<Option<Received>> {
        let r = self.inner.recv(deadline)?;
        if let Some(r) = &r {
            self.log(r.timestamp.unwrap_or_else(now), &r.frame)?;
        }
        Ok(r)
    }

    fn counters(&self) -> TransportCounters {
        self.inner.counters()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::can::bus::Bus;
    use std::time::Duration;

    #[test]
    fn a_recording_holds_what_was_sent_and_received() {
        let dir = std::env::temp_dir().join(format!("rl-can-record-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bus = Bus::new();
        let mut peer = bus.endpoint();
        let mut rec = Recording::new(
            bus.endpoint(),
            Some(PcapLog::create(&dir.join("x.pcap")).unwrap()),
            Some(CandumpLog::create(&dir.join("x.log"), "can0").unwrap()),
        );
        rec.send(&Frame::standard(0x080, &[]).unwrap()).unwrap();
        rec.flush(Instant::now()).unwrap();
        peer.send(&Frame::standard(0x181, &[0x27, 0x06]).unwrap())
            .unwrap();
        peer.flush(Instant::now()).unwrap();
        rec.recv(Instant::now() + Duration::from_secs(1))
            .unwrap()
            .unwrap();
        drop(rec);
        let log = std::fs::read_to_string(dir.join("x.log")).unwrap();
        let lines: Vec<_> = log.lines().collect();
        assert_eq!(lines.len(), 2);
        assert!(lines[0].ends_with(" can0 080#"), "{}", lines[0]);
        assert!(lines[1].ends_with(" can0 181#2706"), "{}", lines[1]);
        for l in &lines {
            candump::parse_line(l).unwrap();
        }
        let pcap = std::fs::read(dir.join("x.pcap")).unwrap();
        // Global header (24 bytes, link type 227), then two records of 16 + 16 bytes.
        assert_eq!(pcap.len(), 24 + 2 * (16 + 16));
        assert_eq!(u32::from_le_bytes(pcap[20..24].try_into().unwrap()), 227);
        assert_eq!(
            &pcap[24 + 16 + 16 + 16..24 + 16 + 16 + 16 + 4],
            &[0, 0, 1, 0x81]
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
