//! The cyclic device for a Franka arm: [`FrankaArm`].
//!
//! - `open`: TCP to the robot's command port, `Connect` with this crate's version and the UDP
//!   port bound for states (the robot refuses another version: a typed error names both), the
//!   first state (which fixes the robot's UDP port: later datagrams from anywhere else are
//!   counted and dropped), and the robot's URDF (`GetRobotModel`, kept for the caller to build
//!   the dynamics from: the protocol carries no mass matrix, Coriolis or gravity).
//! - `start`: automatic error recovery if configured and the robot reports errors; the
//!   configured settings (collision behaviour, joint and Cartesian impedance, `NE_T_EE`,
//!   `EE_T_K`, load), each answered before the next; `Move` with the controller and motion
//!   generator of the [`ControlMode`]; then states until the robot reports the motion's modes.
//!   The buffered command starts where the robot stands (`q_d`, zero velocity, zero torque).
//! - `step`: polls the TCP channel (a motion's end arrives there: `Success`, or why the robot
//!   stopped it), answers the newest state with the buffered command (carrying that state's
//!   `message_id`), then waits for the next state, bounded by the caller's budget
//!   ([`CyclicDevice::step_within`](crate::CyclicDevice::step_within)) and the configured wait.
//!   Every state id the robot sent that this client did not answer is a command the robot
//!   counts lost; the run of them in a row is kept (the robot stops after
//!   [`MAX_LOST_IN_A_ROW`](super::MAX_LOST_IN_A_ROW)). A reflex (robot mode `Reflex`, or a
//!   `Move` answer other than success) faults the device at once with the reflex's errors.
//! - `stop`: a running motion is finished the way libfranka finishes it — the last command
//!   with `motion_generation_finished` (or `torque_command_finished`) until the robot reports
//!   idle, then `Move`'s final answer; a robot that does not end it gets `StopMove`. After a
//!   reflex the motion is over already; automatic error recovery follows if configured.
//! - `close`: drops both sockets; the counts stay.
//!
//! `step` allocates nothing and makes no system call beyond the two sockets' (tested with the
//! counting allocator).

use core::time::Duration;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::time::Instant;

use super::command::{ControllerCommand, MotionGeneratorCommand, RobotCommand};
use super::connect::{ConnectRequest, ConnectResponse, VERSION};
use super::errors::{ErrorSet, ReflexCounts};
use super::link::{Answer, CommandChannel, LinkError, StateChannel};
use super::message::{
    BaseStatus, CollisionBehavior, Command, Deviation, Load, MoveControllerMode,
    MoveMotionGeneratorMode, MoveRequest, MoveStatus, Request, Status,
};
use super::state::{ControllerMode, MotionGeneratorMode, RobotMode, RobotState, STATE_LEN};
use super::{COMMAND_PORT, CYCLE, DOF, MAX_LOST_IN_A_ROW};
use crate::capability::{
    CartesianPositionSensor, Delivery, JointDevice, JointPositionActuator, JointPositionSensor,
    JointTorqueActuator, JointTorqueSensor, JointVelocityActuator, JointVelocitySensor,
    LinkStatistics, LinkStatisticsSensor, Pose,
};
use crate::device::{Driver, Error, FirstError, Lifecycle, Operation, State, impl_cyclic_device};

/// How long a step waits for the next state unless its caller gives a budget: two cycles, so
/// one late state is waited for and a lost one is counted without holding the loop long.
pub const RECOMMENDED_STATE_WAIT: Duration = Duration::from_millis(2);

const SOURCE: &str = "Franka";

/// What the client commands during a motion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ControlMode {
    /// Joint positions `q_c`, tracked by the robot's own controller
    /// ([`FrankaConfig::controller`]).
    #[default]
    JointPosition,
    /// Joint velocities `dq_c`, tracked by the robot's own controller.
    JointVelocity,
    /// Joint torques `tau_J_d` (the robot adds gravity), no motion generator.
    JointTorque,
}

impl ControlMode {
    const fn motion_generator(self) -> MoveMotionGeneratorMode {
        match self {
            Self::JointPosition => MoveMotionGeneratorMode::JointPosition,
            Self::JointVelocity => MoveMotionGeneratorMode::JointVelocity,
            Self::JointTorque => MoveMotionGeneratorMode::None,
        }
    }

    const fn state_motion_generator(self) -> MotionGeneratorMode {
        match self {
            Self::JointPosition => MotionGeneratorMode::JointPosition,
            Self::JointVelocity => MotionGeneratorMode::JointVelocity,
            Self::JointTorque => MotionGeneratorMode::None,
        }
    }

    const fn name(self) -> &'static str {
        match self {
            Self::JointPosition => "joint position",
            Self::JointVelocity => "joint velocity",
            Self::JointTorque => "joint torque",
        }
    }
}

/// Settings sent to the robot at `start`, before the motion (the robot accepts them only
/// while no motion runs). `None` leaves the robot's value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrankaSettings {
    /// Contact and collision thresholds.
    pub collision_behavior: Option<CollisionBehavior>,
    /// Stiffness of the internal joint impedance controller, N·m/rad.
    pub joint_impedance: Option<[f64; DOF]>,
    /// Stiffness of the internal Cartesian impedance controller.
    pub cartesian_impedance: Option<[f64; 6]>,
    /// End effector in the nominal end-effector frame (`setEE`), column-major.
    pub ne_t_ee: Option<[f64; 16]>,
    /// Stiffness frame in the end-effector frame (`setK`), column-major.
    pub ee_t_k: Option<[f64; 16]>,
    /// The load on the flange.
    pub load: Option<Load>,
}

