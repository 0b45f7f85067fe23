//! The 7-segment jerk-limited profile with trapezoidal acceleration ("double S") from rest to
//! rest, after Biagiotti & Melchiorri, *Trajectory Planning for Automatic Machines and Robots*
//! (Springer 2008), §3.4: jerk `+J, 0, -J, 0, -J, 0, +J`. For rest-to-rest motion this is the
//! time-optimal profile under velocity, acceleration and jerk limits (the same duration as
//! Ruckig's). Axes are synchronised by stretching each faster axis in time to the slowest
//! duration, which keeps every limit (velocity scales by `k`, acceleration `k²`, jerk `k³`,
//! `k ≤ 1`).

use glam::{DQuat, DVec3};

use super::{
    Limits, Piecewise, RotationSample, RotationTrajectory, Sample, Trajectory, TrajectoryError,
    check_finite_points, clamp_time,
};

/// Phase durations `(Tj, Ta, Tv)` of the time-optimal rest-to-rest profile of every axis
/// (Biagiotti & Melchiorri eqs. 3.30-3.33 with zero boundary velocities). The quotients of
/// distance and limits come first, for all axes at once, so the divisions vectorise; the case
/// distinctions follow per axis.
fn phase_times<const D: usize>(
    start: &[f64; D],
    goal: &[f64; D],
    limits: &Limits<D>,
) -> [(f64, f64, f64); D] {
    let (mut h, mut a_j, mut v_a, mut v_j) = ([0.0; D], [0.0; D], [0.0; D], [0.0; D]);
    let (mut h_v, mut h_a, mut h_2j, mut short) = ([0.0; D], [0.0; D], [0.0; D], [0.0; D]);
    for axis in 0..D {
        let (v, a, j) = (
            limits.velocity[axis],
            limits.acceleration[axis],
            limits.jerk[axis],
        );
        h[axis] = libm::fabs(goal[axis] - start[axis]);
        a_j[axis] = a / j;
        v_a[axis] = v / a;
        v_j[axis] = v / j;
        h_v[axis] = h[axis] / v;
        h_a[axis] = h[axis] / a;
        h_2j[axis] = h[axis] / (2.0 * j);
        // Below this distance the acceleration limit is not reached.
        short[axis] = 2.0 * a * a * a / (j * j);
    }
    core::array::from_fn(|axis| {
        if h[axis] == 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let (v, a, j) = (
            limits.velocity[axis],
            limits.acceleration[axis],
            limits.jerk[axis],
        );
        let (mut tj, mut ta) = if v * j >= a * a {
            (a_j[axis], a_j[axis] + v_a[axis])
        } else {
            let tj = libm::sqrt(v_j[axis]);
            (tj, 2.0 * tj)
        };
        let mut tv = h_v[axis] - ta;
        if tv < 0.0 {
            tv = 0.0;
            if h[axis] >= short[axis] {
                tj = a_j[axis];
                ta = 0.5 * tj + libm::sqrt(0.25 * tj * tj + h_a[axis]);
            } else {
                tj = libm::cbrt(h_2j[axis]);
                ta = 2.0 * tj;
            }
        }
        (tj, ta, tv)
    })
}

/// Jerk-limited rest-to-rest motion of `D` axes, synchronised to the slowest axis.
///
/// The seven phases are symmetric about the midpoint `T/2`: `p(T - t) = start + goal - p(t)`,
/// velocity and jerk are even, acceleration is odd. So only the four phases of the first half
/// are stored (jerk up, constant acceleration, jerk down, cruise) and the second half is
/// evaluated mirrored: construction integrates three phases, evaluation picks one of four.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JerkLimited<const D: usize> {
    start: [f64; D],
    goal: [f64; D],
    /// The first-half phases in order.
    phases: [Phase<D>; 4],
    duration: f64,
}

/// One first-half phase of every axis: its start time and the state there.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Phase<const D: usize> {
    begin: [f64; D],
    /// Displacement from the start.
    displacement: [f64; D],
    velocity: [f64; D],
    acceleration: [f64; D],
    /// Constant jerk of the phase.
    jerk: [f64; D],
}

