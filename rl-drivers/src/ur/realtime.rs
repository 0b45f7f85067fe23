//! The cyclic device for a Universal Robots controller's real-time interface (port 30003, or
//! 30013 read only): [`UrRealtime`], RL's `UniversalRobotsRealtime`.
//!
//! The controller streams its state to every client of the port, unasked, each of its cycles
//! (500 Hz on e-Series, 125 Hz on CB3), as [`crate::proto::ur_realtime`] lays it out; the
//! port also takes URScript. The device reads; it commands nothing but the scripts queued
//! with [`UrRealtime::queue_script`] (RL's `doScript`).
//!
//! - `open`: connects (bounded), reads the first message so the state is known from `open`
//!   on, and takes the controller's cycle from the message length (e-Series from 1140 bytes:
//!   2 ms; CB3: 8 ms) unless configured.
//! - `start`, `stop`: nothing goes on the wire (the stream runs from the connection on).
//! - `step`: sends a queued script, then takes every message that came and, if none did,
//!   waits for the next until the caller's budget or [`UrRealtimeConfig::state_wait`].
//!   Messages that piled up behind the newest are counted (`late`), gaps in the controller's
//!   time too (`skipped`: the controller's or the network's loss); a step without a message
//!   is `lost` (a timeout). A message that does not decode (a mode that is not an integer)
//!   is counted `corrupt` and passed over; a length field that names no layout ends the
//!   stream (its framing is that field alone): every step fails with a protocol error saying
//!   why until the device faults and is closed. A closed connection disconnects.
//! - `close`: drops the connection.
//!
//! `step` allocates nothing (tested with the counting allocator); the safety and robot modes
//! are read, not judged: the device is a monitor, and a protective stop is for the caller to
//! act on ([`UrRealtime::realtime_state`]).

use core::time::Duration;
use std::net::{IpAddr, SocketAddr};
use std::time::Instant;

use crate::capability::{
    CartesianPositionSensor, Delivery, DigitalInputReader, JointDevice, JointPositionSensor,
    JointVelocitySensor, LinkStatistics, LinkStatisticsSensor, Pose, SixAxisForceTorqueSensor,
};
use crate::device::{Driver, Error, Lifecycle, Operation, State, impl_cyclic_device};
use crate::proto::ur_realtime::{self, RealtimeState};
use crate::transport::TcpLink;

use super::DOF;

const SOURCE: &str = "UR real-time interface";
/// Bytes the receive buffer holds (13 messages of 1220 bytes).
const RX: usize = 16 * 1024;
/// Bytes a queued script may have.
pub const SCRIPT_CAPACITY: usize = 16 * 1024;

/// Configuration of a [`UrRealtime`].
#[derive(Clone, Debug, PartialEq)]
pub struct UrRealtimeConfig {
    /// The controller's address.
    pub host: IpAddr,
    /// The port: 30003 (takes scripts too) or 30013 (read only).
    pub port: u16,
    /// The controller's cycle; `None`: from the message length (2 ms from 1140 bytes, the
    /// e-Series' layouts; else 8 ms, CB3's).
    pub period: Option<Duration>,
    /// Largest wait of `open` (connection and first message).
    pub timeout: Duration,
    /// Largest wait of a step for the next message (a caller's budget can shorten it).
    pub state_wait: Duration,
    /// Failed steps in a row that fault the device.
    pub max_failures: u32,
}

impl UrRealtimeConfig {
    /// A controller at `host` on port 30003.
    pub fn new(host: IpAddr) -> Self {
        Self {
            host,
            port: ur_realtime::PORT,
            period: None,
            timeout: Duration::from_secs(3),
            state_wait: Duration::from_millis(10),
            max_failures: 10,
        }
    }
}

/// What the link has seen; kept across `close`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UrRealtimeCounters {
    /// Messages taken.
    pub messages: u64,
    /// Steps that waited for a message in vain.
    pub lost: u64,
    /// Messages that had piled up behind the newest (the step came late).
    pub late: u64,
    /// Messages the stream lacks (gaps in the controller's time).
    pub skipped: u64,
    /// Messages that did not decode (the stream ends at the first).
    pub corrupt: u64,
    /// Scripts sent.
    pub scripts_sent: u64,
}

/// A Universal Robots controller's real-time interface (RL's `UniversalRobotsRealtime`).
#[derive(Debug)]
pub struct UrRealtime {
    config: UrRealtimeConfig,
    lifecycle: Lifecycle,
    tcp: Option<TcpLink>,
    rx: Box<[u8; RX]>,
    /// Bytes read and not yet taken: `rx[head..tail]`.
    head: usize,
    tail: usize,
    script: Box<[u8; SCRIPT_CAPACITY]>,
    script_len: usize,
    state: RealtimeState,
    have_state: bool,
    /// The stream could not be framed (an unknown length): it stays unreadable until `close`.
    desync: Option<ur_realtime::RealtimeError>,
    period: Duration,
    counters: UrRealtimeCounters,
}

