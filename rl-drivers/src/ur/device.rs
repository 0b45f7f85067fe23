//! The cyclic device for a Universal Robots arm over RTDE: [`UniversalRobot`].
//!
//! - `open`: RTDE (protocol version 2, else 1), the controller's version, the output recipe
//!   (joints, speeds, tool pose and force, modes, I/O, the program's handshake register) at
//!   500 Hz on e-Series (125 Hz on CB3), two input recipes (the command register and six joint
//!   registers; the digital outputs), one package read (outputs started, then paused: the
//!   joints are known before `start`), and the dashboard if it answers.
//! - `start`: with [`UrConfig::power_on`], powers the arm on and releases its brakes through
//!   the dashboard; starts the outputs; checks that the robot runs and no safety stop holds
//!   (else a typed error that says what to do); writes the joints where they stand and the
//!   command 1; sends the [`FollowerProgram`] to the script port; waits (bounded) until the
//!   controller plays it and its handshake register reads 1.
//! - `step`: sends the buffered joints (and the digital outputs when they changed), then takes
//!   the controller's next package (it sends one every 2 ms on its own clock), waiting at most
//!   the caller's budget or [`UrConfig::state_wait`]. Packages that piled up are counted
//!   (`late`), gaps in the controller's timestamps too (`skipped`: the controller dropped
//!   packages); a step without a package is `lost`. A safety stop (protective, safeguard,
//!   emergency) or a program that stopped (its watchdog, the dashboard, the pendant) fails the
//!   step with [`ErrorKind::Device`](crate::ErrorKind::Device); a closed connection
//!   disconnects.
//! - `stop`: writes the command 0 (the program leaves its loop, `stopj`, clears the
//!   handshake), waits for the program's end (bounded; else the dashboard's `stop`), pauses
//!   the outputs.
//! - `close`: drops the connections.
//!
//! `step` allocates nothing (tested with the counting allocator).

use core::time::Duration;
use std::net::{IpAddr, SocketAddr};
use std::time::Instant;

use super::dashboard::{self, Dashboard};
use super::link::{LinkError, Package, RtdeLink};
use super::program::{FollowerProgram, MODE_POSITION, MODE_VELOCITY};
use crate::capability::{
    CartesianPositionSensor, Delivery, DigitalInputReader, DigitalOutputWriter, JointDevice,
    JointPositionActuator, JointPositionSensor, JointVelocityActuator, JointVelocitySensor,
    LinkStatistics, LinkStatisticsSensor, Pose,
};
use crate::device::{Description, Driver, Error, Lifecycle, Operation, State, impl_cyclic_device};
use crate::proto::rtde::types::Writer;
use crate::proto::rtde::{Message, PROTOCOL_VERSION, PackageType, Recipe};

const SOURCE: &str = "UR controller";
/// Joints of a UR arm.
pub const DOF: usize = 6;

/// Robot modes (`robot_mode`), as the RTDE guide numbers them.
pub mod robot_mode {
    /// Powered off.
    pub const POWER_OFF: i32 = 3;
    /// Powering on.
    pub const POWER_ON: i32 = 4;
    /// Powered, brakes applied.
    pub const IDLE: i32 = 5;
    /// Powered, brakes released.
    pub const RUNNING: i32 = 7;
}

/// The name of a robot mode.
pub fn robot_mode_name(m: i32) -> &'static str {
    match m {
        -1 => "NO_CONTROLLER",
        0 => "DISCONNECTED",
        1 => "CONFIRM_SAFETY",
        2 => "BOOTING",
        3 => "POWER_OFF",
        4 => "POWER_ON",
        5 => "IDLE",
        6 => "BACKDRIVE",
        7 => "RUNNING",
        8 => "UPDATING_FIRMWARE",
        _ => "UNKNOWN",
    }
}

/// The name of a safety mode; `None` for the modes a program may run in.
pub fn safety_stop_name(m: i32) -> Option<&'static str> {
    match m {
        1 | 2 => None,
        3 => Some("protective stop"),
        4 => Some("recovery"),
        5 => Some("safeguard stop"),
        6 => Some("system emergency stop"),
        7 => Some("robot emergency stop"),
        8 => Some("violation"),
        9 => Some("fault"),
        11 => Some("safety stop"),
        _ => Some("unknown safety mode"),
    }
}

