//! A fake Franka robot (FR3) on the wire: the FCI command server on TCP (port 1337 by default)
//! and the 1 kHz robot-state / robot-command exchange on UDP, answering libfranka (tested with
//! libfranka 0.21.2 through franky-control) and [`FrankaArm`](crate::franka::FrankaArm).
//!
//! It behaves like the robot where the robot's behaviour is known (libfranka's sources and
//! documentation, franky-sim's server; `rl-drivers/NOTES.md` lists what is and what is not):
//! - **Its own 1 ms cycle.** One thread ticks at absolute 1 ms deadlines (at a real-time
//!   priority when its starter gives it one: [`FakeFrankaConfig::on_thread_start`]): it takes
//!   the TCP requests and the UDP commands that came, advances the arm one millisecond, and
//!   sends the state of that millisecond (`message_id` + 1). A tick that wakes more than half
//!   a cycle late does not catch up with a burst of ticks the client could not answer (the
//!   fake's scheduling on a shared machine is not the client's fault): its clock slips, and
//!   the slips and the latest wake-up are reported.
//! - **Commands answer states.** A command counts for the cycle whose state id it carries,
//!   if it arrives before the next tick; an older id is late, and a cycle without its command
//!   is lost: the motion generator extrapolates at constant acceleration (a torque is held).
//!   [`crate::franka::MAX_LOST_IN_A_ROW`] lost in a row raise
//!   `communication_constraints_violation`. `control_command_success_rate` is the share of the
//!   last 100 cycles of a motion whose command came.
//! - **It refuses what the robot refuses.** Another version at `Connect`
//!   (`IncompatibleLibraryVersion`); a second client while one is connected (closed); requests
//!   before `Connect` (ignored, counted); `Move` while a motion runs or while the robot is in
//!   reflex (`CommandNotPossibleRejected`), with deviations that are not positive or an
//!   impedance controller without a motion generator (`InvalidArgumentRejected`); settings
//!   while a motion runs (`CommandNotPossibleRejected`) or out of range
//!   (`InvalidArgumentRejected`: negative thresholds or stiffness, a matrix that is not a
//!   transform, a negative mass).
//! - **It raises the robot's reflexes.** A first joint position command away from where the
//!   robot stands; positions beyond the limits; velocities beyond the position-based velocity
//!   limits; accelerations beyond 10 rad/s² (velocity discontinuity) and jerks beyond
//!   5000 rad/s³ (acceleration discontinuity); torque steps beyond 1 N·m per ms; the measured
//!   joints beyond their position or velocity limits; lost commands. A reflex stops the arm
//!   (brakes), answers `Move` with `ReflexAborted`, sets `errors` and `reflex_reason`, and
//!   holds until `AutomaticErrorRecovery`.
//! - **The arm.** Without a model it is kinematic: joints are where the motion generator puts
//!   them, and torques do not move it. With the arm's URDF ([`FakeFrankaConfig::with_urdf`]) it
//!   serves that URDF, takes the joint limits from it, and integrates its dynamics with
//!   rl-core's ABA: in torque control the client's torques plus gravity compensation (the robot
//!   adds gravity), in position and velocity control the robot's joint controller (computed
//!   torque, 50 rad/s, critically damped); torques are clipped at the joints' effort limits.
//!
//! Not simulated: the Cartesian motion generators and the asynchronous one (`Move` is
//! refused with `CommandNotPossibleRejected`), a motion generator under the external
//! controller (the torques alone count), contacts and collisions (`joint_reflex` and
//! `cartesian_reflex` are never raised), friction, the elastic joints (`theta = q`), the hand.

mod arm;
mod urdf;

