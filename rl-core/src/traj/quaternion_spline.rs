//! Rotation trajectories: orientation as a unit quaternion with world-frame angular velocity and
//! acceleration. Slerp at constant rate, and a cubic quaternion spline through orientations
//! with given end angular velocities (Kim, Kim & Shin, "A general construction scheme for unit
//! quaternion curves with simple high order derivatives", SIGGRAPH 1995).

use glam::{DQuat, DVec3};
use heapless::Vec;

use super::{TrajectoryError, check_times, clamp_time};
use crate::rotation::{Slerp, exp, log, pure};

/// Orientation, angular velocity and angular acceleration (world frame) at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationSample {
    /// Unit quaternion, world from body.
    pub orientation: DQuat,
    /// World-frame angular velocity in rad/s.
    pub angular_velocity: DVec3,
    /// World-frame angular acceleration in rad/s².
    pub angular_acceleration: DVec3,
}

/// A rotation as a function of time on `[0, duration]` (times clamped to the interval).
pub trait RotationTrajectory {
    /// Length of the time interval in seconds.
    fn duration(&self) -> f64;
    /// Orientation, angular velocity and angular acceleration at `t`.
    fn rotation(&self, t: f64) -> RotationSample;
}

/// Slerp from one orientation to another at constant angular velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlerpTrajectory {
    slerp: Slerp,
    duration: f64,
}

impl SlerpTrajectory {
    /// The shorter rotation from `q0` to `q1` in `duration` seconds.
    pub fn new(q0: DQuat, q1: DQuat, duration: f64) -> Result<Self, TrajectoryError> {
        if !(duration > 0.0 && duration.is_finite()) {
            return Err(TrajectoryError::BadDuration);
        }
        if !q0.is_finite() || !q1.is_finite() {
            return Err(TrajectoryError::NotFinite {
                what: "quaternion",
                index: 0,
            });
        }
        Ok(Self {
            slerp: Slerp::new(q0.normalize(), q1.normalize()),
            duration,
        })
    }
}

impl RotationTrajectory for SlerpTrajectory {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn rotation(&self, t: f64) -> RotationSample {
        let s = clamp_time(t, self.duration) / self.duration;
        RotationSample {
            orientation: self.slerp.value(s),
            angular_velocity: self.slerp.angular_velocity() / self.duration,
            angular_acceleration: DVec3::ZERO,
        }
    }
}

/// One cubic segment in cumulative Bézier form: `q(s) = q0 Π_k exp(½ w_k β_k(s))`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct CubicSegment {
    q0: DQuat,
    w: [DVec3; 3],
    duration: f64,
}

/// Cumulative cubic Bernstein basis and its first two derivatives at `s`.
#[inline]
fn basis(s: f64) -> [[f64; 3]; 3] {
    let r = 1.0 - s;
    [
        [1.0 - r * r * r, 3.0 * s * s - 2.0 * s * s * s, s * s * s],
        [3.0 * r * r, 6.0 * s * r, 3.0 * s * s],
        [-6.0 * r, 6.0 - 12.0 * s, 6.0 * s],
    ]
}

impl CubicSegment {
    /// From orientations and world angular velocities at both ends (rad/s).
    fn new(q0: DQuat, q1: DQuat, omega0: DVec3, omega1: DVec3, duration: f64) -> Self {
        let w1 = q0.conjugate().mul_vec3(omega0) * (duration / 3.0);
        let w3 = q1.conjugate().mul_vec3(omega1) * (duration / 3.0);
        let qb = q0 * exp(w1 * 0.5);
        let qc = q1 * exp(w3 * -0.5);
        let w2 = log(qb.conjugate() * qc) * 2.0;
        Self {
            q0,
            w: [w1, w2, w3],
            duration,
        }
    }