/// Configuration of a [`UniversalRobot`].
#[derive(Clone, Debug, PartialEq)]
pub struct UrConfig {
    /// The controller's address.
    pub host: IpAddr,
    /// RTDE's port.
    pub rtde_port: u16,
    /// The dashboard's port (`None`: not used).
    pub dashboard_port: Option<u16>,
    /// The script port the program goes to (30002, the secondary interface).
    pub script_port: u16,
    /// The program's registers (see [`FollowerProgram`]).
    pub register_base: u8,
    /// `servoj`'s lookahead time and gain.
    pub lookahead_time: f64,
    /// See [`lookahead_time`](Self::lookahead_time).
    pub gain: f64,
    /// The program's watchdog: it stops when the command register is not written this often.
    pub watchdog_hz: f64,
    /// `speedj`'s acceleration while joint speeds are commanded
    /// ([`JointVelocityActuator`]), rad/s² of the leading joint: the controller ramps to each
    /// new speed at it (1.4, URScript's default joint acceleration).
    pub speed_acceleration: f64,
    /// Power on and release the brakes at `start` (through the dashboard).
    pub power_on: bool,
    /// Largest wait of `open`, `start` and `stop` for the controller.
    pub timeout: Duration,
    /// Largest wait of a step for the next package (a caller's budget can shorten it).
    pub state_wait: Duration,
    /// Failed steps in a row that fault the device.
    pub max_failures: u32,
}

impl UrConfig {
    /// A controller at `host` on the standard ports.
    pub fn new(host: IpAddr) -> Self {
        Self {
            host,
            rtde_port: crate::proto::rtde::PORT,
            dashboard_port: Some(dashboard::PORT),
            script_port: 30002,
            register_base: 24,
            lookahead_time: 0.1,
            gain: 300.0,
            watchdog_hz: 10.0,
            speed_acceleration: 1.4,
            power_on: false,
            timeout: Duration::from_secs(3),
            state_wait: Duration::from_millis(4),
            max_failures: 10,
        }
    }
}

/// What the controller sent last.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UrState {
    /// The controller's time, s.
    pub timestamp: f64,
    /// Measured joints, rad.
    pub q: [f64; DOF],
    /// Measured joint speeds, rad/s.
    pub qd: [f64; DOF],
    /// Target joints, rad.
    pub target_q: [f64; DOF],
    /// Motor currents, A.
    pub current: [f64; DOF],
    /// The tool pose: x, y, z (m) and a rotation vector (rad).
    pub tcp_pose: [f64; 6],
    /// The tool's force and torque, N and N·m.
    pub tcp_force: [f64; 6],
    /// See [`robot_mode`].
    pub robot_mode: i32,
    /// The joints' modes.
    pub joint_mode: [i32; DOF],
    /// The safety mode.
    pub safety_mode: i32,
    /// The safety status bits.
    pub safety_status_bits: u32,
    /// 1 stopped, 2 playing, 4 paused.
    pub runtime_state: u32,
    /// Bit 0 power on, bit 1 program running.
    pub robot_status_bits: u32,
    /// The speed slider's fraction in effect.
    pub speed_scaling: f64,
    /// Digital inputs (standard 0–7, configurable 8–15, tool 16–17).
    pub digital_inputs: u64,
    /// Digital outputs, same numbering.
    pub digital_outputs: u64,
    /// The program's handshake register.
    pub handshake: i32,
}

/// What the link has seen; kept across `close`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UrCounters {
    /// Output packages taken.
    pub packages: u64,
    /// Input packages sent.
    pub inputs_sent: u64,
    /// Steps that waited for a package in vain.
    pub lost: u64,
    /// Packages that had piled up behind the newest (the step came late).
    pub late: u64,
    /// Packages the controller skipped (gaps in its timestamps).
    pub skipped: u64,
    /// Packages that did not decode, or were not for our recipe.
    pub corrupt: u64,
    /// Text messages from the controller.
    pub text_messages: u64,
}

/// The driver's buffered command.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Command {
    /// Joint positions or speeds, as `mode` says.
    q: [f64; DOF],
    /// The command register: 0 (the program ends), [`MODE_POSITION`] or [`MODE_VELOCITY`].
    mode: i32,
    outputs: u16,
    outputs_mask: u16,
    outputs_dirty: bool,
}

