//! The generator in a control loop: one call per cycle with the newest goal.
//!
//! [`Otg`] keeps the trajectory it follows and the state it commanded last. Each cycle the
//! controller hands it the goal (target state, limits, interface, synchronisation, minimum
//! duration, waypoints); when the goal differs from the one of the current trajectory (bit for
//! bit), it recalculates from the last commanded state, so the motion stays continuous in
//! position, velocity and acceleration whatever the new goal; otherwise it only steps one cycle
//! along the trajectory, in constant time ([`Otg::step`]). [`Otg::brake`] replaces the goal by
//! the time-optimal jerk-limited stop from the current state (every stop request of a
//! supervised run uses it), and [`braking`] answers the same question without changing state.
//!
//! Nothing here allocates. A generator keeps two trajectories: the one it follows and the one a
//! recalculation writes, which takes over only when it succeeds — a goal that cannot be reached
//! leaves the motion under way untouched. Of 7 axes it is about 13 KB.

use core::time::Duration;

use super::calculate_into;
use super::error::OtgError;
use super::input::{Input, Interface, Limits, State, Synchronization};
use super::trajectory::OtgTrajectory;
use crate::traj::Sample;

/// What one cycle commands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output<const N: usize> {
    /// Position, velocity, acceleration and jerk to command now.
    pub sample: Sample<N>,
    /// Time along the current trajectory (seconds since it was calculated).
    pub time: f64,
    /// The goal is reached (the time is past the trajectory's duration).
    pub finished: bool,
    /// This cycle calculated a new trajectory (the goal changed).
    pub recalculated: bool,
}

/// The online trajectory generator of a control loop (see the module docs).
#[derive(Clone, Debug)]
pub struct Otg<const N: usize> {
    cycle: f64,
    /// The goal of the current trajectory; `current` is the state it started from.
    goal: Input<N>,
    /// The trajectory followed (`trajectories[active]`) and the one recalculated into.
    trajectories: [OtgTrajectory<N>; 2],
    active: usize,
    time: f64,
    cursor: [usize; N],
    state: State<N>,
}

/// Whether two goals ask for the same (everything but the current state, bit for bit).
fn same_goal<const N: usize>(a: &Input<N>, b: &Input<N>) -> bool {
    let bits = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits());
    let (la, lb) = (&a.limits, &b.limits);
    a.interface == b.interface
        && a.synchronization == b.synchronization
        && a.minimum_duration.map(f64::to_bits) == b.minimum_duration.map(f64::to_bits)
        && bits(&a.target.position, &b.target.position)
        && bits(&a.target.velocity, &b.target.velocity)
        && bits(&a.target.acceleration, &b.target.acceleration)
        && bits(&la.max_velocity, &lb.max_velocity)
        && bits(&la.min_velocity, &lb.min_velocity)
        && bits(&la.max_acceleration, &lb.max_acceleration)
        && bits(&la.min_acceleration, &lb.min_acceleration)
        && bits(&la.max_jerk, &lb.max_jerk)
        && bits(&la.min_position, &lb.min_position)
        && bits(&la.max_position, &lb.max_position)
        && a.waypoints.len() == b.waypoints.len()
        && a.waypoints
            .as_slice()
            .iter()
            .zip(b.waypoints.as_slice())
            .all(|(p, q)| bits(p, q))
}

impl<const N: usize> Otg<N> {
    /// A generator with control period `cycle`, holding `state` until the first goal.
    pub fn new(cycle: Duration, state: State<N>) -> Self {
        let hold = OtgTrajectory::hold(state.position, state.velocity, state.acceleration);
        let mut goal = Input::new(state, state, Limits::uniform(0.0, 0.0, 0.0));
        // No goal yet: a NaN target never equals a real one, so the first update calculates.
        goal.target.position = [f64::NAN; N];
        Self {
            cycle: cycle.as_secs_f64(),
            goal,
            trajectories: [hold, hold],
            active: 0,
            time: 0.0,
            cursor: [0; N],
            state,
        }
    }

    /// The control period in seconds.
    pub fn cycle(&self) -> f64 {
        self.cycle
    }

    /// The state commanded last (where the next trajectory starts).
    pub fn state(&self) -> &State<N> {
        &self.state
    }