use std::io::{self, Read, Write};
use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use self::arm::{Arm, Generator, is_transform, to_matrix};
use crate::franka::command::{COMMAND_LEN, RobotCommand};
use crate::franka::connect::{ConnectResponse, VERSION};
use crate::franka::errors::{ErrorSet, ReflexCounts, RobotError};
use crate::franka::limits::{FR3, JointLimits};
use crate::franka::message::{
    BaseStatus, Command, ConnectStatus, HEADER_LEN, Header, MoveControllerMode,
    MoveMotionGeneratorMode, MoveRequest, MoveStatus, RecoveryStatus, Request, Response,
    SetterStatus, Status, StopMoveStatus,
};
use crate::franka::state::{
    ControllerMode, IDENTITY, MotionGeneratorMode, RobotMode, RobotState, STATE_LEN,
};
use crate::franka::{CYCLE, DOF, MAX_LOST_IN_A_ROW};

/// Franka's "ready" pose (libfranka's examples move there first), rad.
pub const READY: [f64; DOF] = [
    0.0,
    -core::f64::consts::FRAC_PI_4,
    0.0,
    -3.0 * core::f64::consts::FRAC_PI_4,
    0.0,
    core::f64::consts::FRAC_PI_2,
    core::f64::consts::FRAC_PI_4,
];

/// A tick this late lets the fake's clock slip instead of catching up.
const SLIP: Duration = Duration::from_micros(500);
/// Largest request the fake reads (the longest is 428 bytes).
const MAX_REQUEST: usize = 4096;

/// A URDF of an arm shaped like the FR3 (its joint origins and limits) with made-up inertias,
/// for tests and demos of the fake's dynamics without the FR3's own URDF.
pub fn fr3_shaped_urdf() -> String {
    urdf::fr3_shaped_urdf()
}

/// Configuration of the fake robot.
#[derive(Clone, Debug)]
pub struct FakeFrankaConfig {
    /// Address of the command server and the state sender (loopback by default).
    pub bind: IpAddr,
    /// The command server's port ([`COMMAND_PORT`](crate::franka::COMMAND_PORT); 0: a free
    /// one).
    pub command_port: u16,
    /// The URDF `GetRobotModel` answers with; `None`: one written from the FR3's limits.
    pub urdf: Option<String>,
    /// Integrate the arm's dynamics from `urdf` (needs its inertias).
    pub dynamics: bool,
    /// The rotor inertia of each joint's drive reflected to the joint (kg·m²), which the
    /// URDF has no field for: the integrated arm carries it (rl-core's `Model::armature`).
    /// The FR3 in franky-sim's MuJoCo model: 0.195 on joints 1–4, 0.074 on 5–7.
    pub armature: [f64; DOF],
    /// The joints at power-up, rad.
    pub initial_q: [f64; DOF],
    /// The research-interface version it speaks.
    pub version: u16,
    /// Called first on the fake's thread (to give it a real-time priority: rl-drivers sets no
    /// scheduling policy itself).
    pub on_thread_start: Option<fn()>,
}

impl FakeFrankaConfig {
    /// A kinematic FR3 on 127.0.0.1:1337 at [`READY`].
    pub fn loopback() -> Self {
        Self {
            bind: IpAddr::V4(Ipv4Addr::LOCALHOST),
            command_port: crate::franka::COMMAND_PORT,
            urdf: None,
            dynamics: false,
            armature: [0.0; DOF],
            initial_q: READY,
            version: VERSION,
            on_thread_start: None,
        }
    }

    /// The same with the robot's URDF: its limits, and its dynamics.
    #[must_use]
    pub fn with_urdf(mut self, urdf: String) -> Self {
        self.urdf = Some(urdf);
        self.dynamics = true;
        self
    }
}