/// Indices of the output recipe's fields.
mod field {
    pub const TIMESTAMP: usize = 0;
    pub const ACTUAL_Q: usize = 1;
    pub const ACTUAL_QD: usize = 2;
    pub const TARGET_Q: usize = 3;
    pub const CURRENT: usize = 4;
    pub const TCP_POSE: usize = 5;
    pub const TCP_FORCE: usize = 6;
    pub const ROBOT_MODE: usize = 7;
    pub const JOINT_MODE: usize = 8;
    pub const SAFETY_MODE: usize = 9;
    pub const SAFETY_BITS: usize = 10;
    pub const RUNTIME_STATE: usize = 11;
    pub const ROBOT_BITS: usize = 12;
    pub const SPEED_SCALING: usize = 13;
    pub const DIGITAL_IN: usize = 14;
    pub const DIGITAL_OUT: usize = 15;
    pub const HANDSHAKE: usize = 16;
}

const OUTPUTS: [&str; 16] = [
    "timestamp",
    "actual_q",
    "actual_qd",
    "target_q",
    "actual_current",
    "actual_TCP_pose",
    "actual_TCP_force",
    "robot_mode",
    "joint_mode",
    "safety_mode",
    "safety_status_bits",
    "runtime_state",
    "robot_status_bits",
    "speed_scaling",
    "actual_digital_input_bits",
    "actual_digital_output_bits",
];

/// A Universal Robots arm (e-Series or CB3) over RTDE (RL's `UniversalRobotsRtde`).
#[derive(Debug)]
pub struct UniversalRobot {
    config: UrConfig,
    lifecycle: Lifecycle,
    link: Option<RtdeLink>,
    dashboard: Option<Dashboard>,
    outputs: Recipe<24>,
    joints_recipe: u8,
    io_recipe: u8,
    version: Option<[u32; 4]>,
    period: Duration,
    state: UrState,
    have_state: bool,
    command: Command,
    /// The program runs (from `start`'s handshake until `stop`).
    following: bool,
    counters: UrCounters,
    last_text: Option<Description>,
}

impl UniversalRobot {
    /// A closed device for `config`.
    pub fn new(config: UrConfig) -> Result<Self, Error> {
        if config.timeout.is_zero() || config.state_wait.is_zero() {
            return Err(Error::InvalidArgument {
                what: "UR waits (timeout, state_wait) in µs",
                expected: 1,
                got: 0,
            });
        }
        if config.register_base > 42 {
            return Err(Error::InvalidArgument {
                what: "UR register base (its six joint registers must fit 0..=47)",
                expected: 42,
                got: usize::from(config.register_base),
            });
        }
        if !(config.watchdog_hz > 0.0 && config.lookahead_time > 0.0 && config.gain > 0.0) {
            return Err(Error::InvalidArgument {
                what: "UR watchdog frequency, lookahead time and gain (positive)",
                expected: 1,
                got: 0,
            });
        }
        Ok(Self {
            lifecycle: Lifecycle::with_failure_limit(config.max_failures),
            link: None,
            dashboard: None,
            outputs: Recipe::new(),
            joints_recipe: 0,
            io_recipe: 0,
            version: None,
            period: Duration::from_millis(2),
            state: UrState::default(),
            have_state: false,
            command: Command {
                q: [0.0; DOF],
                mode: 0,
                outputs: 0,
                outputs_mask: 0,
                outputs_dirty: false,
            },
            following: false,
            counters: UrCounters::default(),
            last_text: None,
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &UrConfig {
        &self.config
    }

    /// The last state the controller sent.
    pub fn ur_state(&self) -> &UrState {
        &self.state
    }

    /// The counts so far.
    pub fn counters(&self) -> UrCounters {
        self.counters
    }

    /// The controller's version (major, minor, bugfix, build), after `open`.
    pub fn controller_version(&self) -> Option<[u32; 4]> {
        self.version
    }

    /// The last error or warning text the controller sent over RTDE.
    pub fn last_text_message(&self) -> Option<Description> {
        self.last_text
    }

    /// The dashboard, if it answered at `open` (for commands outside the loop).
    pub fn dashboard(&mut self) -> Option<&mut Dashboard> {
        self.dashboard.as_mut()
    }

    /// The program the driver sends at `start`.
    pub fn program(&self) -> FollowerProgram {
        FollowerProgram {
            register_base: self.config.register_base,
            servo_time: self.period.as_secs_f64(),
            lookahead_time: self.config.lookahead_time,
            gain: self.config.gain,
            watchdog_hz: self.config.watchdog_hz,
            speed_acceleration: self.config.speed_acceleration,
        }
    }

    fn rtde_addr(&self) -> SocketAddr {
        SocketAddr::new(self.config.host, self.config.rtde_port)
    }

    fn link(&mut self, operation: Operation) -> Result<&mut RtdeLink, Error> {
        self.link.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })
    }

    fn link_error(&self, operation: Operation, e: LinkError) -> Error {
        match e {
            LinkError::Io(e) if e.kind() == std::io::ErrorKind::TimedOut => Error::Timeout {
                operation,
                waited: self.config.timeout,
            },
            LinkError::Io(e) => Error::io(operation, &e),
            LinkError::Closed => Error::Disconnected { operation },
            LinkError::Rtde(e) => Error::protocol(operation, "RTDE", &e),
        }
    }

    /// Sends a control request and waits for its answer (data packages and texts on the way
    /// are taken as usual).
    fn request(
        &mut self,
        operation: Operation,
        m: Message<'_>,
        wanted: PackageType,
    ) -> Result<Package, Error> {
        let deadline = Instant::now() + self.config.timeout;
        let r = self.link(operation)?.send(&m, deadline);
        r.map_err(|e| self.link_error(operation, e))?;
        loop {
            let next = self.link(operation)?.next(deadline);
            let p = match next {
                Ok(Some(p)) => p,
                Ok(None) => {
                    return Err(Error::Timeout {
                        operation,
                        waited: self.config.timeout,
                    });
                }
                Err(e) => return Err(self.link_error(operation, e)),
            };
            if p.header.kind == wanted.code() {
                return Ok(p);
            }
            self.take(operation, &p)?;
        }
    }

    /// Decodes an answer package.
    fn answer(&self, operation: Operation, p: &Package) -> Result<Message<'_>, Error> {
        let link = self.link.as_ref().ok_or(Error::State {
            operation,
            state: State::Closed,
        })?;
        Message::decode_answer(p.header, link.payload(p), link.version)
            .map_err(|e| Error::protocol(operation, "RTDE answer", &e))
    }

