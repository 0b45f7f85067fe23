//! The control cycle: read, supervise, take inputs, run the law, check its command, send it,
//! step.

use core::fmt;
use std::time::Duration;

use rl_core::{Data, Model};
use rl_drivers::safety::{StopReason, Verdict};
use rl_drivers::{Error as DeviceError, LinkStatistics, State};
use rl_rt::MonoTime;

use super::follower::TrajectoryFollower;
use super::input::{InputReceiver, InputReport, Inputs};
use super::law::{BrakeReason, Command, CommandMode, Context, ControlLaw, LawStatus, Measured};
use super::plan::{MotionLimits, Plan, PlanError, check_model};
use super::robot::JointRobot;
use super::safety::SafetyBox;
use super::supervise::{Bounds, Fault, Observation, Supervision, Supervisor, measurement_gap};
use super::telemetry::{CycleRecord, RunState};
use super::tracking::{Tracking, Violation};
use super::{DEFAULT_BODIES, DEFAULT_JOINTS};

/// Tolerance on measured positions against the model's limits (rad or m), beyond the device's
/// resolution, for the statistics of limit violations.
const POSITION_TOLERANCE: f64 = 1e-5;

/// How long a law may take to come to rest by default.
pub const DEFAULT_MAX_BRAKING: Duration = Duration::from_secs(10);

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RunEnd {
    /// The law's motion ran to its end (a trajectory's end).
    Completed,
    /// The duration ended; the arm was brought to rest.
    CycleLimit,
    /// A stop was requested; the arm was brought to rest.
    Stopped,
    /// A second stop request ended the run at once (the arm may still have been moving).
    Aborted,
    /// No input came for longer than the input timeout; the arm was brought to rest.
    InputsStale,
    /// The law did not bring the arm to rest within the braking bound; the run ended at once.
    BrakeTimeout,
    /// A fault ended the run: at rest through the law, or at once when the link or the device
    /// could no longer carry a command ([`Fault::stops_at_once`]).
    Fault(Fault),
}

impl RunEnd {
    /// Whether the run counts as failed.
    pub fn is_failure(&self) -> bool {
        matches!(
            self,
            Self::Fault(_) | Self::InputsStale | Self::BrakeTimeout
        )
    }

    /// Whether the run was interrupted by a stop request.
    pub fn is_interrupted(&self) -> bool {
        matches!(self, Self::Stopped | Self::Aborted)
    }
}

impl fmt::Display for RunEnd {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Completed => f.write_str("completed"),
            Self::CycleLimit => f.write_str("duration reached, brought to rest"),
            Self::Stopped => f.write_str("stopped on request, brought to rest"),
            Self::Aborted => f.write_str("aborted on a second request"),
            Self::InputsStale => f.write_str("inputs stopped coming, brought to rest"),
            Self::BrakeTimeout => {
                f.write_str("the law did not come to rest within its braking time; stopped at once")
            }
            Self::Fault(fault) if fault.stops_at_once() => {
                write!(f, "fault, stopped at once: {fault}")
            }
            Self::Fault(fault) => write!(f, "fault, brought to rest: {fault}"),
        }
    }
}

impl RunEnd {
    /// As its `Display`, with the joints of a fault named from `joints` (the `Display` numbers
    /// them, `#4`).
    pub fn describe(&self, joints: &[String]) -> String {
        match self {
            Self::Fault(fault) if fault.stops_at_once() => {
                format!("fault, stopped at once: {}", fault.describe(joints))
            }
            Self::Fault(fault) => format!("fault, brought to rest: {}", fault.describe(joints)),
            other => other.to_string(),
        }
    }
}

/// When the first fault was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultAt {
    /// The cycle.
    pub cycle: u64,
    /// That cycle's time (the telemetry's `t_s`), s.
    pub time_s: f64,
}

/// The loop's timing of one cycle, for the supervisor and the device's step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CycleTiming {
    /// Deadlines skipped right before this cycle.
    pub skipped_deadlines: u64,
    /// Whether the previous cycle overran its period.
    pub overran: bool,
    /// The time left for the device's step before the loop's next deadline: a reply that has
    /// not come by then is counted lost and the cycle goes on (`None`: the device's own
    /// bound).
    pub step_budget: Option<Duration>,
}

