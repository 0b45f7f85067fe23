//! Trajectories through up to [`MAX_WAYPOINTS`] intermediate positions.
//!
//! The motion is a chain of sections, each a time-synchronised trajectory of this module from
//! one waypoint state to the next (position, a velocity, zero acceleration), so every axis is at
//! every waypoint at the same time. At a waypoint where an axis keeps its direction of travel it
//! passes with velocity `c_i · s · √(2 a · d)` (capped at its velocity limit), where `s` is the
//! direction, `a` its acceleration limit that way and `d` the shorter of the two distances to the
//! neighbouring waypoints (the speed from which it could still stop in that distance); where it
//! turns, or does not move on one side, it passes at rest. One factor `c_i ∈ [0, 1]` per
//! waypoint scales all axes alike (the joint-space direction of passing is kept).
//!
//! The factors minimise the total duration. A section's duration depends only on the factors at
//! its two ends, so the total is a chain: dynamic programming over [`LEVELS`] values per
//! waypoint finds the best combination on that grid, then golden-section steps on each factor in
//! turn (a fixed count, [`REFINE_STEPS`] per factor and [`SWEEPS`] sweeps) refine it. Every
//! count is fixed, nothing depends on a random start; with 8 waypoints this is a few thousand
//! section calculations, about 10 ms: waypoints are for planned motions, not for each control
//! cycle (a goal with waypoints in [`super::Otg`] is refused). Without waypoints the factors
//! are irrelevant and this is [`super::calculate`].
//!
//! This is not Ruckig Pro's time-optimal waypoint trajectory (which also frees the accelerations
//! at the waypoints); the comparison with it is not possible offline (its waypoint calculation
//! runs in a cloud service), and none is claimed.

use super::calculate_into;
use super::error::OtgError;
use super::input::{Input, Interface, MAX_WAYPOINTS, State};
use super::trajectory::{LimitViolation, OtgTrajectory};
use crate::traj::{Sample, Trajectory, clamp_time};

/// Values of each waypoint factor in the grid search.
pub const LEVELS: usize = 6;
/// Golden-section steps per factor and sweep.
pub const REFINE_STEPS: usize = 10;
/// Sweeps over all factors.
pub const SWEEPS: usize = 2;

/// Most sections of a waypoint trajectory.
pub const MAX_SECTIONS: usize = MAX_WAYPOINTS + 1;

/// A trajectory through waypoints: sections played one after another.
#[derive(Clone, Debug)]
pub struct WaypointTrajectory<const N: usize> {
    sections: [OtgTrajectory<N>; MAX_SECTIONS],
    starts: [f64; MAX_SECTIONS],
    count: usize,
    duration: f64,
    /// The state at each waypoint (where section `i` ends).
    passes: [State<N>; MAX_WAYPOINTS],
}

impl<const N: usize> WaypointTrajectory<N> {
    /// Total duration in seconds.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The sections (one more than the waypoints).
    pub fn sections(&self) -> &[OtgTrajectory<N>] {
        &self.sections[..self.count]
    }

    /// When each section starts.
    pub fn section_starts(&self) -> &[f64] {
        &self.starts[..self.count]
    }

    /// The state in which the trajectory passes each waypoint.
    pub fn passes(&self) -> &[State<N>] {
        &self.passes[..self.count - 1]
    }

    /// Position, velocity, acceleration and jerk at `t` (after the end, the last section goes
    /// on: a target at rest stays there).
    pub fn at_time(&self, t: f64) -> Sample<N> {
        let mut k = 0;
        while k + 1 < self.count && t >= self.starts[k + 1] {
            k += 1;
        }
        self.sections[k].at_time(t - self.starts[k])
    }

    /// The worst excess over `limits` of any section ([`OtgTrajectory::limit_violation`]), with
    /// its time on the whole trajectory.
    pub fn limit_violation(
        &self,
        limits: &super::Limits<N>,
        tolerance: f64,
    ) -> Option<LimitViolation> {
        let mut worst: Option<(f64, LimitViolation)> = None;
        for (section, start) in self.sections().iter().zip(self.section_starts()) {
            if let Some(mut v) = section.limit_violation(limits, tolerance, false) {
                v.time += start;
                let excess = (v.value.abs() - v.limit.abs()).abs();
                if worst.is_none_or(|(w, _)| excess > w) {
                    worst = Some((excess, v));
                }
            }
        }
        worst.map(|(_, v)| v)
    }
}