    /// The trajectory being followed.
    pub fn trajectory(&self) -> &OtgTrajectory<N> {
        &self.trajectories[self.active]
    }

    /// Calculates `request` into the spare trajectory and, when that succeeds, follows it from
    /// its start; on an error the trajectory followed stays as it was.
    fn take(&mut self, request: Input<N>) -> Result<(), OtgError> {
        let spare = 1 - self.active;
        calculate_into(&request, &mut self.trajectories[spare])?;
        self.active = spare;
        self.goal = request;
        self.time = 0.0;
        self.cursor = [0; N];
        Ok(())
    }

    /// Time along the trajectory being followed.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Continues from `state` (a measured state, or after a fault) at the next update: the
    /// trajectory is recalculated from there whatever the goal.
    pub fn reset(&mut self, state: State<N>) {
        self.state = state;
        self.goal.target.position = [f64::NAN; N];
        self.trajectories[self.active] =
            OtgTrajectory::hold(state.position, state.velocity, state.acceleration);
        self.time = 0.0;
        self.cursor = [0; N];
    }

    /// One cycle towards `goal` (its `current` is ignored: the generator continues from the
    /// state it commanded last). Recalculates if the goal changed, then steps one cycle. On an
    /// error the previous trajectory stays and nothing advances; the error says why the new
    /// goal cannot be reached (the caller may then [`Otg::brake`]).
    pub fn update(&mut self, goal: &Input<N>) -> Result<Output<N>, OtgError> {
        let mut recalculated = false;
        if !same_goal(goal, &self.goal) {
            let mut request = *goal;
            request.current = self.state;
            self.take(request)?;
            recalculated = true;
        }
        let mut out = self.step();
        out.recalculated = recalculated;
        Ok(out)
    }

    /// One cycle along the current trajectory (no goal check): constant time, no allocation.
    #[inline]
    pub fn step(&mut self) -> Output<N> {
        self.time += self.cycle;
        let trajectory = &self.trajectories[self.active];
        let sample = trajectory.at_time_from(self.time, &mut self.cursor);
        self.state = State {
            position: sample.position,
            velocity: sample.velocity,
            acceleration: sample.acceleration,
        };
        Output {
            sample,
            time: self.time,
            finished: self.time >= trajectory.duration(),
            recalculated: false,
        }
    }

    /// Replaces the goal by stopping: the time-optimal jerk-limited motion from the current state
    /// to rest (velocity and acceleration zero; see [`braking`]). The following [`Otg::step`]s
    /// follow it; an [`Otg::update`] with a goal sets a new one. On an error the trajectory
    /// followed stays.
    pub fn brake(
        &mut self,
        limits: &Limits<N>,
        synchronization: Synchronization,
    ) -> Result<(), OtgError> {
        self.take(braking_input(&self.state, limits, synchronization))
    }

    /// Whether the trajectory followed is complete (the goal reached).
    pub fn is_finished(&self) -> bool {
        self.time >= self.trajectory().duration()
    }
}

/// The input of a stop from `state`: velocity interface to zero velocity and acceleration.
fn braking_input<const N: usize>(
    state: &State<N>,
    limits: &Limits<N>,
    synchronization: Synchronization,
) -> Input<N> {
    let mut input = Input::new(*state, State::at_rest(state.position), *limits);
    input.interface = Interface::Velocity;
    input.synchronization = synchronization;
    input
}

/// The time-optimal jerk-limited stop from `state` under `limits`: every axis to zero velocity
/// and acceleration as fast as its acceleration and jerk limits allow (with
/// [`Synchronization::None`]), or all together (`Time`), or along the current direction of motion
/// where the state allows it (`Phase`). The position where it comes to rest is the end of the
/// trajectory; a state beyond the acceleration limits brakes back within them first.
pub fn braking<const N: usize>(
    state: &State<N>,
    limits: &Limits<N>,
    synchronization: Synchronization,
) -> Result<OtgTrajectory<N>, OtgError> {
    let mut trajectory = OtgTrajectory::hold(state.position, state.velocity, state.acceleration);
    calculate_into(
        &braking_input(state, limits, synchronization),
        &mut trajectory,
    )?;
    Ok(trajectory)
}