/// What one cycle did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleResult<const J: usize> {
    /// The cycle's record (latency and step time are left for the loop to fill).
    pub record: CycleRecord<J>,
    /// Whether the run is over (the device was not stepped in this cycle).
    pub finished: bool,
}

/// The measured state the controller keeps (last reply).
#[derive(Clone, Copy, Debug)]
struct Feedback<const J: usize> {
    position: [f64; J],
    previous: [f64; J],
    velocity: [f64; J],
    torque: [f64; J],
    applied_torque: [f64; J],
    resolution: [f64; J],
    has_velocity: bool,
    has_torque: bool,
    has_applied_torque: bool,
    fresh: bool,
    previous_fresh: bool,
    /// The device's count of its measurements (where it numbers them) at the last fresh
    /// one, and how many of its periods passed between the two last fresh ones.
    last_fresh_sample: Option<u64>,
    samples_between: Option<u64>,
}

/// How the run is being ended.
#[derive(Clone, Copy, Debug, Default)]
struct Ending {
    /// Why the law was asked to brake.
    braking: Option<BrakeReason>,
    /// Cycles since braking began (asked, or the law's own).
    braking_cycles: u64,
    /// A second stop request.
    abort: bool,
    /// The run's duration in cycles, and whether the law arranges it itself.
    cycle_limit: Option<(u64, bool)>,
}

/// The supervised controller: one [`cycle`](Self::cycle) per control period runs the law `L`
/// for a model of up to `B` moving bodies and `J` joints on the device `R`. By default the law
/// is the [`TrajectoryFollower`] (what `rl run` executes).
pub struct Controller<
    R,
    const B: usize = DEFAULT_BODIES,
    const J: usize = DEFAULT_JOINTS,
    L: ControlLaw<B, J> = TrajectoryFollower<J>,
> {
    robot: R,
    model: Model<B>,
    /// Boxed: a large model's workspace (1.3 MB at 256 bodies) is no stack value.
    data: Box<Data<B>>,
    law: L,
    mode: CommandMode,
    dof: usize,
    period_s: f64,
    cycle: u64,
    /// What was commanded for this cycle: the position, or the law's reference.
    setpoint: [f64; J],
    command: Command<J>,
    feedback: Feedback<J>,
    speed_limit: [f64; J],
    effort_limit: [f64; J],
    limit_reached: [bool; J],
    tracking: Tracking<J>,
    supervisor: Supervisor<J>,
    failed_steps: u64,
    last_step_error: Option<DeviceError>,
    torque_clamped: u64,
    fault: Option<Fault>,
    fault_at: Option<FaultAt>,
    /// The current cycle and its time, for `fault_at`.
    now: FaultAt,
    ending: Ending,
    max_braking_cycles: u64,
    receiver: Option<InputReceiver<J, L::Input>>,
    inputs: Inputs<J, L::Input>,
    input_timeout_ns: Option<u64>,
    safety: Option<SafetyBox>,
    end: Option<RunEnd>,
}

impl<R: JointRobot, const B: usize, const J: usize> Controller<R, B, J, TrajectoryFollower<J>> {
    /// A controller following `plan` on a started `robot` whose last reply holds the plan's
    /// start, running every `period`, supervised with the default [`Supervision`].
    pub fn new(
        robot: R,
        model: Model<B>,
        plan: Plan<J>,
        period: Duration,
    ) -> Result<Self, PlanError> {
        Self::with_supervision(robot, model, plan, period, &Supervision::default())
    }

    /// A controller following `plan` with explicit supervision.
    pub fn with_supervision(
        robot: R,
        model: Model<B>,
        plan: Plan<J>,
        period: Duration,
        supervision: &Supervision,
    ) -> Result<Self, PlanError> {
        if plan.dof() != model.dof() {
            return Err(PlanError::Length {
                what: "the plan".into(),
                expected: model.dof(),
                got: plan.dof(),
            });
        }
        let start = plan.points()[0];
        let limits = *plan.limits();
        let dof = model.dof();
        let law = TrajectoryFollower::new(plan, period);
        Self::with_law(
            robot,
            model,
            law,
            &start[..dof],
            &limits,
            period,
            supervision,
        )
    }

    /// The plan.
    pub fn plan(&self) -> &Plan<J> {
        self.law.plan()
    }

