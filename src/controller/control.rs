//! The control cycle: read, supervise, evaluate, feed forward, command, step.

use core::fmt;
use std::time::Duration;

use rl_core::algo::rnea;
use rl_core::traj::Trajectory;
use rl_core::{Data, Model};
use rl_drivers::{Error as DeviceError, LinkStatistics, State};

use super::clock::{HaltReason, TrajectoryClock};
use super::plan::{Plan, PlanError, check_model};
use super::robot::JointRobot;
use super::supervise::{Bounds, Fault, Observation, Supervision, Supervisor};
use super::telemetry::CycleRecord;
use super::tracking::{Tracking, Violation};
use super::{DEFAULT_BODIES, DEFAULT_JOINTS};

/// Shortest and longest controlled stop, s.
const HALT_RANGE_S: (f64, f64) = (0.1, 2.0);
/// Tolerance on measured positions against the model's limits (rad or m), beyond the device's
/// resolution, for the statistics of limit violations.
const POSITION_TOLERANCE: f64 = 1e-5;

/// Cycles of a controlled stop: long enough that its extra deceleration, `|q'·ṙ| ≤ v·π/(2·T)`,
/// stays within the planned acceleration.
fn halt_cycles<const J: usize>(plan: &Plan<J>, period_s: f64) -> u64 {
    let l = plan.limits();
    let halt_s = (0..plan.dof())
        .map(|k| 0.5 * core::f64::consts::PI * l.velocity[k] / l.acceleration[k])
        .fold(HALT_RANGE_S.0, f64::max)
        .min(HALT_RANGE_S.1);
    (halt_s / period_s).ceil() as u64
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RunEnd {
    /// The trajectory ran to its end.
    Completed,
    /// The cycle budget ended; the arm was brought to rest on the path.
    CycleLimit,
    /// A stop was requested; the arm was brought to rest on the path.
    Stopped,
    /// A second stop request ended the run at once (the arm may still have been moving).
    Aborted,
    /// A fault ended the run: at rest along the path, or at once when the link or the device
    /// could no longer carry a command ([`Fault::stops_at_once`]).
    Fault(Fault),
}

impl RunEnd {
    /// Whether the run counts as failed.
    pub fn is_failure(&self) -> bool {
        matches!(self, Self::Fault(_))
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
            Self::Fault(fault) if fault.stops_at_once() => {
                write!(f, "fault, stopped at once: {fault}")
            }
            Self::Fault(fault) => write!(f, "fault, brought to rest: {fault}"),
        }
    }
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

/// The supervised position controller: one [`cycle`](Self::cycle) per control period, for a
/// model of up to `B` moving bodies and `J` joints.
pub struct Controller<R, const B: usize = DEFAULT_BODIES, const J: usize = DEFAULT_JOINTS> {
    robot: R,
    model: Model<B>,
    /// Boxed: a large model's workspace (1.3 MB at 256 bodies) is no stack value.
    data: Box<Data<B>>,
    plan: Plan<J>,
    dof: usize,
    period_s: f64,
    clock: TrajectoryClock,
    setpoint: [f64; J],
    measured: [f64; J],
    previous: [f64; J],
    resolution: [f64; J],
    feed_forward: [f64; J],
    limit_reached: [bool; J],
    fresh: bool,
    previous_fresh: bool,
    tracking: Tracking<J>,
    supervisor: Supervisor<J>,
    failed_steps: u64,
    last_step_error: Option<DeviceError>,
    fault: Option<Fault>,
    abort: bool,
    end: Option<RunEnd>,
}

impl<R: JointRobot, const B: usize, const J: usize> Controller<R, B, J> {
    /// A controller for a started `robot` whose last reply holds the plan's start, running
    /// every `period`, supervised with the default [`Supervision`].
    pub fn new(
        robot: R,
        model: Model<B>,
        plan: Plan<J>,
        period: Duration,
    ) -> Result<Self, PlanError> {
        Self::with_supervision(robot, model, plan, period, &Supervision::default())
    }

    /// A controller with explicit supervision.
    pub fn with_supervision(
        robot: R,
        model: Model<B>,
        plan: Plan<J>,
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
        if plan.dof() != dof {
            return Err(PlanError::Length {
                what: "the plan".into(),
                expected: dof,
                got: plan.dof(),
            });
        }
        let period_s = period.as_secs_f64();
        if period_s.is_nan() || period_s <= 0.0 {
            return Err(PlanError::Trajectory(
                rl_core::traj::TrajectoryError::BadDuration,
            ));
        }
        let bounds =
            supervision_bounds(&model, &plan, supervision, period_s, robot.update_period());
        let halt_cycles = halt_cycles(&plan, period_s);
        let start = plan.points()[0];
        Ok(Self {
            robot,
            model,
            data: Box::new(Data::new()),
            clock: TrajectoryClock::new(period_s, plan.duration_s(), halt_cycles, None),
            plan,
            dof,
            period_s,
            setpoint: start,
            measured: start,
            previous: start,
            resolution: [0.0; J],
            feed_forward: [0.0; J],
            limit_reached: [false; J],
            fresh: true,
            previous_fresh: false,
            tracking: Tracking::new(dof),
            supervisor: Supervisor::new(supervision, bounds),
            failed_steps: 0,
            last_step_error: None,
            fault: None,
            abort: false,
            end: None,
        })
    }

    /// Ends the run after `cycles` cycles, at rest on the last one.
    pub fn limit_cycles(&mut self, cycles: u64) {
        let halt_cycles = halt_cycles(&self.plan, self.period_s);
        self.clock = TrajectoryClock::new(
            self.period_s,
            self.plan.duration_s(),
            halt_cycles,
            Some(cycles.max(1)),
        );
    }

    /// Brings the arm to rest along its path (Ctrl-C); the run then ends.
    pub fn request_halt(&mut self) {
        self.clock.request_halt();
    }

    /// Ends the run at the next cycle without slowing down.
    pub fn abort(&mut self) {
        self.abort = true;
    }

    /// One control cycle without loop timing (a caller stepping by hand).
    pub fn cycle(&mut self) -> CycleResult<J> {
        self.cycle_timed(CycleTiming::default())
    }

    /// One control cycle: read the measured joints and supervise them, record the tracking
    /// error, then (unless the run is over) advance trajectory time, evaluate the trajectory,
    /// compute the feed-forward torques (RNEA, sent to the device where it takes them), command
    /// the next position and step the device. Allocates nothing.
    pub fn cycle_timed(&mut self, timing: CycleTiming) -> CycleResult<J> {
        let dof = self.dof;
        self.previous = self.measured;
        if self
            .robot
            .joint_position(&mut self.measured[..dof])
            .is_err()
        {
            self.fresh = false;
        }
        for k in 0..dof {
            self.resolution[k] = self.robot.joint_position_resolution(self.measured[k]);
        }
        // Statistics describe the motion up to the first fault: after it the feedback or the
        // command may not be trustworthy.
        if self.fresh && self.fault.is_none() {
            self.tracking
                .record_error(&self.setpoint[..dof], &self.measured[..dof]);
            self.record_violations();
        }
        if self.end.is_none() {
            self.supervise(timing);
        }
        let cycle = self.clock.cycle();
        let mut record = CycleRecord {
            cycle,
            time_s: self.clock.time_s(),
            commanded: self.setpoint,
            measured: self.measured,
            feed_forward: [0.0; J],
            wakeup_latency_ns: 0,
            step_ns: 0,
        };
        if self.end.is_none() && (self.abort || self.clock.is_finished()) {
            self.end = Some(if self.abort {
                RunEnd::Aborted
            } else if let Some(fault) = self.fault {
                RunEnd::Fault(fault)
            } else {
                match self.clock.halting() {
                    None => RunEnd::Completed,
                    Some(HaltReason::Requested) => RunEnd::Stopped,
                    Some(HaltReason::CycleLimit) => RunEnd::CycleLimit,
                    Some(HaltReason::Fault) => RunEnd::Completed,
                }
            });
        }
        if self.end.is_some() {
            return CycleResult {
                record,
                finished: true,
            };
        }

        self.clock.advance();
        let s = self.plan.trajectory().sample(self.clock.time_s());
        let (r, r_dot) = (self.clock.rate(), self.clock.rate_dot());
        let mut qd = [0.0; J];
        let mut qdd = [0.0; J];
        for k in 0..dof {
            qd[k] = s.velocity[k] * r;
            qdd[k] = s.acceleration[k] * r * r + s.velocity[k] * r_dot;
        }
        // Lengths were checked in `new`, so RNEA cannot fail here; a failure would leave the
        // previous torques in place rather than panic.
        if let Ok(tau) = rnea(
            &self.model,
            &mut self.data,
            &s.position[..dof],
            &qd[..dof],
            &qdd[..dof],
        ) {
            self.feed_forward[..dof].copy_from_slice(tau);
        }
        self.tracking.record_feed_forward(&self.feed_forward[..dof]);
        record.feed_forward = self.feed_forward;
        let mut next = s.position;
        if let Some(fault) = self
            .supervisor
            .check_step(&self.setpoint[..dof], &next[..dof])
        {
            // Never command more than the bound: clamp the step, then come to rest.
            let b = self.supervisor.bounds();
            for ((n, s), bound) in next.iter_mut().zip(&self.setpoint).zip(&b.step).take(dof) {
                *n = s + (*n - s).clamp(-bound, *bound);
            }
            self.on_fault(fault);
        }
        self.setpoint = next;

        let ff = &self.feed_forward[..dof];
        let stepped = self
            .robot
            .set_joint_position(&self.setpoint[..dof])
            .and_then(|()| match self.robot.torque_feed_forward() {
                Some(device) => device.set_joint_torque_feed_forward(ff),
                None => Ok(()),
            })
            .and_then(|()| match timing.step_budget {
                Some(budget) => self.robot.step_within(budget),
                None => self.robot.step(),
            });
        self.previous_fresh = self.fresh;
        match stepped {
            Ok(()) => self.fresh = true,
            Err(e) => {
                self.fresh = false;
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
        CycleResult {
            record,
            finished: false,
        }
    }

    /// Feedback, tracking, link and timing checks of this cycle, and the device's own limit
    /// report.
    fn supervise(&mut self, timing: CycleTiming) {
        let dof = self.dof;
        let link = self.robot.link_statistics();
        let observed = self.supervisor.observe(&Observation {
            fresh: self.fresh,
            measured: &self.measured[..dof],
            resolution: &self.resolution[..dof],
            commanded: &self.setpoint[..dof],
            link,
            skipped_deadlines: timing.skipped_deadlines,
            overran: timing.overran,
        });
        if let Some(f) = observed {
            self.on_fault(f);
        }
        if self.fresh {
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
    /// starts the halt along the path; one that does not ends the run now.
    fn on_fault(&mut self, fault: Fault) {
        if self.fault.is_none() {
            self.fault = Some(fault);
        }
        if fault.stops_at_once() {
            if self.end.is_none() {
                self.end = Some(RunEnd::Fault(
                    self.fault.map_or(fault, |f| f.ended_by(fault)),
                ));
            }
        } else {
            self.clock.request_halt_for(HaltReason::Fault);
        }
    }

    /// Position limits, and the speed between two fresh measurements, of the measured joints
    /// (statistics for the report; the supervisor acts on them).
    fn record_violations(&mut self) {
        let cycle = self.clock.cycle();
        let speed_ok = self.previous_fresh;
        for k in 0..self.dof {
            let l = self.model.limits(k);
            let q = self.measured[k];
            let tolerance = POSITION_TOLERANCE + self.resolution[k];
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
                let v = (q - self.previous[k]).abs() / self.period_s;
                if v > l.velocity * 1.01 + tolerance / self.period_s {
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

    /// Restarts the trajectory from its beginning (for benchmarks: the plan returns to its
    /// start, so the command stays continuous).
    pub fn rewind(&mut self) {
        let halt_cycles = halt_cycles(&self.plan, self.period_s);
        self.clock = TrajectoryClock::new(self.period_s, self.plan.duration_s(), halt_cycles, None);
        self.end = None;
    }

    /// How the run ended (`None` while it runs).
    pub fn end(&self) -> Option<RunEnd> {
        self.end
    }

    /// The first fault, if any (the run ends with it, at rest or at once).
    pub fn fault(&self) -> Option<Fault> {
        self.fault
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

    /// The trajectory clock.
    pub fn clock(&self) -> &TrajectoryClock {
        &self.clock
    }

    /// The plan.
    pub fn plan(&self) -> &Plan<J> {
        &self.plan
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

/// The supervisor's bounds for `model` and `plan`: the plan's speed limits (the model's, or the
/// assumed speed), the model's position limits, the control period and the device cycle.
pub(super) fn supervision_bounds<const B: usize, const J: usize>(
    model: &Model<B>,
    plan: &Plan<J>,
    supervision: &Supervision,
    period_s: f64,
    device_period: Duration,
) -> Bounds<J> {
    let dof = model.dof();
    let limits = plan.limits();
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
