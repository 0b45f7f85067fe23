//! The cyclic device for an ATI Net F/T: [`AtiNetFt`].
//!
//! - `open`: binds the UDP socket records arrive at and reads the calibration over TCP
//!   (`READCALINFO`, bounded by [`NetFtConfig::timeout`]) unless the configuration gives it.
//! - `start`: RDT command 2 (or 3, buffered) with sample count 0, then waits (bounded) for the
//!   first record; with [`NetFtConfig::bias_at_start`] it then biases the sensor and waits for
//!   a record taken after the bias.
//! - `step`: sends a bias request if one is buffered ([`AtiNetFt::bias_sensor`]), takes every
//!   datagram that came (without waiting: at 7 kHz a 1 kHz loop finds about seven) and keeps
//!   the newest record. Gaps in `rdt_sequence` are records lost on the network, older records
//!   were reordered and are dropped, repeats are dropped: each is counted. A step that finds
//!   no new record keeps the last wrench; when that record is older than
//!   [`NetFtConfig::stale_after`] the step fails with a timeout (a silent or unplugged
//!   sensor), and [`NetFtConfig::max_failures`] such steps in a row fault the device. A
//!   record whose status word has bit 31 set fails the step with the sensor's error.
//! - `stop`: RDT command 0. `close` drops the socket; the counts stay.
//!
//! `step` allocates nothing and makes no system call beyond the socket's (tested with the
//! counting allocator).

use core::time::Duration;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::time::Instant;

use crate::capability::{Delivery, LinkStatistics, LinkStatisticsSensor, SixAxisForceTorqueSensor};
use crate::device::{Driver, Error, Lifecycle, Operation, State, impl_cyclic_device};
use crate::proto::netft::{
    CALINFO_RESPONSE_LEN, Calibration, RDT_PORT, RECORD_LEN, RdtCommand, RdtRecord, RdtRequest,
    TCP_PORT, calinfo_request, records, sequence_step,
};
use crate::transport::{TcpLink, UdpLink};

const SOURCE: &str = "Net F/T";
/// The largest datagram read: 40 buffered records.
const MAX_DATAGRAM: usize = 40 * RECORD_LEN;

/// How the sensor streams.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum StreamMode {
    /// One record per datagram (RDT command 2): the lowest latency.
    #[default]
    RealTime,
    /// Several records per datagram (command 3), as many as the sensor's buffer size.
    Buffered,
}

/// Configuration of an [`AtiNetFt`].
#[derive(Clone, Debug, PartialEq)]
pub struct NetFtConfig {
    /// The sensor's address.
    pub sensor: IpAddr,
    /// Its RDT port ([`RDT_PORT`]).
    pub rdt_port: u16,
    /// Its TCP port for the calibration ([`TCP_PORT`]).
    pub tcp_port: u16,
    /// Where records are received (port 0: a free one).
    pub local: SocketAddr,
    /// The calibration; `None`: read from the sensor at `open`.
    pub calibration: Option<Calibration>,
    /// How the sensor streams.
    pub mode: StreamMode,
    /// The control loop's period (the device's [`update_period`](crate::CyclicDevice::update_period)).
    pub period: Duration,
    /// A step whose newest record is older than this fails (timeout).
    pub stale_after: Duration,
    /// Failed steps in a row that fault the device.
    pub max_failures: u32,
    /// Largest wait at `open` (calibration) and `start` (first record).
    pub timeout: Duration,
    /// Bias the sensor at `start` (its software bias: the current load becomes zero).
    pub bias_at_start: bool,
}

impl NetFtConfig {
    /// A sensor at `sensor` on the standard ports, streaming in real time to a 1 kHz loop.
    pub fn new(sensor: IpAddr) -> Self {
        let local = if sensor.is_loopback() {
            IpAddr::V4(Ipv4Addr::LOCALHOST)
        } else {
            IpAddr::V4(Ipv4Addr::UNSPECIFIED)
        };
        Self {
            sensor,
            rdt_port: RDT_PORT,
            tcp_port: TCP_PORT,
            local: SocketAddr::new(local, 0),
            calibration: None,
            mode: StreamMode::RealTime,
            period: Duration::from_millis(1),
            stale_after: Duration::from_millis(5),
            max_failures: 10,
            timeout: Duration::from_secs(1),
            bias_at_start: false,
        }
    }
}