    /// The trajectory clock.
    pub fn clock(&self) -> &super::TrajectoryClock {
        self.law.clock()
    }

    /// Restarts the trajectory from its beginning (for benchmarks: the plan returns to its
    /// start, so the command stays continuous).
    pub fn rewind(&mut self) {
        self.law.rewind();
        self.cycle = 0;
        self.ending = Ending::default();
        self.end = None;
    }
}

impl<R: JointRobot, const B: usize, const J: usize, L: ControlLaw<B, J>> Controller<R, B, J, L> {
    /// A controller running `law` on a started `robot` whose last reply holds `start`, every
    /// `period`, with the supervisor's bounds from `limits`' speed limits (the model's, or the
    /// speed assumed where it gives none). Refused when the model does not fit the capacity or
    /// the device, or when the device takes no command of the law's [`CommandMode`].
    pub fn with_law(
        mut robot: R,
        model: Model<B>,
        law: L,
        start: &[f64],
        limits: &MotionLimits<J>,
        period: Duration,
        supervision: &Supervision,
    ) -> Result<Self, PlanError> {
        check_model::<B, J>(&model)?;
        let dof = model.dof();
        if robot.dof() != dof {
            return Err(PlanError::DeviceJoints {
                model: dof,
                device: robot.dof(),
            });
        }
        if start.len() != dof {
            return Err(PlanError::Length {
                what: "the start".into(),
                expected: dof,
                got: start.len(),
            });
        }
        let period_s = period.as_secs_f64();
        if period_s.is_nan() || period_s <= 0.0 {
            return Err(PlanError::Trajectory(
                rl_core::traj::TrajectoryError::BadDuration,
            ));
        }
        let mode = law.mode();
        let takes = match mode {
            CommandMode::Position => true,
            CommandMode::Velocity => robot.joint_velocity_actuator().is_some(),
            CommandMode::Torque => robot.joint_torque_actuator().is_some(),
        };
        if !takes {
            return Err(PlanError::CommandMode { mode });
        }
        let bounds =
            supervision_bounds(&model, limits, supervision, period_s, robot.update_period());
        let mut position = [0.0; J];
        position[..dof].copy_from_slice(start);
        let mut effort_limit = [f64::INFINITY; J];
        for (k, e) in effort_limit.iter_mut().enumerate().take(dof) {
            let effort = model.limits(k).effort;
            if effort > 0.0 {
                *e = effort;
            }
        }
        Ok(Self {
            robot,
            model,
            data: Box::new(Data::new()),
            law,
            mode,
            dof,
            period_s,
            cycle: 0,
            setpoint: position,
            command: Command::hold(position),
            feedback: Feedback {
                position,
                previous: position,
                velocity: [0.0; J],
                torque: [0.0; J],
                applied_torque: [0.0; J],
                resolution: [0.0; J],
                has_velocity: false,
                has_torque: false,
                has_applied_torque: false,
                fresh: true,
                previous_fresh: false,
                last_fresh_sample: None,
                samples_between: None,
            },
            speed_limit: limits.speed_limit,
            effort_limit,
            limit_reached: [false; J],
            tracking: Tracking::new(dof),
            supervisor: Supervisor::new(supervision, bounds),
            failed_steps: 0,
            last_step_error: None,
            torque_clamped: 0,
            fault: None,
            fault_at: None,
            now: FaultAt {
                cycle: 0,
                time_s: 0.0,
            },
            ending: Ending::default(),
            max_braking_cycles: cycles(DEFAULT_MAX_BRAKING, period_s),
            receiver: None,
            inputs: Inputs::default(),
            input_timeout_ns: None,
            safety: None,
            end: None,
        })
    }

    /// Takes inputs from `receiver` (the other end of an [`input::channel`](super::input)),
    /// each cycle before the law runs.
    pub fn attach_inputs(&mut self, receiver: InputReceiver<J, L::Input>) {
        self.receiver = Some(receiver);
    }

    /// Brings the arm to rest through the law once no input has come for `timeout` (counted
    /// from the first cycle until the first input).
    pub fn input_timeout(&mut self, timeout: Duration) {
        self.input_timeout_ns = Some(timeout.as_nanos().min(u128::from(u64::MAX)) as u64);
    }

