//! A fake Mitsubishi H7 controller: a UDP server for real-time packets that runs on the
//! controller's own 7.11 ms cycle, and an R3 TCP responder that accepts the program upload,
//! switches the servo and reports `DSTATE` and `JPOSF`. Faults can be injected to test a
//! client's error handling.
//!
//! It behaves like the hardware where the hardware's behaviour is known
//! (`rl-drivers/NOTES.md` lists what is and what is not):
//! - **One answer per controller cycle.** Real-time packets are queued as they arrive; at each
//!   cycle tick the oldest one is handled and answered. A client that sends faster than the
//!   cycle sees its replies fall behind, as it would on a real controller. The cycle starts
//!   [`Pacing::ControllerCycle`]`::offset` after the first packet of a session reached the
//!   socket (the kernel's receive timestamp, so a fake thread that woke late does not shift
//!   the phase) and again after the client has been silent for a cycle (a real controller's
//!   cycle runs on regardless, at a phase of its own; set the offset near the period to put a
//!   client on the cycle's edge).
//!   The fake measures how late each tick's reply went out against the tick's scheduled time
//!   ([`FakeH7Status::max_tick_lateness`], [`FakeH7Status::late_ticks`]): sharing the CPUs
//!   with other real-time work can hold it up, which a real controller never is.
//! - **Only while the program runs.** Real-time packets are answered only while the uploaded
//!   MXT program runs (`RUN`), only from the address of its `OPEN "ENET:…"` line, and commands
//!   of another kind than its `MXT` mode are ignored; its filter time constant (ms) sets the
//!   arm's lag. Everything refused is counted.
//! - **The simulated arm.** A joint command is clamped to the joint limits (a limit hit) and
//!   then to what the speed limit allows in the cycles since the last command (a speed clamp):
//!   the result is the controller's command value, reported as type 2 (joint command). The
//!   joints follow it through a first-order filter with the program's time constant plus the
//!   arm's own servo lag (two cycles by default); types 5 and 8 report them. With [`ForwardKinematics`] (a robot model) the pose types are the
//!   forward kinematics of the commanded and the simulated joints; without, the pose replies
//!   hold the last commanded pose through the same filter. Pulses are joints ×
//!   `pulses_per_rad`; currents a synthetic `1000 %/rad × (command − actual)`, clamped to
//!   ±100 %.
//! - **R3.** Several clients at once (one thread each). A command the fake does not implement
//!   is answered `QeR<n>` with `ERRORMES<n>` explaining it — never a bare `QoK`. Replies end
//!   with a carriage return unless [`FakeH7Config::r3_terminator`] is off. A read interrupted
//!   by a signal goes on; it does not drop the client.
//! - **Operation rights** (`CNTLON` … `CNTLOFF`) belong to the connection that took them and
//!   end with it: another client's `CNTLON` meanwhile is refused (`QeR4002`), and its `SRVON`
//!   or `RUN` without rights too (`QeR4000`, `QeR4001`). What the real controller does here is
//!   not in the references at hand (RL's client and `shared/reference/mitsubishi-h7.md` only
//!   show one client taking and giving back the rights; Mitsubishi's R protocol manual,
//!   BFP-A4288, was not available); the fake takes the stricter reading — rights that outlive
//!   their connection would let a second client switch the servo on unasked.
//!   [`FakeH7::reset_r3_connections`] drops every R3 connection, as a controller that resets
//!   them.

use std::collections::{HashMap, VecDeque};
use std::fmt;
use std::io::{self, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::os::fd::AsFd;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::DVec3;
use rl_core::model::{Data as ModelData, Model};
use rl_core::rotation::euler;

use super::tcp_server::{self, Polled};
use crate::capability::Pose;
use crate::proto::h7::{
    CYCLE_US, Command, Data, DataShape, IoType, MAX_AXES, Mode, MxtType, PACKET_LEN, Packet,
    PoseData,
};
use crate::proto::r3::{self, DState, JointReport, ProgramInfo, Request, run_bits};
use crate::transport::{Readiness, timestamp};

const POLL: Duration = Duration::from_millis(20);
/// The controller's cycle.
pub const CYCLE: Duration = Duration::from_micros(CYCLE_US);
/// Packets the fake queues between ticks before it drops them (a socket buffer).
pub const QUEUE_CAPACITY: usize = 64;
/// A tick whose reply went out later than this after its scheduled time is counted as late
/// ([`FakeH7Status::late_ticks`]): a tenth of the cycle.
pub const LATE_TICK: Duration = Duration::from_micros(CYCLE_US / 10);

/// The fake's own R3 error numbers (answered as `QeR<n>`; `ERRORMES<n>` explains them).
pub mod r3_errors {
    /// `SRVON` without operation rights (`CNTLON`).
    pub const NO_CONTROL: u32 = 4000;
    /// `RUN` refused: no operation rights, servo off, or another program name.
    pub const CANNOT_RUN: u32 = 4001;
    /// `CNTLON` while another connection holds the operation rights.
    pub const CONTROL_HELD: u32 = 4002;
    /// Injected with [`FakeH7::set_r3_rejection`](super::FakeH7::set_r3_rejection).
    pub const REJECTED: u32 = 4100;
    /// The uploaded program has no usable `OPEN "ENET:…"` or `MXT` line.
    pub const BAD_PROGRAM: u32 = 4200;
    /// The request is not `<robot>;<slot>;<command>`.
    pub const BAD_REQUEST: u32 = 9100;
    /// A command the fake does not implement.
    pub const NOT_IMPLEMENTED: u32 = 9101;
}

/// A fault applied to every `every`-th reply (counting handled packets from 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultPlan {
    /// Period in packets (1 = every reply).
    pub every: u32,
    /// What happens to that reply.
    pub fault: Fault,
}

/// What the fake does to a faulted reply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// Sends nothing.
    Drop,
    /// Sends it after this delay (the cycle goes on meanwhile).
    Delay(Duration),
    /// Writes an invalid data type code (0xFFFF) into `recvType`.
    Corrupt,
    /// Sends only the first 100 bytes.
    Truncate,
    /// Sends it from another UDP port.
    ForeignPort,
    /// Sends the previous reply again instead (same counter, same data): a frozen reply.
    Replay,
}

