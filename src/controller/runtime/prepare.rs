//! Phase one of a run, before anything moves: the options and the scheduling are checked, the
//! device is opened and asked where the arm stands, the control period is checked against
//! the device's, and the law is made — the trajectory follower's plan checked against the
//! model's limits (bounded in time, cancellable), or the user's law prepared — and put into a
//! [`Controller`] that checks the device takes the law's commands. Every error path closes the
//! device again.

use std::time::Duration;

use rl_core::Model;
use rl_rt::{CyclicLoop, OverrunPolicy, Policy, RtThreadBuilder};

use super::{RunError, RunOptions};
use crate::controller::control::{Controller, supervision_bounds};
use crate::controller::follower::TrajectoryFollower;
use crate::controller::law::{ControlLaw, Start};
use crate::controller::plan::{
    Motion, MotionLimits, Plan, PlanBudget, PlanError, default_waypoints, joint_name,
};
use crate::controller::robot::JointRobot;

/// An opened device, the arm's start and the checked timing: what a law is made from.
pub(super) struct Prepared<R, const B: usize, const J: usize> {
    robot: R,
    model: Model<B>,
    limits: MotionLimits<J>,
    builder: RtThreadBuilder,
    joints: Vec<String>,
    start: Vec<f64>,
    period: Duration,
    device_period: Duration,
    #[cfg(feature = "view")]
    view: Option<crate::controller::view::ViewPublisher>,
}

/// What a law is, for the report.
pub(super) struct LawInfo {
    pub(super) joints: Vec<String>,
    pub(super) period: Duration,
    pub(super) device_period: Duration,
    pub(super) duration_s: f64,
    pub(super) source: String,
    pub(super) description: String,
    pub(super) assumed_speed: Vec<String>,
}

/// What the real-time thread is started with.
pub(super) struct LoopSetup {
    pub(super) builder: RtThreadBuilder,
    pub(super) looped: CyclicLoop,
    pub(super) start: Vec<f64>,
    pub(super) joints: Vec<String>,
    pub(super) period: Duration,
    #[cfg(feature = "view")]
    pub(super) view: Option<crate::controller::view::ViewPublisher>,
}

impl<R: JointRobot, const B: usize, const J: usize> Prepared<R, B, J> {
    /// Checks the options and the scheduling (on a throw-away thread), opens the device, reads
    /// where the arm stands and checks the control period.
    pub(super) fn open(
        mut robot: R,
        model: Model<B>,
        options: &RunOptions,
    ) -> Result<Self, RunError> {
        if !(options.speed > 0.0 && options.speed <= 1.0) {
            return Err(RunError::Options(format!(
                "speed fraction {} must be above 0 and at most 1 (of the model's speed limits)",
                options.speed
            )));
        }
        let limits = MotionLimits::<J>::from_model(&model, options.speed)?;
        let builder = scheduling(options)?;
        let dof = model.dof();
        let joints: Vec<String> = (0..dof).map(|k| joint_name(&model, k)).collect();
        #[cfg(feature = "view")]
        let view = options.view.as_ref().map(|v| v.attach(dof)).transpose()?;
        robot.open().map_err(|error| RunError::Device {
            stage: "open",
            error,
        })?;
        let timing = start_and_period(&mut robot, &model, options);
        let (start, period, device_period) = match timing {
            Ok(t) => t,
            Err(e) => {
                let _ = robot.close();
                return Err(e);
            }
        };
        Ok(Self {
            robot,
            model,
            limits,
            builder,
            joints,
            start,
            period,
            device_period,
            #[cfg(feature = "view")]
            view,
        })
    }

    /// The trajectory follower's plan: a tour from where the arm stands, or a given trajectory
    /// (the arm must stand at its start within the tracking bound), checked against the model's
    /// limits within the run's budget and against the device's cycle.
    pub(super) fn plan(
        &mut self,
        motion: Motion<J>,
        options: &RunOptions,
    ) -> Result<TrajectoryFollower<J>, RunError> {
        let model = &self.model;
        let budget = PlanBudget {
            max_duration: options.max_plan_duration,
            stop: Some(options.stop.clone()),
        };
        let (plan, source, description) = match motion {
            Motion::Tour => {
                let waypoints = options
                    .waypoints
                    .clone()
                    .unwrap_or_else(|| default_waypoints(model, &self.start));
                let n = waypoints.len();
                let plan =
                    Plan::<J>::with_budget(model, &self.start, &waypoints, &self.limits, &budget)?;
                let description = format!(
                    "tour through {n} waypoint{} and back to the start",
                    if n == 1 { "" } else { "s" }
                );
                (plan, "tour".to_owned(), description)
            }
            Motion::Trajectory(follow) => {
                let plan =
                    Plan::<J>::from_trajectory(model, follow.trajectory, &self.limits, &budget)?;
                self.check_at_start(plan.start(), options)?;
                self.start.copy_from_slice(plan.start());
                (plan, follow.source, follow.description)
            }
        };
        plan.check_step(model, self.period, self.device_period)?;
        Ok(TrajectoryFollower::new(plan, self.period).described(source, description))
    }

    /// The arm must stand where a trajectory starts, within the tracking bound the run
    /// supervises.
    fn check_at_start(&self, planned: &[f64], options: &RunOptions) -> Result<(), RunError> {
        let bounds = supervision_bounds(
            &self.model,
            &self.limits,
            &options.supervision,
            self.period.as_secs_f64(),
            self.device_period,
        );
        for (k, (&measured, &planned)) in self.start.iter().zip(planned).enumerate() {
            let tolerance = bounds.tracking[k] + self.robot.joint_position_resolution(planned);
            let off = (measured - planned).abs();
            if off.is_nan() || off > tolerance {
                return Err(RunError::NotAtStart {
                    joint: self.joints[k].clone(),
                    start: planned,
                    measured,
                    tolerance,
                });
            }
        }
        Ok(())
    }

