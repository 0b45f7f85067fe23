//! The common duration of all axes and each axis' profile for it.
//!
//! Time synchronisation (Berscheid & Kröger 2021, §III-E): the common duration is the smallest
//! candidate — an axis' shortest duration, the end of one of its blocked intervals, or the
//! minimum duration asked for — that is at least every axis' shortest duration and inside no
//! axis' blocked interval. The axis whose candidate it is (the limiting axis) plays its extremal
//! profile; every other axis plays the blend of [`super::block`] for that duration.

use super::block::{Axis, Plan};
use super::error::OtgError;
use super::input::{Input, Synchronization};
use super::phase;
use super::profile::AxisProfile;
use super::trajectory::OtgTrajectory;

/// The smallest duration that suits every axis in `synced`, not below `minimum`, and the axis
/// it comes from (`None` when it is the minimum duration).
pub(crate) fn common_duration<const N: usize>(
    axes: &[Axis; N],
    synced: &[bool; N],
    minimum: Option<f64>,
) -> Result<(f64, Option<usize>), OtgError> {
    let mut lower = minimum.unwrap_or(0.0);
    for (axis, &s) in axes.iter().zip(synced) {
        if s {
            lower = lower.max(axis.t_min);
        }
    }
    let suits = |t: f64| {
        t >= lower
            && t.is_finite()
            && axes
                .iter()
                .zip(synced)
                .all(|(axis, &s)| !s || !axis.is_blocked(t))
    };
    let mut best = (f64::INFINITY, None);
    let mut consider = |t: f64, from: Option<usize>| {
        if t < best.0 && suits(t) {
            best = (t, from);
        }
    };
    if let Some(m) = minimum {
        consider(m, None);
    }
    for (i, axis) in axes.iter().enumerate() {
        if !synced[i] {
            continue;
        }
        consider(axis.t_min, Some(i));
        for &(_, right) in &axis.blocked[..axis.n_blocked] {
            consider(right, Some(i));
        }
    }
    if best.0.is_finite() {
        Ok(best)
    } else if let Some(axis) = (0..N).find(|&i| synced[i] && axes[i].n_blocked > 0) {
        Err(OtgError::ZeroLimits { axis })
    } else {
        Err(OtgError::NoCommonDuration)
    }
}

/// The profile of one axis from its start: braking, then `plan`.
pub(crate) fn build_axis(profile: &mut AxisProfile, axis: &Axis, start: [f64; 3], plan: &Plan) {
    profile.reset(start[0], start[1], start[2]);
    append_axis(profile, axis, plan);
}

/// Appends to `profile` the braking of `axis`, then `plan`.
pub(crate) fn append_axis(profile: &mut AxisProfile, axis: &Axis, plan: &Plan) {
    let b = &axis.brake;
    if b.second_order {
        profile.push_acceleration(b.t[0], b.a);
    } else {
        profile.push_jerk(b.t[0], b.j[0]);
        profile.push_jerk(b.t[1], b.j[1]);
    }
    profile.mark_brake_end();
    match plan {
        Plan::One(shape) => profile.push_shape(shape),
        Plan::Blend(first, second, weight) => profile.push_blend(first, second, *weight),
    }
}

/// Step 2 and assembly for inputs without waypoints: the common duration, each axis' plan
/// (phase-synchronised where possible), and the trajectory.
pub(crate) fn synchronize<const N: usize>(
    input: &Input<N>,
    axes: &[Axis; N],
    trajectory: &mut OtgTrajectory<N>,
) -> Result<(), OtgError> {
    let mode = input.synchronization;
    let synced = [mode != Synchronization::None; N];
    let min_durations: [f64; N] = core::array::from_fn(|i| axes[i].t_min);
    let starts: [[f64; 3]; N] = core::array::from_fn(|i| {
        [
            input.current.position[i],
            input.current.velocity[i],
            input.current.acceleration[i],
        ]
    });
    trajectory.min_durations = min_durations;

    if mode == Synchronization::None {
        for i in 0..N {
            build_axis(
                &mut trajectory.axes[i],
                &axes[i],
                starts[i],
                &Plan::One(axes[i].fastest()),
            );
        }
        trajectory.duration = min_durations.iter().fold(0.0, |d: f64, &t| d.max(t));
        return Ok(());
    }

    let (duration, limiting) = common_duration(axes, &synced, input.minimum_duration)?;
    trajectory.duration = duration;

    if mode == Synchronization::Phase
        && let Some(limiting) = limiting
        && let Some(shapes) = phase::scaled(axes, limiting, duration)
    {
        for i in 0..N {
            build_axis(
                &mut trajectory.axes[i],
                &axes[i],
                starts[i],
                &Plan::One(shapes[i]),
            );
        }
        return Ok(());
    }

    for i in 0..N {
        let at_rest = input.target.velocity[i] == 0.0 && input.target.acceleration[i] == 0.0;
        let plan = if mode == Synchronization::TimeIfNecessary && at_rest {
            Plan::One(axes[i].fastest())
        } else {
            axes[i].plan(i, duration)?
        };
        build_axis(&mut trajectory.axes[i], &axes[i], starts[i], &plan);
    }
    Ok(())
}