/// What the link and the sensor have shown; kept across `close`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NetFtCounters {
    /// RDT requests sent.
    pub requests: u64,
    /// Datagrams received from the sensor.
    pub datagrams: u64,
    /// Records taken (newer than every earlier one).
    pub records: u64,
    /// Records missing from the sequence (lost on the network, or never sent).
    pub dropped: u64,
    /// Records older than one already taken, dropped.
    pub reordered: u64,
    /// Records repeated, dropped.
    pub duplicated: u64,
    /// Datagrams of a length no number of records has.
    pub malformed: u64,
    /// Datagrams from anyone but the sensor.
    pub foreign: u64,
    /// Records whose status word reported an error (bit 31).
    pub status_errors: u64,
    /// Steps that found no new record (and kept the last wrench).
    pub repeated_steps: u64,
    /// Steps that failed because the newest record was too old.
    pub stale_steps: u64,
    /// The status word of the newest record.
    pub last_status: u32,
    /// The newest record's `rdt_sequence` and `ft_sequence`.
    pub last_sequence: (u32, u32),
    /// Biases requested from the sensor.
    pub biases: u64,
}

/// An ATI force/torque sensor behind a Net F/T (RL's `SixAxisForceTorqueSensor`, over RDT).
#[derive(Debug)]
pub struct AtiNetFt {
    config: NetFtConfig,
    lifecycle: Lifecycle,
    udp: Option<UdpLink>,
    calibration: Option<Calibration>,
    rx: Box<[u8; MAX_DATAGRAM + 1]>,
    newest: Option<(RdtRecord, Instant)>,
    wrench: [f64; 6],
    tare: [f64; 6],
    bias_requested: bool,
    counters: NetFtCounters,
}

