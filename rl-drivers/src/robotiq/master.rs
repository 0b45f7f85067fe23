//! Modbus masters (clients): one request, one response, bounded by a deadline, over RTU on a
//! [`SerialLine`] ([`RtuMaster`]) or over TCP ([`TcpMaster`]). Nothing is lost silently: bytes
//! that wait before a request (the late answer to an earlier one), frames with a wrong CRC,
//! frames that are not the answer asked for, answers that never came are all counted.
//!
//! A transaction allocates nothing.

use core::fmt;
use std::io;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

use super::serial::SerialLine;
use crate::proto::modbus::rtu::{self, FrameLength};
use crate::proto::modbus::tcp::{self, MBAP_LEN, Mbap};
use crate::proto::modbus::{MAX_PDU, ModbusError, Request, Response};
use crate::transport::TcpLink;

/// Why a transaction failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MasterError {
    /// No complete answer before the deadline (a silent or unpowered server).
    Timeout,
    /// An answer whose CRC does not match (noise on the line).
    Crc {
        /// The CRC of the bytes received.
        computed: u16,
        /// The CRC the frame carried.
        received: u16,
    },
    /// Bytes that are not the answer asked for: unparsable, from another unit, to another
    /// function or transaction, of the wrong length.
    Garbage(ModbusError),
    /// The line or the connection is gone (an unplugged adapter, a closed socket).
    Disconnected,
    /// The operating system refused an operation.
    Io(io::ErrorKind),
    /// The request itself cannot be encoded.
    Request(ModbusError),
}

impl fmt::Display for MasterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Timeout => f.write_str("no answer before the deadline"),
            Self::Crc { computed, received } => write!(
                f,
                "answer with CRC {received:#06x}, computed {computed:#06x}"
            ),
            Self::Garbage(e) => write!(f, "not the answer asked for: {e}"),
            Self::Disconnected => f.write_str("the line is gone"),
            Self::Io(k) => write!(f, "I/O error: {k}"),
            Self::Request(e) => write!(f, "request: {e}"),
        }
    }
}

impl MasterError {
    fn from_io(e: &io::Error) -> Self {
        match e.kind() {
            io::ErrorKind::BrokenPipe
            | io::ErrorKind::ConnectionReset
            | io::ErrorKind::ConnectionAborted
            | io::ErrorKind::NotConnected
            | io::ErrorKind::UnexpectedEof => Self::Disconnected,
            io::ErrorKind::TimedOut => Self::Timeout,
            k => Self::Io(k),
        }
    }
}

/// What a master has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MasterCounters {
    /// Requests sent.
    pub requests: u64,
    /// Answers taken (exceptions included).
    pub responses: u64,
    /// Exception answers.
    pub exceptions: u64,
    /// Requests without an answer by the deadline.
    pub timeouts: u64,
    /// Answers with a wrong CRC.
    pub crc_errors: u64,
    /// Answers that were not what was asked.
    pub garbage: u64,
    /// Bytes found waiting before a request (late answers to earlier ones, noise), dropped.
    pub stale_bytes: u64,
}

impl MasterCounters {
    /// Counts a transaction's outcome.
    fn count(&mut self, result: &Result<usize, MasterError>) {
        match result {
            Ok(_) => self.responses += 1,
            Err(MasterError::Timeout) => self.timeouts += 1,
            Err(MasterError::Crc { .. }) => self.crc_errors += 1,
            Err(MasterError::Garbage(_)) => self.garbage += 1,
            Err(_) => {}
        }
    }
}

/// A Modbus master: sends one request to `unit` and returns the answer's PDU.
pub trait ModbusMaster {
    /// Sends `request` to `unit` and waits for its answer until `deadline`; the answer's PDU is
    /// written to `pdu`, its length returned. An exception is an answer (decode it).
    fn transact(
        &mut self,
        unit: u8,
        request: &Request<'_>,
        pdu: &mut [u8; MAX_PDU],
        deadline: Instant,
    ) -> Result<usize, MasterError>;

    /// The counts so far.
    fn counters(&self) -> MasterCounters;

    /// Where the server is, for messages (`/dev/ttyUSB0`, `tcp://10.0.0.5:502`).
    fn describe(&self) -> &str;
}

/// Decodes an answer PDU and checks it answers `request`.
pub fn check_answer<'a>(request: &Request<'_>, pdu: &'a [u8]) -> Result<Response<'a>, MasterError> {
    let r = Response::decode(pdu).map_err(MasterError::Garbage)?;
    r.check_answers(request).map_err(MasterError::Garbage)?;
    Ok(r)
}

/// A Modbus RTU master on a serial line.
#[derive(Debug)]
pub struct RtuMaster<S> {
    line: S,
    baud: u32,
    bits_per_char: u32,
    frame: [u8; rtu::MAX_FRAME],
    /// When the line last carried a frame (ours or an answer): the next request waits out the
    /// silent interval after it.
    last_activity: Option<Instant>,
    /// Resynchronise (wait for a silent line) before the next request.
    resync: bool,
    counters: MasterCounters,
    name: String,
}