    /// Checks `chain` every cycle, before the law runs (see [`super::safety`]); arm it with
    /// [`arm_safety`](Self::arm_safety) before the device starts.
    pub fn attach_safety(&mut self, chain: SafetyBox) {
        self.safety = Some(chain);
    }

    /// Arms the attached safety chain (drives off, `period` apart): `Err` when it does not read
    /// closed with the enable held; nothing may start then. Without a chain: `Ok`.
    pub fn arm_safety(&mut self) -> Result<(), StopReason> {
        let period = Duration::from_secs_f64(self.period_s);
        match &mut self.safety {
            Some(chain) => chain.arm(period, &mut std::thread::sleep),
            None => Ok(()),
        }
    }

    /// After the device was stopped: tells the chain the drives are off (a brake output still
    /// energised for a category-1 stop drops), holds its watchdog and hands it back.
    pub fn detach_safety(&mut self) -> Option<SafetyBox> {
        let mut chain = self.safety.take()?;
        let _ = chain.cycle(false);
        chain.stop_watchdog();
        let _ = chain.cycle(false);
        Some(chain)
    }

    /// Ends the run at once if the law has not come to rest `max` after braking began.
    pub fn max_braking(&mut self, max: Duration) {
        self.max_braking_cycles = cycles(max, self.period_s);
    }

    /// Ends the run after `cycles` cycles: at rest on the last one when the law arranges it
    /// ([`ControlLaw::limit_cycles`]), otherwise the law is asked to brake then.
    pub fn limit_cycles(&mut self, cycles: u64) {
        let by_law = self.law.limit_cycles(cycles);
        self.ending.cycle_limit = Some((cycles.max(1), by_law));
    }

    /// Brings the arm to rest through the law (Ctrl-C); the run then ends.
    pub fn request_halt(&mut self) {
        self.brake(BrakeReason::Requested);
    }

    /// Ends the run at the next cycle without slowing down.
    pub fn abort(&mut self) {
        self.ending.abort = true;
    }

    /// One control cycle without loop timing (a caller stepping by hand).
    pub fn cycle(&mut self) -> CycleResult<J> {
        self.cycle_timed(CycleTiming::default())
    }

    /// One control cycle: read the measured joints and supervise them, record the tracking
    /// error, take the inputs, then (unless the run is over) run the law, check its command,
    /// send it and step the device. Allocates nothing.
    pub fn cycle_timed(&mut self, timing: CycleTiming) -> CycleResult<J> {
        self.now = FaultAt {
            cycle: self.cycle,
            time_s: self.time_s(),
        };
        self.read_feedback();
        // Statistics describe the motion up to the first fault: after it the feedback or the
        // command may not be trustworthy.
        let counted = self.feedback.fresh && self.fault.is_none();
        if counted {
            let dof = self.dof;
            self.tracking
                .record_error(&self.setpoint[..dof], &self.feedback.position[..dof]);
            self.record_violations(timing.skipped_deadlines);
        }
        if self.end.is_none() {
            self.supervise(timing);
            self.check_safety();
            self.take_inputs();
            self.check_ending();
        }
        let mut record = CycleRecord {
            cycle: self.now.cycle,
            time_s: self.now.time_s,
            commanded: self.setpoint,
            measured: self.feedback.position,
            feed_forward: [0.0; J],
            wakeup_latency_ns: 0,
            step_ns: 0,
            counted,
            state: RunState::Running,
        };
        if self.end.is_none() {
            if self.ending.abort {
                self.end = Some(RunEnd::Aborted);
            } else {
                let status = self.run_law(false);
                if status.is_over() {
                    self.end = Some(self.end_for(status));
                } else if status == LawStatus::Braking || self.ending.braking.is_some() {
                    self.ending.braking_cycles += 1;
                }
            }
        }
        if self.end.is_some() {
            record.state = RunState::Stopped;
            return CycleResult {
                record,
                finished: true,
            };
        }
        self.check_command();
        record.feed_forward = self.command.torque;
        self.tracking
            .record_feed_forward(&self.command.torque[..self.dof]);
        self.setpoint = self.command.position;
        self.cycle += 1;
        let stepped = self.send_command(timing.step_budget, true);
        self.after_step(stepped);
        record.state = if self.fault.is_some() {
            RunState::Fault
        } else if self.ending.braking_cycles > 0 {
            RunState::Braking
        } else {
            RunState::Running
        };
        CycleResult {
            record,
            finished: false,
        }
    }

