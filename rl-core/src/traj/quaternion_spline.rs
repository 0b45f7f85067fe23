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

/// A C¹ cubic quaternion spline through orientations at given times, with given world angular
/// velocities at both ends. Interior angular velocities are the mean of the neighbouring
/// segments' average angular velocities (Catmull-Rom style), so the angular velocity is
/// continuous at every waypoint; the angular acceleration may jump there.
#[derive(Clone, Debug)]
pub struct CubicQuaternionSpline<const MAX: usize> {
    segments: Vec<CubicSegment, MAX>,
    starts: [f64; MAX],
    duration: f64,
}

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
        let q = |i: usize| -> DQuat { orientations[i].normalize() };
        // Sign-consistent copies are computed on the fly from the previous one.
        let mut prev = q(0);
        let mut cur = if prev.dot(q(1)) < 0.0 { -q(1) } else { q(1) };
        // World rotation vector of segment i divided by its duration.
        let rate = |a: DQuat, b: DQuat, h: f64| log(b * a.conjugate()) * (2.0 / h);
        let mut omega_prev = omega_start;
        let mut spline = Self {
            segments: Vec::new(),
            starts: [0.0; MAX],
            duration: 0.0,
        };
        for i in 0..n - 1 {
            let h = times[i + 1] - times[i];
            let omega_next = if i + 2 < n {
                let next = if cur.dot(q(i + 2)) < 0.0 {
                    -q(i + 2)
                } else {
                    q(i + 2)
                };
                let w = (rate(prev, cur, h) + rate(cur, next, times[i + 2] - times[i + 1])) * 0.5;
                let seg = CubicSegment::new(prev, cur, omega_prev, w, h);
                spline.push(seg)?;
                prev = cur;
                cur = next;
                w
            } else {
                spline.push(CubicSegment::new(prev, cur, omega_prev, omega_end, h))?;
                omega_end
            };
            omega_prev = omega_next;
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