impl<const N: usize> Trajectory<N> for WaypointTrajectory<N> {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; N] {
        self.sample(t).derivative(order)
    }

    fn sample(&self, t: f64) -> Sample<N> {
        self.at_time(clamp_time(t, self.duration))
    }
}

/// The waypoint velocity of every axis at factor 1 (see the module docs).
fn passing_velocities<const N: usize>(
    input: &Input<N>,
    points: &[[f64; N]],
) -> [[f64; N]; MAX_WAYPOINTS] {
    let l = &input.limits;
    let mut out = [[0.0; N]; MAX_WAYPOINTS];
    for k in 1..points.len() - 1 {
        for i in 0..N {
            let before = points[k][i] - points[k - 1][i];
            let after = points[k + 1][i] - points[k][i];
            if before == 0.0 || after == 0.0 || (before > 0.0) != (after > 0.0) {
                continue;
            }
            let d = before.abs().min(after.abs());
            out[k - 1][i] = if after > 0.0 {
                libm::sqrt(2.0 * l.max_acceleration[i] * d).min(l.max_velocity[i])
            } else {
                -libm::sqrt(2.0 * -l.min_acceleration[i] * d).min(-l.min_velocity[i])
            };
        }
    }
    out
}

/// Section `k` from waypoint state `k - 1` (or the start) to waypoint `k` (or the target) with
/// the given factors at its ends; its duration (infinite if it cannot be calculated).
#[allow(clippy::too_many_arguments)]
fn section<const N: usize>(
    input: &Input<N>,
    points: &[[f64; N]],
    velocity: &[[f64; N]; MAX_WAYPOINTS],
    k: usize,
    c_from: f64,
    c_to: f64,
    out: &mut OtgTrajectory<N>,
) -> f64 {
    let last = points.len() - 1;
    let from = if k == 1 {
        input.current
    } else {
        State {
            position: points[k - 1],
            velocity: velocity[k - 2].map(|v| v * c_from),
            acceleration: [0.0; N],
        }
    };
    let to = if k == last {
        input.target
    } else {
        State {
            position: points[k],
            velocity: velocity[k - 1].map(|v| v * c_to),
            acceleration: [0.0; N],
        }
    };
    let mut request = *input;
    request.current = from;
    request.target = to;
    request.waypoints.clear();
    match calculate_into(&request, out) {
        Ok(()) => out.duration(),
        Err(_) => f64::INFINITY,
    }
}