/// What the fake has seen and where its arm is.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FakeFrankaStatus {
    /// The robot's mode.
    pub robot_mode: RobotMode,
    /// Joints, rad.
    pub q: [f64; DOF],
    /// Joint velocities, rad/s.
    pub dq: [f64; DOF],
    /// Measured torques, N·m.
    pub tau_j: [f64; DOF],
    /// Errors active now.
    pub errors: ErrorSet,
    /// Why the last motion was stopped.
    pub reflex_reason: ErrorSet,
    /// How often each error was raised.
    pub raised: Vec<(RobotError, u32)>,
    /// Ticks run.
    pub ticks: u64,
    /// Ticks that woke more than half a cycle late, after which the fake's clock slipped
    /// (its own scheduling, not the client's: the robot's cycle never slips).
    pub slips: u64,
    /// The latest a tick woke after its deadline, µs.
    pub max_lateness_us: u64,
    /// States sent.
    pub states: u64,
    /// States not sent on purpose ([`FakeFranka::drop_states`]).
    pub dropped_states: u64,
    /// Clients accepted; clients refused because one was connected.
    pub clients: u64,
    /// Connections refused because another client was connected.
    pub refused_clients: u64,
    /// Connects refused for their version.
    pub version_refusals: u64,
    /// Requests before `Connect`, or that did not decode.
    pub bad_requests: u64,
    /// Requests answered with a refusal.
    pub refused_requests: u64,
    /// Commands used (in time, for the current cycle).
    pub commands: u64,
    /// Cycles of a motion without their command.
    pub lost: u64,
    /// The longest run of lost commands.
    pub max_lost_in_a_row: u32,
    /// Commands for an earlier cycle.
    pub late: u64,
    /// Datagrams from anyone but the client, or of the wrong length.
    pub foreign: u64,
    /// Commands outside a motion.
    pub outside_motion: u64,
    /// Motions started, finished as commanded, stopped by a reflex.
    pub motions: u64,
    /// Motions that ended as commanded.
    pub finished: u64,
    /// Motions a reflex stopped.
    pub reflexes: u64,
    /// Automatic error recoveries.
    pub recoveries: u64,
    /// Torques clipped at the effort limits.
    pub torque_clips: u64,
    /// Whether the arm's dynamics are integrated.
    pub dynamics: bool,
    /// `control_command_success_rate` of the last state.
    pub success_rate: f64,
}

struct Shared {
    stop: AtomicBool,
    drop_states: AtomicU32,
    status: Mutex<FakeFrankaStatus>,
}

/// A running fake robot; its thread stops when this is dropped.
pub struct FakeFranka {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    addr: SocketAddr,
}

impl FakeFranka {
    /// Binds the command server and starts the robot's thread.
    pub fn spawn(config: FakeFrankaConfig) -> io::Result<Self> {
        let invalid = |e: String| io::Error::new(io::ErrorKind::InvalidInput, e);
        let urdf = match &config.urdf {
            Some(u) => u.clone(),
            None => urdf::limits_only_urdf(&FR3),
        };
        let limits = urdf::joint_limits(&urdf).map_err(invalid)?;
        let dynamics = if config.dynamics {
            Some(urdf::dynamics(&urdf, &config.armature).map_err(invalid)?)
        } else {
            None
        };
        for (i, l) in limits.iter().enumerate() {
            let q = config.initial_q[i];
            if !(l.lower..=l.upper).contains(&q) {
                return Err(invalid(format!(
                    "initial joint {} at {q} rad outside [{}, {}]",
                    i + 1,
                    l.lower,
                    l.upper
                )));
            }
        }
        let listener = TcpListener::bind((config.bind, config.command_port))?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let udp = UdpSocket::bind((config.bind, 0))?;
        udp.set_nonblocking(true)?;
        let shared = Arc::new(Shared {
            stop: AtomicBool::new(false),
            drop_states: AtomicU32::new(0),
            status: Mutex::new(FakeFrankaStatus::default()),
        });
        let mut robot = Robot::new(&config, limits, dynamics, urdf, listener, udp);
        robot.publish(&shared);
        let s = shared.clone();
        let on_start = config.on_thread_start;
        let thread = std::thread::Builder::new()
            .name("fake-franka".into())
            .spawn(move || {
                if let Some(f) = on_start {
                    f();
                }
                robot.run(&s);
            })?;
        Ok(Self {
            shared,
            thread: Some(thread),
            addr,
        })
    }

    /// The command server's address.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// What the fake has seen so far.
    pub fn status(&self) -> FakeFrankaStatus {
        self.shared
            .status
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }

    /// Leaves out the next `n` states (network loss of states): the client cannot answer
    /// those cycles, so the robot counts their commands lost.
    pub fn drop_states(&self, n: u32) {
        self.shared.drop_states.store(n, Ordering::Relaxed);
    }

