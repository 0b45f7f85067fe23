//! A fake ATI Net F/T sensor on the wire: RDT streaming on UDP (port 49152 by default), the
//! calibration query on TCP (49151, `READCALINFO`) and the sensor's `netftapi2.xml` over HTTP
//! (what PyPI `pynetft` reads its calibration from), answering
//! [`AtiNetFt`](crate::ati::AtiNetFt), PyPI `netft` and `pynetft`.
//!
//! It behaves like the sensor where its behaviour is documented (`rl-drivers/NOTES.md` says
//! what is and what is not):
//! - **Its own clock.** One thread sends a record every `1 / rdt_rate_hz` (7000 Hz by default,
//!   the Net F/T's fastest) at absolute deadlines; `ft_sequence` counts the sensor's internal
//!   7 kHz samples since power-up, `rdt_sequence` the records of the current stream from 1. A
//!   tick that wakes more than a period late does not send a burst: the fake's clock slips,
//!   which is counted (`slips`), and the sequence numbers stay gapless.
//! - **The requester gets the stream.** Start commands (2 real time, 3 buffered, 4 multi-unit,
//!   which streams as 2) send to the address the request came from, the latest requester
//!   winning; `sample_count` ends the stream after that many records; command 0 stops it.
//!   Requests of a wrong length, header or command are ignored and counted.
//! - **Bias.** Command 0x42 takes the current reading as the zero of the following records
//!   (the sensor's software bias); [`FakeNetFt::set_offset`] gives the unloaded sensor an
//!   offset (what a bias removes).
//! - **The load.** [`FakeNetFt::set_wrench`] sets the wrench on the sensor (N, N·m, in the
//!   sensor's frame); records carry it in counts of the configured [`Calibration`], rounded
//!   and saturated as the sensor's are.
//! - **Faults to inject**, each counted: dropped datagrams (their sequence numbers are
//!   skipped, as a network loses them), a reordered pair, a repeated datagram, silence (an
//!   unplugged cable: the sensor keeps counting), a status word (bit 31: error), and garbage
//!   datagrams to the streaming client.

use std::io::{self, Read};
use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::proto::netft::{
    CALINFO_REQUEST_LEN, Calibration, INTERNAL_RATE_HZ, RDT_PORT, RECORD_LEN, RdtCommand,
    RdtRecord, RdtRequest, TCP_PORT, decode_tcp_request,
};

/// Largest HTTP request head the fake reads.
const MAX_HTTP_REQUEST: usize = 4096;
/// How long a TCP or HTTP client may take to send its request.
const CLIENT_TIMEOUT: Duration = Duration::from_secs(2);
/// The tick while no stream runs.
const IDLE_TICK: Duration = Duration::from_millis(1);

/// Configuration of the fake sensor.
#[derive(Clone, Debug)]
pub struct FakeNetFtConfig {
    /// The address every server binds (loopback by default).
    pub bind: IpAddr,
    /// The RDT port ([`RDT_PORT`]; 0: a free one).
    pub rdt_port: u16,
    /// The calibration server's TCP port ([`TCP_PORT`]; 0: a free one; `None`: none).
    pub tcp_port: Option<u16>,
    /// The HTTP server's port (the sensor's is 80; 0: a free one; `None`: none).
    pub http_port: Option<u16>,
    /// The calibration the sensor reports and scales its counts by.
    pub calibration: Calibration,
    /// Records per second (the Net F/T's "RDT output rate": up to 7000).
    pub rdt_rate_hz: u32,
    /// Records per datagram in the buffered mode.
    pub buffer_size: u32,
    /// The serial number the web page shows.
    pub serial: String,
    /// Called first on the fake's thread (to give it a real-time priority).
    pub on_thread_start: Option<fn()>,
}

impl FakeNetFtConfig {
    /// A sensor on 127.0.0.1 at the standard ports (HTTP on 8080, not 80, so no privilege is
    /// needed), 1 000 000 counts per N and per N·m, 7000 records a second.
    pub fn loopback() -> Self {
        Self {
            bind: IpAddr::V4(Ipv4Addr::LOCALHOST),
            rdt_port: RDT_PORT,
            tcp_port: Some(TCP_PORT),
            http_port: Some(8080),
            calibration: Calibration::si(1_000_000, 1_000_000),
            rdt_rate_hz: INTERNAL_RATE_HZ,
            buffer_size: 10,
            serial: "FT00001".into(),
            on_thread_start: None,
        }
    }

