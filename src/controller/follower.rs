//! The joint-space trajectory follower: the [`ControlLaw`] `rl run` executes.
//!
//! Each cycle it advances trajectory time by one period ([`TrajectoryClock`]), evaluates the
//! checked [`Plan`]'s trajectory, computes the inverse-dynamics feed-forward torques
//! `τ = RNEA(q, q̇, q̈)` in the model's workspace, and commands the position (with the torques,
//! for a device that takes them). Braking slows trajectory time to rest along the path
//! ([`TrajectoryClock`]'s half-cosine ramp); a duration limit is arranged by the clock so the
//! arm is at rest on the last cycle. Allocates nothing.

use std::time::Duration;

use rl_core::algo::rnea;
use rl_core::traj::Trajectory;

use super::clock::{HaltReason, TrajectoryClock};
use super::law::{BrakeReason, Command, Context, ControlLaw, LawStatus};
use super::plan::Plan;

/// Shortest and longest controlled stop, s.
const HALT_RANGE_S: (f64, f64) = (0.1, 2.0);

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

/// Follows a checked [`Plan`] with inverse-dynamics feed-forward, at a fixed control period.
#[derive(Clone, Debug)]
pub struct TrajectoryFollower<const J: usize> {
    plan: Plan<J>,
    clock: TrajectoryClock,
    period_s: f64,
    halt_cycles: u64,
    source: String,
    description: String,
}

impl<const J: usize> TrajectoryFollower<J> {
    /// Follows `plan`, one `period` per cycle.
    pub fn new(plan: Plan<J>, period: Duration) -> Self {
        let period_s = period.as_secs_f64();
        let halt_cycles = halt_cycles(&plan, period_s);
        Self {
            clock: TrajectoryClock::new(period_s, plan.duration_s(), halt_cycles, None),
            plan,
            period_s,
            halt_cycles,
            source: "plan".to_owned(),
            description: String::new(),
        }
    }

    /// Names where the trajectory came from, for the report (`"tour"`, `"plan"`) and says it
    /// in one line.
    pub fn described(mut self, source: impl Into<String>, description: impl Into<String>) -> Self {
        self.source = source.into();
        self.description = description.into();
        self
    }

    /// The plan.
    pub fn plan(&self) -> &Plan<J> {
        &self.plan
    }

    /// The trajectory clock.
    pub fn clock(&self) -> &TrajectoryClock {
        &self.clock
    }

    /// Restarts the trajectory from its beginning (for benchmarks: a tour returns to its
    /// start, so the command stays continuous).
    pub fn rewind(&mut self) {
        self.clock = TrajectoryClock::new(
            self.period_s,
            self.plan.duration_s(),
            self.halt_cycles,
            None,
        );
    }
}

impl<const B: usize, const J: usize> ControlLaw<B, J> for TrajectoryFollower<J> {
    type Input = ();

    fn name(&self) -> &str {
        &self.source
    }

    fn describe(&self) -> String {
        self.description.clone()
    }

    fn cycle(&mut self, cx: &mut Context<'_, B, J, ()>, out: &mut Command<J>) -> LawStatus {
        if self.clock.is_finished() {
            return match self.clock.halting() {
                None => LawStatus::Completed,
                Some(_) => LawStatus::AtRest,
            };
        }
        self.clock.advance();
        let s = self.plan.trajectory().sample(self.clock.time_s());
        let (r, r_dot) = (self.clock.rate(), self.clock.rate_dot());
        let dof = cx.dof;
        let mut qdd = [0.0; J];
        for (k, a) in qdd.iter_mut().enumerate().take(dof) {
            out.velocity[k] = s.velocity[k] * r;
            *a = s.acceleration[k] * r * r + s.velocity[k] * r_dot;
        }
        // Lengths were checked when the controller was made, so RNEA cannot fail here; a
        // failure would leave the torques at zero rather than panic.
        if let Ok(tau) = rnea(
            cx.model,
            cx.data,
            &s.position[..dof],
            &out.velocity[..dof],
            &qdd[..dof],
        ) {
            out.torque[..dof].copy_from_slice(tau);
        }
        out.position = s.position;
        if self.clock.halting().is_some() {
            LawStatus::Braking
        } else {
            LawStatus::Running
        }
    }

    fn brake(&mut self, reason: BrakeReason) {
        self.clock.request_halt_for(match reason {
            BrakeReason::Duration => HaltReason::CycleLimit,
            BrakeReason::Fault => HaltReason::Fault,
            BrakeReason::Requested | BrakeReason::InputsStale => HaltReason::Requested,
        });
    }

    fn limit_cycles(&mut self, cycles: u64) -> bool {
        self.clock = TrajectoryClock::new(
            self.period_s,
            self.plan.duration_s(),
            self.halt_cycles,
            Some(cycles.max(1)),
        );
        true
    }

    fn time_s(&self) -> Option<f64> {
        Some(self.clock.time_s())
    }

    fn duration_s(&self) -> Option<f64> {
        Some(self.plan.duration_s())
    }
}