/// The trajectory from `input.current` through `input.waypoints` to `input.target` (see the
/// module docs). Without waypoints, the single section of [`super::calculate`].
pub fn calculate_waypoints<const N: usize>(
    input: &Input<N>,
) -> Result<WaypointTrajectory<N>, OtgError> {
    input.validate()?;
    if input.interface != Interface::Position || input.minimum_duration.is_some() {
        return Err(OtgError::WaypointsUnsupported);
    }
    let l = &input.limits;
    for point in input.waypoints.as_slice() {
        for i in 0..N {
            if point[i] < l.min_position[i] || point[i] > l.max_position[i] {
                return Err(OtgError::TargetOutsidePositionLimits { axis: i });
            }
        }
    }
    let mut points = [[0.0; N]; MAX_SECTIONS + 1];
    let wp = input.waypoints.as_slice();
    points[0] = input.current.position;
    points[1..=wp.len()].copy_from_slice(wp);
    points[wp.len() + 1] = input.target.position;
    let points = &points[..wp.len() + 2];
    let sections = points.len() - 1;
    let velocity = passing_velocities(input, points);

    let mut scratch = OtgTrajectory::hold([0.0; N], [0.0; N], [0.0; N]);
    let mut factors = [0.0; MAX_WAYPOINTS];
    let waypoints = sections - 1;
    if waypoints > 0 {
        // Dynamic programming over the grid: best[k][j] = shortest time to waypoint k passing at
        // level j, from[k][j] the level at waypoint k - 1 it came from.
        let level = |j: usize| j as f64 / (LEVELS - 1) as f64;
        let mut best = [[f64::INFINITY; LEVELS]; MAX_WAYPOINTS];
        let mut from = [[0usize; LEVELS]; MAX_WAYPOINTS];
        for j in 0..LEVELS {
            best[0][j] = section(input, points, &velocity, 1, 0.0, level(j), &mut scratch);
        }
        for k in 1..waypoints {
            for j in 0..LEVELS {
                for i in 0..LEVELS {
                    if !best[k - 1][i].is_finite() {
                        continue;
                    }
                    let t = best[k - 1][i]
                        + section(
                            input,
                            points,
                            &velocity,
                            k + 1,
                            level(i),
                            level(j),
                            &mut scratch,
                        );
                    if t < best[k][j] {
                        best[k][j] = t;
                        from[k][j] = i;
                    }
                }
            }
        }
        let mut end = (f64::INFINITY, 0);
        for j in 0..LEVELS {
            let t = best[waypoints - 1][j]
                + section(
                    input,
                    points,
                    &velocity,
                    sections,
                    level(j),
                    0.0,
                    &mut scratch,
                );
            if t < end.0 {
                end = (t, j);
            }
        }
        if !end.0.is_finite() {
            // Even passing at rest everywhere failed: report the section's own error below.
            factors = [0.0; MAX_WAYPOINTS];
        } else {
            let mut j = end.1;
            for k in (0..waypoints).rev() {
                factors[k] = level(j);
                j = from[k][j];
            }
        }
        // Golden-section refinement of each factor between its grid neighbours.
        let phi = 0.5 * (libm::sqrt(5.0) - 1.0);
        let step = 1.0 / (LEVELS - 1) as f64;
        for _ in 0..SWEEPS {
            for k in 0..waypoints {
                let c_before = if k == 0 { 0.0 } else { factors[k - 1] };
                let c_after = if k + 1 == waypoints {
                    0.0
                } else {
                    factors[k + 1]
                };
                let cost = |c: f64, scratch: &mut OtgTrajectory<N>| {
                    section(input, points, &velocity, k + 1, c_before, c, scratch)
                        + section(input, points, &velocity, k + 2, c, c_after, scratch)
                };
                let (mut lo, mut hi) = ((factors[k] - step).max(0.0), (factors[k] + step).min(1.0));
                let mut x1 = hi - phi * (hi - lo);
                let mut x2 = lo + phi * (hi - lo);
                let (mut f1, mut f2) = (cost(x1, &mut scratch), cost(x2, &mut scratch));
                for _ in 0..REFINE_STEPS {
                    if f1 <= f2 {
                        hi = x2;
                        x2 = x1;
                        f2 = f1;
                        x1 = hi - phi * (hi - lo);
                        f1 = cost(x1, &mut scratch);
                    } else {
                        lo = x1;
                        x1 = x2;
                        f1 = f2;
                        x2 = lo + phi * (hi - lo);
                        f2 = cost(x2, &mut scratch);
                    }
                }
                let current = cost(factors[k], &mut scratch);
                let (c, f) = if f1 <= f2 { (x1, f1) } else { (x2, f2) };
                if f < current {
                    factors[k] = c;
                }
            }
        }
    }

    // The chosen sections, for real (errors reported this time).
    let mut result = WaypointTrajectory {
        sections: core::array::from_fn(|_| scratch),
        starts: [0.0; MAX_SECTIONS],
        count: sections,
        duration: 0.0,
        passes: [State::at_rest([0.0; N]); MAX_WAYPOINTS],
    };
    let mut t = 0.0;
    let mut from = input.current;
    for k in 1..=sections {
        let to = if k == sections {
            input.target
        } else {
            State {
                position: points[k],
                velocity: velocity[k - 1].map(|v| v * factors[k - 1]),
                acceleration: [0.0; N],
            }
        };
        let mut request = *input;
        request.current = from;
        request.target = to;
        request.waypoints.clear();
        calculate_into(&request, &mut result.sections[k - 1])?;
        result.starts[k - 1] = t;
        t += result.sections[k - 1].duration();
        if k < sections {
            result.passes[k - 1] = to;
        }
        from = to;
    }
    result.duration = t;
    Ok(result)
}
