//! Position limits: no axis ever leaves `[min_position, max_position]`.
//!
//! The time-optimal trajectory is kept when every axis stays inside (checked exactly: the
//! position extremes of every segment). Otherwise each axis that leaves, and each axis that
//! would leave at the longer common duration this brings, gets a motion that stays inside at
//! the cost of time:
//!
//! - target at rest: its own time-optimal profile, then it rests at the target;
//! - start at rest: it rests at the start, then its own time-optimal profile;
//! - otherwise it stops at the limit it would cross (at rest exactly there), waits there as
//!   long as the common duration asks, and goes on to the target from there.
//!
//! Each of these takes any duration from its own shortest on, so the common duration is the
//! smallest that suits them and the other axes (time synchronisation as in [`super::sync`]).
//! An axis moving too fast to stop before the limit is [`OtgError::CannotStopBeforePositionLimit`];
//! a target state that cannot be reached from rest inside the limits (its velocity carries it
//! from beyond one) is [`OtgError::PositionLimitsUnreachable`].
//!
//! This is not the time-optimal motion under position limits (which may touch a limit without
//! stopping there); it is the time-optimal one whenever that stays inside, and a valid one
//! otherwise.

use super::block::{Axis, Plan};
use super::error::OtgError;
use super::input::{Input, Interface, Synchronization};
use super::profile::AxisProfile;
use super::sync::{append_axis, common_duration};
use super::trajectory::OtgTrajectory;

/// Slack on a position limit (relative to the limit above 1): rounding only.
pub(crate) const POSITION_SLACK: f64 = 1e-9;

/// Whether `profile` stays in `[lo, hi]` (with [`POSITION_SLACK`]); `Some(crossed_high)` if not.
fn crossing(profile: &AxisProfile, lo: f64, hi: f64) -> Option<bool> {
    let [min, max, ..] = profile.position_extrema();
    let slack = |x: f64| POSITION_SLACK * f64::max(1.0, x.abs());
    if max > hi + slack(hi) {
        Some(true)
    } else if min < lo - slack(lo) {
        Some(false)
    } else {
        None
    }
}

/// How an axis that must avoid a limit moves.
#[derive(Clone, Copy, Debug)]
#[allow(clippy::large_enum_variant)]
enum Detour {
    /// Its own time-optimal profile, then rest at the target.
    ArriveEarly,
    /// Rest at the start, then its own time-optimal profile.
    LeaveLate,
    /// Stop at the limit (`first`), wait, then on to the target (`second`).
    ViaLimit { first: Axis, second: Axis, at: f64 },
}

/// The detour of axis `i` and its shortest duration; `crossed_high` tells which limit its
/// synchronised profile left.
fn detour<const N: usize>(
    input: &Input<N>,
    axes: &[Axis; N],
    i: usize,
    crossed_high: bool,
) -> Result<(Detour, f64), OtgError> {
    let (lo, hi) = (input.limits.min_position[i], input.limits.max_position[i]);
    let start = [
        input.current.position[i],
        input.current.velocity[i],
        input.current.acceleration[i],
    ];
    let target = [
        input.target.position[i],
        input.target.velocity[i],
        input.target.acceleration[i],
    ];
    let own = &axes[i];
    let mut own_profile = AxisProfile::at_rest(0.0, 0.0, 0.0);
    own_profile.reset(start[0], start[1], start[2]);
    append_axis(&mut own_profile, own, &Plan::One(own.fastest()));
    let own_inside = crossing(&own_profile, lo, hi).is_none();
    if own_inside && target[1] == 0.0 && target[2] == 0.0 {
        return Ok((Detour::ArriveEarly, own.t_min));
    }
    if own_inside && start[1] == 0.0 && start[2] == 0.0 {
        return Ok((Detour::LeaveLate, own.t_min));
    }
    // Stop at the limit the own profile crosses (or, if it stays inside, the synchronised one).
    let crossed_high = crossing(&own_profile, lo, hi).unwrap_or(crossed_high);
    let at = if crossed_high { hi } else { lo };
    let mut first = Axis::IDLE;
    first.init(i, false, start, [at, 0.0, 0.0], own.bounds)?;
    let mut second = Axis::IDLE;
    second.init(i, false, [at, 0.0, 0.0], target, own.bounds)?;
    let mut profile = AxisProfile::at_rest(0.0, 0.0, 0.0);
    profile.reset(start[0], start[1], start[2]);
    append_axis(&mut profile, &first, &Plan::One(first.fastest()));
    if crossing(&profile, lo, hi).is_some() {
        return Err(OtgError::CannotStopBeforePositionLimit { axis: i });
    }
    profile.reset(at, 0.0, 0.0);
    append_axis(&mut profile, &second, &Plan::One(second.fastest()));
    if crossing(&profile, lo, hi).is_some() {
        return Err(OtgError::PositionLimitsUnreachable { axis: i });
    }
    let duration = first.t_min + second.t_min;
    Ok((Detour::ViaLimit { first, second, at }, duration))
}

