//! The generated trajectory: one profile per axis, evaluated at any time.

use super::input::Limits;
use super::profile::AxisProfile;
use crate::traj::{Sample, Trajectory, clamp_time};

/// A derivative of the motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Derivative {
    /// Position.
    Position,
    /// Velocity.
    Velocity,
    /// Acceleration.
    Acceleration,
    /// Jerk.
    Jerk,
}

/// The worst excess over a limit found by [`OtgTrajectory::limit_violation`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitViolation {
    /// Axis.
    pub axis: usize,
    /// Which limit.
    pub derivative: Derivative,
    /// When (seconds).
    pub time: f64,
    /// The value there.
    pub value: f64,
    /// The limit it exceeds.
    pub limit: f64,
}

/// A trajectory of `N` axes from the generator: position, velocity, acceleration and jerk at any
/// time from closed forms (cubic polynomials per segment). Before 0 it holds the start state;
/// after [`OtgTrajectory::duration`] every axis continues from its target state with constant
/// acceleration (a moving target keeps moving; a target at rest stays there).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OtgTrajectory<const N: usize> {
    pub(crate) axes: [AxisProfile; N],
    pub(crate) duration: f64,
    /// Each axis' shortest duration on its own (before synchronisation).
    pub(crate) min_durations: [f64; N],
}

impl<const N: usize> OtgTrajectory<N> {
    /// A trajectory that stays at `state` forever.
    pub fn hold(position: [f64; N], velocity: [f64; N], acceleration: [f64; N]) -> Self {
        Self {
            axes: core::array::from_fn(|i| {
                AxisProfile::at_rest(position[i], velocity[i], acceleration[i])
            }),
            duration: 0.0,
            min_durations: [0.0; N],
        }
    }

    /// Duration in seconds until every axis has reached its target.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The shortest duration of each axis on its own (the synchronised duration is the
    /// earliest time every axis can make).
    pub fn min_durations(&self) -> [f64; N] {
        self.min_durations
    }

    /// The profile of one axis.
    pub fn axis(&self, axis: usize) -> Option<&AxisProfile> {
        self.axes.get(axis)
    }

    /// Position, velocity, acceleration and jerk of every axis at `t` seconds.
    #[inline]
    pub fn at_time(&self, t: f64) -> Sample<N> {
        self.at_time_from(t, &mut [0; N])
    }

    /// As [`Self::at_time`], starting each axis' search at the segment in `cursor` and leaving
    /// there the segment found: for increasing times (a control loop) this is a constant-time
    /// step.
    #[inline]
    pub fn at_time_from(&self, t: f64, cursor: &mut [usize; N]) -> Sample<N> {
        let mut s = Sample {
            position: [0.0; N],
            velocity: [0.0; N],
            acceleration: [0.0; N],
            jerk: [0.0; N],
        };
        for (i, axis) in self.axes.iter().enumerate() {
            let k = axis.find(t, cursor[i]);
            cursor[i] = k;
            [s.position[i], s.velocity[i], s.acceleration[i], s.jerk[i]] = axis.at_index(t, k);
        }
        s
    }

    /// Smallest and largest position of each axis over the trajectory
    /// (`[min, max, time of min, time of max]`).
    pub fn position_extrema(&self) -> [[f64; 4]; N] {
        core::array::from_fn(|i| self.axes[i].position_extrema())
    }
}

impl<const N: usize> OtgTrajectory<N> {
    /// The worst excess over `limits` anywhere on the trajectory, beyond
    /// `tolerance · max(1, |limit|)`, or `None`. Exact, not sampled: the extremes of each segment
    /// are its ends and, for the velocity, where the acceleration crosses zero; for the
    /// position, where the velocity does.
    ///
    /// A start beyond the limits is exempt while the trajectory brings it back: the braking
    /// part, and a velocity (acceleration) until it is first within its limits. With
    /// `velocity_free` (the velocity interface) velocity limits are not checked.
    pub fn limit_violation(
        &self,
        limits: &Limits<N>,
        tolerance: f64,
        velocity_free: bool,
    ) -> Option<LimitViolation> {
        let mut worst: Option<(f64, LimitViolation)> = None;
        let mut note = |excess: f64, v: LimitViolation| {
            if excess > tolerance * f64::max(1.0, v.limit.abs())
                && worst.is_none_or(|(w, _)| excess > w)
            {
                worst = Some((excess, v));
            }
        };
        for (axis, profile) in self.axes.iter().enumerate() {
            let (v_max, v_min) = (limits.max_velocity[axis], limits.min_velocity[axis]);
            let (a_max, a_min) = (limits.max_acceleration[axis], limits.min_acceleration[axis]);
            let (p_max, p_min) = (limits.max_position[axis], limits.min_position[axis]);
            let j_max = limits.max_jerk[axis];
            let mut v_armed = velocity_free;
            let mut a_armed = false;
            let mut check =
                |t: f64, [p, v, a, j]: [f64; 4], v_armed: &mut bool, a_armed: &mut bool| {
                    let mk = |derivative, value, limit| LimitViolation {
                        axis,
                        derivative,
                        time: t,
                        value,
                        limit,
                    };
                    note(p - p_max, mk(Derivative::Position, p, p_max));
                    note(p_min - p, mk(Derivative::Position, p, p_min));
                    if t < profile.brake_end {
                        return;
                    }
                    *v_armed |= v <= v_max && v >= v_min;
                    *a_armed |= a <= a_max && a >= a_min;
                    if *v_armed && !velocity_free {
                        note(v - v_max, mk(Derivative::Velocity, v, v_max));
                        note(v_min - v, mk(Derivative::Velocity, v, v_min));
                    }
                    if *a_armed {
                        note(a - a_max, mk(Derivative::Acceleration, a, a_max));
                        note(a_min - a, mk(Derivative::Acceleration, a, a_min));
                    }
                    note(j.abs() - j_max, mk(Derivative::Jerk, j, j_max));
                };
            for s in &profile.segments[..profile.len] {
                let length = s.length;
                let end = s.start + length;
                check(s.start, s.at(0.0), &mut v_armed, &mut a_armed);
                // Interior extremes: velocity where a = 0, position where v = 0.
                if s.j != 0.0 {
                    let tau = -s.a / s.j;
                    if tau > 0.0 && tau < length {
                        check(s.start + tau, s.at(tau), &mut v_armed, &mut a_armed);
                    }
                }
                let mut roots = [0.0; 2];
                let n = super::roots::quadratic(0.5 * s.j, s.a, s.v, &mut roots);
                for &tau in &roots[..n] {
                    if tau > 0.0 && tau < length {
                        check(s.start + tau, s.at(tau), &mut v_armed, &mut a_armed);
                    }
                }
                let mut at_end = s.at(length);
                at_end[3] = 0.0;
                check(end, at_end, &mut v_armed, &mut a_armed);
            }
            let [p, v, a] = profile.end;
            check(profile.duration, [p, v, a, 0.0], &mut v_armed, &mut a_armed);
        }
        worst.map(|(_, v)| v)
    }
}

impl<const N: usize> Trajectory<N> for OtgTrajectory<N> {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; N] {
        self.sample(t).derivative(order)
    }

    /// Clamped to `[0, duration]` as the trait requires ([`OtgTrajectory::at_time`] is not).
    fn sample(&self, t: f64) -> Sample<N> {
        self.at_time(clamp_time(t, self.duration))
    }
}
