//! Online trajectory generation: from any state to any target state, time-optimal and
//! jerk-limited, for `N` axes, fast enough to recompute every control cycle.
//!
//! Given the current position, velocity and acceleration of every axis, a target state, and
//! per-axis limits (velocity, acceleration and jerk, separately for each direction, and
//! optionally position limits), [`calculate`] returns the [`OtgTrajectory`] that reaches the
//! target in the shortest time every axis can make, with every axis arriving at once (time
//! synchronisation), on a straight line in joint space where the input allows
//! ([`Synchronization::Phase`]), or each in its own shortest time ([`Synchronization::None`]).
//! With [`Interface::Velocity`] the target is a velocity (the position free). A
//! [minimum duration](Input::minimum_duration) stretches the motion; position limits are never
//! left (module `position_limits.rs`: detours when the time-optimal motion would leave them,
//! typed errors when nothing can stay inside); [`calculate_waypoints`] passes up to
//! [`MAX_WAYPOINTS`] intermediate positions. [`Otg`] is the generator of a control loop: one
//! call per cycle with the newest goal, recalculating from the last commanded state only when
//! the goal changed and otherwise stepping along in constant time; [`braking`] and
//! [`Otg::brake`] give the time-optimal stop from any state.
//!
//! The method is that of Berscheid & Kröger, "Jerk-limited Real-time Trajectory Generation with
//! Arbitrary Target States", RSS 2021 (Ruckig), in three steps (one file each):
//!
//! 1. per axis (`block.rs`), braking back inside the limits if the start is beyond them
//!    (`brake.rs`), then every extremal profile — the seven-phase jerk profiles at the borders
//!    of the durations in which the axis can reach its target — from one polynomial equation per
//!    profile type (`third_order.rs`; `velocity.rs` and `lower_order.rs` for the velocity
//!    interface and infinite limits). The shortest is the axis' time-optimal profile; between
//!    others lie the blocked durations, told apart by one reachability test between each pair.
//! 2. the common duration: the smallest that every axis can make (`sync.rs`); phase
//!    synchronisation scales the limiting axis' profile where the input is collinear
//!    (`phase.rs`).
//! 3. per axis, a profile of exactly that duration. Here this differs from Ruckig: instead of
//!    solving a second set of polynomial equations per profile type, the axis plays a convex
//!    combination of its profiles with the largest and the smallest displacement in that
//!    duration (closed forms), which is exact, keeps every limit (the limits are convex in the
//!    jerk function), and cannot miss a solution.
//!
//! # Numbers
//!
//! - Polynomial roots (degree ≤ 4, `roots.rs`): Budan–Fourier counts first, isolation between
//!   the roots of the derivative where more than one may lie, Halley steps inside the bracket
//!   with bisection as the fallback, a bounded number of steps. Every candidate profile is
//!   then integrated phase by phase and checked against its target and every limit before it
//!   is used. Tolerances (`frame.rs`): the end state within `1e-8` (position, velocity) and
//!   `1e-10` (acceleration) of the target — absolute, as Ruckig's, or 64 units in the last
//!   place of the largest value met where that is larger — and the limits within `1e-12`
//!   relative. Durations agree with Ruckig's within `1e-11` relative (worst over 10^6 random jobs
//!   per category, `scripts/otg-vs-ruckig`; the README has the table and the known
//!   disagreements: near-zero limits and one high-limit blend); [`OtgTrajectory::limit_violation`] checks a trajectory exactly.
//! - Deterministic: the same input gives the same bits (no randomness, bounded iteration counts,
//!   `libm`); every failure is a typed [`OtgError`] naming the axis, never a NaN.
//! - No allocation, no panic; a trajectory of 7 axes takes about 5.5 KB, a generator 13 KB, a
//!   waypoint trajectory of 7 axes 50 KB. A 7-axis calculation from a moving start takes a few
//!   microseconds, a control-loop step about 30 ns (`benches/otg.rs`).
//!
//! # Zero and infinite limits
//!
//! An infinite jerk limit lets the acceleration jump (second-order profiles), an infinite
//! acceleration limit the velocity (first order). A zero jerk limit, or a zero acceleration limit
//! in either direction, leaves the axis its current acceleration: it reaches the target only
//! with a single phase of constant acceleration (as in Ruckig), otherwise
//! [`OtgError::ZeroLimits`]; a moving axis with zero limits can then only arrive at that one
//! time. A zero velocity limit in one direction forbids motion that way.
//!
//! # Example
//!
//! ```
//! use rl_core::traj::otg::{self, Input, Limits, State};
//!
//! let limits = Limits::<2>::new([1.0, 2.0], [2.0, 3.0], [10.0, 20.0]);
//! let current = State { position: [0.0, 0.0], velocity: [0.5, -0.2], acceleration: [0.0, 1.0] };
//! let target = State::at_rest([1.0, -0.5]);
//! let trajectory = otg::calculate(&Input::new(current, target, limits))?;
//! let end = trajectory.at_time(trajectory.duration());
//! assert!((end.position[0] - 1.0).abs() < 1e-9 && end.velocity[1].abs() < 1e-9);
//! # Ok::<(), otg::OtgError>(())
//! ```