/// Configuration of a [`FrankaArm`].
#[derive(Clone, Debug, PartialEq)]
pub struct FrankaConfig {
    /// The robot's address (the FCI address of its controller).
    pub robot: IpAddr,
    /// Its command port ([`COMMAND_PORT`]).
    pub command_port: u16,
    /// Where states are received: an unspecified address becomes the one that routes to the
    /// robot, port 0 a free port.
    pub local: SocketAddr,
    /// What the client commands.
    pub mode: ControlMode,
    /// The robot's controller for the position and velocity modes (joint or Cartesian
    /// impedance); torque mode always runs the external controller.
    pub controller: MoveControllerMode,
    /// Settings sent at `start`.
    pub settings: FrankaSettings,
    /// Run automatic error recovery at `start` when the robot reports errors or a reflex (and
    /// after a reflex at `stop`).
    pub automatic_recovery: bool,
    /// Largest wait for a TCP answer and for the robot to take up or end a motion.
    pub command_timeout: Duration,
    /// Largest wait of a step for the next state (a caller's budget can shorten it).
    pub state_wait: Duration,
    /// Ask for the robot's URDF at `open`.
    pub fetch_model: bool,
}

impl FrankaConfig {
    /// A robot at `robot` on the standard port, joint position mode with joint impedance.
    pub fn new(robot: IpAddr) -> Self {
        Self {
            robot,
            command_port: COMMAND_PORT,
            local: SocketAddr::new(IpAddr::V4(Ipv4Addr::UNSPECIFIED), 0),
            mode: ControlMode::JointPosition,
            controller: MoveControllerMode::JointImpedance,
            settings: FrankaSettings::default(),
            automatic_recovery: false,
            command_timeout: Duration::from_secs(2),
            state_wait: RECOMMENDED_STATE_WAIT,
            fetch_model: true,
        }
    }

    /// The same in `mode`.
    #[must_use]
    pub fn with_mode(mut self, mode: ControlMode) -> Self {
        self.mode = mode;
        self
    }
}

/// How the last motion ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotionEnd {
    /// As commanded (`Move` answered `Success`).
    Finished,
    /// A reflex stopped it: the errors that did (`reflex_reason`).
    Reflex(ErrorSet),
    /// The robot ended it otherwise (preempted, user stop, …).
    Aborted(MoveStatus),
}

/// What the link and the robot have seen; kept across `close`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrankaCounters {
    /// States received and used.
    pub states: u64,
    /// Commands sent.
    pub commands: u64,
    /// State ids the client did not answer: commands the robot counts lost.
    pub unanswered: u64,
    /// Steps whose command went to a newer state than the one it was computed for (the step
    /// came a cycle or more late).
    pub late_steps: u64,
    /// States older than one already used, dropped.
    pub stale_states: u64,
    /// Steps that waited for a state in vain.
    pub timeouts: u64,
    /// Datagrams from anyone but the robot.
    pub foreign: u64,
    /// Datagrams from the robot that did not decode.
    pub corrupt: u64,
    /// The current run of unanswered states.
    pub unanswered_in_a_row: u32,
    /// The longest such run.
    pub max_unanswered_in_a_row: u32,
    /// Motions the robot stopped by a reflex.
    pub reflexes: u32,
    /// Motions started.
    pub motions: u32,
    /// Automatic error recoveries done.
    pub recoveries: u32,
}

/// The motion in progress.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Motion {
    /// `Move`'s command id: its final answer carries it.
    id: u32,
    /// The robot reported the motion's modes.
    active: bool,
    /// `Move`'s final answer, once it came.
    answer: Option<MoveStatus>,
}

/// A Franka arm (FR3, Panda) over FCI. See the module documentation for the session.
#[derive(Debug)]
pub struct FrankaArm {
    config: FrankaConfig,
    lifecycle: Lifecycle,
    tcp: Option<CommandChannel>,
    udp: Option<StateChannel>,
    rx: Box<[u8; STATE_LEN + 1]>,
    state: Box<RobotState>,
    /// Whether `state` holds a received state.
    have_state: bool,
    /// The id of the last state answered.
    answered: Option<u64>,
    /// The highest state id answered or counted unanswered (during a motion).
    accounted: Option<u64>,
    command: RobotCommand,
    motion: Option<Motion>,
    last_end: Option<MotionEnd>,
    server_version: Option<u16>,
    urdf: Option<String>,
    counters: FrankaCounters,
    errors: ReflexCounts,
    /// Answers to commands other than the running `Move`, awaited outside a motion.
    awaited: Option<(u32, Status)>,
    /// The robot's cycle, measured at `open`.
    cycle: Duration,
}