impl<S: SerialLine> RtuMaster<S> {
    /// A master on `line` at `baud` (8N1: 10 bits a character), named `name` in messages.
    pub fn new(line: S, baud: u32, name: impl Into<String>) -> Self {
        Self {
            line,
            baud,
            bits_per_char: 10,
            frame: [0; rtu::MAX_FRAME],
            last_activity: None,
            resync: false,
            counters: MasterCounters::default(),
            name: name.into(),
        }
    }

    /// The serial line.
    pub fn line(&mut self) -> &mut S {
        &mut self.line
    }

    fn gap(&self) -> Duration {
        rtu::frame_gap(self.baud, self.bits_per_char)
    }

    /// Drops what waits on the line (counted); after a failure, until the line was silent for
    /// a frame gap.
    fn drain(&mut self, deadline: Instant) -> Result<(), MasterError> {
        let io = |e: S::Error| MasterError::from_io(&to_io(&e));
        loop {
            while self.line.read_ready().map_err(io)? {
                let n = self.line.read(&mut self.frame).map_err(io)?;
                self.counters.stale_bytes += n as u64;
                self.last_activity = Some(Instant::now());
            }
            if !self.resync {
                return Ok(());
            }
            let quiet_until = Instant::now() + self.gap();
            if quiet_until > deadline {
                return Err(MasterError::Timeout);
            }
            if !self.line.wait_readable(quiet_until).map_err(io)? {
                self.resync = false;
                return Ok(());
            }
        }
    }

    /// Reads one answer frame into `frame`; returns its length.
    fn receive(&mut self, unit: u8, deadline: Instant) -> Result<usize, MasterError> {
        let io = |e: S::Error| MasterError::from_io(&to_io(&e));
        let mut got = 0;
        loop {
            let want = match rtu::response_len(&self.frame[..got]) {
                FrameLength::Known(n) if got >= n => return Ok(got),
                FrameLength::Known(n) | FrameLength::AtLeast(n) => n,
                FrameLength::Unknown => {
                    return Err(MasterError::Garbage(ModbusError::UnsupportedFunction(
                        self.frame[1],
                    )));
                }
            };
            if want > rtu::MAX_FRAME {
                return Err(MasterError::Garbage(ModbusError::TooLong {
                    what: "RTU answer",
                    expected: rtu::MAX_FRAME,
                    got: want,
                }));
            }
            if got > 0 && self.frame[0] != unit {
                return Err(MasterError::Garbage(ModbusError::WrongUnit {
                    expected: unit,
                    got: self.frame[0],
                }));
            }
            if !self.line.wait_readable(deadline).map_err(io)? {
                return Err(MasterError::Timeout);
            }
            got += self.line.read(&mut self.frame[got..want]).map_err(io)?;
        }
    }
}

/// The `io::Error` of an embedded-io error (kind only).
fn to_io<E: embedded_io::Error>(e: &E) -> io::Error {
    use embedded_io::ErrorKind as K;
    io::Error::from(match e.kind() {
        K::NotFound => io::ErrorKind::NotFound,
        K::PermissionDenied => io::ErrorKind::PermissionDenied,
        K::ConnectionRefused => io::ErrorKind::ConnectionRefused,
        K::ConnectionReset => io::ErrorKind::ConnectionReset,
        K::ConnectionAborted => io::ErrorKind::ConnectionAborted,
        K::NotConnected => io::ErrorKind::NotConnected,
        K::BrokenPipe => io::ErrorKind::BrokenPipe,
        K::InvalidInput => io::ErrorKind::InvalidInput,
        K::InvalidData => io::ErrorKind::InvalidData,
        K::TimedOut => io::ErrorKind::TimedOut,
        K::Interrupted => io::ErrorKind::Interrupted,
        K::Unsupported => io::ErrorKind::Unsupported,
        K::OutOfMemory => io::ErrorKind::OutOfMemory,
        K::WriteZero => io::ErrorKind::WriteZero,
        _ => io::ErrorKind::Other,
    })
}

impl<S: SerialLine> ModbusMaster for RtuMaster<S> {
    fn transact(
        &mut self,
        unit: u8,
        request: &Request<'_>,
        pdu: &mut [u8; MAX_PDU],
        deadline: Instant,
    ) -> Result<usize, MasterError> {
        let result = self.transact_inner(unit, request, pdu, deadline);
        self.counters.count(&result);
        if result.is_err() {
            self.resync = true;
        }
        result
    }

    fn counters(&self) -> MasterCounters {
        self.counters
    }

    fn describe(&self) -> &str {
        &self.name
    }
}