/// The servo lag of a simulated arm ([`FakeH7Config::for_model`]): two controller cycles.
pub const SERVO_TIME_CONSTANT_S: f64 = 2.0 * CYCLE.as_secs_f64();

/// When the fake answers real-time packets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pacing {
    /// On the controller's 7.11 ms cycle: one packet per tick; the first tick of a session
    /// comes `offset` after its first packet.
    ControllerCycle {
        /// Time from a session's first packet to the first tick.
        offset: Duration,
    },
    /// As fast as packets arrive, each packet one controller cycle of the simulated arm
    /// whenever it comes: for benchmarks of a client's own cost, and for tests of the arm's
    /// model that must not depend on the machine's load.
    Immediate,
}

impl Default for Pacing {
    fn default() -> Self {
        Pacing::ControllerCycle { offset: CYCLE / 2 }
    }
}

/// Forward kinematics for the fake's pose replies: joints in rad to the tool pose (m).
#[derive(Clone)]
pub struct ForwardKinematics(Arc<PoseFn>);

/// Joints to a pose.
type PoseFn = dyn Fn(&[f64]) -> Option<Pose> + Send + Sync;

impl ForwardKinematics {
    /// Any function of the joints.
    pub fn new(f: impl Fn(&[f64]) -> Option<Pose> + Send + Sync + 'static) -> Self {
        Self(Arc::new(f))
    }

    /// The world pose of a frame fixed to `body` of an rl-core model at `placement` (the
    /// tool, say: RL's last frame, a URDF's last link).
    pub fn from_model<const N: usize>(model: Model<N>, body: usize, placement: Pose) -> Self {
        let data = Mutex::new(Box::new(ModelData::<N>::new()));
        Self::new(move |q| {
            let mut data = data.lock().unwrap_or_else(|p| p.into_inner());
            let q = q.get(..model.nq())?;
            rl_core::algo::forward_position(&model, &mut data, q).ok()?;
            (body < model.body_count()).then(|| *data.world_pose(body) * placement)
        })
    }

    /// The pose for joints `q`.
    pub fn pose(&self, q: &[f64]) -> Option<Pose> {
        (self.0)(q)
    }
}

impl fmt::Debug for ForwardKinematics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ForwardKinematics(..)")
    }
}

impl PartialEq for ForwardKinematics {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Configuration of the fake controller; joint limits are plain data so they can come from a
/// loaded robot model.
#[derive(Clone, Debug)]
pub struct FakeH7Config {
    /// UDP address for real-time packets (port 0: any free port).
    pub udp_bind: SocketAddr,
    /// TCP address of the R3 responder; `None` runs without it (and then answers real-time
    /// packets from anyone, as if a joint-mode program ran).
    pub r3_bind: Option<SocketAddr>,
    /// Number of axes simulated (at most 8); `JPOSF` reports this many.
    pub dof: usize,
    /// Lower joint limits in rad.
    pub lower_rad: [f64; MAX_AXES],
    /// Upper joint limits in rad.
    pub upper_rad: [f64; MAX_AXES],
    /// Joints at power-up in rad.
    pub initial_rad: [f64; MAX_AXES],
    /// The filter time constant in ms until a program sets its own (without R3: always).
    pub filter_ms: u32,
    /// The arm's own position loop: the measured joints follow the command value with this
    /// first-order time constant (s), on top of the program's filter. A real arm lags its
    /// command; [`FakeH7Config::for_model`] sets two controller cycles
    /// ([`SERVO_TIME_CONSTANT_S`]), which makes the tracking error at constant speed
    /// `2 · v · 7.11 ms`. 0 ([`FakeH7Config::loopback`]): the joints are the filtered command.
    pub servo_time_constant_s: f64,
    /// Joint speed limits in rad/s (infinite: none); the command value is clamped to them.
    pub max_speed_rad_s: [f64; MAX_AXES],
    /// Motor pulses per rad, for pulse replies.
    pub pulses_per_rad: f64,
    /// DSTATE polls after `SRVON` before the servo reports on (exercises a client's polling).
    pub servo_on_polls: u32,
    /// Fault injection (can be changed while running with [`FakeH7::set_fault`]).
    pub fault: Option<FaultPlan>,
    /// When real-time packets are answered.
    pub pacing: Pacing,
    /// Pose replies from forward kinematics of the joints.
    pub kinematics: Option<ForwardKinematics>,
    /// End R3 replies with a carriage return (as a controller configured for an end code).
    pub r3_terminator: bool,
    /// Called first on the thread that runs the controller's cycle: a real controller answers
    /// on its own CPU, unhindered by the client's machine, so a test or a demo gives the
    /// fake's thread a real-time priority here (rl-drivers sets no scheduler policy itself;
    /// rl-rt does that). Without one the cycle thread's phase follows whenever the machine
    /// lets it read the session's first packet.
    pub on_thread_start: Option<fn()>,
}

impl FakeH7Config {
    /// A `dof`-axis arm on 127.0.0.1 with free ports for UDP and R3, limits ±π, no speed
    /// limit, paced at the controller's cycle.
    pub fn loopback(dof: usize) -> Self {
        let any: SocketAddr = SocketAddr::from(([127, 0, 0, 1], 0));
        Self {
            udp_bind: any,
            r3_bind: Some(any),
            dof,
            lower_rad: [-core::f64::consts::PI; MAX_AXES],
            upper_rad: [core::f64::consts::PI; MAX_AXES],
            initial_rad: [0.0; MAX_AXES],
            filter_ms: 0,
            servo_time_constant_s: 0.0,
            max_speed_rad_s: [f64::INFINITY; MAX_AXES],
            pulses_per_rad: 2f64.powi(20) / core::f64::consts::TAU,
            servo_on_polls: 2,
            fault: None,
            pacing: Pacing::default(),
            kinematics: None,
            r3_terminator: true,
            on_thread_start: None,
        }
    }