impl FrankaArm {
    /// A closed device for `config`.
    pub fn new(config: FrankaConfig) -> Result<Self, Error> {
        if config.state_wait.is_zero() || config.command_timeout.is_zero() {
            return Err(Error::InvalidArgument {
                what: "Franka waits (state_wait, command_timeout) in µs",
                expected: 1,
                got: 0,
            });
        }
        Ok(Self {
            lifecycle: Lifecycle::with_failure_limit(MAX_LOST_IN_A_ROW),
            tcp: None,
            udp: None,
            rx: Box::new([0; STATE_LEN + 1]),
            state: Box::default(),
            have_state: false,
            answered: None,
            accounted: None,
            command: RobotCommand::default(),
            motion: None,
            last_end: None,
            server_version: None,
            urdf: None,
            counters: FrankaCounters::default(),
            errors: ReflexCounts::default(),
            awaited: None,
            cycle: CYCLE,
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &FrankaConfig {
        &self.config
    }

    /// Changes the control mode for the next `start` (refused while running).
    pub fn set_mode(&mut self, mode: ControlMode) -> Result<(), Error> {
        if self.lifecycle.state() == State::Running {
            return Err(Error::State {
                operation: Operation::Set,
                state: State::Running,
            });
        }
        self.config.mode = mode;
        Ok(())
    }

    /// The last state received (all of it: poses, torques, errors, modes).
    pub fn robot_state(&self) -> &RobotState {
        &self.state
    }

    /// The robot's URDF, as it sent it at `open`.
    pub fn robot_model_urdf(&self) -> Option<&str> {
        self.urdf.as_deref()
    }

    /// The version the robot reported at `open`.
    pub fn server_version(&self) -> Option<u16> {
        self.server_version
    }

    /// The counts so far.
    pub fn counters(&self) -> FrankaCounters {
        let mut c = self.counters;
        if let Some(u) = &self.udp {
            c.foreign += u.foreign;
            c.corrupt += u.wrong_length;
        }
        c
    }

    /// How often the robot raised each error (rising edges of `errors` in the states).
    pub fn reflex_counts(&self) -> &ReflexCounts {
        &self.errors
    }

    /// How the last motion ended, once it has.
    pub fn motion_end(&self) -> Option<MotionEnd> {
        self.last_end
    }

    /// The local address states arrive at (after `open`).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.udp.as_ref().and_then(|u| u.local_addr().ok())
    }

    /// The robot's UDP address, learned from its first state.
    pub fn robot_udp_addr(&self) -> Option<SocketAddr> {
        self.udp.as_ref().and_then(StateChannel::peer)
    }

    /// Clears the robot's errors (libfranka's `automaticErrorRecovery`); only while no motion
    /// runs (open).
    pub fn automatic_error_recovery(&mut self) -> Result<(), Error> {
        self.idle_command(Request::AutomaticErrorRecovery)
    }

    /// Sets contact and collision thresholds now (open: no motion runs).
    pub fn set_collision_behavior(&mut self, c: &CollisionBehavior) -> Result<(), Error> {
        self.idle_command(Request::SetCollisionBehavior(*c))
    }

    /// Sets the internal joint impedance controller's stiffness now.
    pub fn set_joint_impedance(&mut self, k_theta: &[f64; DOF]) -> Result<(), Error> {
        self.idle_command(Request::SetJointImpedance(*k_theta))
    }

    /// Sets the internal Cartesian impedance controller's stiffness now.
    pub fn set_cartesian_impedance(&mut self, k_x: &[f64; 6]) -> Result<(), Error> {
        self.idle_command(Request::SetCartesianImpedance(*k_x))
    }

    /// Sets `NE_T_EE` now.
    pub fn set_ee(&mut self, ne_t_ee: &[f64; 16]) -> Result<(), Error> {
        self.idle_command(Request::SetNeToEe(*ne_t_ee))
    }

    /// Sets `EE_T_K` now.
    pub fn set_k(&mut self, ee_t_k: &[f64; 16]) -> Result<(), Error> {
        self.idle_command(Request::SetEeToK(*ee_t_k))
    }

    /// Sets the load now.
    pub fn set_load(&mut self, load: &Load) -> Result<(), Error> {
        self.idle_command(Request::SetLoad(*load))
    }

    /// A configuration command outside a motion (the device open, not running).
    fn idle_command(&mut self, request: Request) -> Result<(), Error> {
        let state = self.lifecycle.state();
        if state != State::Open {
            return Err(Error::State {
                operation: Operation::Set,
                state,
            });
        }
        self.execute(Operation::Set, request)
    }

    fn tcp(&mut self, operation: Operation) -> Result<&mut CommandChannel, Error> {
        self.tcp.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })
    }

    fn link_error(operation: Operation, e: LinkError) -> Error {
        match e {
            LinkError::Io(e) if e.kind() == std::io::ErrorKind::TimedOut => Error::Timeout {
                operation,
                waited: Duration::ZERO,
            },
            LinkError::Io(e) => Error::io(operation, &e),
            LinkError::Closed => Error::Disconnected { operation },
            LinkError::Message(m) => Error::protocol(operation, "Franka TCP answer", &m),
        }
    }

    /// Handles one TCP answer: the running `Move`'s final answer, or one being awaited.
    fn on_answer(&mut self, a: Answer) {
        if let (Some(m), Status::Move(s)) = (&mut self.motion, a.status)
            && a.header.command == Command::Move
            && a.header.command_id == m.id
            && s != MoveStatus::MotionStarted
        {
            m.answer = Some(s);
            return;
        }
        self.awaited = Some((a.header.command_id, a.status));
    }