    /// Reads the measured positions (and velocities and torques where the device gives them).
    fn read_feedback(&mut self) {
        let dof = self.dof;
        let f = &mut self.feedback;
        f.previous = f.position;
        if self.robot.joint_position(&mut f.position[..dof]).is_err() {
            f.fresh = false;
        }
        f.samples_between = None;
        if f.fresh {
            let sample = self.robot.joint_position_sample();
            if let (Some(now), Some(before)) = (sample, f.last_fresh_sample) {
                f.samples_between = Some(now.saturating_sub(before));
            }
            f.last_fresh_sample = sample;
        }
        for k in 0..dof {
            f.resolution[k] = self.robot.joint_position_resolution(f.position[k]);
        }
        f.has_velocity = self
            .robot
            .joint_velocity_sensor()
            .is_some_and(|s| s.joint_velocity(&mut f.velocity[..dof]).is_ok());
        f.has_torque = self
            .robot
            .joint_torque_sensor()
            .is_some_and(|s| s.joint_torque(&mut f.torque[..dof]).is_ok());
        f.has_applied_torque = self
            .robot
            .joint_torque_actuator()
            .is_some_and(|a| a.applied_joint_torque(&mut f.applied_torque[..dof]));
    }

    /// The safety chain's cycle (the watchdog toggles); a stop it finds is the run's fault.
    fn check_safety(&mut self) {
        let Some(chain) = &mut self.safety else {
            return;
        };
        if let Verdict::Stop { category, reason } = chain.cycle(true) {
            self.on_fault(Fault::Safety { category, reason });
        }
    }

    /// Hands what other threads sent to the law, and brakes when inputs went stale.
    fn take_inputs(&mut self) {
        let Some(receiver) = &mut self.receiver else {
            return;
        };
        let law = &mut self.law;
        self.inputs
            .receive(receiver, MonoTime::now(), |input| law.input(input));
        if let Some(timeout) = self.input_timeout_ns {
            if self.inputs.went_stale(timeout) {
                self.brake(BrakeReason::InputsStale);
            }
        }
    }

    /// The duration and the braking bound.
    fn check_ending(&mut self) {
        if let Some((limit, false)) = self.ending.cycle_limit {
            if self.cycle >= limit {
                self.brake(BrakeReason::Duration);
            }
        }
        if self.ending.braking_cycles > self.max_braking_cycles {
            self.end = Some(RunEnd::BrakeTimeout);
        }
    }

    /// Asks the law to brake (once: the first reason stays).
    fn brake(&mut self, reason: BrakeReason) {
        if self.ending.braking.is_none() {
            self.ending.braking = Some(reason);
            self.law.brake(reason);
        }
    }

    /// Runs the law for this cycle into `self.command` (with `first`, its hold command for the
    /// device's first exchange).
    fn run_law(&mut self, first: bool) -> LawStatus {
        let dof = self.dof;
        let f = &self.feedback;
        let mut cx = Context {
            cycle: self.cycle,
            time_s: self.cycle as f64 * self.period_s,
            period_s: self.period_s,
            dof,
            measured: Measured {
                position: &f.position[..dof],
                velocity: f.has_velocity.then_some(&f.velocity[..dof]),
                torque: f.has_torque.then_some(&f.torque[..dof]),
                applied_torque: f.has_applied_torque.then_some(&f.applied_torque[..dof]),
                fresh: f.fresh,
            },
            commanded: &self.setpoint[..dof],
            model: &self.model,
            data: &mut self.data,
            inputs: &self.inputs,
            braking: self.ending.braking,
        };
        self.command = Command::hold(self.setpoint);
        if first {
            self.law.hold(&mut cx, &mut self.command);
            LawStatus::Running
        } else {
            self.law.cycle(&mut cx, &mut self.command)
        }
    }

    /// How the run ends when the law says it is over.
    fn end_for(&self, status: LawStatus) -> RunEnd {
        if let Some(fault) = self.fault {
            return RunEnd::Fault(fault);
        }
        match self.ending.braking {
            Some(BrakeReason::Requested) => RunEnd::Stopped,
            Some(BrakeReason::Duration) => RunEnd::CycleLimit,
            Some(BrakeReason::InputsStale) => RunEnd::InputsStale,
            Some(BrakeReason::Fault) => RunEnd::Completed,
            None => match (status, self.ending.cycle_limit) {
                // The law braked on its own for the duration it arranged.
                (LawStatus::AtRest, Some((limit, true))) if self.cycle + 1 >= limit => {
                    RunEnd::CycleLimit
                }
                _ => RunEnd::Completed,
            },
        }
    }