    fn rotation(&self, t: f64) -> RotationSample {
        let s = clamp_time(t, self.duration) / self.duration;
        let b = basis(s);
        let mut e = [DQuat::IDENTITY; 3];
        let mut d1 = [DQuat::IDENTITY; 3];
        let mut d2 = [DQuat::IDENTITY; 3];
        for k in 0..3 {
            let h = pure(self.w[k] * 0.5);
            e[k] = exp(self.w[k] * (0.5 * b[0][k]));
            d1[k] = e[k] * h * b[1][k];
            d2[k] = e[k]
                * (h * b[2][k]
                    + DQuat::IDENTITY * (-0.25 * self.w[k].length_squared() * b[1][k] * b[1][k]));
        }
        let q = self.q0 * e[0] * e[1] * e[2];
        let qs = self.q0 * (d1[0] * e[1] * e[2] + e[0] * d1[1] * e[2] + e[0] * e[1] * d1[2]);
        let qss = self.q0
            * (d2[0] * e[1] * e[2]
                + e[0] * d2[1] * e[2]
                + e[0] * e[1] * d2[2]
                + (d1[0] * d1[1] * e[2] + d1[0] * e[1] * d1[2] + e[0] * d1[1] * d1[2]) * 2.0);
        let inv_t = 1.0 / self.duration;
        let qc = q.conjugate();
        RotationSample {
            orientation: q,
            angular_velocity: (qs * qc).xyz() * (2.0 * inv_t),
            angular_acceleration: (qss * qc).xyz() * (2.0 * inv_t * inv_t),
        }
    }
}

/// A cubic quaternion spline through orientations at given times, with given world angular
/// velocities at both ends: each segment is a cubic in Kim-Kim-Shin cumulative form, so the
/// angular velocity is continuous at every waypoint (C¹) by construction. The interior angular
/// velocities are then chosen by a Newton iteration so that the angular acceleration is
/// continuous too (C², as RL's `SplineQuaternion`); [`CubicQuaternionSpline::acceleration_jump`]
/// reports how far that got (it converges in a few steps unless neighbouring orientations are
/// far apart).
#[derive(Clone, Debug)]
pub struct CubicQuaternionSpline<const MAX: usize> {
    segments: Vec<CubicSegment, MAX>,
    starts: [f64; MAX],
    duration: f64,
    acceleration_jump: f64,
}

/// Newton steps towards continuous angular acceleration, and when to stop.
const C2_ITERATIONS: usize = 30;
const C2_TOLERANCE: f64 = 1e-13;