    /// A loopback arm with `model`'s joints: its position limits (continuous joints unlimited),
    /// its speed limits (none where the model gives none), a real arm's servo lag, standing at
    /// `start` clamped into the limits.
    pub fn for_model<const N: usize>(model: &Model<N>, start: &[f64]) -> io::Result<Self> {
        let dof = model.dof();
        if dof == 0 || dof > MAX_AXES {
            return Err(invalid(format!(
                "the model has {dof} joints; the fake H7 simulates 1 to {MAX_AXES} axes"
            )));
        }
        let mut c = Self::loopback(dof);
        c.servo_time_constant_s = SERVO_TIME_CONSTANT_S;
        for k in 0..dof {
            let l = model.limits(k);
            if !l.wraparound {
                c.lower_rad[k] = l.lower;
                c.upper_rad[k] = l.upper;
            } else {
                c.lower_rad[k] = f64::NEG_INFINITY;
                c.upper_rad[k] = f64::INFINITY;
            }
            if l.velocity.is_finite() && l.velocity > 0.0 {
                c.max_speed_rad_s[k] = l.velocity;
            }
            c.initial_rad[k] = start.get(k).map_or(0.0, |&q| l.clamp(q));
        }
        Ok(c)
    }

    /// Sets the joint speed limits (rad/s) from a slice of length `dof`.
    pub fn with_speed_limits(mut self, max_speed_rad_s: &[f64]) -> io::Result<Self> {
        if max_speed_rad_s.len() != self.dof {
            return Err(invalid(format!(
                "speed limits: expected {} values, got {}",
                self.dof,
                max_speed_rad_s.len()
            )));
        }
        if let Some((i, v)) = max_speed_rad_s
            .iter()
            .enumerate()
            .find(|(_, v)| v.is_nan() || **v <= 0.0)
        {
            return Err(invalid(format!(
                "joint {i}: speed limit {v} is not positive"
            )));
        }
        self.max_speed_rad_s[..self.dof].copy_from_slice(max_speed_rad_s);
        Ok(self)
    }

    /// Sets the joint limits from slices of length `dof`.
    pub fn with_limits(mut self, lower_rad: &[f64], upper_rad: &[f64]) -> io::Result<Self> {
        if lower_rad.len() != self.dof || upper_rad.len() != self.dof {
            return Err(invalid(format!(
                "joint limits: expected {} lower and upper values, got {} and {}",
                self.dof,
                lower_rad.len(),
                upper_rad.len()
            )));
        }
        for (i, (lo, hi)) in lower_rad.iter().zip(upper_rad).enumerate() {
            if lo > hi || lo.is_nan() || hi.is_nan() {
                return Err(invalid(format!(
                    "joint {i}: lower limit {lo} above upper {hi}"
                )));
            }
        }
        self.lower_rad[..self.dof].copy_from_slice(lower_rad);
        self.upper_rad[..self.dof].copy_from_slice(upper_rad);
        Ok(self)
    }
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// What the fake has seen and where its arm is (a snapshot).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FakeH7Status {
    /// Axes simulated.
    pub dof: usize,
    /// Real-time datagrams received (valid or not, handled or not).
    pub packets: u64,
    /// Packets that did not decode.
    pub bad_packets: u64,
    /// Packets received while no MXT program was running, not answered.
    pub packets_outside_program: u64,
    /// Packets from another address than the program's `ENET:` client, not answered.
    pub rejected: u64,
    /// Packets dropped because the queue between ticks was full.
    pub overflowed: u64,
    /// Packets received while the controller was frozen, dropped.
    pub dropped_frozen: u64,
    /// Controller cycles (ticks) that handled a packet.
    pub cycles: u64,
    /// Replies sent (including faulted ones that were still sent).
    pub replies: u64,
    /// Move commands received.
    pub moves: u64,
    /// Move commands of another kind than the program's mode, ignored.
    pub wrong_mode: u64,
    /// End packets (command 255) received.
    pub ends: u64,
    /// Faults injected.
    pub faults_injected: u64,
    /// Joint commands clamped to a position limit.
    pub limit_hits: u64,
    /// Joint commands clamped to a speed limit.
    pub speed_clamps: u64,
    /// `cCount` of the last packet handled.
    pub last_c_count: u32,
    /// The last commanded joints in rad (before clamping).
    pub commanded_rad: [f64; MAX_AXES],
    /// The controller's command value in rad (after clamping).
    pub command_rad: [f64; MAX_AXES],
    /// The simulated joints in rad.
    pub actual_rad: [f64; MAX_AXES],
    /// Output words written, by `bitTop`.
    pub outputs: HashMap<u16, u16>,
    /// Servo state as reported by DSTATE.
    pub servo_on: bool,
    /// Whether the uploaded program is running.
    pub program_running: bool,
    /// The uploaded program text (lines separated by `\v`).
    pub program: String,
    /// What the saved program says: client address, mode, filter (ms).
    pub program_info: Option<ProgramInfo>,
    /// Name given with `LOAD=`.
    pub program_name: String,
    /// Every R3 request body in order (`STOP`, `NEW`, `LOAD=1432`, ...).
    pub r3_log: Vec<String>,
    /// R3 clients accepted.
    pub r3_clients: u64,
    /// R3 requests answered `QeR` because the fake does not implement them.
    pub r3_not_implemented: u64,
    /// The last address real-time packets came from.
    pub client: Option<SocketAddr>,
    /// Cycle ticks ([`Pacing::ControllerCycle`]) that handled a packet and sent its reply more
    /// than [`LATE_TICK`] after their scheduled time: the fake's thread woke late or was held
    /// up. A real controller has its own CPU; a fake that shares one with other (real-time)
    /// work may be held up, and the report of a run can tell that apart from a fault of the
    /// link or of the client.
    pub late_ticks: u64,
    /// The longest a tick's work (the reply sent) ended after the tick's scheduled time.
    pub max_tick_lateness: Duration,
}

#[derive(Debug)]
struct Shared {
    config: FakeH7Config,
    status: FakeH7Status,
    target_rad: [f64; MAX_AXES],
    pose: PoseData,
    target_pose: PoseData,
    inputs: HashMap<u16, u16>,
    frozen: bool,
    frozen_until: Option<Instant>,
    reject: Option<String>,
    /// The R3 connection holding the operation rights, if one.
    control: Option<u64>,
    /// R3 connections accepted so far (each one's id).
    r3_ids: u64,
    /// Raised to drop every R3 connection open now ([`FakeH7::reset_r3_connections`]).
    r3_reset: u64,
    servo_polls_left: Option<u32>,
    drop_fraction: f64,
    drop_seen: u64,
    /// Replies still to drop in a row ([`FakeH7::drop_next`]).
    drop_burst: u32,
    r3_split: Option<(usize, Duration)>,
    last_reply: Option<Packet>,
    handled: u64,
}

impl Shared {
    fn is_frozen(&mut self) -> bool {
        if let Some(until) = self.frozen_until {
            if Instant::now() >= until {
                self.frozen_until = None;
                self.frozen = false;
            }
        }
        self.frozen
    }