    /// Never sends more than the bounds allow: a position (or reference) step beyond what the
    /// speed limit allows in one cycle, or a velocity beyond the speed limit, is clamped and
    /// is a fault (the law then brakes); torques beyond the model's effort limits are clamped
    /// and counted; anything not a number is a fault and is replaced by holding. A torque law
    /// commands no position (its `position` reports where the arm is, which after replies lost
    /// on the way moves by several cycles at once): its steps are not checked.
    fn check_command(&mut self) {
        let dof = self.dof;
        let c = &mut self.command;
        let mut fault = if self.mode == CommandMode::Torque {
            None
        } else {
            self.supervisor
                .check_step(&self.setpoint[..dof], &c.position[..dof])
        };
        if fault.is_some() {
            let b = self.supervisor.bounds();
            for ((n, s), bound) in c
                .position
                .iter_mut()
                .zip(&self.setpoint)
                .zip(&b.step)
                .take(dof)
            {
                let step = (*n - s).clamp(-bound, *bound);
                *n = if step.is_nan() { *s } else { s + step };
            }
        }
        match self.mode {
            CommandMode::Position => {}
            CommandMode::Velocity => {
                for k in 0..dof {
                    let (v, limit) = (c.velocity[k], self.speed_limit[k]);
                    if v.is_nan() || v.abs() > limit * (1.0 + 1e-9) {
                        c.velocity[k] = if v.is_nan() {
                            0.0
                        } else {
                            v.clamp(-limit, limit)
                        };
                        fault =
                            fault.or(self.supervisor.is_enabled().then_some(Fault::CommandStep {
                                joint: k,
                                step: v.abs() * self.period_s,
                                bound: limit * self.period_s,
                            }));
                    }
                }
            }
            CommandMode::Torque => {
                let mut clamped = false;
                for k in 0..dof {
                    let (t, limit) = (c.torque[k], self.effort_limit[k]);
                    if t.is_nan() {
                        c.torque[k] = 0.0;
                        fault =
                            fault.or(self.supervisor.is_enabled().then_some(Fault::CommandStep {
                                joint: k,
                                step: f64::NAN,
                                bound: self.supervisor.bounds().step[k],
                            }));
                    } else if t.abs() > limit {
                        c.torque[k] = t.clamp(-limit, limit);
                        clamped = true;
                    }
                }
                self.torque_clamped += u64::from(clamped);
            }
        }
        if let Some(f) = fault {
            self.on_fault(f);
        }
    }

    /// Sends the command (and, with `feed_forward`, the feed-forward torques to a device that
    /// takes them) and steps.
    fn send_command(
        &mut self,
        budget: Option<Duration>,
        feed_forward: bool,
    ) -> Result<(), DeviceError> {
        let dof = self.dof;
        let c = &self.command;
        let robot = &mut self.robot;
        match self.mode {
            CommandMode::Position => robot.set_joint_position(&c.position[..dof]),
            CommandMode::Velocity => match robot.joint_velocity_actuator() {
                Some(a) => a.set_joint_velocity(&c.velocity[..dof]),
                None => Err(unsupported()),
            },
            CommandMode::Torque => match robot.joint_torque_actuator() {
                Some(a) => a.set_joint_torque(&c.torque[..dof]),
                None => Err(unsupported()),
            },
        }
        .and_then(|()| match (self.mode, feed_forward) {
            (CommandMode::Position | CommandMode::Velocity, true) => {
                match robot.torque_feed_forward() {
                    Some(device) => device.set_joint_torque_feed_forward(&c.torque[..dof]),
                    None => Ok(()),
                }
            }
            _ => Ok(()),
        })
        .and_then(|()| match budget {
            Some(budget) => robot.step_within(budget),
            None => robot.step(),
        })
    }

