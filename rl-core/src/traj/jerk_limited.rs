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

/// Jerk pattern of the seven phases.
const JERK_SIGN: [f64; 7] = [1.0, 0.0, -1.0, 0.0, -1.0, 0.0, 1.0];

/// Phase durations `(Tj, Ta, Tv)` of the time-optimal rest-to-rest profile over distance
/// `h ≥ 0` (Biagiotti & Melchiorri eqs. 3.30-3.33 with zero boundary velocities).
fn phase_times(h: f64, v: f64, a: f64, j: f64) -> (f64, f64, f64) {
    if h == 0.0 {
        return (0.0, 0.0, 0.0);
    }
    let (mut tj, mut ta) = if v * j >= a * a {
        (a / j, a / j + v / a)
    } else {
        let tj = libm::sqrt(v / j);
        (tj, 2.0 * tj)
    };
    let mut tv = h / v - ta;
    if tv < 0.0 {
        tv = 0.0;
        if h >= 2.0 * a * a * a / (j * j) {
            tj = a / j;
            ta = 0.5 * tj + libm::sqrt(0.25 * tj * tj + h / a);
        } else {
            tj = libm::cbrt(h / (2.0 * j));
            ta = 2.0 * tj;
        }
    }
    (tj, ta, tv)
}

/// Jerk-limited rest-to-rest motion of `D` axes, synchronised to the slowest axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JerkLimited<const D: usize> {
    /// Phase end times, `[phase][axis]`; phase `i` starts at `end[i - 1]` (the first at 0).
    /// Stored axis-minor so construction runs over all axes at once.
    end: [[f64; D]; 7],
    /// Position, velocity and acceleration at each phase start, `[phase][quantity][axis]`.
    state: [[[f64; D]; 3]; 7],
    /// Jerk of the first phase of each axis; phase `i` has `JERK_SIGN[i]` times it.
    jerk: [f64; D],
    duration: f64,
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
        let mut times = [(0.0, 0.0, 0.0); D];
        let mut duration: f64 = 0.0;
        for axis in 0..D {
            let h = libm::fabs(goal[axis] - start[axis]);
            times[axis] = phase_times(
                h,
                limits.velocity[axis],
                limits.acceleration[axis],
                limits.jerk[axis],
            );
            let (_, ta, tv) = times[axis];
            duration = duration.max(2.0 * ta + tv);
        }
        if !duration.is_finite() {
            return Err(TrajectoryError::Unreachable);
        }
        // Phase durations stretched by 1/k (k = own duration / common duration ≤ 1) and
        // jerks scaled by k³, then the seven phases integrated for all axes at once.
        let mut out = Self {
            end: [[0.0; D]; 7],
            state: [[[0.0; D]; 3]; 7],
            jerk: [0.0; D],
            duration,
        };
        let mut durations = [[0.0; D]; 7];
        for axis in 0..D {
            let (tj, ta, tv) = times[axis];
            let own = 2.0 * ta + tv;
            let k = if duration > 0.0 { own / duration } else { 1.0 };
            let stretch = if k > 0.0 { 1.0 / k } else { 0.0 };
            let sign = if goal[axis] >= start[axis] { 1.0 } else { -1.0 };
            out.jerk[axis] = sign * limits.jerk[axis] * k * k * k;
            let (tj, cruise_a) = (tj * stretch, (ta - 2.0 * tj).max(0.0) * stretch);
            for (i, d) in [tj, cruise_a, tj, tv * stretch, tj, cruise_a, tj]
                .into_iter()
                .enumerate()
            {
                durations[i][axis] = d;
            }
        }
        let mut x = start;
        let (mut v, mut a, mut t) = ([0.0; D], [0.0; D], [0.0; D]);
        for i in 0..7 {
            out.state[i] = [x, v, a];
            for axis in 0..D {
                let (d, j) = (durations[i][axis], JERK_SIGN[i] * out.jerk[axis]);
                x[axis] += d * (v[axis] + d * (0.5 * a[axis] + d * j * (1.0 / 6.0)));
                v[axis] += d * (a[axis] + 0.5 * d * j);
                a[axis] += d * j;
                t[axis] += d;
            }
            out.end[i] = t;
        }
        Ok(out)
    }

    /// End time of each of the seven phases of `axis` (velocity and acceleration peak at
    /// these boundaries; zero-length phases repeat a time). `None` for an axis out of range.
    pub fn phase_ends(&self, axis: usize) -> Option<[f64; 7]> {
        (axis < D).then(|| core::array::from_fn(|i| self.end[i][axis]))
    }

    /// Position, velocity, acceleration and jerk of one axis at `t` (clamped to the axis's
    /// own end, which is the common end for moving axes).
    #[inline]
    fn eval_axis(&self, axis: usize, t: f64) -> [f64; 4] {
        let t = clamp_time(t, self.end[6][axis]);
        // Phase ends are sorted; scan from the first phase. In a control loop `t` advances
        // slowly, so the exit branch is predicted (NaN stops at phase 0).
        let mut i = 0;
        while i < 6 && t >= self.end[i][axis] {
            i += 1;
        }
        let tau = t - if i > 0 { self.end[i - 1][axis] } else { 0.0 };
        let [x, v, a] = [0, 1, 2].map(|q| self.state[i][q][axis]);
        let j = JERK_SIGN[i] * self.jerk[axis];
        [
            x + tau * (v + tau * (0.5 * a + tau * j * (1.0 / 6.0))),
            v + tau * (a + 0.5 * tau * j),
            a + tau * j,
            j,
        ]
    }

    /// The duration each axis would need alone (its time-optimal duration).
    pub fn axis_durations(start: [f64; D], goal: [f64; D], limits: &Limits<D>) -> [f64; D] {
        core::array::from_fn(|axis| {
            let (_, ta, tv) = phase_times(
                libm::fabs(goal[axis] - start[axis]),
                limits.velocity[axis],
                limits.acceleration[axis],
                limits.jerk[axis],
            );
            2.0 * ta + tv
        })
    }
}

impl<const D: usize> Trajectory<D> for JerkLimited<D> {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; D] {
        core::array::from_fn(|axis| {
            if order < 4 {
                self.eval_axis(axis, t)[order]
            } else {
                0.0
            }
        })
    }

    #[inline]
    fn sample(&self, t: f64) -> Sample<D> {
        let mut s = Sample {
            position: [0.0; D],
            velocity: [0.0; D],
            acceleration: [0.0; D],
            jerk: [0.0; D],
        };
        for axis in 0..D {
            let [p, v, a, j] = self.eval_axis(axis, t);
            s.position[axis] = p;
            s.velocity[axis] = v;
            s.acceleration[axis] = a;
            s.jerk[axis] = j;
        }
        s
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
        let [p, v, a, _] = self.angle.eval_axis(0, t);
        RotationSample {
            orientation: DQuat::from_axis_angle(self.axis, p) * self.start,
            angular_velocity: self.axis * v,
            angular_acceleration: self.axis * a,
        }
    }
}