    /// Polls the TCP channel (non-blocking) and dispatches what it holds.
    fn poll_tcp(&mut self, operation: Operation) -> Result<(), Error> {
        let mut answers: [Option<Answer>; 8] = [None; 8];
        let mut n = 0;
        let mut urdf: Option<String> = None;
        let tcp = self.tcp(operation)?;
        // Only outside a motion (a URDF is copied into a new string).
        let accept_urdf = tcp.may_grow;
        tcp.poll(|a, rest| {
            if accept_urdf && a.header.command == Command::GetRobotModel {
                urdf = Some(String::from_utf8_lossy(rest).into_owned());
            }
            if let Some(slot) = answers.get_mut(n) {
                *slot = Some(a);
                n += 1;
            }
        })
        .map_err(|e| Self::link_error(operation, e))?;
        if urdf.is_some() {
            self.urdf = urdf;
        }
        for a in answers.into_iter().flatten() {
            self.on_answer(a);
        }
        Ok(())
    }

    /// Sends `request` and waits (bounded) for its answer, reading states meanwhile so the
    /// newest is known; returns its status.
    fn request(&mut self, operation: Operation, request: Request) -> Result<Status, Error> {
        let deadline = Instant::now() + self.config.command_timeout;
        self.awaited = None;
        let id = self
            .tcp(operation)?
            .send(&request, deadline)
            .map_err(|e| Self::link_error(operation, e))?;
        loop {
            self.poll_tcp(operation)?;
            // Another id is a stray answer (to a motion given up on): dropped.
            if let Some((got, status)) = self.awaited.take()
                && got == id
            {
                return Ok(status);
            }
            self.drain_states(operation)?;
            let now = Instant::now();
            if now >= deadline {
                return Err(Error::Timeout {
                    operation,
                    waited: self.config.command_timeout,
                });
            }
            let tcp = self.tcp(operation)?;
            tcp.wait(deadline.min(now + Duration::from_millis(5)))
                .map_err(|e| Error::io(operation, &e))?;
        }
    }

    /// [`request`](Self::request) that must succeed.
    fn execute(&mut self, operation: Operation, request: Request) -> Result<(), Error> {
        let status = self.request(operation, request)?;
        if status.is_success() {
            if request == Request::AutomaticErrorRecovery {
                self.counters.recoveries += 1;
            }
            Ok(())
        } else {
            Err(refused(operation, request.command(), status))
        }
    }

    /// Takes every pending state without waiting; keeps the newest. Returns whether one came.
    fn drain_states(&mut self, operation: Operation) -> Result<bool, Error> {
        let mut any = false;
        let deadline = Instant::now() + CYCLE;
        while self.receive(operation, deadline, false)? {
            any |= self.take_state();
        }
        Ok(any)
    }