    /// The same on free ports (for tests).
    #[must_use]
    pub fn free_ports(mut self) -> Self {
        self.rdt_port = 0;
        self.tcp_port = self.tcp_port.map(|_| 0);
        self.http_port = self.http_port.map(|_| 0);
        self
    }
}

/// What the fake has seen and sent.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FakeNetFtStatus {
    /// RDT requests understood.
    pub requests: u64,
    /// RDT datagrams ignored (wrong length, header or command).
    pub bad_requests: u64,
    /// Whether a stream runs, and to whom.
    pub streaming_to: Option<SocketAddr>,
    /// Streams started.
    pub streams: u64,
    /// Records sent (in any datagram).
    pub records: u64,
    /// Datagrams sent.
    pub datagrams: u64,
    /// Records left out on purpose (dropped, or during silence).
    pub dropped: u64,
    /// Pairs sent in swapped order.
    pub reordered: u64,
    /// Datagrams sent twice.
    pub duplicated: u64,
    /// Garbage datagrams sent.
    pub garbage: u64,
    /// Bias commands taken.
    pub biases: u64,
    /// Threshold latch resets.
    pub latch_resets: u64,
    /// `READCALINFO` answers.
    pub calinfo_requests: u64,
    /// Other TCP requests (ignored).
    pub bad_tcp_requests: u64,
    /// HTTP requests answered (any path).
    pub http_requests: u64,
    /// Ticks that woke more than a period late (the fake's scheduling, not the sensor's).
    pub slips: u64,
    /// The latest a tick woke after its deadline, µs.
    pub max_lateness_us: u64,
    /// The current software bias, counts.
    pub bias_counts: [i32; 6],
    /// The last record sent.
    pub last: RdtRecord,
}

/// What a test or the tool injects.
#[derive(Clone, Debug, Default)]
struct Control {
    wrench: [f64; 6],
    offset: [f64; 6],
    status_word: u32,
    drop: u32,
    reorder: u32,
    duplicate: u32,
    silent_until: Option<Instant>,
    garbage: Vec<Vec<u8>>,
}

struct Shared {
    stop: AtomicBool,
    control: Mutex<Control>,
    status: Mutex<FakeNetFtStatus>,
}

/// A running fake sensor; its thread stops when this is dropped.
pub struct FakeNetFt {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    rdt_addr: SocketAddr,
    tcp_addr: Option<SocketAddr>,
    http_addr: Option<SocketAddr>,
}

impl FakeNetFt {
    /// Binds the servers and starts the sensor's thread.
    pub fn spawn(config: FakeNetFtConfig) -> io::Result<Self> {
        let invalid = |e: String| io::Error::new(io::ErrorKind::InvalidInput, e);
        config
            .calibration
            .check()
            .map_err(|e| invalid(e.to_string()))?;
        if config.rdt_rate_hz == 0 || config.rdt_rate_hz > INTERNAL_RATE_HZ {
            return Err(invalid(format!(
                "RDT rate {} Hz: 1 to {INTERNAL_RATE_HZ}",
                config.rdt_rate_hz
            )));
        }
        if config.buffer_size == 0 || config.buffer_size as usize * RECORD_LEN > 1400 {
            return Err(invalid(format!(
                "buffer size {}: 1 to {} records",
                config.buffer_size,
                1400 / RECORD_LEN
            )));
        }
        let udp = UdpSocket::bind((config.bind, config.rdt_port))?;
        udp.set_nonblocking(true)?;
        let listen = |port: Option<u16>| -> io::Result<Option<TcpListener>> {
            port.map(|p| {
                let l = TcpListener::bind((config.bind, p))?;
                l.set_nonblocking(true)?;
                Ok(l)
            })
            .transpose()
        };
        let tcp = listen(config.tcp_port)?;
        let http = listen(config.http_port)?;
        let rdt_addr = udp.local_addr()?;
        let tcp_addr = tcp.as_ref().map(TcpListener::local_addr).transpose()?;
        let http_addr = http.as_ref().map(TcpListener::local_addr).transpose()?;
        let shared = Arc::new(Shared {
            stop: AtomicBool::new(false),
            control: Mutex::new(Control::default()),
            status: Mutex::new(FakeNetFtStatus::default()),
        });
        let mut sensor = Sensor {
            period: Duration::from_nanos(1_000_000_000 / u64::from(config.rdt_rate_hz)),
            config,
            udp,
            tcp,
            http,
            clients: Vec::new(),
            stream: None,
            power_up: Instant::now(),
            pending: Vec::new(),
            held: None,
            status: FakeNetFtStatus::default(),
        };
        let s = shared.clone();
        let thread = std::thread::Builder::new()
            .name("fake-netft".into())
            .spawn(move || {
                if let Some(f) = sensor.config.on_thread_start {
                    f();
                }
                sensor.run(&s);
            })?;
        Ok(Self {
            shared,
            thread: Some(thread),
            rdt_addr,
            tcp_addr,
            http_addr,
        })
    }