impl AtiNetFt {
    /// A closed device for `config`.
    pub fn new(config: NetFtConfig) -> Result<Self, Error> {
        if config.period.is_zero() || config.stale_after.is_zero() || config.timeout.is_zero() {
            return Err(Error::InvalidArgument {
                what: "Net F/T durations (period, stale_after, timeout) in µs",
                expected: 1,
                got: 0,
            });
        }
        if let Some(c) = &config.calibration {
            c.check()
                .map_err(|e| Error::protocol(Operation::Open, SOURCE, &e))?;
        }
        Ok(Self {
            lifecycle: Lifecycle::with_failure_limit(config.max_failures),
            udp: None,
            calibration: config.calibration,
            rx: Box::new([0; MAX_DATAGRAM + 1]),
            newest: None,
            wrench: [0.0; 6],
            tare: [0.0; 6],
            bias_requested: false,
            counters: NetFtCounters::default(),
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &NetFtConfig {
        &self.config
    }

    /// The calibration in use (after `open`).
    pub fn calibration(&self) -> Option<Calibration> {
        self.calibration
    }

    /// The counts so far.
    pub fn counters(&self) -> NetFtCounters {
        let mut c = self.counters;
        if let Some(u) = &self.udp {
            c.foreign = u.counters().foreign;
        }
        c
    }

    /// The newest record (counts, sequence numbers, status).
    pub fn record(&self) -> Option<RdtRecord> {
        self.newest.map(|(r, _)| r)
    }

    /// How old the newest record is.
    pub fn age(&self) -> Option<Duration> {
        self.newest.map(|(_, t)| t.elapsed())
    }

    /// The local address records arrive at (after `open`).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.udp.as_ref().and_then(|u| u.local_addr().ok())
    }

    /// Asks the sensor to bias itself (RDT command 0x42) at the next step: the load on it then
    /// reads as zero. Refused unless running.
    pub fn bias_sensor(&mut self) -> Result<(), Error> {
        self.lifecycle
            .check(Operation::Step)
            .map_err(|_| Error::State {
                operation: Operation::Set,
                state: self.lifecycle.state(),
            })?;
        self.bias_requested = true;
        Ok(())
    }

    /// Takes the newest wrench as this driver's zero (a bias in the driver, the sensor
    /// untouched); [`clear_tare`](Self::clear_tare) undoes it.
    pub fn tare(&mut self) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        let Some((record, _)) = self.newest else {
            return Err(Error::State {
                operation: Operation::Set,
                state: self.lifecycle.state(),
            });
        };
        if let Some(c) = &self.calibration {
            self.tare = c.to_si(&record.counts);
            self.wrench = [0.0; 6];
        }
        Ok(())
    }

    /// Undoes [`tare`](Self::tare).
    pub fn clear_tare(&mut self) {
        self.tare = [0.0; 6];
    }

    fn udp(&mut self, operation: Operation) -> Result<&mut UdpLink, Error> {
        self.udp.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })
    }

    fn sensor_rdt(&self) -> SocketAddr {
        SocketAddr::new(self.config.sensor, self.config.rdt_port)
    }

    fn request(&mut self, operation: Operation, command: RdtCommand) -> Result<(), Error> {
        let bytes = RdtRequest::new(command, 0).to_bytes();
        self.udp(operation)?
            .send(&bytes)
            .map_err(|e| Error::io(operation, &e))?;
        self.counters.requests += 1;
        Ok(())
    }

    /// Reads the calibration over TCP.
    fn read_calibration(&self) -> Result<Calibration, Error> {
        let op = Operation::Open;
        let peer = SocketAddr::new(self.config.sensor, self.config.tcp_port);
        let deadline = Instant::now() + self.config.timeout;
        let mut tcp = TcpLink::connect(peer, self.config.timeout).map_err(|e| Error::io(op, &e))?;
        tcp.send_all(&calinfo_request(), deadline)
            .map_err(|e| Error::io(op, &e))?;
        let mut answer = [0u8; CALINFO_RESPONSE_LEN];
        let mut got = 0;
        while got < CALINFO_RESPONSE_LEN {
            match tcp.recv(&mut answer[got..], deadline) {
                Ok(0) => return Err(Error::Disconnected { operation: op }),
                Ok(n) => got += n,
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {
                    return Err(Error::Timeout {
                        operation: op,
                        waited: self.config.timeout,
                    });
                }
                Err(e) => return Err(Error::io(op, &e)),
            }
        }
        Calibration::decode(&answer).map_err(|e| Error::protocol(op, "Net F/T calibration", &e))
    }

    /// Takes every datagram that came (until `deadline` at most); returns whether a new record
    /// was taken.
    fn drain(&mut self, operation: Operation, deadline: Instant) -> Result<bool, Error> {
        let mut fresh = false;
        loop {
            let udp = self.udp.as_mut().ok_or(Error::State {
                operation,
                state: State::Closed,
            })?;
            let n = match udp.try_recv(&mut self.rx[..], deadline) {
                Ok(Some(n)) => n,
                Ok(None) => return Ok(fresh),
                Err(e) => return Err(Error::io(operation, &e)),
            };
            fresh |= self.take(n);
        }
    }

    /// Like [`drain`](Self::drain), but waits until a new record came or `deadline` passed.
    fn wait_record(&mut self, operation: Operation, deadline: Instant) -> Result<bool, Error> {
        loop {
            if self.drain(operation, deadline)? {
                return Ok(true);
            }
            let udp = self.udp.as_mut().ok_or(Error::State {
                operation,
                state: State::Closed,
            })?;
            match udp.recv_until(&mut self.rx[..], deadline) {
                Ok(Some(n)) => {
                    if self.take(n) {
                        return Ok(true);
                    }
                }
                Ok(None) => return Ok(false),
                Err(e) => return Err(Error::io(operation, &e)),
            }
        }
    }

    /// Takes the datagram of `n` bytes in `rx`; returns whether it held a new record.
    fn take(&mut self, n: usize) -> bool {
        self.counters.datagrams += 1;
        let now = Instant::now();
        let Ok(recs) = records(&self.rx[..n.min(MAX_DATAGRAM + 1)]) else {
            self.counters.malformed += 1;
            return false;
        };
        let mut fresh = false;
        for r in recs {
            if let Some((last, _)) = self.newest {
                match sequence_step(last.rdt_sequence, r.rdt_sequence) {
                    s if s >= 1 => self.counters.dropped += (s - 1) as u64,
                    0 => {
                        self.counters.duplicated += 1;
                        continue;
                    }
                    _ => {
                        self.counters.reordered += 1;
                        continue;
                    }
                }
            }
            if r.is_error() {
                self.counters.status_errors += 1;
            }
            self.counters.records += 1;
            self.counters.last_status = r.status;
            self.counters.last_sequence = (r.rdt_sequence, r.ft_sequence);
            self.newest = Some((r, now));
            fresh = true;
        }
        fresh
    }

    /// The newest record's wrench into `wrench`, or its error.
    fn update(&mut self, operation: Operation) -> Result<(), Error> {
        let (Some((record, _)), Some(c)) = (self.newest, self.calibration) else {
            return Ok(());
        };
        if record.is_error() {
            return Err(Error::device(
                operation,
                SOURCE,
                &format_args!("status {:#010x} (error)", record.status),
            ));
        }
        let w = c.to_si(&record.counts);
        for ((out, v), t) in self.wrench.iter_mut().zip(w).zip(self.tare) {
            *out = v - t;
        }
        Ok(())
    }

    fn start_command(&self) -> RdtCommand {
        match self.config.mode {
            StreamMode::RealTime => RdtCommand::StartRealTime,
            StreamMode::Buffered => RdtCommand::StartBuffered,
        }
    }
}

