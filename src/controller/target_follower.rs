//! Streamed targets followed online: the [`ControlLaw`] of `rl run --follow`.
//!
//! Each cycle the law takes the newest accepted [`Target`] (sent from any thread through the
//! run's [`InputSender`](super::InputSender), checked there against the joints' limits) and
//! hands it to rl-core's online trajectory generator ([`Otg`]): a new target is planned from
//! the state commanded last — position, velocity and acceleration, so the command stays
//! continuous whatever the target does — to the target state in the shortest time the
//! velocity, acceleration and jerk limits allow, all joints arriving together
//! ([`Synchronization::Time`]); between targets the generator steps along in constant time.
//! A position target is reached at rest or with its velocity; a velocity target is reached and
//! kept.
//!
//! - Limits: the run's [`MotionLimits`] (speed, acceleration and jerk at the run's speed
//!   fraction) and the model's position limits (joints that wrap around have none). The
//!   generator keeps the position limits on the way; beyond a motion's end (a velocity kept, a
//!   target reached moving) the law keeps the invariant that **every commanded state can stop
//!   inside the position limits**: a state from which the time-optimal stop would leave them is
//!   never commanded; the law brakes from the last state instead (counted, `limit_stops`).
//! - A target the generator cannot reach inside the limits is not followed (the previous
//!   motion goes on); counted with the generator's typed reason (`unreachable`).
//! - Every stop — a stop request, the run's duration, a fault that leaves the link working,
//!   targets that stopped coming ([`BrakeReason`]) — brakes along the generator's time-optimal
//!   jerk-limited stop from the state commanded last ([`Otg::brake`]), phase-synchronised
//!   (a straight line in joint space where the motion is one), and ends at rest.
//! - Feed-forward: the inverse-dynamics torques `τ = RNEA(q, q̇, q̈)` of each commanded sample,
//!   for a device that takes them.
//!
//! Real-time thread: nothing here allocates, locks or panics; a recalculation of 7 joints
//! takes a few microseconds, a step about 30 ns, and the stop check one braking calculation
//! per cycle while the arm moves beyond a motion's end.

use std::time::Duration;

/// How long a followed run waits for its next target before it brings the arm to rest and
/// fails (`RunOptions::input_timeout` for `rl run --follow` and Python's `follow=True`).
pub const DEFAULT_INPUT_TIMEOUT: Duration = Duration::from_secs(2);

use rl_core::algo::rnea;
use rl_core::traj::otg::{
    Input as OtgInput, Interface, Limits, Otg, OtgError, Output, State, Synchronization, braking,
};

use super::input::{Input, Target};
use super::law::{
    BrakeReason, Command, Context, ControlLaw, LawError, LawStatus, LawSummary, Refused, Start,
};

/// Follows streamed targets through the online trajectory generator (see the module docs).
#[derive(Clone, Debug)]
pub struct TargetFollower<const J: usize> {
    dof: usize,
    otg: Option<Otg<J>>,
    /// The goal being followed (its `current` is unused).
    goal: OtgInput<J>,
    /// The limits without position limits: braking and the stop check.
    free: Limits<J>,
    /// Targets seen in [`Context::inputs`] (a new count is a new target).
    seen: u64,
    braking: Option<BrakeReason>,
    /// The current motion's end was reached (its time counted in `counts`).
    reached: bool,
    counts: FollowCounts,
}

/// What a [`TargetFollower`] did over a run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FollowCounts {
    /// Targets taken (each a recalculation from the state commanded last).
    pub targets: u64,
    /// Targets the generator could not reach inside the limits (not followed).
    pub unreachable: u64,
    /// The first reason a target was not followed.
    pub first_unreachable: Option<OtgError>,
    /// Times the arm was braked because going on would have left the position limits.
    pub limit_stops: u64,
    /// Longest time from a target's sending to the cycle that took it, s (the sender's
    /// timestamp against the loop's clock: the queue's wait and the loop's phase).
    pub apply_delay_max_s: f64,
    /// Sum of those times over the targets taken, s (their mean: divide by `targets`).
    pub apply_delay_sum_s: f64,
    /// Duration of the last motion that reached its target, s, from the cycle its target was
    /// taken (`None`: none reached yet).
    pub last_reach_s: Option<f64>,
}

impl<const J: usize> Default for TargetFollower<J> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const J: usize> TargetFollower<J> {
    /// A follower; it holds the arm where it stands until the first target.
    pub fn new() -> Self {
        let rest = State::at_rest([0.0; J]);
        Self {
            dof: 0,
            otg: None,
            goal: OtgInput::new(rest, rest, Limits::uniform(1.0, 1.0, 1.0)),
            free: Limits::uniform(1.0, 1.0, 1.0),
            seen: 0,
            braking: None,
            reached: true,
            counts: FollowCounts::default(),
        }
    }

    /// What it did so far.
    pub fn counts(&self) -> &FollowCounts {
        &self.counts
    }