    /// The RDT server's address.
    pub fn rdt_addr(&self) -> SocketAddr {
        self.rdt_addr
    }

    /// The calibration server's address.
    pub fn tcp_addr(&self) -> Option<SocketAddr> {
        self.tcp_addr
    }

    /// The HTTP server's address.
    pub fn http_addr(&self) -> Option<SocketAddr> {
        self.http_addr
    }

    /// What the fake has seen so far.
    pub fn status(&self) -> FakeNetFtStatus {
        *self.shared.status.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn control(&self, f: impl FnOnce(&mut Control)) {
        f(&mut self
            .shared
            .control
            .lock()
            .unwrap_or_else(|p| p.into_inner()));
    }

    /// The load on the sensor: `[Fx, Fy, Fz, Tx, Ty, Tz]` in N and N·m, sensor frame.
    pub fn set_wrench(&self, wrench: [f64; 6]) {
        self.control(|c| c.wrench = wrench);
    }

    /// The reading of the unloaded sensor (what a bias removes), N and N·m.
    pub fn set_offset(&self, offset: [f64; 6]) {
        self.control(|c| c.offset = offset);
    }

    /// The status word of the following records (bit 31: error).
    pub fn set_status_word(&self, status: u32) {
        self.control(|c| c.status_word = status);
    }

    /// Leaves out the next `n` records (their sequence numbers are skipped).
    pub fn drop_records(&self, n: u32) {
        self.control(|c| c.drop += n);
    }

    /// Sends each of the next `n` pairs of records in swapped order.
    pub fn reorder_pairs(&self, n: u32) {
        self.control(|c| c.reorder += n);
    }

    /// Sends each of the next `n` datagrams twice.
    pub fn duplicate_records(&self, n: u32) {
        self.control(|c| c.duplicate += n);
    }

    /// Sends nothing for `duration` (an unplugged cable: the sensor keeps counting).
    pub fn silence(&self, duration: Duration) {
        self.control(|c| c.silent_until = Some(Instant::now() + duration));
    }

    /// Sends `bytes` as one datagram to the streaming client at the next tick.
    pub fn send_garbage(&self, bytes: &[u8]) {
        self.control(|c| c.garbage.push(bytes.to_vec()));
    }

    /// Stops the thread and waits for it (also done on drop).
    pub fn shutdown(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for FakeNetFt {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// The stream in progress.
#[derive(Clone, Copy, Debug)]
struct Stream {
    to: SocketAddr,
    buffered: bool,
    /// Records left to send (`None`: endless).
    left: Option<u32>,
    rdt_sequence: u32,
}

/// A TCP or HTTP client being served.
struct Client {
    stream: TcpStream,
    http: bool,
    rx: Vec<u8>,
    since: Instant,
}

/// The sensor: its thread's state.
struct Sensor {
    config: FakeNetFtConfig,
    period: Duration,
    udp: UdpSocket,
    tcp: Option<TcpListener>,
    http: Option<TcpListener>,
    clients: Vec<Client>,
    stream: Option<Stream>,
    power_up: Instant,
    /// Records of the buffered mode waiting for their datagram.
    pending: Vec<u8>,
    /// A datagram held back to be sent after the next one (reordering).
    held: Option<Vec<u8>>,
    status: FakeNetFtStatus,
}

impl Sensor {
    fn run(&mut self, shared: &Shared) {
        let mut next = Instant::now();
        while !shared.stop.load(Ordering::Relaxed) {
            let period = if self.stream.is_some() {
                self.period
            } else {
                IDLE_TICK
            };
            next += period;
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            }
            let woke = Instant::now();
            let late = woke.saturating_duration_since(next);
            if self.stream.is_some() {
                self.status.max_lateness_us = self
                    .status
                    .max_lateness_us
                    .max(u64::try_from(late.as_micros()).unwrap_or(u64::MAX));
            }
            if late > period {
                // No burst of catch-up records: the clock slips (counted while streaming).
                next = woke;
                if self.stream.is_some() {
                    self.status.slips += 1;
                }
            }
            {
                let mut control = shared.control.lock().unwrap_or_else(|p| p.into_inner());
                self.take_requests(&control);
                if self.stream.is_some() {
                    self.tick(&mut control, woke);
                }
            }
            self.serve_clients();
            *shared.status.lock().unwrap_or_else(|p| p.into_inner()) = self.status;
        }
    }

    /// The load plus the unloaded sensor's offset, in counts.
    fn raw_counts(&self, control: &Control) -> [i32; 6] {
        let mut w = control.wrench;
        for (v, o) in w.iter_mut().zip(control.offset) {
            *v += o;
        }
        self.config.calibration.to_counts(&w)
    }

    fn ft_sequence(&self, now: Instant) -> u32 {
        let samples = now.saturating_duration_since(self.power_up).as_nanos()
            * u128::from(INTERNAL_RATE_HZ)
            / 1_000_000_000;
        // The sensor's counter wraps.
        samples as u32
    }

    fn take_requests(&mut self, control: &Control) {
        let mut buf = [0u8; 64];
        loop {
            let (n, from) = match self.udp.recv_from(&mut buf) {
                Ok(x) => x,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(_) => return,
            };
            let Ok(request) = RdtRequest::decode(&buf[..n]) else {
                self.status.bad_requests += 1;
                continue;
            };
            self.status.requests += 1;
            match request.command {
                RdtCommand::Stop => {
                    self.stream = None;
                    self.status.streaming_to = None;
                }
                RdtCommand::StartRealTime
                | RdtCommand::StartMultiUnit
                | RdtCommand::StartBuffered => {
                    self.stream = Some(Stream {
                        to: from,
                        buffered: request.command == RdtCommand::StartBuffered,
                        left: (request.sample_count > 0).then_some(request.sample_count),
                        rdt_sequence: 0,
                    });
                    self.pending.clear();
                    self.held = None;
                    self.status.streams += 1;
                    self.status.streaming_to = Some(from);
                }
                RdtCommand::SetSoftwareBias => {
                    self.status.bias_counts = self.raw_counts(control);
                    self.status.biases += 1;
                }
                RdtCommand::ResetThresholdLatch => self.status.latch_resets += 1,
            }
        }
    }

    /// One sample of the stream: a record into the next datagram, which leaves when it is full
    /// (one record in real time, `buffer_size` in the buffered mode) or the stream ends.
    fn tick(&mut self, control: &mut Control, now: Instant) {
        let Some(mut stream) = self.stream else {
            return;
        };
        for g in control.garbage.drain(..) {
            if self.udp.send_to(&g, stream.to).is_ok() {
                self.status.garbage += 1;
            }
        }
        stream.rdt_sequence = stream.rdt_sequence.wrapping_add(1);
        let raw = self.raw_counts(control);
        let mut counts = [0; 6];
        for k in 0..6 {
            counts[k] = raw[k].saturating_sub(self.status.bias_counts[k]);
        }
        let record = RdtRecord {
            rdt_sequence: stream.rdt_sequence,
            ft_sequence: self.ft_sequence(now),
            status: control.status_word,
            counts,
        };
        self.status.last = record;
        self.status.records += 1;
        if let Some(left) = &mut stream.left {
            *left = left.saturating_sub(1);
        }
        let finished = stream.left == Some(0);
        self.pending.extend_from_slice(&record.to_bytes());
        let per_datagram = if stream.buffered {
            self.config.buffer_size as usize
        } else {
            1
        };
        if self.pending.len() / RECORD_LEN >= per_datagram || finished {
            let datagram = std::mem::take(&mut self.pending);
            self.emit(datagram, stream.to, control, now);
        }
        if finished {
            self.stream = None;
            self.status.streaming_to = None;
        } else {
            self.stream = Some(stream);
        }
    }

    /// Puts a datagram on the wire, or loses, delays or repeats it as injected.
    fn emit(&mut self, datagram: Vec<u8>, to: SocketAddr, control: &mut Control, now: Instant) {
        let records = (datagram.len() / RECORD_LEN) as u64;
        if control.silent_until.is_some_and(|t| now < t) {
            self.status.dropped += records;
            return;
        }
        control.silent_until = None;
        if control.drop > 0 {
            control.drop -= 1;
            self.status.dropped += records;
            return;
        }
        if control.reorder > 0 && self.held.is_none() {
            // Hold this one back: it follows the next.
            control.reorder -= 1;
            self.held = Some(datagram);
            return;
        }
        let repeat = if control.duplicate > 0 {
            control.duplicate -= 1;
            self.status.duplicated += 1;
            2
        } else {
            1
        };
        for _ in 0..repeat {
            self.put(&datagram, to);
        }
        if let Some(held) = self.held.take() {
            self.put(&held, to);
            self.status.reordered += 1;
        }
    }

    fn put(&mut self, datagram: &[u8], to: SocketAddr) {
        if self.udp.send_to(datagram, to).is_ok() {
            self.status.datagrams += 1;
        }
    }

    /// Accepts TCP and HTTP clients and answers complete requests; a client that sends
    /// nothing useful within [`CLIENT_TIMEOUT`] is dropped.
    fn serve_clients(&mut self) {
        for (listener, http) in [(&self.tcp, false), (&self.http, true)] {
            let Some(listener) = listener else {
                continue;
            };
            while let Ok((stream, _)) = listener.accept() {
                if stream.set_nonblocking(true).is_ok() {
                    let _ = stream.set_nodelay(true);
                    self.clients.push(Client {
                        stream,
                        http,
                        rx: Vec::new(),
                        since: Instant::now(),
                    });
                }
            }
        }
        let mut clients = std::mem::take(&mut self.clients);
        clients.retain_mut(|c| self.serve(c));
        self.clients = clients;
    }

    /// Reads what `client` sent and answers; `false` once it is done with.
    fn serve(&mut self, client: &mut Client) -> bool {
        let mut buf = [0u8; 512];
        loop {
            match client.stream.read(&mut buf) {
                Ok(0) => return false,
                Ok(n) => client.rx.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(_) => return false,
            }
        }
        if client.http {
            return self.serve_http(client);
        }
        while client.rx.len() >= CALINFO_REQUEST_LEN {
            let request: Vec<u8> = client.rx.drain(..CALINFO_REQUEST_LEN).collect();
            match decode_tcp_request(&request) {
                Ok(_) => {
                    self.status.calinfo_requests += 1;
                    let answer = self.config.calibration.to_bytes();
                    if write_all(&mut client.stream, &answer).is_err() {
                        return false;
                    }
                }
                // The sensor's other commands (READFT, WRITETRANSFORM, WRITETHRESHOLD) are not
                // simulated: counted and not answered.
                Err(_) => self.status.bad_tcp_requests += 1,
            }
            client.since = Instant::now();
        }
        client.since.elapsed() < CLIENT_TIMEOUT
    }

    /// Answers one HTTP request (`GET /netftapi2.xml`, or 404) and closes.
    fn serve_http(&mut self, client: &mut Client) -> bool {
        let Some(end) = client.rx.windows(4).position(|w| w == b"\r\n\r\n") else {
            return client.rx.len() < MAX_HTTP_REQUEST && client.since.elapsed() < CLIENT_TIMEOUT;
        };
        let head = String::from_utf8_lossy(&client.rx[..end]).into_owned();
        let mut words = head.lines().next().unwrap_or("").split_whitespace();
        let (method, path) = (words.next().unwrap_or(""), words.next().unwrap_or(""));
        self.status.http_requests += 1;
        let (code, body) = if method == "GET" && path == "/netftapi2.xml" {
            ("200 OK", self.netftapi2())
        } else {
            ("404 Not Found", String::from("not found\n"))
        };
        let answer = format!(
            "HTTP/1.1 {code}\r\nContent-Type: text/xml\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
            body.len()
        );
        let _ = write_all(&mut client.stream, answer.as_bytes());
        false
    }

    /// The sensor's configuration page, with the fields a client reads the calibration from.
    fn netftapi2(&self) -> String {
        let c = &self.config.calibration;
        format!(
            "<?xml version=\"1.0\" encoding=\"utf-8\"?>\r\n<netft>\r\n<setserial>{}</setserial>\r\n\
             <comrdtrate>{}</comrdtrate>\r\n<comrdtbsiz>{}</comrdtbsiz>\r\n<runstat>{:#010x}</runstat>\r\n\
             <cfgcpf>{}</cfgcpf>\r\n<cfgcpt>{}</cfgcpt>\r\n<scfgfu>{}</scfgfu>\r\n<scfgtu>{}</scfgtu>\r\n</netft>\r\n",
            self.config.serial,
            self.config.rdt_rate_hz,
            self.config.buffer_size,
            self.status.last.status,
            c.counts_per_force,
            c.counts_per_torque,
            c.force_unit.name(),
            c.torque_unit.name(),
        )
    }
}

/// Writes all of `bytes` to a non-blocking stream, waiting briefly when it is full.
fn write_all(stream: &mut TcpStream, bytes: &[u8]) -> io::Result<()> {
    super::tcp_server::write_all_within(stream, bytes, CLIENT_TIMEOUT)
}