    /// One datagram from the robot into `rx`: what is pending, or (`wait`) the next until
    /// `deadline`. `Ok(false)`: none.
    fn receive(
        &mut self,
        operation: Operation,
        deadline: Instant,
        wait: bool,
    ) -> Result<bool, Error> {
        let udp = self.udp.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })?;
        let got = if wait {
            udp.recv_until(&mut self.rx, deadline)
        } else {
            udp.try_recv(&mut self.rx, deadline)
        };
        got.map_err(|e| Error::io(operation, &e))
    }

    /// Decodes the datagram in `rx`; uses it if it is newer than the last. Returns whether it
    /// was used.
    fn take_state(&mut self) -> bool {
        let id = u64::from_le_bytes(self.rx[..8].try_into().unwrap_or_default());
        if self.have_state && id <= self.state.message_id {
            self.counters.stale_states += 1;
            return false;
        }
        if self.state.decode_into(&self.rx[..STATE_LEN]).is_err() {
            self.counters.corrupt += 1;
            return false;
        }
        self.have_state = true;
        self.counters.states += 1;
        self.errors.record(self.state.errors);
        // Ids between the last one accounted for and this one were never answered.
        if let Some(done) = self.accounted {
            let skipped = id.saturating_sub(done).saturating_sub(1);
            if skipped > 0 {
                self.counters.unanswered += skipped;
                let run = self.counters.unanswered_in_a_row;
                self.counters.unanswered_in_a_row =
                    run.saturating_add(u32::try_from(skipped).unwrap_or(u32::MAX));
                self.counters.max_unanswered_in_a_row = self
                    .counters
                    .max_unanswered_in_a_row
                    .max(self.counters.unanswered_in_a_row);
            }
            self.accounted = Some(done.max(id - 1));
        }
        true
    }

    /// Waits (bounded) for a state newer than the one held.
    fn wait_state(&mut self, operation: Operation, deadline: Instant) -> Result<bool, Error> {
        loop {
            if !self.receive(operation, deadline, true)? {
                return Ok(false);
            }
            if self.take_state() {
                return Ok(true);
            }
        }
    }

    /// Answers state `id` with the buffered command.
    fn send_command(&mut self, operation: Operation, id: u64) -> Result<(), Error> {
        if self.answered.is_some_and(|a| a >= id) {
            return Ok(());
        }
        self.command.message_id = id;
        let udp = self.udp.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })?;
        udp.send(&self.command)
            .map_err(|e| Error::io(operation, &e))?;
        self.counters.commands += 1;
        self.answered = Some(id);
        if self.accounted.is_some_and(|a| a < id) || self.accounted.is_none() {
            self.accounted = Some(id);
        }
        self.counters.unanswered_in_a_row = 0;
        Ok(())
    }

    /// The buffered command set to hold where the robot is.
    fn hold_command(&mut self) {
        self.command = RobotCommand {
            message_id: self.state.message_id,
            motion: MotionGeneratorCommand {
                q_c: self.state.q_d,
                O_T_EE_c: self.state.O_T_EE_d,
                elbow_c: self.state.elbow_d,
                ..MotionGeneratorCommand::default()
            },
            control: ControllerCommand::default(),
        };
    }

    /// The motion ended: records how, and the error it is to the caller (none if finished).
    fn end_motion(&mut self, operation: Operation, end: MotionEnd) -> Option<Error> {
        self.motion = None;
        self.last_end = Some(end);
        match end {
            MotionEnd::Finished => None,
            MotionEnd::Reflex(reasons) => {
                self.counters.reflexes += 1;
                Some(Error::device(operation, "Franka reflex", &reasons))
            }
            MotionEnd::Aborted(s) => Some(Error::device(operation, "Franka Move", &s)),
        }
    }

    /// Checks the newest state and TCP answers for the motion's end.
    fn check_motion(&mut self, operation: Operation) -> Result<(), Error> {
        let Some(m) = self.motion else {
            return Ok(());
        };
        if m.answer == Some(MoveStatus::ReflexAborted) && self.state.robot_mode != RobotMode::Reflex
        {
            // The answer can overtake the state that says why: wait for it (bounded).
            let deadline = Instant::now() + 10 * CYCLE;
            while self.state.robot_mode != RobotMode::Reflex
                && self.wait_state(operation, deadline)?
            {}
        }
        let reflex = self.state.robot_mode == RobotMode::Reflex;
        let end = match m.answer {
            Some(MoveStatus::Success) => Some(MotionEnd::Finished),
            Some(MoveStatus::ReflexAborted) => Some(MotionEnd::Reflex(self.state.reflex_reason)),
            Some(s) => Some(MotionEnd::Aborted(s)),
            None if reflex => Some(MotionEnd::Reflex(self.state.reflex_reason)),
            None => None,
        };
        match end {
            Some(MotionEnd::Finished) if operation == Operation::Step => {
                // The robot ended a motion nobody asked it to end.
                self.end_motion(operation, MotionEnd::Finished);
                Err(Error::device(
                    operation,
                    SOURCE,
                    &"the robot ended the motion unasked",
                ))
            }
            Some(e) => self.end_motion(operation, e).map_or(Ok(()), Err),
            None => Ok(()),
        }
    }

    fn check_command(&self, mode: ControlMode, len: usize) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        Error::check_len("joint vector length", DOF, len)?;
        if self.config.mode != mode {
            return Err(Error::InvalidArgument {
                what: match mode {
                    ControlMode::JointPosition => {
                        "joint position command: the arm is configured for another mode"
                    }
                    ControlMode::JointVelocity => {
                        "joint velocity command: the arm is configured for another mode"
                    }
                    ControlMode::JointTorque => {
                        "joint torque command: the arm is configured for another mode"
                    }
                },
                expected: 0,
                got: 0,
            });
        }
        Ok(())
    }

    fn read(&self, values: &[f64; DOF], out: &mut [f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", DOF, out.len())?;
        if !self.have_state {
            return Err(Error::protocol(
                Operation::Get,
                SOURCE,
                &"no state received yet",
            ));
        }
        out.copy_from_slice(values);
        Ok(())
    }

    /// Runs the motion's end as libfranka does: the finishing flag in every command until the
    /// robot is idle, then `Move`'s final answer; bounded by the command timeout.
    fn finish_motion(&mut self, operation: Operation) -> Result<(), Error> {
        let deadline = Instant::now() + self.config.command_timeout;
        match self.config.mode {
            ControlMode::JointTorque => self.command.control.torque_command_finished = true,
            _ => self.command.motion.motion_generation_finished = true,
        }
        loop {
            self.poll_tcp(operation)?;
            if let Some(m) = self.motion
                && m.answer.is_some()
            {
                return self.check_motion(operation);
            }
            let idle = matches!(self.state.motion_generator_mode, MotionGeneratorMode::Idle)
                && self.state.controller_mode != ControllerMode::ExternalController;
            if !idle {
                let id = self.state.message_id;
                self.send_command(operation, id)?;
            }
            if Instant::now() >= deadline {
                return Err(Error::Timeout {
                    operation,
                    waited: self.config.command_timeout,
                });
            }
            let next = (Instant::now() + self.config.state_wait).min(deadline);
            if self.wait_state(operation, next)? && self.state.robot_mode == RobotMode::Reflex {
                return self.check_motion(operation);
            }
            if idle {
                let tcp = self.tcp(operation)?;
                tcp.wait((Instant::now() + CYCLE).min(deadline))
                    .map_err(|e| Error::io(operation, &e))?;
            }
        }
    }
}

/// A command the robot refused.
fn refused(operation: Operation, command: Command, status: Status) -> Error {
    struct Refusal(Command, Status);
    impl core::fmt::Display for Refusal {
        fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
            write!(f, "{}: {}", self.0, self.1)
        }
    }
    Error::device(operation, SOURCE, &Refusal(command, status))
}

impl Driver for FrankaArm {
    const STOP_DESCRIPTION: &'static str = "motion finished, robot idle";
    /// The robot sends a state every millisecond on its own clock.
    const RUNS_OWN_CYCLE: bool = true;