    /// Counts a failed step; a lost link or a faulted device is a fault.
    fn after_step(&mut self, stepped: Result<(), DeviceError>) {
        self.feedback.previous_fresh = self.feedback.fresh;
        match stepped {
            Ok(()) => self.feedback.fresh = true,
            Err(e) => {
                self.feedback.fresh = false;
                self.failed_steps += 1;
                self.last_step_error = Some(e);
                let faulted = self.robot.state() == State::Faulted;
                let fault = self
                    .supervisor
                    .check_step_error(&self.robot.fault().unwrap_or(e), faulted);
                match fault {
                    Some(f) => self.on_fault(f),
                    // Even unsupervised, a device that refuses to step ends the run.
                    None if faulted => {
                        self.end = Some(RunEnd::Fault(Fault::Device {
                            error: self.robot.fault().unwrap_or(e),
                        }));
                    }
                    None => {}
                }
            }
        }
    }

    /// The device's first exchange, before the loop: sends the law's hold command
    /// ([`ControlLaw::hold`]: by default the start position, zero velocity or zero torque),
    /// checked as every command is, without feed-forward, and steps once.
    pub(super) fn first_exchange(&mut self) -> Result<(), DeviceError> {
        self.read_feedback();
        self.run_law(true);
        self.check_command();
        self.send_command(None, false)
    }

    /// Feedback, tracking, link and timing checks of this cycle, and the device's own limit
    /// report.
    fn supervise(&mut self, timing: CycleTiming) {
        let dof = self.dof;
        let link = self.robot.link_statistics();
        let f = &self.feedback;
        let observed = self.supervisor.observe(&Observation {
            fresh: f.fresh,
            measured: &f.position[..dof],
            resolution: &f.resolution[..dof],
            commanded: &self.setpoint[..dof],
            link,
            skipped_deadlines: timing.skipped_deadlines,
            overran: timing.overran,
            samples_between: f.samples_between,
        });
        if let Some(f) = observed {
            self.on_fault(f);
        }
        if self.feedback.fresh {
            if let Some(sensor) = self.robot.joint_limit_sensor() {
                if sensor
                    .joint_limit_reached(&mut self.limit_reached[..dof])
                    .is_ok()
                {
                    if let Some(f) = self
                        .supervisor
                        .check_device_limits(&self.limit_reached[..dof])
                    {
                        self.on_fault(f);
                    }
                }
            }
        }
    }

    /// Records a fault: the first one is the run's reason. A fault that leaves a working link
    /// has the law bring the arm to rest; one that does not ends the run now.
    fn on_fault(&mut self, fault: Fault) {
        if self.fault.is_none() {
            self.fault = Some(fault);
            self.fault_at = Some(self.now);
        }
        if fault.stops_at_once() {
            if self.end.is_none() {
                self.end = Some(RunEnd::Fault(
                    self.fault.map_or(fault, |f| f.ended_by(fault)),
                ));
            }
        } else {
            self.brake(BrakeReason::Fault);
        }
    }

    /// Position limits, and the speed between two fresh measurements, of the measured joints
    /// (statistics for the report; the supervisor acts on them).
    fn record_violations(&mut self, skipped_deadlines: u64) {
        let cycle = self.cycle;
        let f = &self.feedback;
        // The time between the two measurements: the device's count of its periods where it
        // numbers them (a state lost between two readings doubles it), else one period.
        let gap = measurement_gap(f.samples_between, 1, skipped_deadlines);
        let interval = gap as f64 * self.period_s;
        let speed_ok = f.previous_fresh;
        for k in 0..self.dof {
            let l = self.model.limits(k);
            let q = f.position[k];
            let tolerance = POSITION_TOLERANCE + f.resolution[k];
            let inside = q >= l.lower - tolerance && q <= l.upper + tolerance;
            if !(l.wraparound || inside) {
                self.tracking.record_violation(Violation {
                    cycle,
                    joint: k,
                    quantity: "position",
                    value: q,
                    limit: if q < l.lower { l.lower } else { l.upper },
                });
            }
            if speed_ok {
                let v = (q - f.previous[k]).abs() / interval;
                if v > l.velocity * 1.01 + tolerance / interval {
                    self.tracking.record_violation(Violation {
                        cycle,
                        joint: k,
                        quantity: "speed",
                        value: v,
                        limit: l.velocity,
                    });
                }
            }
        }
    }