impl UrRealtime {
    /// A closed device for `config`.
    pub fn new(config: UrRealtimeConfig) -> Result<Self, Error> {
        if config.timeout.is_zero() || config.state_wait.is_zero() {
            return Err(Error::InvalidArgument {
                what: "UR real-time waits (timeout, state_wait) in µs",
                expected: 1,
                got: 0,
            });
        }
        if config.period.is_some_and(|p| p.is_zero()) {
            return Err(Error::InvalidArgument {
                what: "UR real-time period in µs",
                expected: 1,
                got: 0,
            });
        }
        Ok(Self {
            lifecycle: Lifecycle::with_failure_limit(config.max_failures),
            tcp: None,
            rx: Box::new([0; RX]),
            head: 0,
            tail: 0,
            script: Box::new([0; SCRIPT_CAPACITY]),
            script_len: 0,
            state: RealtimeState::default(),
            have_state: false,
            desync: None,
            period: config.period.unwrap_or(Duration::from_millis(2)),
            counters: UrRealtimeCounters::default(),
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &UrRealtimeConfig {
        &self.config
    }

    /// The last message's state (all of it: targets, currents, modes, voltages, payload).
    pub fn realtime_state(&self) -> &RealtimeState {
        &self.state
    }

    /// The counts so far.
    pub fn counters(&self) -> UrRealtimeCounters {
        self.counters
    }

    /// The controller's cycle (from the first message, or configured).
    pub fn controller_period(&self) -> Duration {
        self.period
    }

    /// Queues a URScript program (or a line of it) to be sent at the next step (RL's
    /// `doScript`); on port 30003 the controller compiles and runs it, replacing a running
    /// one. Copied into a fixed buffer: at most [`SCRIPT_CAPACITY`] bytes, together with
    /// what is still queued.
    pub fn queue_script(&mut self, script: &str) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        let end = self.script_len + script.len();
        if end > SCRIPT_CAPACITY {
            return Err(Error::InvalidArgument {
                what: "UR script bytes queued (SCRIPT_CAPACITY)",
                expected: SCRIPT_CAPACITY,
                got: end,
            });
        }
        self.script[self.script_len..end].copy_from_slice(script.as_bytes());
        self.script_len = end;
        Ok(())
    }

    fn addr(&self) -> SocketAddr {
        SocketAddr::new(self.config.host, self.config.port)
    }

    /// Reads what is there without waiting; `Ok(false)`: nothing.
    fn fill(&mut self, operation: Operation) -> Result<bool, Error> {
        if self.head > 0 && RX - self.tail < ur_realtime::MAX_LEN {
            self.rx.copy_within(self.head..self.tail, 0);
            self.tail -= self.head;
            self.head = 0;
        }
        let tcp = self.tcp.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })?;
        match tcp.try_recv(&mut self.rx[self.tail..]) {
            Ok(Some(0)) => Err(Error::Disconnected { operation }),
            Ok(Some(n)) => {
                self.tail += n;
                Ok(true)
            }
            Ok(None) => Ok(false),
            Err(e) => Err(Error::io(operation, &e)),
        }
    }

    /// Decodes the complete messages in the buffer; returns how many. A message that does not
    /// decode is counted and passed over; a length field that names no layout ends the
    /// stream (nothing after it can be framed).
    fn take(&mut self, operation: Operation) -> Result<u64, Error> {
        if let Some(e) = self.desync {
            return Err(Error::protocol(operation, SOURCE, &e));
        }
        let mut taken = 0;
        loop {
            let bytes = &self.rx[self.head..self.tail];
            let len = match ur_realtime::message_length(bytes) {
                Ok(Some(len)) if bytes.len() >= len => len,
                Ok(_) => return Ok(taken),
                Err(e) => {
                    self.counters.corrupt += 1;
                    self.desync = Some(e);
                    (self.head, self.tail) = (0, 0);
                    return Err(Error::protocol(operation, SOURCE, &e));
                }
            };
            let decoded = RealtimeState::decode(&bytes[..len]);
            self.head += len;
            let Ok(next) = decoded else {
                self.counters.corrupt += 1;
                continue;
            };
            if self.have_state {
                let gap = (next.time - self.state.time) / self.period.as_secs_f64();
                if gap > 1.5 {
                    self.counters.skipped += (gap.round() as u64).saturating_sub(1);
                }
            }
            self.state = next;
            self.have_state = true;
            self.counters.messages += 1;
            taken += 1;
        }
    }

    /// Takes every message that came and, if none did, waits for one until `deadline`.
    /// Returns whether a message came.
    fn receive(&mut self, operation: Operation, deadline: Instant) -> Result<bool, Error> {
        let mut taken = self.take(operation)?;
        while self.fill(operation)? {
            taken += self.take(operation)?;
        }
        while taken == 0 {
            let fd = match self.tcp.as_ref() {
                Some(t) => std::os::fd::AsFd::as_fd(t),
                None => {
                    return Err(Error::State {
                        operation,
                        state: State::Closed,
                    });
                }
            };
            if !crate::transport::wait(fd, crate::transport::Readiness::Readable, deadline)
                .map_err(|e| Error::io(operation, &e))?
            {
                return Ok(false);
            }
            while self.fill(operation)? {
                taken += self.take(operation)?;
            }
        }
        if taken > 1 {
            self.counters.late += taken - 1;
        }
        Ok(true)
    }