    /// The generator (`None` before the run starts): the state commanded last, the trajectory
    /// followed and the time along it.
    pub fn generator(&self) -> Option<&Otg<J>> {
        self.otg.as_ref()
    }

    /// The goal being followed (target state, limits, interface).
    pub fn goal(&self) -> &OtgInput<J> {
        &self.goal
    }

    /// Brakes along the time-optimal stop from the state commanded last.
    fn brake_now(otg: &mut Otg<J>, free: &Limits<J>) {
        if otg.brake(free, Synchronization::Phase).is_err() {
            // Phase synchronisation found no profile for this state: each joint on its own.
            let _ = otg.brake(free, Synchronization::None);
        }
    }

    fn command<const B: usize>(
        cx: &mut Context<'_, B, J, ()>,
        step: &Output<J>,
        out: &mut Command<J>,
    ) {
        let s = &step.sample;
        let dof = cx.dof;
        out.position[..dof].copy_from_slice(&s.position[..dof]);
        out.velocity[..dof].copy_from_slice(&s.velocity[..dof]);
        // Lengths were checked when the controller was made, so RNEA cannot fail here; a
        // failure would leave the torques at zero rather than panic.
        if let Ok(tau) = rnea(
            cx.model,
            cx.data,
            &s.position[..dof],
            &s.velocity[..dof],
            &s.acceleration[..dof],
        ) {
            out.torque[..dof].copy_from_slice(tau);
        }
    }
}

impl<const B: usize, const J: usize> ControlLaw<B, J> for TargetFollower<J> {
    type Input = ();

    fn name(&self) -> &str {
        "follow"
    }

    fn describe(&self) -> String {
        "streamed targets, followed online: time-optimal jerk-limited motions from the state \
         commanded last; every stop along the time-optimal jerk-limited braking profile"
            .to_owned()
    }

    fn start(&mut self, start: &Start<'_, B, J>) -> Result<(), LawError> {
        let dof = start.position.len().min(J);
        let l = start.limits;
        let mut limits = Limits::uniform(1.0, 1.0, 1.0);
        for k in 0..dof {
            let (v, a, j) = (l.velocity[k], l.acceleration[k], l.jerk[k]);
            if !(v > 0.0 && a > 0.0 && j > 0.0) {
                return Err(format!(
                    "joint {k}: the run's limits give it no motion (speed {v}, acceleration {a}, \
                     jerk {j})"
                )
                .into());
            }
            limits.max_velocity[k] = v;
            limits.min_velocity[k] = -v;
            limits.max_acceleration[k] = a;
            limits.min_acceleration[k] = -a;
            limits.max_jerk[k] = j;
        }
        self.free = limits;
        for k in 0..dof {
            let joint = start.model.limits(k);
            if !joint.wraparound {
                limits.min_position[k] = joint.lower;
                limits.max_position[k] = joint.upper;
            }
        }
        let mut here = [0.0; J];
        here[..dof].copy_from_slice(&start.position[..dof]);
        let rest = State::at_rest(here);
        self.dof = dof;
        self.goal = OtgInput::new(rest, rest, limits);
        self.otg = Some(Otg::new(Duration::from_secs_f64(start.period_s), rest));
        self.seen = 0;
        self.braking = None;
        self.reached = true;
        self.counts = FollowCounts::default();
        Ok(())
    }

    fn input(&mut self, input: &Input<J, ()>) -> Result<(), Refused> {
        match input {
            Input::Target(_) if self.braking.is_some() => {
                Err(Refused("the arm is being brought to rest"))
            }
            Input::Target(_) => Ok(()),
            Input::Other(()) => Err(Refused("this law takes targets only")),
        }
    }

    fn cycle(&mut self, cx: &mut Context<'_, B, J, ()>, out: &mut Command<J>) -> LawStatus {
        let Some(otg) = self.otg.as_mut() else {
            // `start` was not called: hold.
            return LawStatus::AtRest;
        };
        if self.braking.is_some() {
            let step = otg.step();
            Self::command(cx, &step, out);
            return if step.finished {
                LawStatus::AtRest
            } else {
                LawStatus::Braking
            };
        }
        let last = *otg.state();
        let previous = self.goal;
        // The time from a new target's sending to this cycle, s.
        let mut new_target = None;
        if cx.inputs.targets() != self.seen
            && let Some(target) = cx.inputs.target().copied()
        {
            self.seen = cx.inputs.targets();
            self.goal = goal_for(&self.goal, self.dof, &target);
            new_target = Some(cx.inputs.target_age_s().unwrap_or(0.0));
        }
        let mut step = match otg.update(&self.goal) {
            Ok(step) => {
                if let Some(delay) = new_target {
                    self.counts.targets += 1;
                    self.counts.apply_delay_max_s = self.counts.apply_delay_max_s.max(delay);
                    self.counts.apply_delay_sum_s += delay;
                }
                step
            }
            Err(e) => {
                // Unreachable inside the limits: not taken, the previous motion goes on.
                self.counts.unreachable += 1;
                self.counts.first_unreachable.get_or_insert(e);
                self.goal = previous;
                otg.step()
            }
        };
        if stop_leaves_limits(self.dof, &self.free, &self.goal.limits, otg.state()).is_some() {
            // Going on would leave the position limits: from the last state, which could stop
            // inside them, to rest where its stop ends.
            self.counts.limit_stops += 1;
            let stop_at = stop_position(&self.free, &last);
            self.goal.interface = Interface::Position;
            self.goal.target = State::at_rest(stop_at);
            otg.reset(last);
            step = match otg.update(&self.goal) {
                Ok(step) => step,
                Err(_) => {
                    Self::brake_now(otg, &self.free);
                    otg.step()
                }
            };
        }
        if step.recalculated {
            self.reached = false;
        }
        if step.finished && !self.reached {
            self.reached = true;
            self.counts.last_reach_s = Some(step.time);
        }
        Self::command(cx, &step, out);
        LawStatus::Running
    }