    /// Stops the thread and waits for it (also done on drop).
    pub fn shutdown(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for FakeFranka {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// The connected client.
struct Client {
    stream: TcpStream,
    rx: Vec<u8>,
    tx: Vec<u8>,
    /// Where states go, after `Connect`.
    udp: Option<SocketAddr>,
}

/// The running motion.
#[derive(Clone, Copy, Debug)]
struct Motion {
    id: u32,
    generator: Generator,
    motion_generator: MotionGeneratorMode,
    controller: ControllerMode,
}

/// The robot: its thread's state.
struct Robot {
    version: u16,
    urdf: String,
    listener: TcpListener,
    udp: UdpSocket,
    client: Option<Client>,
    arm: Arm,
    mode: RobotMode,
    motion: Option<Motion>,
    errors: ErrorSet,
    reflex_reason: ErrorSet,
    raised: ReflexCounts,
    message_id: u64,
    cycle_command: Option<RobotCommand>,
    lost_in_a_row: u32,
    window: [bool; 100],
    window_at: usize,
    state: Box<RobotState>,
    status: FakeFrankaStatus,
    rx: [u8; COMMAND_LEN + 1],
    tx: Box<[u8; STATE_LEN]>,
}

impl Robot {
    fn new(
        config: &FakeFrankaConfig,
        limits: [JointLimits; DOF],
        dynamics: Option<arm::Dynamics>,
        urdf: String,
        listener: TcpListener,
        udp: UdpSocket,
    ) -> Self {
        let has_dynamics = dynamics.is_some();
        let mut state = Box::<RobotState>::default();
        state.robot_mode = RobotMode::Idle;
        Self {
            version: config.version,
            urdf,
            listener,
            udp,
            client: None,
            arm: Arm::new(limits, config.initial_q, dynamics),
            mode: RobotMode::Idle,
            motion: None,
            errors: ErrorSet::EMPTY,
            reflex_reason: ErrorSet::EMPTY,
            raised: ReflexCounts::default(),
            message_id: 0,
            cycle_command: None,
            lost_in_a_row: 0,
            window: [true; 100],
            window_at: 0,
            state,
            status: FakeFrankaStatus {
                dynamics: has_dynamics,
                ..FakeFrankaStatus::default()
            },
            rx: [0; COMMAND_LEN + 1],
            tx: Box::new([0; STATE_LEN]),
        }
    }

    fn run(&mut self, shared: &Shared) {
        let mut next = Instant::now() + CYCLE;
        while !shared.stop.load(Ordering::Relaxed) {
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            }
            let woke = Instant::now();
            let late = woke.saturating_duration_since(next);
            self.status.max_lateness_us = self
                .status
                .max_lateness_us
                .max(u64::try_from(late.as_micros()).unwrap_or(u64::MAX));
            let drop = shared.drop_states.load(Ordering::Relaxed);
            let send = if drop > 0 {
                shared.drop_states.store(drop - 1, Ordering::Relaxed);
                self.status.dropped_states += 1;
                false
            } else {
                true
            };
            self.tick(send);
            // A tick that woke more than half a cycle late does not catch up: the fake's own
            // scheduling is not the client's fault, and a burst of ticks would leave the client
            // no chance to answer. Its clock slips instead (counted).
            next += CYCLE;
            if late > SLIP {
                next = woke + CYCLE;
                self.status.slips += 1;
            }
            self.publish(shared);
        }
        self.publish(shared);
    }

    fn publish(&mut self, shared: &Shared) {
        let s = &mut self.status;
        s.robot_mode = self.mode;
        s.q = self.arm.q;
        s.dq = self.arm.dq;
        s.tau_j = self.arm.tau_j;
        s.errors = self.errors;
        s.reflex_reason = self.reflex_reason;
        s.raised = self.raised.iter().collect();
        s.torque_clips = self.arm.torque_clips;
        s.success_rate = self.state.control_command_success_rate;
        *shared.status.lock().unwrap_or_else(|p| p.into_inner()) = s.clone();
    }

    /// One millisecond.
    fn tick(&mut self, send: bool) {
        self.status.ticks += 1;
        self.accept();
        self.serve_tcp();
        self.take_commands();
        self.advance();
        // The state of the next millisecond: a command must carry this id to count for it.
        self.message_id += 1;
        if send {
            self.send_state();
        }
    }

    fn accept(&mut self) {
        while let Ok((stream, _)) = self.listener.accept() {
            if self.client.is_some() {
                // One client at a time.
                self.status.refused_clients += 1;
                drop(stream);
                continue;
            }
            if stream.set_nonblocking(true).is_err() {
                continue;
            }
            let _ = stream.set_nodelay(true);
            self.status.clients += 1;
            self.client = Some(Client {
                stream,
                rx: Vec::with_capacity(MAX_REQUEST),
                tx: Vec::new(),
                udp: None,
            });
        }
    }

    fn serve_tcp(&mut self) {
        let Some(client) = &mut self.client else {
            return;
        };
        let mut buf = [0u8; MAX_REQUEST];
        let mut closed = false;
        loop {
            match client.stream.read(&mut buf) {
                Ok(0) => {
                    closed = true;
                    break;
                }
                Ok(n) => client.rx.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(_) => {
                    closed = true;
                    break;
                }
            }
        }
        // Complete requests.
        loop {
            let Some(client) = &mut self.client else {
                return;
            };
            if client.rx.len() < HEADER_LEN {
                break;
            }
            let header = match Header::decode(&client.rx, MAX_REQUEST) {
                Ok(h) => h,
                Err(_) => {
                    // Unparsable: the stream cannot be resynchronised.
                    self.status.bad_requests += 1;
                    closed = true;
                    break;
                }
            };
            let size = header.size as usize;
            if client.rx.len() < size {
                break;
            }
            let payload: Vec<u8> = client.rx[HEADER_LEN..size].to_vec();
            client.rx.drain(..size);
            match Request::decode(&header, &payload) {
                Ok(r) => self.handle(header.command_id, r),
                Err(_) => self.status.bad_requests += 1,
            }
        }
        if let Some(client) = &mut self.client
            && !client.tx.is_empty()
        {
            match client.stream.write(&client.tx) {
                Ok(n) => {
                    client.tx.drain(..n);
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
                Err(_) => closed = true,
            }
        }
        if closed {
            self.disconnect();
        }
    }

    /// The client went away: a running motion loses its commands.
    fn disconnect(&mut self) {
        self.client = None;
        if self.motion.is_some() {
            self.reflex(ErrorSet::EMPTY.with(RobotError::CommunicationConstraintsViolation));
        }
    }

    /// Queues an answer to the client.
    fn answer(&mut self, id: u32, command: Command, status: Status, rest: &[u8]) {
        let Some(client) = &mut self.client else {
            return;
        };
        let start = client.tx.len();
        client.tx.resize(start + HEADER_LEN + 1 + rest.len(), 0);
        if Response::encode(id, command, status, rest, &mut client.tx[start..]).is_err() {
            client.tx.truncate(start);
        }
        if !status.is_success() {
            self.status.refused_requests += 1;
        }
        // Send what fits now.
        if let Some(client) = &mut self.client
            && let Ok(n) = client.stream.write(&client.tx)
        {
            client.tx.drain(..n);
        }
    }

    fn handle(&mut self, id: u32, request: Request) {
        let connected = self.client.as_ref().is_some_and(|c| c.udp.is_some());
        let command = request.command();
        if !connected && command != Command::Connect {
            self.status.bad_requests += 1;
            return;
        }
        let setter = |ok: bool, moving: bool| {
            Status::Setter(if moving {
                SetterStatus::CommandNotPossibleRejected
            } else if ok {
                SetterStatus::Success
            } else {
                SetterStatus::InvalidArgumentRejected
            })
        };
        let moving = self.motion.is_some();
        let nonneg = |v: &[f64]| v.iter().all(|x| x.is_finite() && *x >= 0.0);
        match request {
            Request::Connect(c) => {
                if connected {
                    self.status.bad_requests += 1;
                    return;
                }
                let status = if c.version == self.version {
                    ConnectStatus::Success
                } else {
                    self.status.version_refusals += 1;
                    ConnectStatus::IncompatibleLibraryVersion
                };
                let payload = ConnectResponse {
                    status,
                    version: self.version,
                }
                .encode();
                self.answer(id, command, Status::Connect(status), &payload[1..]);
                if status == ConnectStatus::Success
                    && let Some(client) = &mut self.client
                    && let Ok(peer) = client.stream.peer_addr()
                {
                    client.udp = Some(SocketAddr::new(peer.ip(), c.udp_port));
                }
            }
            Request::Move(m) => {
                let status = self.start_motion(id, &m);
                self.answer(id, command, Status::Move(status), &[]);
            }
            Request::StopMove => {
                self.answer(id, command, Status::StopMove(StopMoveStatus::Success), &[]);
                if let Some(m) = self.motion.take() {
                    self.arm.halt();
                    self.mode = RobotMode::Idle;
                    self.answer(
                        m.id,
                        Command::Move,
                        Status::Move(MoveStatus::Preempted),
                        &[],
                    );
                }
            }
            Request::SetCollisionBehavior(c) => {
                let ok = [
                    &c.lower_torque_acceleration[..],
                    &c.upper_torque_acceleration,
                    &c.lower_torque_nominal,
                    &c.upper_torque_nominal,
                    &c.lower_force_acceleration,
                    &c.upper_force_acceleration,
                    &c.lower_force_nominal,
                    &c.upper_force_nominal,
                ]
                .iter()
                .all(|v| nonneg(v));
                self.answer(id, command, setter(ok, moving), &[]);
            }
            Request::SetJointImpedance(k) => {
                self.answer(id, command, setter(nonneg(&k), moving), &[]);
            }
            Request::SetCartesianImpedance(k) => {
                self.answer(id, command, setter(nonneg(&k), moving), &[]);
            }
            Request::SetGuidingMode { .. } => self.answer(id, command, setter(true, moving), &[]),
            Request::SetEeToK(t) => {
                let ok = is_transform(&t);
                if ok && !moving {
                    self.state.EE_T_K = t;
                }
                self.answer(id, command, setter(ok, moving), &[]);
            }
            Request::SetNeToEe(t) => {
                let ok = is_transform(&t);
                if ok && !moving {
                    self.state.NE_T_EE = t;
                }
                self.answer(id, command, setter(ok, moving), &[]);
            }
            Request::SetLoad(l) => {
                let ok = l.mass.is_finite()
                    && l.mass >= 0.0
                    && l.center_of_mass.iter().all(|x| x.is_finite())
                    && l.inertia.iter().all(|x| x.is_finite());
                if ok && !moving {
                    self.state.m_load = l.mass;
                    self.state.F_x_Cload = l.center_of_mass;
                    self.state.I_load = l.inertia;
                }
                self.answer(id, command, setter(ok, moving), &[]);
            }
            Request::AutomaticErrorRecovery => {
                let status = if moving {
                    RecoveryStatus::CommandNotPossibleRejected
                } else {
                    if !self.errors.is_empty() || self.mode == RobotMode::Reflex {
                        self.status.recoveries += 1;
                    }
                    self.errors = ErrorSet::EMPTY;
                    self.mode = RobotMode::Idle;
                    RecoveryStatus::Success
                };
                self.answer(id, command, Status::Recovery(status), &[]);
            }
            Request::GetRobotModel => {
                let urdf = std::mem::take(&mut self.urdf);
                self.answer(
                    id,
                    command,
                    Status::Base(BaseStatus::Success),
                    urdf.as_bytes(),
                );
                self.urdf = urdf;
            }
        }
    }

    /// `Move`: the answer to send now.
    fn start_motion(&mut self, id: u32, m: &MoveRequest) -> MoveStatus {
        if self.motion.is_some() || self.mode == RobotMode::Reflex || !self.errors.is_empty() {
            return MoveStatus::CommandNotPossibleRejected;
        }
        let positive = |d: &crate::franka::message::Deviation| {
            [d.translation, d.rotation, d.elbow]
                .iter()
                .all(|x| x.is_finite() && *x > 0.0)
        };
        if !positive(&m.maximum_path_deviation) || !positive(&m.maximum_goal_pose_deviation) {
            return MoveStatus::InvalidArgumentRejected;
        }
        if m.async_maximum_velocity.is_some() {
            return MoveStatus::CommandNotPossibleRejected;
        }
        let (generator, motion_generator, controller) =
            match (m.controller_mode, m.motion_generator_mode) {
                (MoveControllerMode::ExternalController, g) => (
                    Generator::Torque,
                    match g {
                        MoveMotionGeneratorMode::None => MotionGeneratorMode::None,
                        MoveMotionGeneratorMode::JointPosition => {
                            MotionGeneratorMode::JointPosition
                        }
                        MoveMotionGeneratorMode::JointVelocity => {
                            MotionGeneratorMode::JointVelocity
                        }
                        _ => return MoveStatus::CommandNotPossibleRejected,
                    },
                    ControllerMode::ExternalController,
                ),
                (_, MoveMotionGeneratorMode::None) => return MoveStatus::InvalidArgumentRejected,
                (c, g) => {
                    let (generator, mg) = match g {
                        MoveMotionGeneratorMode::JointPosition => {
                            (Generator::Position, MotionGeneratorMode::JointPosition)
                        }
                        MoveMotionGeneratorMode::JointVelocity => {
                            (Generator::Velocity, MotionGeneratorMode::JointVelocity)
                        }
                        _ => return MoveStatus::CommandNotPossibleRejected,
                    };
                    let controller = if c == MoveControllerMode::JointImpedance {
                        ControllerMode::JointImpedance
                    } else {
                        ControllerMode::CartesianImpedance
                    };
                    (generator, mg, controller)
                }
            };
        self.motion = Some(Motion {
            id,
            generator,
            motion_generator,
            controller,
        });
        self.arm.begin();
        self.mode = RobotMode::Move;
        self.reflex_reason = ErrorSet::EMPTY;
        self.cycle_command = None;
        self.lost_in_a_row = 0;
        self.window = [true; 100];
        self.status.motions += 1;
        MoveStatus::MotionStarted
    }

    /// Takes the datagrams that came: this cycle's command, late ones, foreign ones.
    fn take_commands(&mut self) {
        let peer = self.client.as_ref().and_then(|c| c.udp);
        loop {
            match self.udp.recv_from(&mut self.rx) {
                Ok((n, from)) => {
                    if Some(from) != peer || n != COMMAND_LEN {
                        self.status.foreign += 1;
                        continue;
                    }
                    let Ok(c) = RobotCommand::decode(&self.rx[..n]) else {
                        self.status.foreign += 1;
                        continue;
                    };
                    if self.motion.is_none() {
                        self.status.outside_motion += 1;
                    } else if c.message_id == self.message_id && self.message_id > 0 {
                        self.cycle_command = Some(c);
                    } else {
                        self.status.late += 1;
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(_) => return,
            }
        }
    }

    /// Advances the arm by this cycle's command.
    fn advance(&mut self) {
        let Some(m) = self.motion else {
            let hold = if self.mode == RobotMode::Reflex {
                // Brakes: nothing moves.
                return;
            } else {
                Generator::Hold
            };
            let _ = self.arm.tick(hold, None, None, None);
            return;
        };
        let command = self.cycle_command.take();
        self.window[self.window_at] = command.is_some();
        self.window_at = (self.window_at + 1) % self.window.len();
        match &command {
            Some(_) => {
                self.status.commands += 1;
                self.lost_in_a_row = 0;
            }
            None => {
                self.status.lost += 1;
                self.lost_in_a_row += 1;
                self.status.max_lost_in_a_row =
                    self.status.max_lost_in_a_row.max(self.lost_in_a_row);
                if self.lost_in_a_row >= MAX_LOST_IN_A_ROW {
                    self.reflex(
                        ErrorSet::EMPTY.with(RobotError::CommunicationConstraintsViolation),
                    );
                    return;
                }
            }
        }
        let finished = command.is_some_and(|c| match m.generator {
            Generator::Torque => c.control.torque_command_finished,
            _ => c.motion.motion_generation_finished,
        });
        let (q_c, dq_c, tau) = match (&command, m.generator) {
            (Some(c), Generator::Position) => (Some(&c.motion.q_c), None, None),
            (Some(c), Generator::Velocity) => (None, Some(&c.motion.dq_c), None),
            (Some(c), Generator::Torque) => (None, None, Some(&c.control.tau_J_d)),
            _ => (None, None, None),
        };
        let errors = self.arm.tick(m.generator, q_c, dq_c, tau);
        if !errors.is_empty() {
            self.reflex(errors);
            return;
        }
        if finished {
            self.motion = None;
            self.mode = RobotMode::Idle;
            self.arm.halt();
            self.status.finished += 1;
            self.answer(m.id, Command::Move, Status::Move(MoveStatus::Success), &[]);
        }
    }

    /// A reflex: the arm stops, the motion ends with `ReflexAborted`, the errors stay.
    fn reflex(&mut self, errors: ErrorSet) {
        self.errors = self.errors.union(errors);
        self.reflex_reason = errors;
        self.raised.record(self.errors);
        self.mode = RobotMode::Reflex;
        self.arm.halt();
        self.status.reflexes += 1;
        if let Some(m) = self.motion.take() {
            self.answer(
                m.id,
                Command::Move,
                Status::Move(MoveStatus::ReflexAborted),
                &[],
            );
        }
    }

    fn send_state(&mut self) {
        let success = self.window.iter().filter(|c| **c).count() as f64 / self.window.len() as f64;
        let flange = self.arm.flange_pose();
        let (q_d, dq_d, ddq_d) = self.arm.desired();
        let s = &mut *self.state;
        s.message_id = self.message_id;
        s.q = self.arm.q;
        s.dq = self.arm.dq;
        s.theta = self.arm.q;
        s.dtheta = self.arm.dq;
        s.tau_J = self.arm.tau_j;
        s.tau_J_d = self.arm.tau_j_d;
        s.q_d = q_d;
        s.dq_d = dq_d;
        s.ddq_d = ddq_d;
        s.F_T_EE = to_matrix(&(arm::from_matrix(&s.F_T_NE) * arm::from_matrix(&s.NE_T_EE)));
        let o_t_ee = to_matrix(&(arm::from_matrix(&flange) * arm::from_matrix(&s.F_T_EE)));
        s.O_T_EE = o_t_ee;
        s.O_T_EE_d = o_t_ee;
        s.O_T_EE_c = o_t_ee;
        s.elbow = [s.q[2], if s.q[3] < 0.0 { -1.0 } else { 1.0 }];
        s.elbow_d = [q_d[2], s.elbow[1]];
        s.elbow_c = s.elbow_d;
        s.errors = self.errors;
        s.reflex_reason = self.reflex_reason;
        s.robot_mode = self.mode;
        let (mg, cm) = self
            .motion
            .map_or((MotionGeneratorMode::Idle, ControllerMode::Other), |m| {
                (m.motion_generator, m.controller)
            });
        s.motion_generator_mode = mg;
        s.controller_mode = cm;
        s.control_command_success_rate = if self.motion.is_some() { success } else { 0.0 };
        if s.F_T_NE == [0.0; 16] {
            s.F_T_NE = IDENTITY;
        }
        let Some(to) = self.client.as_ref().and_then(|c| c.udp) else {
            return;
        };
        s.encode(&mut self.tx);
        if self.udp.send_to(&self.tx[..], to).is_ok() {
            self.status.states += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ready_is_inside_the_fr3_limits() {
        for (q, l) in READY.iter().zip(FR3.iter()) {
            assert!((l.lower..=l.upper).contains(q));
        }
    }
}