impl<const MAX: usize> CubicQuaternionSpline<MAX> {
    /// Through `orientations` at `times` (strictly increasing) with world angular velocities
    /// `omega_start` and `omega_end` (rad/s). Orientations are normalised and made
    /// sign-consistent (each in the hemisphere of the one before).
    pub fn new(
        times: &[f64],
        orientations: &[DQuat],
        omega_start: DVec3,
        omega_end: DVec3,
    ) -> Result<Self, TrajectoryError> {
        let n = orientations.len();
        if times.len() != n {
            return Err(TrajectoryError::TooFewWaypoints {
                required: n,
                given: times.len(),
            });
        }
        if n < 2 {
            return Err(TrajectoryError::TooFewWaypoints {
                required: 2,
                given: n,
            });
        }
        if n - 1 > MAX {
            return Err(TrajectoryError::Capacity {
                capacity: MAX,
                requested: n - 1,
            });
        }
        check_times(times)?;
        for (index, q) in orientations.iter().enumerate() {
            if !q.is_finite() || q.length_squared() == 0.0 {
                return Err(TrajectoryError::NotFinite {
                    what: "orientation",
                    index,
                });
            }
        }
        if !omega_start.is_finite() || !omega_end.is_finite() {
            return Err(TrajectoryError::NotFinite {
                what: "end angular velocity",
                index: 0,
            });
        }
        // Sign-consistent unit orientations: knots 0..n-2 in `qs`, the last one apart (the
        // arrays hold MAX entries and there are up to MAX + 1 knots).
        let mut qs = [DQuat::IDENTITY; MAX];
        let mut q_last = orientations[0].normalize();
        for (i, q) in orientations.iter().enumerate() {
            let mut q = q.normalize();
            if q.dot(q_last) < 0.0 {
                q = -q;
            }
            if i < n - 1 {
                qs[i] = q;
            }
            q_last = q;
        }
        let quat = |i: usize| if i < n - 1 { qs[i] } else { q_last };
        let h = |i: usize| times[i + 1] - times[i];
        // Knot angular velocities: the ends are given; interior ones start as the mean of the
        // neighbouring segments' average rates (Catmull-Rom), C¹.
        let rate = |i: usize| log(quat(i + 1) * quat(i).conjugate()) * (2.0 / h(i));
        let mut w = [DVec3::ZERO; MAX];
        w[0] = omega_start;
        for (i, wi) in w.iter_mut().enumerate().take(n - 1).skip(1) {
            *wi = (rate(i - 1) + rate(i)) * 0.5;
        }
        let omega = |w: &[DVec3; MAX], i: usize| if i < n - 1 { w[i] } else { omega_end };
        let segment = |w: &[DVec3; MAX], i: usize| {
            CubicSegment::new(quat(i), quat(i + 1), omega(w, i), omega(w, i + 1), h(i))
        };
        // Largest jump of the angular acceleration over interior knots, relative to its size,
        // and the residuals r_i = α_left - α_right.
        let residuals = |w: &[DVec3; MAX], r: &mut [DVec3; MAX]| -> f64 {
            let mut worst: f64 = 0.0;
            let mut left_end = segment(w, 0).rotation(h(0)).angular_acceleration;
            for i in 1..n - 1 {
                let seg = segment(w, i);
                let right_start = seg.rotation(0.0).angular_acceleration;
                r[i] = left_end - right_start;
                let size = 1.0 + left_end.length().max(right_start.length());
                worst = worst.max(r[i].length() / size);
                left_end = seg.rotation(h(i)).angular_acceleration;
            }
            worst
        };
        // Newton iteration towards C² with the Jacobian of the Euclidean cubic spline
        // (∂r_i/∂ω_{i-1} = 2/h_{i-1}, ∂r_i/∂ω_i = 4/h_{i-1} + 4/h_i, ∂r_i/∂ω_{i+1} = 2/h_i),
        // keeping the best knot velocities seen.
        let mut r = [DVec3::ZERO; MAX];
        let mut best = w;
        let mut best_jump = residuals(&w, &mut r);
        let mut jump = best_jump;
        for _ in 0..C2_ITERATIONS {
            if jump <= C2_TOLERANCE || n < 3 {
                break;
            }
            // Thomas algorithm over rows 1..n-2 (Δ_0 = Δ_{n-1} = 0).
            let mut c_prime = [0.0; MAX];
            let mut d_prime = [DVec3::ZERO; MAX];
            for i in 1..n - 1 {
                let sub = if i > 1 { 2.0 / h(i - 1) } else { 0.0 };
                let sup = if i < n - 2 { 2.0 / h(i) } else { 0.0 };
                let diag = 4.0 / h(i - 1) + 4.0 / h(i);
                let denom = diag - sub * c_prime[i - 1];
                c_prime[i] = sup / denom;
                d_prime[i] = (-r[i] - d_prime[i - 1] * sub) / denom;
            }
            let mut next = DVec3::ZERO;
            for i in (1..n - 1).rev() {
                let delta = d_prime[i] - next * c_prime[i];
                w[i] += delta;
                next = delta;
            }
            jump = residuals(&w, &mut r);
            if !(jump < best_jump) {
                break;
            }
            best = w;
            best_jump = jump;
        }
        let mut spline = Self {
            segments: Vec::new(),
            starts: [0.0; MAX],
            duration: 0.0,
            acceleration_jump: best_jump,
        };
        for i in 0..n - 1 {
            spline.push(segment(&best, i))?;
        }
        Ok(spline)
    }

    fn push(&mut self, seg: CubicSegment) -> Result<(), TrajectoryError> {
        let index = self.segments.len();
        let d = seg.duration;
        if self.segments.push(seg).is_err() {
            return Err(TrajectoryError::Capacity {
                capacity: MAX,
                requested: index + 1,
            });
        }
        self.starts[index] = self.duration;
        self.duration += d;
        Ok(())
    }

    /// Number of segments.
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    /// The largest jump of the angular acceleration at an interior waypoint, relative to
    /// `1 + |α|` there: about 1e-13 when the Newton iteration reached C², larger when it stopped
    /// early (then the spline is still C¹).
    pub fn acceleration_jump(&self) -> f64 {
        self.acceleration_jump
    }

    /// `true` without segments (never, once constructed).
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// Start time of each segment.
    pub fn starts(&self) -> &[f64] {
        &self.starts[..self.segments.len()]
    }
}

impl<const MAX: usize> RotationTrajectory for CubicQuaternionSpline<MAX> {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn rotation(&self, t: f64) -> RotationSample {
        let n = self.segments.len();
        if n == 0 {
            return RotationSample {
                orientation: DQuat::IDENTITY,
                angular_velocity: DVec3::ZERO,
                angular_acceleration: DVec3::ZERO,
            };
        }
        let t = clamp_time(t, self.duration);
        let i = self.starts[1..n].partition_point(|&s| s <= t);
        self.segments[i].rotation(t - self.starts[i])
    }
}