    /// Takes a package that is not an awaited answer: a data package (the state), a text
    /// message (counted, kept), anything else counted corrupt. Returns whether it was state.
    fn take(&mut self, operation: Operation, p: &Package) -> Result<bool, Error> {
        let Some(link) = self.link.as_ref() else {
            return Ok(false);
        };
        let payload = link.payload(p);
        match Message::decode_answer(p.header, payload, link.version) {
            Ok(Message::Data { recipe, payload }) => {
                if recipe.is_some_and(|r| r != 1) || self.outputs.check(payload).is_err() {
                    self.counters.corrupt += 1;
                    return Ok(false);
                }
                let before = self.state.timestamp;
                let had = self.have_state;
                read_state(&self.outputs, payload, &mut self.state);
                self.have_state = true;
                self.counters.packages += 1;
                if had {
                    let gap = (self.state.timestamp - before) / self.period.as_secs_f64();
                    if gap > 1.5 {
                        self.counters.skipped += (gap.round() as u64).saturating_sub(1);
                    }
                }
                Ok(true)
            }
            Ok(Message::Text { level, message, .. }) => {
                self.counters.text_messages += 1;
                if level <= crate::proto::rtde::message::level::WARNING {
                    self.last_text = Some(Description::from_display(&message));
                }
                Ok(false)
            }
            Ok(_) => {
                self.counters.corrupt += 1;
                Ok(false)
            }
            Err(_) => {
                let _ = operation;
                self.counters.corrupt += 1;
                Ok(false)
            }
        }
    }

    /// Sends the joints-and-command package (and the digital outputs when they changed).
    fn send_inputs(&mut self, operation: Operation, deadline: Instant) -> Result<(), Error> {
        let mut payload = [0u8; 4 + 8 * DOF];
        {
            let mut w = Writer::new(&mut payload);
            let _ = w.i32(self.command.mode);
            for q in self.command.q {
                let _ = w.f64(q);
            }
        }
        let m = Message::Data {
            recipe: Some(self.joints_recipe),
            payload: &payload,
        };
        let r = self.link(operation)?.send(&m, deadline);
        r.map_err(|e| self.link_error(operation, e))?;
        self.counters.inputs_sent += 1;
        if self.command.outputs_dirty {
            let (v, m) = (self.command.outputs, self.command.outputs_mask);
            let io = [
                (m & 0xFF) as u8,
                (v & 0xFF) as u8,
                (m >> 8) as u8,
                (v >> 8) as u8,
            ];
            let msg = Message::Data {
                recipe: Some(self.io_recipe),
                payload: &io,
            };
            let r = self.link(operation)?.send(&msg, deadline);
            r.map_err(|e| self.link_error(operation, e))?;
            self.counters.inputs_sent += 1;
            self.command.outputs_dirty = false;
            self.command.outputs_mask = 0;
        }
        Ok(())
    }