    /// A user's law, prepared from where the arm stands ([`ControlLaw::start`]).
    pub(super) fn start_law<L: ControlLaw<B, J>>(&mut self, mut law: L) -> Result<L, RunError> {
        let device_adds_gravity = self
            .robot
            .joint_torque_actuator()
            .is_some_and(|a| a.adds_gravity());
        law.start(&Start {
            device_adds_gravity,
            position: &self.start,
            model: &self.model,
            limits: &self.limits,
            period_s: self.period.as_secs_f64(),
            device_period_s: self.device_period.as_secs_f64(),
        })
        .map_err(|e| RunError::Law(e.to_string()))?;
        Ok(law)
    }

    /// Closes the device after `error`, which it returns.
    pub(super) fn abandon(mut self, error: RunError) -> RunError {
        let _ = self.robot.close();
        error
    }

    /// The controller running `law` (checked against the device's commands), the loop it
    /// runs in, and what the report says of the law.
    #[allow(clippy::type_complexity)] // three parts handed to three places
    pub(super) fn into_controller<L: ControlLaw<B, J>>(
        self,
        law: L,
        options: &RunOptions,
    ) -> Result<(LawInfo, Box<Controller<R, B, J, L>>, LoopSetup), RunError> {
        let looped = match CyclicLoop::new(self.period) {
            Ok(l) => l.overrun_policy(OverrunPolicy::Skip),
            Err(e) => return Err(self.abandon(RunError::Loop(e.to_string()))),
        };
        if options.stop.is_stop_requested() {
            return Err(self.abandon(RunError::Cancelled));
        }
        let info = LawInfo {
            joints: self.joints.clone(),
            period: self.period,
            device_period: self.device_period,
            duration_s: law.duration_s().unwrap_or(0.0),
            source: law.name().to_owned(),
            description: law.describe(),
            assumed_speed: (0..self.joints.len())
                .filter(|&k| self.limits.assumed_speed[k])
                .map(|k| self.joints[k].clone())
                .collect(),
        };
        // Dropping the opened device (inside, on an error) closes its connections.
        let mut controller = Box::new(Controller::with_law(
            self.robot,
            self.model,
            law,
            &self.start,
            &self.limits,
            self.period,
            &options.supervision,
        )?);
        if let Some(d) = options.duration {
            controller.limit_cycles((d.as_secs_f64() / self.period.as_secs_f64()).round() as u64);
        }
        if let Some(timeout) = options.input_timeout {
            controller.input_timeout(timeout);
        }
        if let Some(handle) = &options.safety {
            match handle.take() {
                Some(chain) => controller.attach_safety(chain),
                None => {
                    let mut robot = controller.into_robot();
                    let _ = robot.close();
                    return Err(RunError::Safety(
                        "the chain is in use by another run".into(),
                    ));
                }
            }
        }
        controller.max_braking(options.max_braking);
        let setup = LoopSetup {
            builder: self.builder,
            looped,
            start: self.start,
            joints: self.joints,
            period: self.period,
            #[cfg(feature = "view")]
            view: self.view,
        };
        Ok((info, controller, setup))
    }
}

/// The control thread's scheduling, tried on a throw-away thread before anything starts: a bad
/// priority or CPU is refused here; a missing privilege is degraded (best effort) and
/// reported.
fn scheduling(options: &RunOptions) -> Result<RtThreadBuilder, RunError> {
    let mut builder = RtThreadBuilder::new("rl-control")
        .policy(Policy::Fifo)
        .priority(options.priority)
        .lock_memory(options.lock_memory)
        .best_effort(true);
    if !options.cpus.is_empty() {
        builder = builder.cpus(options.cpus.iter().copied());
    }
    let probe = builder
        .clone()
        .lock_memory(false)
        .spawn(|| ())
        .map_err(|e| RunError::Options(format!("priority/CPU: {e}")))?;
    // The probe thread does nothing; its end cannot fail.
    let _ = probe.join();
    Ok(builder)
}

/// Where the opened device reports the arm (a joint on its limit, reported a rounding beyond
/// it, is put on it), the control period and the device's.
fn start_and_period<R: JointRobot, const B: usize>(
    robot: &mut R,
    model: &Model<B>,
    options: &RunOptions,
) -> Result<(Vec<f64>, Duration, Duration), RunError> {
    let dof = model.dof();
    if robot.dof() != dof {
        return Err(RunError::Plan(PlanError::DeviceJoints {
            model: dof,
            device: robot.dof(),
        }));
    }
    let mut start = vec![0.0; dof];
    robot
        .joint_position(&mut start)
        .map_err(|error| RunError::Device {
            stage: "read the start position",
            error,
        })?;
    for (k, q) in start.iter_mut().enumerate() {
        let l = model.limits(k);
        let tolerance = robot.joint_position_resolution(*q);
        if !l.wraparound && q.is_finite() {
            if *q < l.lower && *q >= l.lower - tolerance {
                *q = l.lower;
            } else if *q > l.upper && *q <= l.upper + tolerance {
                *q = l.upper;
            }
        }
    }
    let device_period = robot.update_period();
    let period = options.period.unwrap_or(device_period);
    if period.is_zero() {
        return Err(RunError::Options(
            "the control period must be positive".into(),
        ));
    }
    if period < device_period {
        return Err(RunError::Options(format!(
            "a control period of {:.3} ms is shorter than the device's cycle of {:.3} ms: \
             the device cannot answer more often",
            period.as_secs_f64() * 1e3,
            device_period.as_secs_f64() * 1e3
        )));
    }
    Ok((start, period, device_period))
}