/// Builds axis `i` on its detour for the common `duration`.
fn build_detour<const N: usize>(
    input: &Input<N>,
    axes: &[Axis; N],
    i: usize,
    detour: &Detour,
    duration: f64,
    profile: &mut AxisProfile,
) {
    profile.reset(
        input.current.position[i],
        input.current.velocity[i],
        input.current.acceleration[i],
    );
    let own = &axes[i];
    match detour {
        Detour::ArriveEarly => append_axis(profile, own, &Plan::One(own.fastest())),
        Detour::LeaveLate => {
            profile.push_jerk(duration - own.t_min, 0.0);
            append_axis(profile, own, &Plan::One(own.fastest()));
        }
        Detour::ViaLimit { first, second, at } => {
            append_axis(profile, first, &Plan::One(first.fastest()));
            // At rest exactly on the limit while waiting (the end of `first` is there to
            // rounding).
            let wait = duration - first.t_min - second.t_min;
            profile.end = [*at, 0.0, 0.0];
            profile.push_jerk(wait, 0.0);
            append_axis(profile, second, &Plan::One(second.fastest()));
        }
    }
}

/// Checks the position limits of `trajectory` (calculated without them) and, where an axis
/// leaves them, replaces the trajectory by one with detours (see the module docs).
pub(crate) fn enforce<const N: usize>(
    input: &Input<N>,
    axes: &[Axis; N],
    trajectory: &mut OtgTrajectory<N>,
) -> Result<(), OtgError> {
    let l = &input.limits;
    for i in 0..N {
        if input.current.position[i] < l.min_position[i]
            || input.current.position[i] > l.max_position[i]
        {
            return Err(OtgError::CurrentOutsidePositionLimits { axis: i });
        }
        let target = input.target.position[i];
        if input.interface == Interface::Position
            && (target < l.min_position[i] || target > l.max_position[i])
        {
            return Err(OtgError::TargetOutsidePositionLimits { axis: i });
        }
    }
    let outside =
        |t: &OtgTrajectory<N>, i: usize| crossing(&t.axes[i], l.min_position[i], l.max_position[i]);
    if (0..N).all(|i| outside(trajectory, i).is_none()) {
        return Ok(());
    }
    if input.interface == Interface::Velocity {
        // The position is free there: a velocity that runs into a limit is the caller's to
        // change.
        let axis = (0..N)
            .find(|&i| outside(trajectory, i).is_some())
            .unwrap_or(0);
        return Err(OtgError::CannotStopBeforePositionLimit { axis });
    }
    let mut detours: [Option<(Detour, f64)>; N] = [None; N];
    // Each round adds the axes that leave the limits at the new duration; an axis once on a
    // detour stays on it, so this ends within N rounds.
    for _ in 0..N {
        for i in 0..N {
            if detours[i].is_none()
                && let Some(high) = outside(trajectory, i)
            {
                detours[i] = Some(detour(input, axes, i, high)?);
            }
        }
        if input.synchronization == Synchronization::None {
            // Every axis on its own: a detour at its own shortest duration.
            let mut longest = 0.0f64;
            for i in 0..N {
                match &detours[i] {
                    Some((d, t)) => {
                        build_detour(input, axes, i, d, *t, &mut trajectory.axes[i]);
                        longest = longest.max(*t);
                    }
                    None => longest = longest.max(axes[i].t_min),
                }
            }
            trajectory.duration = longest;
            return Ok(());
        }
        let free: [bool; N] = core::array::from_fn(|i| detours[i].is_none());
        let longest_detour = detours
            .iter()
            .flatten()
            .fold(input.minimum_duration.unwrap_or(0.0), |m, (_, t)| m.max(*t));
        let (duration, _) = common_duration(axes, &free, Some(longest_detour))?;
        trajectory.duration = duration;
        for i in 0..N {
            match &detours[i] {
                Some((d, _)) => build_detour(input, axes, i, d, duration, &mut trajectory.axes[i]),
                None => {
                    let start = [
                        input.current.position[i],
                        input.current.velocity[i],
                        input.current.acceleration[i],
                    ];
                    trajectory.axes[i].reset(start[0], start[1], start[2]);
                    append_axis(
                        &mut trajectory.axes[i],
                        &axes[i],
                        &axes[i].plan(i, duration)?,
                    );
                }
            }
        }
        if (0..N).all(|i| outside(trajectory, i).is_none()) {
            return Ok(());
        }
    }
    let axis = (0..N)
        .find(|&i| outside(trajectory, i).is_some())
        .unwrap_or(0);
    Err(OtgError::PositionLimitsUnreachable { axis })
}
