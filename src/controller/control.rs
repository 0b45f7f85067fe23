//! The control cycle: read, evaluate, feed forward, command, step.

use core::fmt;
use std::time::Duration;

use rl_core::Data;
use rl_core::algo::rnea;
use rl_core::traj::Trajectory;
use rl_drivers::{
    CyclicDevice, Error as DeviceError, JointPositionActuator, JointPositionSensor,
    LinkStatisticsSensor, State,
};

use super::clock::{HaltReason, TrajectoryClock};
use super::plan::{Plan, PlanError, check_model};
use super::telemetry::CycleRecord;
use super::tracking::{Tracking, Violation};
use super::{MAX_BODIES, MAX_JOINTS, RobotModel};

/// Shortest and longest controlled stop, s.
const HALT_RANGE_S: (f64, f64) = (0.1, 2.0);
/// Tolerance on measured positions against the model's limits (rad or m): the wire carries
/// `f32`.
const POSITION_TOLERANCE: f64 = 1e-5;

/// A device the controller can drive: cyclic, joint positions in and out, and link statistics.
/// Any driver with these capabilities is one; the controller names no driver.
pub trait JointRobot:
    CyclicDevice<Error = DeviceError>
    + JointPositionActuator
    + JointPositionSensor
    + LinkStatisticsSensor
{
}

impl<T> JointRobot for T where
    T: CyclicDevice<Error = DeviceError>
        + JointPositionActuator
        + JointPositionSensor
        + LinkStatisticsSensor
        + ?Sized
{
}

/// Cycles of a controlled stop: long enough that its extra deceleration, `|q'·ṙ| ≤ v·π/(2·T)`,
/// stays within the planned acceleration.
fn halt_cycles(plan: &Plan, period_s: f64) -> u64 {
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
    /// The device faulted (too many failed steps, or a refused command).
    DeviceFault(DeviceError),
}

impl RunEnd {
    /// Whether the run counts as failed.
    pub fn is_failure(&self) -> bool {
        matches!(self, Self::DeviceFault(_))
    }
}

impl fmt::Display for RunEnd {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Completed => f.write_str("completed"),
            Self::CycleLimit => f.write_str("duration reached, brought to rest"),
            Self::Stopped => f.write_str("stopped on request, brought to rest"),
            Self::Aborted => f.write_str("aborted on a second request"),
            Self::DeviceFault(e) => write!(f, "device fault: {e}"),
        }
    }
}

/// What one cycle did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleResult {
    /// The cycle's record (latency and step time are left for the loop to fill).
    pub record: CycleRecord,
    /// Whether the run is over (the device was not stepped in this cycle).
    pub finished: bool,
}

/// The position controller: one [`cycle`](Self::cycle) per control period.
pub struct Controller<R> {
    robot: R,
    model: RobotModel,
    data: Data<MAX_BODIES>,
    plan: Plan,
    dof: usize,
    period_s: f64,
    clock: TrajectoryClock,
    setpoint: [f64; MAX_JOINTS],
    measured: [f64; MAX_JOINTS],
    previous: [f64; MAX_JOINTS],
    feed_forward: [f64; MAX_JOINTS],
    fresh: bool,
    previous_fresh: bool,
    tracking: Tracking,
    failed_steps: u64,
    last_step_error: Option<DeviceError>,
    abort: bool,
    end: Option<RunEnd>,
}

impl<R: JointRobot> Controller<R> {
    /// A controller for a started `robot` whose last reply holds the plan's start, running
    /// every `period`.
    pub fn new(
        robot: R,
        model: RobotModel,
        plan: Plan,
        period: Duration,
    ) -> Result<Self, PlanError> {
        check_model(&model)?;
        let dof = model.dof();
        if plan.dof() != dof || robot.dof() != dof {
            return Err(PlanError::Length {
                what: "the plan or the device".into(),
                expected: dof,
                got: if plan.dof() != dof {
                    plan.dof()
                } else {
                    robot.dof()
                },
            });
        }
        let period_s = period.as_secs_f64();
        if period_s.is_nan() || period_s <= 0.0 {
            return Err(PlanError::Trajectory(
                rl_core::traj::TrajectoryError::BadDuration,
            ));
        }
        let halt_cycles = halt_cycles(&plan, period_s);
        let start = plan.points()[0];
        Ok(Self {
            robot,
            model,
            data: Data::new(),
            clock: TrajectoryClock::new(period_s, plan.duration_s(), halt_cycles, None),
            plan,
            dof,
            period_s,
            setpoint: start,
            measured: start,
            previous: start,
            feed_forward: [0.0; MAX_JOINTS],
            fresh: true,
            previous_fresh: false,
            tracking: Tracking::new(dof),
            failed_steps: 0,
            last_step_error: None,
            abort: false,
            end: None,
        })
    }