    /// Takes every package that came and, if none of them was state, waits for one until
    /// `deadline`. Returns whether new state came.
    fn receive(&mut self, operation: Operation, deadline: Instant) -> Result<bool, Error> {
        let mut states = 0u64;
        let mut wait_until = Instant::now();
        loop {
            let next = self.link(operation)?.next(wait_until);
            match next {
                Ok(Some(p)) => {
                    if self.take(operation, &p)? {
                        states += 1;
                        // Drain what else is there, without waiting.
                        wait_until = Instant::now();
                    }
                }
                Ok(None) if states == 0 && wait_until < deadline => wait_until = deadline,
                Ok(None) => break,
                Err(e) => return Err(self.link_error(operation, e)),
            }
        }
        if states > 1 {
            self.counters.late += states - 1;
        }
        Ok(states > 0)
    }

    /// A safety stop or a program that stopped, as an error.
    fn check_state(&self, operation: Operation) -> Result<(), Error> {
        let s = &self.state;
        if let Some(stop) = safety_stop_name(s.safety_mode) {
            return Err(Error::device(
                operation,
                SOURCE,
                &format_args!("{stop} (safety mode {})", s.safety_mode),
            ));
        }
        if self.following && (s.runtime_state != 2 || s.handshake != 1) {
            return Err(Error::device(
                operation,
                SOURCE,
                &format_args!(
                    "the program stopped (runtime state {}, robot mode {})",
                    s.runtime_state,
                    robot_mode_name(s.robot_mode)
                ),
            ));
        }
        Ok(())
    }