impl<const D: usize> Phase<D> {
    /// The phase that starts when this one has lasted `length` (per axis), with `jerk`.
    #[inline]
    fn then(&self, length: &[f64; D], jerk: [f64; D]) -> Self {
        let mut next = Self {
            begin: [0.0; D],
            displacement: [0.0; D],
            velocity: [0.0; D],
            acceleration: [0.0; D],
            jerk,
        };
        for axis in 0..D {
            let d = length[axis];
            let (x, v, a, j) = (
                self.displacement[axis],
                self.velocity[axis],
                self.acceleration[axis],
                self.jerk[axis],
            );
            next.begin[axis] = self.begin[axis] + d;
            next.displacement[axis] = x + d * (v + d * (0.5 * a + d * j * (1.0 / 6.0)));
            next.velocity[axis] = v + d * (a + 0.5 * d * j);
            next.acceleration[axis] = a + d * j;
        }
        next
    }
}

impl<const D: usize> JerkLimited<D> {
    /// The time-optimal motion from `start` to `goal` at rest under finite, positive limits.
    pub fn new(
        start: [f64; D],
        goal: [f64; D],
        limits: &Limits<D>,
    ) -> Result<Self, TrajectoryError> {
        limits.validate(true)?;
        check_finite_points(&[start, goal])?;
        let times = phase_times(&start, &goal, limits);
        let duration = times
            .iter()
            .fold(0.0, |d: f64, (_, ta, tv)| d.max(2.0 * ta + tv));
        if !duration.is_finite() {
            return Err(TrajectoryError::Unreachable);
        }
        // Phase durations stretched by 1/k (k = own duration / common duration ≤ 1) and
        // jerks scaled by k³; the cruise takes up what the common duration leaves.
        let zero = [0.0; D];
        let (mut jerk, mut jerk_time, mut accel_time) = (zero, zero, zero);
        for axis in 0..D {
            let (tj, ta, tv) = times[axis];
            let own = 2.0 * ta + tv;
            let k = if duration > 0.0 { own / duration } else { 1.0 };
            let stretch = if k > 0.0 { 1.0 / k } else { 0.0 };
            let sign = if goal[axis] >= start[axis] { 1.0 } else { -1.0 };
            jerk[axis] = sign * limits.jerk[axis] * k * k * k;
            jerk_time[axis] = tj * stretch;
            accel_time[axis] = (ta - 2.0 * tj).max(0.0) * stretch;
        }
        let rising = Phase {
            begin: zero,
            displacement: zero,
            velocity: zero,
            acceleration: zero,
            jerk,
        };
        let constant = rising.then(&jerk_time, zero);
        let falling = constant.then(&accel_time, jerk.map(|j| -j));
        let mut cruise = falling.then(&jerk_time, zero);
        // The cruise starts by the midpoint, also after rounding, so the phase ends are sorted.
        for begin in cruise.begin.iter_mut() {
            *begin = begin.min(0.5 * duration);
        }
        Ok(Self {
            start,
            goal,
            phases: [rising, constant, falling, cruise],
            duration,
        })
    }

    /// End time of each of the seven phases of `axis` (velocity and acceleration peak at
    /// these boundaries; zero-length phases repeat a time, an axis that does not move cruises
    /// at rest from 0 to the end). `None` for an axis out of range.
    pub fn phase_ends(&self, axis: usize) -> Option<[f64; 7]> {
        (axis < D).then(|| {
            let t = self.duration;
            let [e1, e2, e3] = [1, 2, 3].map(|i| self.phases[i].begin[axis]);
            [e1, e2, e3, t - e3, t - e2, t - e1, t]
        })
    }

    /// Samples `t` (clamped) in the first half, or with `MIRRORED` in the second half, where
    /// `u = T - t` is the time to the end. At a phase boundary (a time [`Self::phase_ends`]
    /// returns) the jerk is that of the phase starting there, in both halves.
    #[inline(always)]
    fn half<const MIRRORED: bool>(&self, t: f64, u: f64) -> Sample<D> {
        // Whether first-half phase `begin` has been reached; in the second half, compared
        // with the phase end exactly as `phase_ends` computes it.
        let duration = self.duration;
        let after = |begin: f64| {
            if MIRRORED {
                t < duration - begin
            } else {
                t >= begin
            }
        };
        let mut s = Sample {
            position: [0.0; D],
            velocity: [0.0; D],
            acceleration: [0.0; D],
            jerk: [0.0; D],
        };
        let [p0, p1, p2, p3] = &self.phases;
        for axis in 0..D {
            // In a control loop `u` moves slowly, so these branches are predicted.
            let (phase, jerk) = if !after(p1.begin[axis]) {
                (p0, p0.jerk[axis])
            } else if !after(p2.begin[axis]) {
                (p1, p1.jerk[axis])
            } else if !after(p3.begin[axis]) {
                (p2, p2.jerk[axis])
            } else {
                // A cruise of zero length ends at the midpoint, where phase 5 starts.
                let cruise_over = !MIRRORED && t >= duration - p3.begin[axis];
                (p3, if cruise_over { p2.jerk[axis] } else { 0.0 })
            };
            let tau = u - phase.begin[axis];
            let (x, v, a, j) = (
                phase.displacement[axis],
                phase.velocity[axis],
                phase.acceleration[axis],
                phase.jerk[axis],
            );
            let x = x + tau * (v + tau * (0.5 * a + tau * j * (1.0 / 6.0)));
            let a_now = a + tau * j;
            if MIRRORED {
                s.position[axis] = self.goal[axis] - x;
                s.acceleration[axis] = -a_now;
            } else {
                s.position[axis] = self.start[axis] + x;
                s.acceleration[axis] = a_now;
            }
            s.velocity[axis] = v + tau * (a + 0.5 * tau * j);
            s.jerk[axis] = jerk;
        }
        s
    }