    fn summary(&self) -> Option<LawSummary> {
        let c = &self.counts;
        let mut line = format!(
            "follow: {} target{} taken, {} not reachable inside the limits",
            c.targets,
            if c.targets == 1 { "" } else { "s" },
            c.unreachable
        );
        if let Some(e) = &c.first_unreachable {
            line.push_str(&format!(" (first: {e})"));
        }
        if c.limit_stops > 0 {
            line.push_str(&format!(
                ", {} stop{} before a position limit",
                c.limit_stops,
                if c.limit_stops == 1 { "" } else { "s" }
            ));
        }
        let mean_delay_s = c.apply_delay_sum_s / c.targets.max(1) as f64;
        if c.targets > 0 {
            line.push_str(&format!(
                "; each taken at most {:.3} ms (mean {:.3} ms) after it was sent",
                c.apply_delay_max_s * 1e3,
                mean_delay_s * 1e3
            ));
        }
        if let Some(t) = c.last_reach_s {
            line.push_str(&format!("; the last target reached in {t:.3} s"));
        }
        Some(LawSummary {
            lines: vec![line],
            json: serde_json::json!({
                    "law": "follow",
                    "targets": c.targets,
                    "unreachable": c.unreachable,
                    "first_unreachable": c.first_unreachable.map(|e| e.to_string()),
                    "limit_stops": c.limit_stops,
                    "last_reach_s": c.last_reach_s,
                    "apply_delay_max_s": c.apply_delay_max_s,
                    "apply_delay_mean_s": (c.targets > 0).then_some(mean_delay_s),
            }),
            headline: serde_json::Value::Null,
            failure: None,
        })
    }

    fn brake(&mut self, reason: BrakeReason) {
        self.braking = Some(reason);
        if let Some(otg) = self.otg.as_mut() {
            Self::brake_now(otg, &self.free);
        }
    }
}

/// `target` as the generator's goal, from the goal before it: unused joints stay at rest
/// where they are; a velocity target keeps the last target position (unused).
fn goal_for<const J: usize>(before: &OtgInput<J>, dof: usize, target: &Target<J>) -> OtgInput<J> {
    let mut goal = *before;
    goal.minimum_duration = None;
    match target {
        Target::Position { position, velocity } => {
            goal.interface = Interface::Position;
            goal.target = State::at_rest(*position);
            if let Some(v) = velocity {
                goal.target.velocity = *v;
            }
        }
        Target::Velocity { velocity } => {
            goal.interface = Interface::Velocity;
            goal.target = State::at_rest(before.target.position);
            goal.target.velocity = *velocity;
        }
    }
    for k in dof..J {
        goal.target.position[k] = 0.0;
        goal.target.velocity[k] = 0.0;
    }
    goal
}

/// Where the time-optimal stop from `state` (each joint on its own) comes to rest.
fn stop_position<const J: usize>(free: &Limits<J>, state: &State<J>) -> [f64; J] {
    match braking(state, free, Synchronization::None) {
        Ok(stop) => stop.at_time(stop.duration()).position,
        Err(_) => state.position,
    }
}

/// The first joint whose time-optimal stop from `state` would leave its position limits
/// (`None`: the arm can stop inside them from `state`, or is at rest).
fn stop_leaves_limits<const J: usize>(
    dof: usize,
    free: &Limits<J>,
    limits: &Limits<J>,
    state: &State<J>,
) -> Option<usize> {
    let moving = (0..dof).any(|k| state.velocity[k] != 0.0 || state.acceleration[k] != 0.0);
    if !moving {
        return None;
    }
    let Ok(stop) = braking(state, free, Synchronization::None) else {
        return Some(0);
    };
    let extrema = stop.position_extrema();
    (0..dof)
        .find(|&k| extrema[k][0] < limits.min_position[k] || extrema[k][1] > limits.max_position[k])
}