    fn open_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Open;
        let timeout = self.config.command_timeout;
        let peer = SocketAddr::new(self.config.robot, self.config.command_port);
        let tcp = CommandChannel::connect(peer, timeout).map_err(|e| {
            if e.kind() == std::io::ErrorKind::TimedOut {
                Error::Timeout {
                    operation: OP,
                    waited: timeout,
                }
            } else {
                Error::io(OP, &e)
            }
        })?;
        let udp = StateChannel::bind(self.config.local, self.config.robot)
            .map_err(|e| Error::io(OP, &e))?;
        let port = udp.local_addr().map_err(|e| Error::io(OP, &e))?.port();
        self.tcp = Some(tcp);
        self.udp = Some(udp);
        self.have_state = false;
        self.answered = None;
        self.motion = None;
        let opened = self.connect(OP, port);
        if opened.is_err() {
            self.tcp = None;
            self.udp = None;
        }
        opened
    }

    fn start_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Start;
        self.poll_tcp(OP)?;
        self.drain_states(OP)?;
        if !self.have_state {
            let deadline = Instant::now() + self.config.command_timeout;
            if !self.wait_state(OP, deadline)? {
                return Err(Error::Timeout {
                    operation: OP,
                    waited: self.config.command_timeout,
                });
            }
        }
        let in_error = !self.state.errors.is_empty() || self.state.robot_mode == RobotMode::Reflex;
        if in_error && self.config.automatic_recovery {
            self.execute(OP, Request::AutomaticErrorRecovery)?;
        }
        let s = self.config.settings;
        let requests = [
            s.collision_behavior.map(Request::SetCollisionBehavior),
            s.joint_impedance.map(Request::SetJointImpedance),
            s.cartesian_impedance.map(Request::SetCartesianImpedance),
            s.ne_t_ee.map(Request::SetNeToEe),
            s.ee_t_k.map(Request::SetEeToK),
            s.load.map(Request::SetLoad),
        ];
        for r in requests.into_iter().flatten() {
            self.execute(OP, r)?;
        }
        let mode = self.config.mode;
        let controller = match mode {
            ControlMode::JointTorque => MoveControllerMode::ExternalController,
            _ => self.config.controller,
        };
        let request = Request::Move(MoveRequest {
            controller_mode: controller,
            motion_generator_mode: mode.motion_generator(),
            maximum_path_deviation: Deviation::DEFAULT,
            maximum_goal_pose_deviation: Deviation::DEFAULT,
            async_maximum_velocity: None,
        });
        let deadline = Instant::now() + self.config.command_timeout;
        let id = {
            let tcp = self.tcp(OP)?;
            tcp.send(&request, deadline)
                .map_err(|e| Self::link_error(OP, e))?
        };
        self.motion = Some(Motion {
            id,
            active: false,
            answer: None,
        });
        self.counters.motions += 1;
        let want_controller = match controller {
            MoveControllerMode::JointImpedance => ControllerMode::JointImpedance,
            MoveControllerMode::CartesianImpedance => ControllerMode::CartesianImpedance,
            MoveControllerMode::ExternalController => ControllerMode::ExternalController,
        };
        // As libfranka: states until the robot runs the motion's modes; a refusal ends it.
        loop {
            self.poll_tcp(OP)?;
            if let Some((got, status)) = self.awaited.take() {
                if got == id && status != Status::Move(MoveStatus::MotionStarted) {
                    self.motion = None;
                    return Err(refused(OP, Command::Move, status));
                }
            }
            if let Some(m) = self.motion
                && m.answer.is_some()
            {
                self.check_motion(OP)?;
                return Err(Error::device(OP, SOURCE, &"the motion ended as it started"));
            }
            if self.state.motion_generator_mode == mode.state_motion_generator()
                && self.state.controller_mode == want_controller
                && self.state.robot_mode == RobotMode::Move
            {
                break;
            }
            if Instant::now() >= deadline {
                self.motion = None;
                return Err(Error::Timeout {
                    operation: OP,
                    waited: self.config.command_timeout,
                });
            }
            let next = (Instant::now() + self.config.state_wait).min(deadline);
            self.wait_state(OP, next)?;
        }
        if let Some(m) = &mut self.motion {
            m.active = true;
        }
        self.hold_command();
        // While the motion runs, the answer buffer does not grow.
        self.tcp(OP)?.may_grow = false;
        self.answered = None;
        self.accounted = Some(self.state.message_id.saturating_sub(1));
        self.counters.unanswered_in_a_row = 0;
        Ok(())
    }

    fn stop_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Stop;
        let mut steps = FirstError::default();
        if self.motion.is_some() {
            let finished = self.finish_motion(OP);
            if finished.is_err() && self.motion.is_some() {
                // The robot did not end it: StopMove.
                steps.keep(finished);
                let stopped = self.execute(OP, Request::StopMove);
                self.motion = None;
                steps.keep(stopped);
            } else {
                steps.keep(finished);
            }
        }
        if let Some(tcp) = &mut self.tcp {
            tcp.may_grow = true;
        }
        if self.config.automatic_recovery && matches!(self.last_end, Some(MotionEnd::Reflex(_))) {
            steps.keep(self.execute(OP, Request::AutomaticErrorRecovery));
        }
        steps.into_result()
    }

    fn close_sequence(&mut self) -> Result<(), Error> {
        if let Some(u) = &self.udp {
            self.counters.foreign += u.foreign;
            self.counters.corrupt += u.wrong_length;
        }
        self.tcp = None;
        self.udp = None;
        self.motion = None;
        Ok(())
    }

    /// The robot's cycle: 1 ms, or a slower simulator's measured one ([`FrankaArm::cycle`]).
    fn period(&self) -> Duration {
        self.cycle
    }

    fn exchange(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Step;
        // A simulator slower than the robot gets two of its cycles.
        let state_wait = self.config.state_wait.max(2 * self.cycle);
        let wait = self
            .lifecycle
            .step_budget()
            .map_or(state_wait, |b| b.min(state_wait));
        let begin = Instant::now();
        // A motion's end comes over TCP.
        let ended = self.poll_tcp(OP).and_then(|()| self.check_motion(OP));
        if let Err(e) = ended {
            return Err(self.lifecycle.fail(e));
        }
        // The command answers the state it was computed from (as libfranka's does); a newer
        // state already waiting means this step came late, and the robot may count it so.
        let answering = self.state.message_id;
        self.drain_states(OP)?;
        if self.state.message_id != answering {
            self.counters.late_steps += 1;
        }
        self.send_command(OP, answering)?;
        if self.state.robot_mode == RobotMode::Reflex
            && let Err(e) = self.check_motion(OP)
        {
            return Err(self.lifecycle.fail(e));
        }
        if self.state.message_id != answering {
            // A fresh state is here already.
            return Ok(());
        }
        let deadline = begin + wait;
        if self.wait_state(OP, deadline)? {
            if self.state.robot_mode == RobotMode::Reflex
                && let Err(e) = self.check_motion(OP)
            {
                return Err(self.lifecycle.fail(e));
            }
            Ok(())
        } else {
            self.counters.timeouts += 1;
            Err(Error::Timeout {
                operation: OP,
                waited: wait,
            })
        }
    }
}

