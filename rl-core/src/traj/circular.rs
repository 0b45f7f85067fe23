//! Circular arcs in 2-D and 3-D at constant angular rate, with derivatives of every order from
//! the closed form: `p(t) = c + cos θ u + sin θ w`, `θ = ω t`, so
//! `p⁽ⁿ⁾(t) = ωⁿ (cos(θ + nπ/2) u + sin(θ + nπ/2) w)`.

use core::f64::consts::{FRAC_PI_2, TAU};

use glam::DVec3;

use super::{Sample, Trajectory, TrajectoryError, clamp_time};

/// A circular arc with `D = 2` or `D = 3` axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Circular<const D: usize> {
    center: [f64; D],
    /// From the centre to the start point.
    u: [f64; D],
    /// `u` turned by +90° in the arc's plane, in the direction of motion.
    w: [f64; D],
    rate: f64,
    angle: f64,
    duration: f64,
}

fn vec3<const D: usize>(p: &[f64; D]) -> Result<DVec3, TrajectoryError> {
    for (index, x) in p.iter().enumerate() {
        if !x.is_finite() {
            return Err(TrajectoryError::NotFinite {
                what: "arc point coordinate",
                index,
            });
        }
    }
    Ok(DVec3::new(
        p[0],
        if D > 1 { p[1] } else { 0.0 },
        if D > 2 { p[2] } else { 0.0 },
    ))
}

fn array<const D: usize>(v: DVec3) -> [f64; D] {
    let a = v.to_array();
    core::array::from_fn(|i| a[i])
}

impl<const D: usize> Circular<D> {
    /// The arc from `p0` through `p1` to `p2` (`angle = None`), or from `p0` sweeping `angle`
    /// radians (0 < angle ≤ 2π) on the circle through the three points in the direction of
    /// `p1`, in `duration` seconds.
    fn from_points(
        p0: &[f64; D],
        p1: &[f64; D],
        p2: &[f64; D],
        angle: Option<f64>,
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        if !(duration > 0.0 && duration.is_finite()) {
            return Err(TrajectoryError::BadDuration);
        }
        let (a0, a1, a2) = (vec3(p0)?, vec3(p1)?, vec3(p2)?);
        let a = a1 - a0;
        let b = a2 - a0;
        let n = a.cross(b);
        let n2 = n.length_squared();
        let scale = a.length_squared().max(b.length_squared());
        if !(n2 > 1e-24 * scale * scale) {
            return Err(TrajectoryError::Degenerate);
        }
        let center = a0 + (b * a.length_squared() - a * b.length_squared()).cross(n) / (2.0 * n2);
        let u = a0 - center;
        let w = n.normalize().cross(u);
        let sweep = match angle {
            Some(angle) => {
                if !(angle > 0.0 && angle <= TAU) {
                    return Err(TrajectoryError::Degenerate);
                }
                angle
            }
            None => {
                let r = a2 - center;
                let theta = libm::atan2(w.dot(r), u.dot(r));
                if theta <= 0.0 { theta + TAU } else { theta }
            }
        };
        Ok(Self {
            center: array(center),
            u: array(u),
            w: array(w),
            rate: sweep / duration,
            angle: sweep,
            duration,
        })
    }

    /// Centre of the circle.
    pub fn center(&self) -> [f64; D] {
        self.center
    }

    /// Radius of the circle.
    pub fn radius(&self) -> f64 {
        libm::sqrt(self.u.iter().map(|x| x * x).sum())
    }

    /// Swept angle in radians.
    pub fn angle(&self) -> f64 {
        self.angle
    }
}

impl Circular<2> {
    /// Arc from `p0` through `p1` to `p2` in the plane.
    pub fn through(
        p0: [f64; 2],
        p1: [f64; 2],
        p2: [f64; 2],
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_points(&p0, &p1, &p2, None, duration)
    }

    /// Arc from `p0` sweeping `angle` (≤ 2π) on the circle through the three points, towards
    /// `p1`.
    pub fn through_with_angle(
        p0: [f64; 2],
        p1: [f64; 2],
        p2: [f64; 2],
        angle: f64,
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_points(&p0, &p1, &p2, Some(angle), duration)
    }
}

impl Circular<3> {
    /// Arc from `p0` through `p1` to `p2` in space.
    pub fn through(
        p0: [f64; 3],
        p1: [f64; 3],
        p2: [f64; 3],
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_points(&p0, &p1, &p2, None, duration)
    }

    /// Arc from `p0` sweeping `angle` (≤ 2π) on the circle through the three points, towards
    /// `p1`.
    pub fn through_with_angle(
        p0: [f64; 3],
        p1: [f64; 3],
        p2: [f64; 3],
        angle: f64,
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_points(&p0, &p1, &p2, Some(angle), duration)
    }
}

impl<const D: usize> Trajectory<D> for Circular<D> {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; D] {
        let theta = self.rate * clamp_time(t, self.duration) + order as f64 * FRAC_PI_2;
        let scale = libm::pow(self.rate, order as f64);
        let (s, c) = (libm::sin(theta) * scale, libm::cos(theta) * scale);
        core::array::from_fn(|i| {
            let base = if order == 0 { self.center[i] } else { 0.0 };
            base + c * self.u[i] + s * self.w[i]
        })
    }

    fn sample(&self, t: f64) -> Sample<D> {
        let theta = self.rate * clamp_time(t, self.duration);
        let (s, c) = (libm::sin(theta), libm::cos(theta));
        let r = self.rate;
        let mut out = Sample {
            position: self.center,
            velocity: [0.0; D],
            acceleration: [0.0; D],
            jerk: [0.0; D],
        };
        for i in 0..D {
            let along_u = c * self.u[i] + s * self.w[i];
            let along_w = -s * self.u[i] + c * self.w[i];
            out.position[i] += along_u;
            out.velocity[i] = r * along_w;
            out.acceleration[i] = -r * r * along_u;
            out.jerk[i] = -r * r * r * along_w;
        }
        out
    }
}
