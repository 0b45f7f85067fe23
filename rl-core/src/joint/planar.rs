//! Planar joint: translation in the joint frame's x-y plane and rotation about its z axis.

use glam::DVec3;

use super::revolute::rotation;
use crate::spatial::PlueckerTransform;

/// `q = [x, y, θ]`; velocities `v = [vx, vy, ω]` in the child (body) frame, so the motion
/// subspace is constant, as for the six-DOF joint.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Planar;

impl Planar {
    /// `X_J(q)`.
    #[inline]
    pub fn transform(&self, x: f64, y: f64, theta: f64) -> PlueckerTransform {
        PlueckerTransform::new(rotation(DVec3::Z, theta), DVec3::new(x, y, 0.0))
    }

    /// `q ⊕ v dt` by the SE(2) exponential of the body velocity.
    pub fn integrate(q: &[f64], v: &[f64], dt: f64, out: &mut [f64]) {
        let (dx, dy, th) = (v[0] * dt, v[1] * dt, v[2] * dt);
        let (a, b) = if libm::fabs(th) < 1e-8 {
            (1.0 - th * th / 6.0, th / 2.0 - th * th * th / 24.0)
        } else {
            (libm::sin(th) / th, (1.0 - libm::cos(th)) / th)
        };
        let (lx, ly) = (a * dx - b * dy, b * dx + a * dy);
        let (s, c) = (libm::sin(q[2]), libm::cos(q[2]));
        out[0] = q[0] + c * lx - s * ly;
        out[1] = q[1] + s * lx + c * ly;
        out[2] = q[2] + th;
    }
}