impl FrankaArm {
    /// `Connect`, the first state, the URDF.
    fn connect(&mut self, operation: Operation, udp_port: u16) -> Result<(), Error> {
        let deadline = Instant::now() + self.config.command_timeout;
        let request = Request::Connect(ConnectRequest::new(udp_port));
        let tcp = self.tcp(operation)?;
        let id = tcp
            .send(&request, deadline)
            .map_err(|e| Self::link_error(operation, e))?;
        // The version follows the status byte: read the raw answer.
        let mut answer: Option<Result<ConnectResponse, Error>> = None;
        loop {
            let tcp = self.tcp(operation)?;
            tcp.poll(|a, rest| {
                if a.header.command == Command::Connect && a.header.command_id == id {
                    let mut payload = [0u8; 8];
                    let n = (rest.len() + 1).min(8);
                    payload[0] = a.status.code();
                    payload[1..n].copy_from_slice(&rest[..n - 1]);
                    answer = Some(
                        ConnectResponse::decode(&payload[..rest.len() + 1])
                            .map_err(|e| Error::protocol(operation, "Franka Connect", &e)),
                    );
                }
            })
            .map_err(|e| Self::link_error(operation, e))?;
            if let Some(a) = answer.take() {
                let response = a?;
                self.server_version = Some(response.version);
                response
                    .check(VERSION)
                    .map_err(|v| Error::device(operation, "Franka Connect", &v))?;
                break;
            }
            if Instant::now() >= deadline {
                return Err(Error::Timeout {
                    operation,
                    waited: self.config.command_timeout,
                });
            }
            tcp.wait(deadline).map_err(|e| Error::io(operation, &e))?;
        }
        if !self.wait_state(operation, deadline)? {
            return Err(Error::Timeout {
                operation,
                waited: self.config.command_timeout,
            });
        }
        self.measure_cycle(operation)?;
        if self.config.fetch_model {
            self.urdf = None;
            let status = self.request(operation, Request::GetRobotModel)?;
            if status != Status::Base(BaseStatus::Success) {
                return Err(refused(operation, Command::GetRobotModel, status));
            }
            if self.urdf.as_deref().is_none_or(str::is_empty) {
                return Err(Error::protocol(
                    operation,
                    "Franka Get Robot Model",
                    &"the robot sent no URDF",
                ));
            }
        }
        Ok(())
    }
}

impl FrankaArm {
    /// Times the robot's states for 20 intervals (at most half a second): a robot sends one
    /// a millisecond, and its cycle is [`CYCLE`]; a simulator slower than real time
    /// (franky-sim: about one every 4 ms on a 2-vCPU VM) is followed at its pace, so a loop
    /// steps once per state. The median interval counts, rounded to 0.1 ms; below 1.5 ms it is
    /// the robot's 1 ms.
    fn measure_cycle(&mut self, operation: Operation) -> Result<(), Error> {
        let mut intervals = [Duration::ZERO; 20];
        let mut n = 0;
        let deadline = Instant::now() + Duration::from_millis(500);
        let mut last = Instant::now();
        let mut last_id = self.state.message_id;
        while n < intervals.len() && self.wait_state(operation, deadline)? {
            let now = Instant::now();
            let ids = self.state.message_id.saturating_sub(last_id).max(1);
            // Per state id: a lost datagram does not lengthen the cycle.
            intervals[n] = (now - last) / u32::try_from(ids).unwrap_or(u32::MAX);
            last = now;
            last_id = self.state.message_id;
            n += 1;
        }
        let measured = &mut intervals[..n];
        measured.sort();
        let median = measured.get(n / 2).copied().unwrap_or(CYCLE);
        self.cycle = if median < CYCLE * 3 / 2 {
            CYCLE
        } else {
            Duration::from_micros(((median.as_micros() as u64).div_ceil(100)) * 100)
        };
        Ok(())
    }