    /// The duration each axis would need alone (its time-optimal duration).
    pub fn axis_durations(start: [f64; D], goal: [f64; D], limits: &Limits<D>) -> [f64; D] {
        phase_times(&start, &goal, limits).map(|(_, ta, tv)| 2.0 * ta + tv)
    }
}

impl<const D: usize> Trajectory<D> for JerkLimited<D> {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; D] {
        let s = self.sample(t);
        match order {
            0 => s.position,
            1 => s.velocity,
            2 => s.acceleration,
            3 => s.jerk,
            _ => [0.0; D],
        }
    }

    #[inline]
    fn sample(&self, t: f64) -> Sample<D> {
        let t = clamp_time(t, self.duration);
        // Exact for t ≥ T/2 (Sterbenz), where it is used.
        let rest = self.duration - t;
        if t > rest {
            self.half::<true>(t, rest)
        } else {
            self.half::<false>(t, t)
        }
    }
}

/// Jerk-limited rest-to-rest moves through `points` in order (a spline of jerk-limited
/// profiles). Needs capacity for `n - 1` moves.
pub fn jerk_limited_through<const D: usize, const MAX: usize>(
    points: &[[f64; D]],
    limits: &Limits<D>,
) -> Result<Piecewise<JerkLimited<D>, MAX>, TrajectoryError> {
    if points.len() < 2 {
        return Err(TrajectoryError::TooFewWaypoints {
            required: 2,
            given: points.len(),
        });
    }
    if points.len() - 1 > MAX {
        return Err(TrajectoryError::Capacity {
            capacity: MAX,
            requested: points.len() - 1,
        });
    }
    let mut spline = Piecewise::new();
    for pair in points.windows(2) {
        spline.push(JerkLimited::new(pair[0], pair[1], limits)?)?;
    }
    Ok(spline)
}

/// A rotation from rest to rest about a fixed world axis, with the rotation angle following the
/// jerk-limited profile (limits on angular velocity, acceleration and jerk in rad/s^n).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JerkLimitedRotation {
    start: DQuat,
    axis: DVec3,
    angle: JerkLimited<1>,
}

impl JerkLimitedRotation {
    /// Shortest rotation from `q0` to `q1`.
    pub fn new(
        q0: DQuat,
        q1: DQuat,
        velocity: f64,
        acceleration: f64,
        jerk: f64,
    ) -> Result<Self, TrajectoryError> {
        if !q0.is_finite() || !q1.is_finite() {
            return Err(TrajectoryError::NotFinite {
                what: "quaternion",
                index: 0,
            });
        }
        let q0 = q0.normalize();
        let mut delta = q1.normalize() * q0.conjugate();
        if delta.w < 0.0 {
            delta = -delta;
        }
        let (axis, angle) = delta.to_axis_angle();
        let limits = Limits::uniform(velocity, acceleration, jerk);
        Ok(Self {
            start: q0,
            axis,
            angle: JerkLimited::new([0.0], [angle], &limits)?,
        })
    }
}

impl RotationTrajectory for JerkLimitedRotation {
    fn duration(&self) -> f64 {
        self.angle.duration
    }

    fn rotation(&self, t: f64) -> RotationSample {
        let s = self.angle.sample(t);
        RotationSample {
            orientation: DQuat::from_axis_angle(self.axis, s.position[0]) * self.start,
            angular_velocity: self.axis * s.velocity[0],
            angular_acceleration: self.axis * s.acceleration[0],
        }
    }
}