    /// Ends the run after `cycles` cycles, at rest on the last one.
    pub fn limit_cycles(&mut self, cycles: u64) {
        let halt_cycles = self.halt_cycles();
        self.clock = TrajectoryClock::new(
            self.period_s,
            self.plan.duration_s(),
            halt_cycles,
            Some(cycles.max(1)),
        );
    }

    fn halt_cycles(&self) -> u64 {
        halt_cycles(&self.plan, self.period_s)
    }

    /// Brings the arm to rest along its path (Ctrl-C); the run then ends.
    pub fn request_halt(&mut self) {
        self.clock.request_halt();
    }

    /// Ends the run at the next cycle without slowing down.
    pub fn abort(&mut self) {
        self.abort = true;
    }

    /// One control cycle: read the measured joints, record the tracking error, then (unless
    /// the run is over) advance trajectory time, evaluate the trajectory, compute the
    /// feed-forward torques (RNEA), command the next position and step the device.
    /// Allocates nothing.
    pub fn cycle(&mut self) -> CycleResult {
        let dof = self.dof;
        self.previous = self.measured;
        if self
            .robot
            .joint_position(&mut self.measured[..dof])
            .is_err()
        {
            self.fresh = false;
        }
        self.tracking
            .record_error(&self.setpoint[..dof], &self.measured[..dof]);
        self.check_measured();
        let cycle = self.clock.cycle();
        let mut record = CycleRecord {
            cycle,
            time_s: self.clock.time_s(),
            commanded: self.setpoint,
            measured: self.measured,
            feed_forward: [0.0; MAX_JOINTS],
            wakeup_latency_ns: 0,
            step_ns: 0,
        };
        if self.end.is_some() {
            return CycleResult {
                record,
                finished: true,
            };
        }
        if self.abort || self.clock.is_finished() {
            self.end = Some(if self.abort {
                RunEnd::Aborted
            } else {
                match self.clock.halting() {
                    None => RunEnd::Completed,
                    Some(HaltReason::Requested) => RunEnd::Stopped,
                    Some(HaltReason::CycleLimit) => RunEnd::CycleLimit,
                }
            });
            return CycleResult {
                record,
                finished: true,
            };
        }

        self.clock.advance();
        let s = self.plan.trajectory().sample(self.clock.time_s());
        let (r, r_dot) = (self.clock.rate(), self.clock.rate_dot());
        let mut qd = [0.0; MAX_JOINTS];
        let mut qdd = [0.0; MAX_JOINTS];
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
        self.setpoint = s.position;

        let stepped = self
            .robot
            .set_joint_position(&self.setpoint[..dof])
            .and_then(|()| self.robot.step());
        self.previous_fresh = self.fresh;
        match stepped {
            Ok(()) => self.fresh = true,
            Err(e) => {
                self.fresh = false;
                self.failed_steps += 1;
                self.last_step_error = Some(e);
                if self.robot.state() == State::Faulted {
                    self.end = Some(RunEnd::DeviceFault(self.robot.fault().unwrap_or(e)));
                }
            }
        }
        CycleResult {
            record,
            finished: false,
        }
    }

    /// Position limits, and the speed between two fresh measurements, of the measured joints.
    fn check_measured(&mut self) {
        let cycle = self.clock.cycle();
        let speed_ok = self.fresh && self.previous_fresh;
        for k in 0..self.dof {
            let l = self.model.limits(k);
            let q = self.measured[k];
            let inside = q >= l.lower - POSITION_TOLERANCE && q <= l.upper + POSITION_TOLERANCE;
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
                if v > l.velocity * 1.01 + POSITION_TOLERANCE / self.period_s {
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
        let halt_cycles = self.halt_cycles();
        self.clock = TrajectoryClock::new(self.period_s, self.plan.duration_s(), halt_cycles, None);
        self.end = None;
    }

    /// How the run ended (`None` while it runs).
    pub fn end(&self) -> Option<RunEnd> {
        self.end
    }

    /// Tracking, feed-forward and limit statistics.
    pub fn tracking(&self) -> &Tracking {
        &self.tracking
    }

    /// Steps that failed (no usable reply): lost packets.
    pub fn failed_steps(&self) -> u64 {
        self.failed_steps
    }

    /// The last failed step's error.
    pub fn last_step_error(&self) -> Option<DeviceError> {
        self.last_step_error
    }

    /// The trajectory clock.
    pub fn clock(&self) -> &TrajectoryClock {
        &self.clock
    }

    /// The plan.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// The model.
    pub fn model(&self) -> &RobotModel {
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