    /// The robot's cycle as measured at `open` ([`CYCLE`] for a real robot).
    pub fn cycle(&self) -> Duration {
        self.cycle
    }
}

impl_cyclic_device!(FrankaArm, lifecycle);

impl LinkStatisticsSensor for FrankaArm {
    fn link_statistics(&self) -> LinkStatistics {
        let c = self.counters();
        LinkStatistics {
            sent: c.commands,
            received: c.states,
            lost: c.unanswered + c.timeouts,
            late: c.late_steps + c.stale_states,
            rejected: c.foreign,
            corrupt: c.corrupt,
            consecutive_failures: self
                .lifecycle
                .consecutive_failures()
                .max(c.unanswered_in_a_row),
            delivery: Delivery::default(),
        }
    }
}

impl JointDevice for FrankaArm {
    fn dof(&self) -> usize {
        DOF
    }

    fn joint_velocity_actuator(&mut self) -> Option<&mut dyn JointVelocityActuator<Error = Error>> {
        (self.config.mode == ControlMode::JointVelocity).then_some(self as _)
    }

    fn joint_torque_actuator(&mut self) -> Option<&mut dyn JointTorqueActuator<Error = Error>> {
        (self.config.mode == ControlMode::JointTorque).then_some(self as _)
    }

    fn joint_velocity_sensor(&self) -> Option<&dyn JointVelocitySensor<Error = Error>> {
        Some(self)
    }

    fn joint_torque_sensor(&self) -> Option<&dyn JointTorqueSensor<Error = Error>> {
        Some(self)
    }
}

impl JointPositionSensor for FrankaArm {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        self.read(&self.state.q, q)
    }

    /// Joints travel as `f32`: half a unit in the last place at `q`.
    fn joint_position_resolution(&self, q: f64) -> f64 {
        #[allow(clippy::cast_possible_truncation)]
        let f = (q as f32).abs();
        if !f.is_finite() {
            return 0.0;
        }
        0.5 * f64::from(f32::from_bits(f.to_bits() + 1) - f)
    }

    /// The state's `message_id`: one per robot cycle.
    fn joint_position_sample(&self) -> Option<u64> {
        self.have_state.then_some(self.state.message_id)
    }
}

impl JointVelocitySensor for FrankaArm {
    fn joint_velocity(&self, dq: &mut [f64]) -> Result<(), Error> {
        self.read(&self.state.dq, dq)
    }
}

impl JointTorqueSensor for FrankaArm {
    /// The measured link-side torques `tau_J` (gravity included).
    fn joint_torque(&self, tau: &mut [f64]) -> Result<(), Error> {
        self.read(&self.state.tau_J, tau)
    }
}

impl JointPositionActuator for FrankaArm {
    /// Buffers `q_c` (joint position mode).
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Error> {
        self.check_command(ControlMode::JointPosition, q.len())?;
        self.command.motion.q_c.copy_from_slice(q);
        Ok(())
    }
}

impl JointVelocityActuator for FrankaArm {
    /// Buffers `dq_c` (joint velocity mode).
    fn set_joint_velocity(&mut self, dq: &[f64]) -> Result<(), Error> {
        self.check_command(ControlMode::JointVelocity, dq.len())?;
        self.command.motion.dq_c.copy_from_slice(dq);
        Ok(())
    }
}

impl JointTorqueActuator for FrankaArm {
    /// Buffers `tau_J_d` (joint torque mode): the torques beyond gravity, which the robot
    /// compensates itself.
    fn set_joint_torque(&mut self, tau: &[f64]) -> Result<(), Error> {
        self.check_command(ControlMode::JointTorque, tau.len())?;
        if tau.iter().any(|t| !t.is_finite()) {
            return Err(Error::InvalidArgument {
                what: "joint torque command: a value is not finite",
                expected: 0,
                got: 0,
            });
        }
        self.command.control.tau_J_d.copy_from_slice(tau);
        Ok(())
    }

    fn adds_gravity(&self) -> bool {
        true
    }

    /// The last state's `tau_J_d`: the command the robot received last, which it compares the
    /// next with (its torque-rate limit).
    fn applied_joint_torque(&self, tau: &mut [f64]) -> bool {
        self.read(&self.state.tau_J_d, tau).is_ok()
    }
}

impl CartesianPositionSensor for FrankaArm {
    /// The measured end-effector pose `O_T_EE`.
    fn cartesian_position(&self) -> Result<Pose, Error> {
        self.lifecycle.check(Operation::Get)?;
        let m = &self.state.O_T_EE;
        let rotation =
            glam::DMat3::from_cols_array(&[m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]]);
        Ok(Pose::new(rotation, glam::DVec3::new(m[12], m[13], m[14])))
    }
}

impl ControlMode {
    /// The mode's name, for messages.
    pub const fn describe(self) -> &'static str {
        self.name()
    }
}