    /// How the run ended (`None` while it runs).
    pub fn end(&self) -> Option<RunEnd> {
        self.end
    }

    /// The first fault, if any (the run ends with it, at rest or at once).
    pub fn fault(&self) -> Option<Fault> {
        self.fault
    }

    /// When the first fault was found.
    pub fn fault_at(&self) -> Option<FaultAt> {
        self.fault_at
    }

    /// Whether the arm is being brought to rest (asked, or the law's own).
    pub fn is_braking(&self) -> bool {
        self.ending.braking_cycles > 0 || self.ending.braking.is_some()
    }

    /// Whether this cycle's measurement is fresh (the device answered; a lost reply leaves the
    /// last measurement in place, which the tracking statistics skip).
    pub fn feedback_fresh(&self) -> bool {
        self.feedback.fresh
    }

    /// Cycles run (the law was called and the device stepped).
    pub fn cycles(&self) -> u64 {
        self.cycle
    }

    /// The law's time of the current cycle (trajectory time for the trajectory follower), or
    /// the run's, s.
    pub fn time_s(&self) -> f64 {
        self.law
            .time_s()
            .unwrap_or(self.cycle as f64 * self.period_s)
    }

    /// Cycles whose torque command was clamped to the model's effort limits.
    pub fn torque_clamped(&self) -> u64 {
        self.torque_clamped
    }

    /// What became of the inputs (`None` without an input channel).
    pub fn input_report(&self) -> Option<InputReport> {
        let timeout_s = self.input_timeout_ns.map(|ns| ns as f64 * 1e-9);
        self.receiver
            .as_ref()
            .map(|r| self.inputs.report(r, timeout_s))
    }

    /// Tells the input senders the run is over.
    pub fn close_inputs(&mut self) {
        if let Some(r) = &mut self.receiver {
            r.close();
        }
    }

    /// Tracking, feed-forward and limit statistics.
    pub fn tracking(&self) -> &Tracking<J> {
        &self.tracking
    }

    /// The supervisor (its bounds).
    pub fn supervisor(&self) -> &Supervisor<J> {
        &self.supervisor
    }

    /// Steps that failed (no usable reply): lost packets.
    pub fn failed_steps(&self) -> u64 {
        self.failed_steps
    }

    /// The last failed step's error.
    pub fn last_step_error(&self) -> Option<DeviceError> {
        self.last_step_error
    }

    /// The device's link counts.
    pub fn link_statistics(&self) -> LinkStatistics {
        self.robot.link_statistics()
    }

    /// The law.
    pub fn law(&self) -> &L {
        &self.law
    }

    /// The law, e.g. to change its parameters between cycles when stepping by hand.
    pub fn law_mut(&mut self) -> &mut L {
        &mut self.law
    }

    /// The model.
    pub fn model(&self) -> &Model<B> {
        &self.model
    }

    /// The device.
    pub fn robot(&self) -> &R {
        &self.robot
    }

    /// The device, to stop and close it after the run.
    pub fn robot_mut(&mut self) -> &mut R {
        &mut self.robot
    }

    /// The device back.
    pub fn into_robot(self) -> R {
        self.robot
    }
}

fn cycles(d: Duration, period_s: f64) -> u64 {
    (d.as_secs_f64() / period_s).ceil() as u64
}

fn unsupported() -> DeviceError {
    DeviceError::InvalidArgument {
        what: "the device no longer takes this kind of command",
        expected: 1,
        got: 0,
    }
}

/// The supervisor's bounds for `model` with `limits`' speed limits (the model's, or the
/// assumed speed), the model's position limits, the control period and the device cycle.
pub(super) fn supervision_bounds<const B: usize, const J: usize>(
    model: &Model<B>,
    limits: &MotionLimits<J>,
    supervision: &Supervision,
    period_s: f64,
    device_period: Duration,
) -> Bounds<J> {
    let dof = model.dof();
    let mut lower = [f64::NEG_INFINITY; J];
    let mut upper = [f64::INFINITY; J];
    for k in 0..dof {
        let l = model.limits(k);
        if !l.wraparound {
            lower[k] = l.lower;
            upper[k] = l.upper;
        }
    }
    Bounds::new(
        supervision,
        &limits.speed_limit[..dof],
        &lower[..dof],
        &upper[..dof],
        period_s,
        device_period.as_secs_f64(),
    )
}