    fn mode(&self) -> Mode {
        self.status.program_info.map_or(Mode::Joint, |p| p.mode)
    }

    fn filter_ms(&self) -> u32 {
        self.status
            .program_info
            .map_or(self.config.filter_ms, |p| p.filter_ms)
    }
}

/// A running fake H7 controller; stops its threads when dropped.
#[derive(Debug)]
pub struct FakeH7 {
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    udp_addr: SocketAddr,
    r3_addr: Option<SocketAddr>,
    foreign: UdpSocket,
    threads: Vec<JoinHandle<()>>,
}

fn lock(shared: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    shared
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl FakeH7 {
    /// Binds the sockets and starts the server threads.
    pub fn spawn(config: FakeH7Config) -> io::Result<FakeH7> {
        if config.dof == 0 || config.dof > MAX_AXES {
            return Err(invalid(format!(
                "dof {} outside 1..={MAX_AXES}",
                config.dof
            )));
        }
        let udp = UdpSocket::bind(config.udp_bind)?;
        let udp_addr = udp.local_addr()?;
        // A second socket on the same address, for replies "from another port" and floods.
        let foreign = UdpSocket::bind(SocketAddr::new(udp_addr.ip(), 0))?;
        let listener = config.r3_bind.map(TcpListener::bind).transpose()?;
        let r3_addr = listener.as_ref().map(TcpListener::local_addr).transpose()?;
        let mut status = FakeH7Status {
            dof: config.dof,
            ..FakeH7Status::default()
        };
        status.actual_rad = config.initial_rad;
        let config_hook = config.on_thread_start;
        status.commanded_rad = config.initial_rad;
        status.command_rad = config.initial_rad;
        let shared = Arc::new(Mutex::new(Shared {
            target_rad: config.initial_rad,
            config,
            status,
            pose: PoseData::default(),
            target_pose: PoseData::default(),
            inputs: HashMap::new(),
            frozen: false,
            frozen_until: None,
            reject: None,
            control: None,
            r3_ids: 0,
            r3_reset: 0,
            servo_polls_left: None,
            drop_fraction: 0.0,
            drop_seen: 0,
            drop_burst: 0,
            r3_split: None,
            last_reply: None,
            handled: 0,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let mut threads = Vec::new();
        let (s, st) = (shared.clone(), stop.clone());
        let other = foreign.try_clone()?;
        let hook = config_hook;
        threads.push(
            std::thread::Builder::new()
                .name("fake-h7-udp".into())
                .spawn(move || {
                    if let Some(f) = hook {
                        f();
                    }
                    Cycle::new(udp, other, s, st).run()
                })?,
        );
        if let Some(listener) = listener {
            listener.set_nonblocking(true)?;
            let (s, st) = (shared.clone(), stop.clone());
            threads.push(
                std::thread::Builder::new()
                    .name("fake-h7-r3".into())
                    .spawn(move || serve_r3(&listener, &s, &st))?,
            );
        }
        Ok(FakeH7 {
            shared,
            stop,
            udp_addr,
            r3_addr,
            foreign,
            threads,
        })
    }

    /// Where real-time packets go.
    pub fn udp_addr(&self) -> SocketAddr {
        self.udp_addr
    }

    /// Where the R3 responder listens; the UDP address's IP with port 0 when it is disabled,
    /// so callers can still build a client configuration.
    pub fn r3_addr(&self) -> SocketAddr {
        self.r3_addr
            .unwrap_or(SocketAddr::new(self.udp_addr.ip(), 0))
    }

    /// A snapshot of what the fake has seen.
    pub fn status(&self) -> FakeH7Status {
        lock(&self.shared).status.clone()
    }

    /// Changes fault injection.
    pub fn set_fault(&self, fault: Option<FaultPlan>) {
        lock(&self.shared).config.fault = fault;
    }

    /// Drops this fraction (0 to 1) of the replies, spread evenly (deterministic).
    pub fn set_drop_fraction(&self, fraction: f64) {
        let mut s = lock(&self.shared);
        s.drop_fraction = fraction.clamp(0.0, 1.0);
        s.drop_seen = 0;
    }

    /// Drops the next `count` replies in a row (a short loss on the link; the controller goes
    /// on handling the packets).
    pub fn drop_next(&self, count: u32) {
        lock(&self.shared).drop_burst = count;
    }

    /// Drops every R3 connection open now (a controller that resets them); their operation
    /// rights end with them. Clients may connect again.
    pub fn reset_r3_connections(&self) {
        lock(&self.shared).r3_reset += 1;
    }

    /// Freezes the controller: while frozen it reads real-time packets but neither handles
    /// nor answers them, and holds R3 requests unanswered until it thaws (a hung controller;
    /// sockets stay open).
    pub fn set_frozen(&self, frozen: bool) {
        let mut s = lock(&self.shared);
        s.frozen = frozen;
        s.frozen_until = None;
    }

    /// Freezes the controller for `duration`, then lets it go on by itself.
    pub fn freeze_for(&self, duration: Duration) {
        let mut s = lock(&self.shared);
        s.frozen = true;
        s.frozen_until = Some(Instant::now() + duration);
    }

    /// Makes the R3 responder answer `QeR4100` to every request with this command name (such as
    /// `SRVON`), as a controller in an error state would; `None` accepts everything again.
    pub fn set_r3_rejection(&self, command: Option<&str>) {
        lock(&self.shared).reject = command.map(str::to_owned);
    }

    /// Writes each R3 reply in pieces of `bytes` with `pause` between them (`None`: at once).
    pub fn set_r3_split(&self, split: Option<(usize, Duration)>) {
        lock(&self.shared).r3_split = split;
    }

    /// Sets the input word at `bit_top` that the fake reports when asked for inputs.
    pub fn set_input(&self, bit_top: u16, value: u16) {
        lock(&self.shared).inputs.insert(bit_top, value);
    }

    /// Sends `count` well-formed packets from another port of the fake's address to the last
    /// client (a flood of foreign datagrams); returns how many were sent.
    pub fn flood_foreign(&self, count: usize) -> io::Result<usize> {
        let Some(client) = lock(&self.shared).status.client else {
            return Ok(0);
        };
        let bytes = Packet::default().to_bytes();
        let mut sent = 0;
        for _ in 0..count {
            match self.foreign.send_to(&bytes, client) {
                Ok(_) => sent += 1,
                // The client's socket buffer is full: the rest would be dropped anyway.
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(e) => return Err(e),
            }
        }
        Ok(sent)
    }

    /// Stops the server threads and waits for them (also done on drop).
    pub fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

impl Drop for FakeH7 {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// The real-time side: the controller's cycle.
struct Cycle {
    udp: UdpSocket,
    foreign: UdpSocket,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    queue: VecDeque<(Packet, SocketAddr)>,
    next_tick: Option<Instant>,
    /// The scheduled time of the last tick (or, unpaced, the time) a packet was handled at.
    last_handled: Option<Instant>,
    delayed: Vec<(Instant, [u8; PACKET_LEN], SocketAddr)>,
}

impl Cycle {
    fn new(
        udp: UdpSocket,
        foreign: UdpSocket,
        shared: Arc<Mutex<Shared>>,
        stop: Arc<AtomicBool>,
    ) -> Self {
        Self {
            udp,
            foreign,
            shared,
            stop,
            queue: VecDeque::with_capacity(QUEUE_CAPACITY),
            next_tick: None,
            last_handled: None,
            delayed: Vec::new(),
        }
    }

    fn run(mut self) {
        let mut buf = [0u8; 1024];
        // Waits go through `ppoll` (nanosecond timeouts); a socket receive timeout would round
        // up to the kernel's tick and make the cycle irregular.
        if self.udp.set_nonblocking(true).is_err() {
            return;
        }
        // The kernel's receive time of each packet: a session's cycle starts from its first
        // packet's arrival, not from whenever this thread got to read it.
        let _ = timestamp::enable(self.udp.as_fd());
        while !self.stop.load(Ordering::Relaxed) {
            let now = Instant::now();
            self.send_due(now);
            let pacing = lock(&self.shared).config.pacing;
            let mut wake = now + POLL;
            if let Some(t) = self.next_tick {
                wake = wake.min(t);
            }
            if let Some(t) = self.delayed.iter().map(|d| d.0).min() {
                wake = wake.min(t);
            }
            if wake > now
                && crate::transport::wait(self.udp.as_fd(), Readiness::Readable, wake)
                    .unwrap_or(false)
            {
                while let Ok((n, from, at)) = timestamp::recv(self.udp.as_fd(), &mut buf) {
                    let Some(from) = from else { continue };
                    // The arrival on the monotonic clock (the read's time without a stamp).
                    let now = Instant::now();
                    let arrived = at.map_or(now, |at| {
                        now.checked_sub(timestamp::since_epoch().saturating_sub(at))
                            .unwrap_or(now)
                    });
                    self.receive(&buf[..n], from, arrived, pacing);
                }
            }
            if let Some(tick) = self.next_tick
                && Instant::now() >= tick
            {
                self.tick(tick);
            }
        }
    }

    fn receive(&mut self, bytes: &[u8], from: SocketAddr, arrived: Instant, pacing: Pacing) {
        let mut s = lock(&self.shared);
        s.status.packets += 1;
        s.status.client = Some(from);
        if s.is_frozen() {
            s.status.dropped_frozen += 1;
            self.queue.clear();
            self.next_tick = None;
            return;
        }
        let packet = match Packet::decode(bytes) {
            Ok(p) => p,
            Err(_) => {
                s.status.bad_packets += 1;
                return;
            }
        };
        match pacing {
            Pacing::Immediate => {
                drop(s);
                // One cycle per packet: controller time is the packet count.
                let at = self.last_handled.map_or_else(Instant::now, |t| t + CYCLE);
                self.handle(packet, from, at);
            }
            Pacing::ControllerCycle { offset } => {
                if self.queue.len() == QUEUE_CAPACITY {
                    s.status.overflowed += 1;
                    return;
                }
                self.queue.push_back((packet, from));
                if self.next_tick.is_none() {
                    self.next_tick = Some(arrived + offset);
                }
            }
        }
    }

    /// One controller cycle: handle the oldest packet; after an idle cycle, wait for the next
    /// packet to start the cycle again.
    fn tick(&mut self, tick: Instant) {
        let frozen = lock(&self.shared).is_frozen();
        if frozen {
            self.queue.clear();
            self.next_tick = None;
            return;
        }
        match self.queue.pop_front() {
            Some((packet, from)) => {
                self.handle(packet, from, tick);
                // How late this tick's work ended against its scheduled time: the thread woke
                // late, or was held up while it handled the packet. A fake that shares its CPUs
                // with other (real-time) work may be; a real controller is not.
                let now = Instant::now();
                let lateness = now.saturating_duration_since(tick);
                {
                    let mut s = lock(&self.shared);
                    if lateness > LATE_TICK {
                        s.status.late_ticks += 1;
                    }
                    s.status.max_tick_lateness = s.status.max_tick_lateness.max(lateness);
                }
                let mut next = tick + CYCLE;
                // A tick that came late does not make the next ones come in a burst.
                while next <= now {
                    next += CYCLE;
                }
                self.next_tick = Some(next);
            }
            None => self.next_tick = None,
        }
    }

    /// Handles a packet at controller time `at` (the tick's scheduled time).
    fn handle(&mut self, packet: Packet, from: SocketAddr, at: Instant) {
        // Controller cycles since the last packet handled: 1 on a continuous cycle.
        let cycles = self.last_handled.map_or(1, |t| {
            let k = at.saturating_duration_since(t).as_secs_f64() / CYCLE.as_secs_f64();
            k.round().clamp(1.0, 10_000.0) as u32
        });
        self.last_handled = Some(at);
        let (reply, fault) = {
            let mut s = lock(&self.shared);
            s.status.cycles += 1;
            let Some(reply) = s.handle(&packet, from, cycles) else {
                return;
            };
            s.handled += 1;
            let count = s.handled;
            let mut fault = s
                .config
                .fault
                .filter(|f| f.every > 0 && count % u64::from(f.every) == 0)
                .map(|f| f.fault);
            if fault.is_none() && s.drop_burst > 0 {
                s.drop_burst -= 1;
                fault = Some(Fault::Drop);
            }
            // Evenly spread drops: drop when the running share falls behind the fraction.
            if fault.is_none() && s.drop_fraction > 0.0 {
                let due = (count as f64 * s.drop_fraction).floor() as u64;
                if due > s.drop_seen {
                    s.drop_seen = due;
                    fault = Some(Fault::Drop);
                }
            }
            if fault.is_some() {
                s.status.faults_injected += 1;
            }
            let previous = s.last_reply.replace(reply);
            let reply = match (fault, previous) {
                (Some(Fault::Replay), Some(p)) => {
                    s.last_reply = Some(p);
                    p
                }
                _ => reply,
            };
            (reply, fault)
        };
        let mut bytes = reply.to_bytes();
        let mut len = PACKET_LEN;
        let mut socket = &self.udp;
        match fault {
            None | Some(Fault::Replay) => {}
            Some(Fault::Drop) => return,
            Some(Fault::Delay(d)) => {
                self.delayed.push((Instant::now() + d, bytes, from));
                return;
            }
            Some(Fault::Corrupt) => bytes[4..6].copy_from_slice(&0xFFFFu16.to_le_bytes()),
            Some(Fault::Truncate) => len = 100,
            Some(Fault::ForeignPort) => socket = &self.foreign,
        }
        if socket.send_to(&bytes[..len], from).is_ok() {
            lock(&self.shared).status.replies += 1;
        }
    }

    fn send_due(&mut self, now: Instant) {
        let mut i = 0;
        while i < self.delayed.len() {
            if self.delayed[i].0 <= now {
                let (_, bytes, to) = self.delayed.swap_remove(i);
                if self.udp.send_to(&bytes, to).is_ok() {
                    lock(&self.shared).status.replies += 1;
                }
            } else {
                i += 1;
            }
        }
    }
}

impl Shared {
    /// Applies one packet to the arm and builds the reply (`None`: not answered).
    fn handle(&mut self, p: &Packet, from: SocketAddr, cycles: u32) -> Option<Packet> {
        let dof = self.config.dof;
        if p.command == Command::End {
            // The end of the session, whether the program still runs or was just stopped.
            self.status.ends += 1;
            self.status.program_running = false;
            return None;
        }
        if self.config.r3_bind.is_some() {
            if !self.status.program_running {
                self.status.packets_outside_program += 1;
                return None;
            }
            if let Some(info) = self.status.program_info
                && info.client != from.ip()
                && !(info.client.is_unspecified())
            {
                self.status.rejected += 1;
                return None;
            }
        }
        self.status.last_c_count = p.c_count;
        match p.command {
            Command::End => return None,
            Command::Move => {
                self.status.moves += 1;
                let mode = self.mode();
                let matches = matches!(
                    (mode, p.send_type.shape()),
                    (Mode::Joint, DataShape::Joint)
                        | (Mode::Pose, DataShape::Pose)
                        | (Mode::Pulse, DataShape::Pulse)
                );
                if !matches {
                    self.status.wrong_mode += 1;
                } else {
                    match p.send_type.shape() {
                        DataShape::Joint => {
                            for (i, j) in p.dat.joints().into_iter().enumerate().take(dof) {
                                self.command_joint(i, f64::from(j));
                            }
                        }
                        DataShape::Pulse => {
                            let per_rad = self.config.pulses_per_rad;
                            for (i, pl) in p.dat.i32s().into_iter().enumerate().take(dof) {
                                self.command_joint(i, f64::from(pl) / per_rad);
                            }
                        }
                        DataShape::Pose => self.target_pose = p.dat.pose(),
                        DataShape::Null | DataShape::Current => {}
                    }
                }
            }
            Command::Null => {}
        }
        if p.send_io_type == IoType::Output {
            let old = self.status.outputs.get(&p.bit_top).copied().unwrap_or(0);
            let new = (old & !p.bit_mask) | (p.io_data & p.bit_mask);
            self.status.outputs.insert(p.bit_top, new);
        }
        self.follow_target(cycles);
        self.advance(cycles);
        let mut reply = Packet {
            command: p.command,
            send_type: p.send_type,
            recv_io_type: p.recv_io_type,
            bit_top: p.bit_top,
            t_count: p.t_count,
            c_count: p.c_count,
            ..Packet::default()
        };
        reply.io_data = match p.recv_io_type {
            IoType::Input => self.inputs.get(&p.bit_top).copied().unwrap_or(0),
            IoType::Output => self.status.outputs.get(&p.bit_top).copied().unwrap_or(0),
            IoType::Null => 0,
        };
        let wanted = [p.recv_type, p.recv_type1, p.recv_type2, p.recv_type3];
        for ((ty, data), want) in reply.blocks_mut().into_iter().zip(wanted) {
            *ty = want;
            *data = self.data_for(want);
        }
        Some(reply)
    }

    /// Takes a request for joint `i`: its target is `q` clamped to the joint limits.
    fn command_joint(&mut self, i: usize, q: f64) {
        self.status.commanded_rad[i] = q;
        if q.is_nan() {
            return;
        }
        let (lo, hi) = (self.config.lower_rad[i], self.config.upper_rad[i]);
        if !(lo..=hi).contains(&q) {
            self.status.limit_hits += 1;
        }
        self.target_rad[i] = q.clamp(lo, hi);
    }

    /// The command value moves to the target, at most as far as the speed limits allow in
    /// `cycles` cycles (a clamped joint counts once per cycle it is clamped). A target within
    /// reach is taken as it is, bit for bit, as the controller takes a command it does not
    /// clamp (`last + (target − last)` is not `target` in floating point: near 0 it differs
    /// by more than the `f32` resolution the client checks the echo against).
    fn follow_target(&mut self, cycles: u32) {
        for i in 0..self.config.dof {
            let last = self.status.command_rad[i];
            let max_step = self.config.max_speed_rad_s[i] * CYCLE.as_secs_f64() * f64::from(cycles);
            let target = self.target_rad[i];
            let step = target - last;
            self.status.command_rad[i] = if step.abs() > max_step {
                self.status.speed_clamps += 1;
                last + step.clamp(-max_step, max_step)
            } else {
                target
            };
        }
    }

    /// Moves the joints (and the pose) toward the command through the first-order filter.
    fn advance(&mut self, cycles: u32) {
        let dt = CYCLE.as_secs_f64();
        let tau = f64::from(self.filter_ms()) * 1e-3 + self.config.servo_time_constant_s.max(0.0);
        let alpha = dt / (tau + dt);
        let gain = 1.0 - (1.0 - alpha).powi(cycles as i32);
        for i in 0..self.config.dof {
            let target = self.status.command_rad[i];
            let a = &mut self.status.actual_rad[i];
            *a += gain * (target - *a);
        }
        let g = gain as f32;
        let f = |a: &mut f32, t: f32| *a += g * (t - *a);
        let t = self.target_pose;
        for k in 0..3 {
            f(&mut self.pose.xyz_mm[k], t.xyz_mm[k]);
            f(&mut self.pose.abc_rad[k], t.abc_rad[k]);
        }
        for k in 0..2 {
            f(&mut self.pose.additional[k], t.additional[k]);
        }
        self.pose.sflg1 = t.sflg1;
        self.pose.sflg2 = t.sflg2;
    }

    /// The pose for joints `q` from the kinematics, as a data block.
    fn kinematic_pose(&self, q: &[f64; MAX_AXES]) -> Option<Data> {
        let k = self.config.kinematics.as_ref()?;
        let pose = k.pose(&q[..self.config.dof])?;
        let t: DVec3 = pose.translation;
        let data = PoseData {
            xyz_mm: [t.x, t.y, t.z].map(|v| (v * 1000.0) as f32),
            abc_rad: euler::to_zyx(&pose.rotation).map(|v| v as f32),
            ..PoseData::default()
        };
        Some(Data::from_pose(&data))
    }

    fn data_for(&self, ty: MxtType) -> Data {
        let dof = self.config.dof;
        let pick = |v: &[f64; MAX_AXES]| -> [f32; MAX_AXES] {
            core::array::from_fn(|i| if i < dof { v[i] as f32 } else { 0.0 })
        };
        let pulses = |v: &[f64; MAX_AXES]| -> [i32; MAX_AXES] {
            core::array::from_fn(|i| {
                if i < dof {
                    (v[i] * self.config.pulses_per_rad).round() as i32
                } else {
                    0
                }
            })
        };
        let command = &self.status.command_rad;
        let actual = &self.status.actual_rad;
        match ty {
            MxtType::Null => Data::ZERO,
            MxtType::Joint => Data::from_joints(&pick(command)),
            MxtType::JointFiltered | MxtType::JointFeedback => Data::from_joints(&pick(actual)),
            MxtType::Pose => self
                .kinematic_pose(command)
                .unwrap_or_else(|| Data::from_pose(&self.target_pose)),
            MxtType::PoseFiltered | MxtType::PoseFeedback => self
                .kinematic_pose(actual)
                .unwrap_or_else(|| Data::from_pose(&self.pose)),
            MxtType::Pulse => Data::from_i32s(&pulses(command)),
            MxtType::PulseFiltered | MxtType::PulseFeedback => Data::from_i32s(&pulses(actual)),
            MxtType::CurrentCommand | MxtType::CurrentFeedback => {
                Data::from_i32s(&core::array::from_fn(|i| {
                    if i < dof {
                        let e = command[i] - actual[i];
                        (1000.0 * e).clamp(-100.0, 100.0).round() as i32
                    } else {
                        0
                    }
                }))
            }
        }
    }

    /// Answers one R3 request body from connection `client`.
    fn r3(&mut self, req: &Request<'_>, client: u64) -> String {
        self.status.r3_log.push(req.body.to_string());
        let error = |code: u32| format!("QeR{code}");
        if self.reject.as_deref() == Some(req.name()) {
            return error(r3_errors::REJECTED);
        }
        let args = req.args();
        match req.name() {
            "STOP" => {
                self.status.program_running = false;
                "QoK".into()
            }
            "NEW" | "SLOTINIT" | "CLOSE" => "QoK".into(),
            "OPEN" => format!("QoK{}", args.trim_start_matches('=')),
            "LOAD" => {
                self.status.program_name = args.trim_start_matches('=').to_string();
                "QoK".into()
            }
            "ECLR" => {
                self.status.program.clear();
                "QoK".into()
            }
            "EMDAT" => {
                if !self.status.program.is_empty() {
                    self.status.program.push(r3::LINE_SEPARATOR);
                }
                self.status.program.push_str(args);
                "QoK".into()
            }
            "SAVE" => match ProgramInfo::parse(&self.status.program) {
                Ok(info) => {
                    self.status.program_info = Some(info);
                    "QoK".into()
                }
                Err(_) => {
                    self.status.program_info = None;
                    error(r3_errors::BAD_PROGRAM)
                }
            },
            "CNTLON" => match self.control {
                Some(holder) if holder != client => error(r3_errors::CONTROL_HELD),
                _ => {
                    self.control = Some(client);
                    "QoK".into()
                }
            },
            "CNTLOFF" => {
                if self.control == Some(client) {
                    self.control = None;
                }
                "QoK".into()
            }
            "SRVON" if self.control != Some(client) => error(r3_errors::NO_CONTROL),
            "SRVON" => {
                self.servo_polls_left = Some(self.config.servo_on_polls);
                "QoK".into()
            }
            "SRVOFF" => {
                self.status.servo_on = false;
                self.servo_polls_left = None;
                "QoK".into()
            }
            "RUN" => {
                let name = args.split(';').next().unwrap_or("");
                if self.control != Some(client)
                    || !self.status.servo_on
                    || name != self.status.program_name
                    || self.status.program_info.is_none()
                {
                    error(r3_errors::CANNOT_RUN)
                } else {
                    self.status.program_running = true;
                    "QoK".into()
                }
            }
            "DSTATE" => {
                if let Some(left) = self.servo_polls_left {
                    if left <= 1 {
                        self.status.servo_on = true;
                        self.servo_polls_left = None;
                    } else {
                        self.servo_polls_left = Some(left - 1);
                    }
                }
                let mut run = run_bits::OPERATION_ENABLED;
                if self.status.servo_on {
                    run |= run_bits::SERVO_ON;
                }
                if self.status.program_running {
                    run |= run_bits::RUN;
                }
                let state = DState {
                    run,
                    stop: 0,
                    error_no: 0,
                    step_no: 0,
                    mech_no: 1,
                };
                let mut buf = [0u8; 64];
                match state.encode(&mut buf) {
                    Ok(n) => format!("QoK{}", String::from_utf8_lossy(&buf[..n])),
                    Err(_) => error(r3_errors::NOT_IMPLEMENTED),
                }
            }
            "JPOSF" => {
                let dof = self.config.dof;
                let mut report = JointReport {
                    axes: dof,
                    ..JointReport::default()
                };
                for i in 0..dof {
                    report.values[i] = self.status.actual_rad[i].to_degrees();
                    report.decimals[i] = 2;
                }
                let mut buf = [0u8; 256];
                match report.encode(&mut buf) {
                    Ok(n) => format!("QoK{}", String::from_utf8_lossy(&buf[..n])),
                    Err(_) => error(r3_errors::NOT_IMPLEMENTED),
                }
            }
            "ERRORMES" => {
                let text = match args.trim().parse::<u32>() {
                    Ok(r3_errors::NO_CONTROL) => "no operation rights (CNTLON first)",
                    Ok(r3_errors::CANNOT_RUN) => "program cannot run",
                    Ok(r3_errors::CONTROL_HELD) => "another connection holds the operation rights",
                    Ok(r3_errors::REJECTED) => "rejected (injected error)",
                    Ok(r3_errors::BAD_PROGRAM) => "program lacks an ENET or MXT line",
                    Ok(r3_errors::BAD_REQUEST) => "malformed request",
                    Ok(r3_errors::NOT_IMPLEMENTED) => "command not implemented by the fake",
                    _ => "unknown error number",
                };
                format!("QoK{text}")
            }
            _ => {
                self.status.r3_not_implemented += 1;
                error(r3_errors::NOT_IMPLEMENTED)
            }
        }
    }
}

fn serve_r3(listener: &TcpListener, shared: &Arc<Mutex<Shared>>, stop: &Arc<AtomicBool>) {
    tcp_server::accept_clients(
        listener,
        "fake-h7-r3-client",
        POLL,
        shared,
        stop,
        |s| lock(s).status.r3_clients += 1,
        serve_r3_client,
    );
}

/// One R3 client: every receive is one request (the protocol has no request terminator;
/// clients wait for each reply before the next request, as RL does; a trailing CR or LF, as
/// serial clients send, is ignored).
fn serve_r3_client(stream: TcpStream, shared: &Mutex<Shared>, stop: &AtomicBool) {
    let (id, reset) = {
        let mut s = lock(shared);
        s.r3_ids += 1;
        (s.r3_ids, s.r3_reset)
    };
    serve_r3_requests(stream, shared, stop, id, reset);
    // The operation rights end with their connection.
    let mut s = lock(shared);
    if s.control == Some(id) {
        s.control = None;
    }
}

/// Serves connection `id` until it closes, the fake stops, or its connections are reset
/// (`reset` is the reset count when it connected).
fn serve_r3_requests(
    mut stream: TcpStream,
    shared: &Mutex<Shared>,
    stop: &AtomicBool,
    id: u64,
    reset: u64,
) {
    if !tcp_server::poll_reads(&stream, POLL) {
        return;
    }
    let mut buf = [0u8; 1024];
    while !stop.load(Ordering::Relaxed) {
        if lock(shared).r3_reset != reset {
            let _ = stream.shutdown(std::net::Shutdown::Both);
            return;
        }
        let n = match tcp_server::read_polled(&mut stream, &mut buf) {
            Polled::Bytes(n) => n,
            Polled::Idle => continue,
            Polled::Closed => return,
        };
        // A frozen controller holds the request until it thaws (or drops the connection).
        while lock(shared).is_frozen() {
            if stop.load(Ordering::Relaxed) {
                return;
            }
            if lock(shared).r3_reset != reset {
                let _ = stream.shutdown(std::net::Shutdown::Both);
                return;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        let mut s = lock(shared);
        let text = trim_request(&buf[..n]);
        let mut reply = match Request::parse(text) {
            Ok(req) => s.r3(&req, id),
            Err(_) => format!("QeR{}", r3_errors::BAD_REQUEST),
        };
        if s.config.r3_terminator {
            reply.push(char::from(r3::TERMINATOR));
        }
        let split = s.r3_split;
        drop(s);
        let written = match split {
            Some((k, pause)) if k > 0 => reply.as_bytes().chunks(k).try_for_each(|piece| {
                stream.write_all(piece)?;
                stream.flush()?;
                std::thread::sleep(pause);
                Ok::<(), io::Error>(())
            }),
            _ => stream.write_all(reply.as_bytes()),
        };
        if written.is_err() {
            return;
        }
    }
}

fn trim_request(bytes: &[u8]) -> &[u8] {
    let end = bytes
        .iter()
        .rposition(|b| !matches!(b, b'\r' | b'\n' | 0))
        .map_or(0, |i| i + 1);
    &bytes[..end]
}