impl<S: SerialLine> RtuMaster<S> {
    fn transact_inner(
        &mut self,
        unit: u8,
        request: &Request<'_>,
        pdu: &mut [u8; MAX_PDU],
        deadline: Instant,
    ) -> Result<usize, MasterError> {
        let io = |e: S::Error| MasterError::from_io(&to_io(&e));
        self.drain(deadline)?;
        // The silent interval after the last frame on the line.
        if let Some(t) = self.last_activity {
            let ready = t + self.gap();
            let now = Instant::now();
            if ready > now {
                std::thread::sleep(ready - now);
            }
        }
        let n =
            rtu::encode_request(unit, request, &mut self.frame).map_err(MasterError::Request)?;
        // embedded-io's `write_all` panics on a write of 0 bytes: a line that takes nothing is
        // gone.
        let mut sent = 0;
        while sent < n {
            match self.line.write(&self.frame[sent..n]).map_err(io)? {
                0 => return Err(MasterError::Disconnected),
                k => sent += k,
            }
        }
        self.counters.requests += 1;
        // The request's own time on the wire, then the answer.
        self.last_activity =
            Some(Instant::now() + rtu::wire_time(n, self.baud, self.bits_per_char));
        if unit == rtu::BROADCAST {
            return Ok(0);
        }
        let got = self.receive(unit, deadline)?;
        self.last_activity = Some(Instant::now());
        let (_, answer) = rtu::decode(&self.frame[..got]).map_err(|e| match e {
            ModbusError::Crc { computed, received } => MasterError::Crc { computed, received },
            e => MasterError::Garbage(e),
        })?;
        let len = answer.len();
        pdu[..len].copy_from_slice(answer);
        check_answer(request, &pdu[..len])?;
        if pdu[0] & 0x80 != 0 {
            self.counters.exceptions += 1;
        }
        Ok(len)
    }
}

/// A Modbus TCP master.
#[derive(Debug)]
pub struct TcpMaster {
    link: TcpLink,
    transaction: u16,
    frame: [u8; tcp::MAX_FRAME],
    counters: MasterCounters,
    name: String,
}

impl TcpMaster {
    /// Connects to `server` within `timeout`.
    pub fn connect(server: SocketAddr, timeout: Duration) -> io::Result<Self> {
        Ok(Self {
            link: TcpLink::connect(server, timeout)?,
            transaction: 0,
            frame: [0; tcp::MAX_FRAME],
            counters: MasterCounters::default(),
            name: format!("tcp://{server}"),
        })
    }

    /// Reads exactly `buf.len()` bytes before `deadline`.
    fn read_exact(&mut self, at: usize, n: usize, deadline: Instant) -> Result<(), MasterError> {
        let mut got = 0;
        while got < n {
            match self.link.recv(&mut self.frame[at + got..at + n], deadline) {
                Ok(0) => return Err(MasterError::Disconnected),
                Ok(k) => got += k,
                Err(e) => return Err(MasterError::from_io(&e)),
            }
        }
        Ok(())
    }

    fn transact_inner(
        &mut self,
        unit: u8,
        request: &Request<'_>,
        pdu: &mut [u8; MAX_PDU],
        deadline: Instant,
    ) -> Result<usize, MasterError> {
        // What waits is a late answer to an earlier request: dropped and counted.
        loop {
            match self.link.try_recv(&mut self.frame) {
                Ok(Some(0)) => return Err(MasterError::Disconnected),
                Ok(Some(n)) => self.counters.stale_bytes += n as u64,
                Ok(None) => break,
                Err(e) => return Err(MasterError::from_io(&e)),
            }
        }
        self.transaction = self.transaction.wrapping_add(1);
        let tid = self.transaction;
        let n = tcp::encode_request(tid, unit, request, &mut self.frame)
            .map_err(MasterError::Request)?;
        self.link
            .send_all(&self.frame[..n], deadline)
            .map_err(|e| MasterError::from_io(&e))?;
        self.counters.requests += 1;
        loop {
            self.read_exact(0, MBAP_LEN, deadline)?;
            let h = Mbap::decode(&self.frame[..MBAP_LEN]).map_err(MasterError::Garbage)?;
            self.read_exact(MBAP_LEN, h.pdu_len, deadline)?;
            if h.transaction != tid {
                // An answer to a request given up on.
                self.counters.stale_bytes += h.frame_len() as u64;
                continue;
            }
            if h.unit != unit {
                return Err(MasterError::Garbage(ModbusError::WrongUnit {
                    expected: unit,
                    got: h.unit,
                }));
            }
            pdu[..h.pdu_len].copy_from_slice(&self.frame[MBAP_LEN..h.frame_len()]);
            check_answer(request, &pdu[..h.pdu_len])?;
            if pdu[0] & 0x80 != 0 {
                self.counters.exceptions += 1;
            }
            return Ok(h.pdu_len);
        }
    }
}

impl ModbusMaster for TcpMaster {
    fn transact(
        &mut self,
        unit: u8,
        request: &Request<'_>,
        pdu: &mut [u8; MAX_PDU],
        deadline: Instant,
    ) -> Result<usize, MasterError> {
        let result = self.transact_inner(unit, request, pdu, deadline);
        self.counters.count(&result);
        result
    }

    fn counters(&self) -> MasterCounters {
        self.counters
    }

    fn describe(&self) -> &str {
        &self.name
    }
}