impl Driver for AtiNetFt {
    const STOP_DESCRIPTION: &'static str = "streaming stopped";

    fn open_sequence(&mut self) -> Result<(), Error> {
        let op = Operation::Open;
        let udp =
            UdpLink::bind(self.config.local, self.sensor_rdt()).map_err(|e| Error::io(op, &e))?;
        if self.config.calibration.is_none() {
            self.calibration = Some(self.read_calibration()?);
        }
        self.udp = Some(udp);
        self.newest = None;
        Ok(())
    }

    fn start_sequence(&mut self) -> Result<(), Error> {
        let op = Operation::Start;
        self.newest = None;
        self.bias_requested = false;
        let deadline = Instant::now() + self.config.timeout;
        // Leftovers of an earlier stream are not this one's.
        self.drain(op, Instant::now())?;
        self.newest = None;
        self.request(op, self.start_command())?;
        if !self.wait_record(op, deadline)? {
            return Err(Error::Timeout {
                operation: op,
                waited: self.config.timeout,
            });
        }
        if self.config.bias_at_start {
            self.request(op, RdtCommand::SetSoftwareBias)?;
            self.counters.biases += 1;
            // The records already on their way were taken before the bias: wait for the
            // sensor's next samples.
            let settle = Instant::now() + Duration::from_millis(2);
            while Instant::now() < settle {
                self.wait_record(op, settle)?;
            }
            if !self.wait_record(op, deadline)? {
                return Err(Error::Timeout {
                    operation: op,
                    waited: self.config.timeout,
                });
            }
        }
        self.update(op)
    }

    fn stop_sequence(&mut self) -> Result<(), Error> {
        self.request(Operation::Stop, RdtCommand::Stop)
    }

    fn close_sequence(&mut self) -> Result<(), Error> {
        self.udp = None;
        Ok(())
    }

    fn period(&self) -> Duration {
        self.config.period
    }

    fn exchange(&mut self) -> Result<(), Error> {
        let op = Operation::Step;
        if self.bias_requested {
            self.bias_requested = false;
            self.request(op, RdtCommand::SetSoftwareBias)?;
            self.counters.biases += 1;
        }
        let budget = self
            .lifecycle
            .step_budget()
            .unwrap_or(self.config.period)
            .min(self.config.period);
        let fresh = self.drain(op, Instant::now() + budget)?;
        if !fresh {
            self.counters.repeated_steps += 1;
            let age = self.newest.map(|(_, t)| t.elapsed());
            if age.is_none_or(|a| a > self.config.stale_after) {
                self.counters.stale_steps += 1;
                return Err(Error::Timeout {
                    operation: op,
                    waited: age.unwrap_or(Duration::ZERO),
                });
            }
        }
        self.update(op)
    }
}

impl_cyclic_device!(AtiNetFt, lifecycle);

impl SixAxisForceTorqueSensor for AtiNetFt {
    fn forces_torques(&self) -> Result<[f64; 6], Error> {
        self.lifecycle.check(Operation::Get)?;
        Ok(self.wrench)
    }
}

impl LinkStatisticsSensor for AtiNetFt {
    fn link_statistics(&self) -> LinkStatistics {
        let c = self.counters();
        LinkStatistics {
            sent: c.requests,
            received: c.records,
            lost: c.dropped + c.stale_steps,
            late: c.reordered + c.duplicated,
            rejected: c.foreign,
            corrupt: c.malformed,
            consecutive_failures: self.lifecycle.consecutive_failures(),
            delivery: Delivery::default(),
        }
    }
}