    /// Waits until `done` holds for the state, taking packages and (when `feed`) feeding the
    /// inputs, until the configured timeout.
    fn wait_for(
        &mut self,
        operation: Operation,
        feed: bool,
        done: impl Fn(&UrState) -> bool,
    ) -> Result<bool, Error> {
        let deadline = Instant::now() + self.config.timeout;
        while Instant::now() < deadline {
            if feed {
                self.send_inputs(operation, deadline)?;
            }
            let step = (Instant::now() + Duration::from_millis(20)).min(deadline);
            if self.receive(operation, step)? && done(&self.state) {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Reads the arm's state once (the outputs started until the first package, then paused),
    /// so its joints are known from `open` on: a caller plans its motion from them before
    /// `start`.
    fn first_state(&mut self, operation: Operation) -> Result<(), Error> {
        let p = self.request(operation, Message::Start, PackageType::Start)?;
        if self.answer(operation, &p)? != Message::StartAccepted(true) {
            return Err(Error::device(operation, SOURCE, &"RTDE start refused"));
        }
        if !self.wait_for(operation, false, |_| true)? {
            return Err(Error::Timeout {
                operation,
                waited: self.config.timeout,
            });
        }
        let p = self.request(operation, Message::Pause, PackageType::Pause)?;
        if self.answer(operation, &p)? != Message::PauseAccepted(true) {
            return Err(Error::device(operation, SOURCE, &"RTDE pause refused"));
        }
        // The stream restarts at `start`: no gap to count across the pause.
        self.have_state = false;
        Ok(())
    }

    fn send_program(&mut self, operation: Operation) -> Result<(), Error> {
        let script = self.program().script();
        let addr = SocketAddr::new(self.config.host, self.config.script_port);
        let deadline = Instant::now() + self.config.timeout;
        let mut tcp = crate::transport::TcpLink::connect(addr, self.config.timeout)
            .map_err(|e| Error::io(operation, &e))?;
        tcp.send_all(script.as_bytes(), deadline)
            .map_err(|e| Error::io(operation, &e))
    }

    fn dashboard_error(operation: Operation, e: &dashboard::DashboardError) -> Error {
        Error::device(operation, "UR dashboard", e)
    }
}

/// Decodes our output recipe's package into `s`.
fn read_state(r: &Recipe<24>, p: &[u8], s: &mut UrState) {
    use field::*;
    s.timestamp = r.f64(p, TIMESTAMP).unwrap_or(s.timestamp);
    s.q = r.vector6d(p, ACTUAL_Q).unwrap_or(s.q);
    s.qd = r.vector6d(p, ACTUAL_QD).unwrap_or(s.qd);
    s.target_q = r.vector6d(p, TARGET_Q).unwrap_or(s.target_q);
    s.current = r.vector6d(p, CURRENT).unwrap_or(s.current);
    s.tcp_pose = r.vector6d(p, TCP_POSE).unwrap_or(s.tcp_pose);
    s.tcp_force = r.vector6d(p, TCP_FORCE).unwrap_or(s.tcp_force);
    s.robot_mode = r.i32(p, ROBOT_MODE).unwrap_or(s.robot_mode);
    s.joint_mode = r.vector6i32(p, JOINT_MODE).unwrap_or(s.joint_mode);
    s.safety_mode = r.i32(p, SAFETY_MODE).unwrap_or(s.safety_mode);
    s.safety_status_bits = r.u32(p, SAFETY_BITS).unwrap_or(s.safety_status_bits);
    s.runtime_state = r.u32(p, RUNTIME_STATE).unwrap_or(s.runtime_state);
    s.robot_status_bits = r.u32(p, ROBOT_BITS).unwrap_or(s.robot_status_bits);
    s.speed_scaling = r.f64(p, SPEED_SCALING).unwrap_or(s.speed_scaling);
    s.digital_inputs = r.u64(p, DIGITAL_IN).unwrap_or(s.digital_inputs);
    s.digital_outputs = r.u64(p, DIGITAL_OUT).unwrap_or(s.digital_outputs);
    s.handshake = r.i32(p, HANDSHAKE).unwrap_or(s.handshake);
}

impl Driver for UniversalRobot {
    const STOP_DESCRIPTION: &'static str = "program ended (stopj), RTDE paused";
    /// The controller sends a package every 2 ms on its own clock.
    const RUNS_OWN_CYCLE: bool = true;

    fn open_sequence(&mut self) -> Result<(), Error> {
        let op = Operation::Open;
        let link = RtdeLink::connect(self.rtde_addr(), self.config.timeout)
            .map_err(|e| Error::io(op, &e))?;
        self.link = Some(link);
        self.have_state = false;
        let r = self.open_rtde().and_then(|()| self.first_state(op));
        if r.is_err() {
            self.link = None;
            return r;
        }
        self.dashboard = self.config.dashboard_port.and_then(|port| {
            Dashboard::connect(SocketAddr::new(self.config.host, port), self.config.timeout).ok()
        });
        Ok(())
    }

    fn start_sequence(&mut self) -> Result<(), Error> {
        let op = Operation::Start;
        self.following = false;
        if self.config.power_on {
            let d = self.dashboard.as_mut().ok_or_else(|| {
                Error::device(
                    op,
                    "UR dashboard",
                    &"power_on needs the dashboard, which did not answer at open",
                )
            })?;
            d.power_on().map_err(|e| Self::dashboard_error(op, &e))?;
            d.brake_release()
                .map_err(|e| Self::dashboard_error(op, &e))?;
        }
        let p = self.request(op, Message::Start, PackageType::Start)?;
        if self.answer(op, &p)? != Message::StartAccepted(true) {
            return Err(Error::device(op, SOURCE, &"RTDE start refused"));
        }
        let want_running = self.config.power_on;
        let ready = self.wait_for(op, false, |s| {
            !want_running || s.robot_mode == robot_mode::RUNNING
        })?;
        if !ready {
            return Err(Error::Timeout {
                operation: op,
                waited: self.config.timeout,
            });
        }
        if self.state.robot_mode != robot_mode::RUNNING {
            return Err(Error::device(
                op,
                SOURCE,
                &format_args!(
                    "robot mode {}: power on and release the brakes (dashboard `power on`, `brake release`, or UrConfig::power_on)",
                    robot_mode_name(self.state.robot_mode)
                ),
            ));
        }
        self.check_state(op)?;
        // Hold where the arm stands, then hand it to the program.
        self.command.q = self.state.q;
        self.command.mode = MODE_POSITION;
        let deadline = Instant::now() + self.config.timeout;
        self.send_inputs(op, deadline)?;
        self.send_program(op)?;
        let playing = self.wait_for(op, true, |s| s.runtime_state == 2 && s.handshake == 1)?;
        if !playing {
            return Err(Error::device(
                op,
                SOURCE,
                &format_args!(
                    "the program did not start within {} ms (runtime state {})",
                    self.config.timeout.as_millis(),
                    self.state.runtime_state
                ),
            ));
        }
        self.following = true;
        Ok(())
    }

    fn stop_sequence(&mut self) -> Result<(), Error> {
        let op = Operation::Stop;
        self.following = false;
        self.command.mode = 0;
        let mut first = crate::device::FirstError::default();
        let ended = match self.wait_for(op, true, |s| s.runtime_state != 2 || s.handshake == 0) {
            Ok(e) => e,
            Err(e) => {
                first.keep(Err(e));
                false
            }
        };
        if !ended && let Some(d) = self.dashboard.as_mut() {
            first.keep(d.stop().map_err(|e| Self::dashboard_error(op, &e)));
        }
        if self.link.is_some() {
            first.keep(
                self.request(op, Message::Pause, PackageType::Pause)
                    .map(drop),
            );
        }
        first.into_result()
    }

    fn close_sequence(&mut self) -> Result<(), Error> {
        self.link = None;
        self.dashboard = None;
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
        self.send_inputs(op, deadline)?;
        if !self.receive(op, deadline)? {
            self.counters.lost += 1;
            return Err(Error::Timeout {
                operation: op,
                waited: wait,
            });
        }
        self.check_state(op)
    }
}

impl UniversalRobot {
    /// RTDE's setup at `open`.
    fn open_rtde(&mut self) -> Result<(), Error> {
        let op = Operation::Open;
        // Protocol version 2, else 1.
        self.link(op)?.version = 1;
        let p = self.request(
            op,
            Message::RequestProtocolVersion(PROTOCOL_VERSION),
            PackageType::RequestProtocolVersion,
        )?;
        if self.answer(op, &p)? == Message::ProtocolVersionAccepted(true) {
            self.link(op)?.version = PROTOCOL_VERSION;
        } else {
            let p = self.request(
                op,
                Message::RequestProtocolVersion(1),
                PackageType::RequestProtocolVersion,
            )?;
            if self.answer(op, &p)? != Message::ProtocolVersionAccepted(true) {
                return Err(Error::device(
                    op,
                    SOURCE,
                    &"RTDE protocol versions 2 and 1 refused",
                ));
            }
        }
        let p = self.request(
            op,
            Message::GetUrcontrolVersion,
            PackageType::GetUrcontrolVersion,
        )?;
        if let Message::UrcontrolVersion {
            major,
            minor,
            bugfix,
            build,
        } = self.answer(op, &p)?
        {
            self.version = Some([major, minor, bugfix, build]);
            // CB3 (major 3) sends at 125 Hz, e-Series at 500 Hz.
            self.period = if major >= 5 {
                Duration::from_millis(2)
            } else {
                Duration::from_millis(8)
            };
        }
        let base = self.config.register_base;
        let mut names = OUTPUTS.join(",");
        names.push_str(&format!(",output_int_register_{base}"));
        let frequency = 1.0 / self.period.as_secs_f64();
        let p = self.request(
            op,
            Message::SetupOutputs {
                frequency: Some(frequency),
                names: &names,
            },
            PackageType::SetupOutputs,
        )?;
        let types = match self.answer(op, &p)? {
            Message::OutputsRecipe { id, types } => {
                if id == Some(0) && !types.contains("NOT_FOUND") {
                    return Err(Error::device(op, SOURCE, &"output recipe refused"));
                }
                Recipe::<24>::from_types(types)
            }
            _ => return Err(Error::protocol(op, "RTDE", &"not an output recipe")),
        };
        self.outputs = types.map_err(|e| Error::device(op, "RTDE output recipe", &e))?;
        let joints: Vec<String> = std::iter::once(format!("input_int_register_{base}"))
            .chain((0..DOF).map(|k| format!("input_double_register_{}", usize::from(base) + k)))
            .collect();
        self.joints_recipe = self.input_recipe(&joints.join(","))?;
        self.io_recipe = self.input_recipe(
            "standard_digital_output_mask,standard_digital_output,configurable_digital_output_mask,configurable_digital_output",
        )?;
        Ok(())
    }

    fn input_recipe(&mut self, names: &str) -> Result<u8, Error> {
        let op = Operation::Open;
        let p = self.request(op, Message::SetupInputs { names }, PackageType::SetupInputs)?;
        match self.answer(op, &p)? {
            Message::InputsRecipe { id, types } => {
                if let Err(e) = Recipe::<8>::from_types(types) {
                    return Err(Error::device(op, "RTDE input recipe", &e));
                }
                if id == 0 {
                    return Err(Error::device(op, "RTDE input recipe", &"refused (id 0)"));
                }
                Ok(id)
            }
            _ => Err(Error::protocol(op, "RTDE", &"not an input recipe")),
        }
    }

    fn read(&self, values: [f64; DOF], out: &mut [f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("UR joints", DOF, out.len())?;
        out.copy_from_slice(&values);
        Ok(())
    }
}

impl_cyclic_device!(UniversalRobot, lifecycle);

impl JointDevice for UniversalRobot {
    fn dof(&self) -> usize {
        DOF
    }
}

impl JointPositionSensor for UniversalRobot {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        self.read(self.state.q, q)
    }
}

impl JointVelocitySensor for UniversalRobot {
    fn joint_velocity(&self, qd: &mut [f64]) -> Result<(), Error> {
        self.read(self.state.qd, qd)
    }
}

impl JointPositionActuator for UniversalRobot {
    /// Joint positions for `servoj` from the next step on (the program follows positions).
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Error> {
        self.set_command(MODE_POSITION, "UR joints (finite)", q)
    }
}

impl JointVelocityActuator for UniversalRobot {
    /// Joint speeds in rad/s for `speedj` from the next step on (the program follows speeds,
    /// ramping to each at [`UrConfig::speed_acceleration`]); a later
    /// [`set_joint_position`](JointPositionActuator::set_joint_position) goes back to
    /// positions, which should then be where the arm is.
    fn set_joint_velocity(&mut self, qd: &[f64]) -> Result<(), Error> {
        self.set_command(MODE_VELOCITY, "UR joint speeds (finite)", qd)
    }
}

impl UniversalRobot {
    /// The command for the next steps: `values` in `mode` while the program runs.
    fn set_command(&mut self, mode: i32, what: &'static str, values: &[f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        Error::check_len(what, DOF, values.len())?;
        if values.iter().any(|x| !x.is_finite()) {
            return Err(Error::InvalidArgument {
                what,
                expected: DOF,
                got: values.iter().filter(|x| x.is_finite()).count(),
            });
        }
        self.command.q.copy_from_slice(values);
        if self.following {
            self.command.mode = mode;
        }
        Ok(())
    }
}

impl CartesianPositionSensor for UniversalRobot {
    fn cartesian_position(&self) -> Result<Pose, Error> {
        self.lifecycle.check(Operation::Get)?;
        Ok(super::convert::tool_pose(&self.state.tcp_pose))
    }
}

impl DigitalInputReader for UniversalRobot {
    fn digital_input_count(&self) -> usize {
        super::convert::DIGITAL_INPUTS
    }

    fn digital_input(&self, index: usize) -> Result<bool, Error> {
        self.lifecycle.check(Operation::Get)?;
        super::convert::digital_input(self.state.digital_inputs, index)
    }
}

impl DigitalOutputWriter for UniversalRobot {
    /// Standard outputs 0–7 and configurable outputs 8–15.
    fn digital_output_count(&self) -> usize {
        16
    }

    fn set_digital_output(&mut self, index: usize, value: bool) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        if index >= 16 {
            return Err(Error::InvalidArgument {
                what: "UR digital output",
                expected: 15,
                got: index,
            });
        }
        let bit = 1u16 << index;
        self.command.outputs = (self.command.outputs & !bit) | if value { bit } else { 0 };
        self.command.outputs_mask |= bit;
        self.command.outputs_dirty = true;
        Ok(())
    }
}

impl LinkStatisticsSensor for UniversalRobot {
    fn link_statistics(&self) -> LinkStatistics {
        let c = self.counters;
        LinkStatistics {
            sent: c.inputs_sent,
            received: c.packages,
            lost: c.lost + c.skipped,
            late: c.late,
            rejected: 0,
            corrupt: c.corrupt,
            consecutive_failures: self.lifecycle.consecutive_failures(),
            delivery: Delivery::default(),
        }
    }
}