pub(crate) mod block;
pub(crate) mod brake;
mod error;
pub(crate) mod frame;
mod generator;
mod input;
pub(crate) mod lower_order;
pub(crate) mod phase;
mod position_limits;
mod profile;
pub(crate) mod roots;
pub(crate) mod sync;
pub(crate) mod third_order;
mod trajectory;
pub(crate) mod velocity;
mod waypoints;

pub use error::{Limit, OtgError, Quantity};
pub use generator::{Otg, Output, braking};
pub use input::{Input, Interface, Limits, MAX_WAYPOINTS, State, Synchronization, Waypoints};
pub use profile::AxisProfile;
pub use trajectory::{Derivative, LimitViolation, OtgTrajectory};
pub use waypoints::{
    LEVELS, MAX_SECTIONS, REFINE_STEPS, SWEEPS, WaypointTrajectory, calculate_waypoints,
};

use block::Axis;
use frame::{Bounds, End};

/// The limits of one axis in the form of the solvers.
fn bounds<const N: usize>(limits: &Limits<N>, axis: usize) -> Bounds {
    Bounds {
        v_max: limits.max_velocity[axis],
        v_min: limits.min_velocity[axis],
        a_max: limits.max_acceleration[axis],
        a_min: limits.min_acceleration[axis],
        j: limits.max_jerk[axis],
    }
}

/// Step 1 for every axis, into `axes`.
fn step1<const N: usize>(input: &Input<N>, axes: &mut [Axis; N]) -> Result<(), OtgError> {
    let velocity = input.interface == Interface::Velocity;
    for (i, axis) in axes.iter_mut().enumerate() {
        axis.init(
            i,
            velocity,
            [
                input.current.position[i],
                input.current.velocity[i],
                input.current.acceleration[i],
            ],
            [
                input.target.position[i],
                input.target.velocity[i],
                input.target.acceleration[i],
            ],
            bounds(&input.limits, i),
        )?;
    }
    Ok(())
}

/// The time-optimal trajectory from `input.current` to `input.target` (see the module docs).
///
/// Does not allocate. Errors name what is wrong and on which axis.
pub fn calculate<const N: usize>(input: &Input<N>) -> Result<OtgTrajectory<N>, OtgError> {
    let mut trajectory = OtgTrajectory::hold([0.0; N], [0.0; N], [0.0; N]);
    calculate_into(input, &mut trajectory)?;
    Ok(trajectory)
}

/// As [`calculate`], writing into `trajectory` (a trajectory of 7 axes is about 5.5 KB: a
/// control loop keeps one and lets the generator overwrite it). On error `trajectory` is left
/// in an unspecified but valid state.
pub fn calculate_into<const N: usize>(
    input: &Input<N>,
    trajectory: &mut OtgTrajectory<N>,
) -> Result<(), OtgError> {
    input.validate()?;
    if !input.waypoints.is_empty() && input.interface == Interface::Position {
        return Err(OtgError::WaypointsUnsupported);
    }
    let mut axes = [Axis::IDLE; N];
    step1(input, &mut axes)?;
    sync::synchronize(input, &axes, trajectory)?;
    let l = &input.limits;
    if l.min_position
        .iter()
        .chain(&l.max_position)
        .any(|p| p.is_finite())
    {
        position_limits::enforce(input, &axes, trajectory)?;
    }
    check_end(input, trajectory)
}

/// Every axis ends in its target state (within the profile tolerances) and nothing is NaN.
fn check_end<const N: usize>(input: &Input<N>, t: &OtgTrajectory<N>) -> Result<(), OtgError> {
    if !t.duration.is_finite() {
        return Err(OtgError::DurationNotFinite);
    }
    let velocity = input.interface == Interface::Velocity;
    for (axis, profile) in t.axes.iter().enumerate() {
        let [p, v, a] = profile.end;
        let end = End {
            p,
            v,
            a,
            scale: profile.scale(),
        };
        let target_p = if velocity {
            f64::NAN
        } else {
            input.target.position[axis]
        };
        // The blend of two profiles rounds twice.
        let ok = p.is_finite()
            && end.reaches_within(
                target_p,
                input.target.velocity[axis],
                input.target.acceleration[axis],
                2.0,
            );
        if !ok {
            return Err(OtgError::NoSynchronization {
                axis,
                duration: t.duration,
            });
        }
    }
    Ok(())
}