    fn read(&self, values: [f64; DOF], out: &mut [f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("UR joints", DOF, out.len())?;
        out.copy_from_slice(&values);
        Ok(())
    }
}

impl Driver for UrRealtime {
    const STOP_DESCRIPTION: &'static str = "reading stopped (the stream goes on until close)";
    /// The controller sends a message every cycle on its own clock.
    const RUNS_OWN_CYCLE: bool = true;

    fn open_sequence(&mut self) -> Result<(), Error> {
        let op = Operation::Open;
        let tcp =
            TcpLink::connect(self.addr(), self.config.timeout).map_err(|e| Error::io(op, &e))?;
        self.tcp = Some(tcp);
        (self.head, self.tail, self.script_len) = (0, 0, 0);
        self.have_state = false;
        self.desync = None;
        let deadline = Instant::now() + self.config.timeout;
        match self.receive(op, deadline) {
            Ok(true) => {}
            Ok(false) => {
                self.tcp = None;
                return Err(Error::Timeout {
                    operation: op,
                    waited: self.config.timeout,
                });
            }
            Err(e) => {
                self.tcp = None;
                return Err(e);
            }
        }
        self.period = self.config.period.unwrap_or(if self.state.length >= 1140 {
            Duration::from_millis(2)
        } else {
            Duration::from_millis(8)
        });
        Ok(())
    }

    fn start_sequence(&mut self) -> Result<(), Error> {
        Ok(())
    }

    fn stop_sequence(&mut self) -> Result<(), Error> {
        Ok(())
    }

    fn close_sequence(&mut self) -> Result<(), Error> {
        self.tcp = None;
        Ok(())
    }

    fn period(&self) -> Duration {
        self.period
    }

    fn exchange(&mut self) -> Result<(), Error> {
        let op = Operation::Step;
        let wait = self
            .lifecycle
            .step_budget()
            .unwrap_or(self.config.state_wait)
            .min(self.config.state_wait);
        let deadline = Instant::now() + wait;
        if self.script_len > 0 {
            let n = self.script_len;
            let tcp = self.tcp.as_mut().ok_or(Error::State {
                operation: op,
                state: State::Closed,
            })?;
            tcp.send_all(&self.script[..n], deadline)
                .map_err(|e| Error::io(op, &e))?;
            self.script_len = 0;
            self.counters.scripts_sent += 1;
        }
        if !self.receive(op, deadline)? {
            self.counters.lost += 1;
            return Err(Error::Timeout {
                operation: op,
                waited: wait,
            });
        }
        Ok(())
    }
}

impl_cyclic_device!(UrRealtime, lifecycle);

impl JointDevice for UrRealtime {
    fn dof(&self) -> usize {
        DOF
    }
}

impl JointPositionSensor for UrRealtime {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        self.read(self.state.q_actual, q)
    }
}

impl JointVelocitySensor for UrRealtime {
    fn joint_velocity(&self, qd: &mut [f64]) -> Result<(), Error> {
        self.read(self.state.qd_actual, qd)
    }
}

impl CartesianPositionSensor for UrRealtime {
    /// The tool's pose in the base frame (its rotation vector as a matrix).
    fn cartesian_position(&self) -> Result<Pose, Error> {
        self.lifecycle.check(Operation::Get)?;
        Ok(super::convert::tool_pose(&self.state.tool_vector_actual))
    }
}

impl SixAxisForceTorqueSensor for UrRealtime {
    /// The controller's estimate of the wrench at the tool ("TCP force"), the payload
    /// compensated, in the base frame as the controller gives it.
    fn forces_torques(&self) -> Result<[f64; 6], Error> {
        self.lifecycle.check(Operation::Get)?;
        Ok(self.state.tcp_force)
    }
}

impl DigitalInputReader for UrRealtime {
    /// Standard inputs 0–7, configurable 8–15, tool 16–17.
    fn digital_input_count(&self) -> usize {
        super::convert::DIGITAL_INPUTS
    }

    fn digital_input(&self, index: usize) -> Result<bool, Error> {
        self.lifecycle.check(Operation::Get)?;
        super::convert::digital_input(self.state.digital_input_bits, index)
    }
}

impl LinkStatisticsSensor for UrRealtime {
    fn link_statistics(&self) -> LinkStatistics {
        let c = self.counters;
        LinkStatistics {
            sent: c.scripts_sent,
            received: c.messages,
            lost: c.lost + c.skipped,
            late: c.late,
            rejected: 0,
            corrupt: c.corrupt,
            consecutive_failures: self.lifecycle.consecutive_failures(),
            delivery: Delivery::default(),
        }
    }
}
