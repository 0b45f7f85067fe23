//! Spherical (ball) joint: free rotation about the joint frame's origin.

use glam::{DMat3, DQuat, DVec3};

use crate::spatial::PlueckerTransform;

/// `q` is a unit quaternion `(x, y, z, w)`; `v` is the angular velocity in the child frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spherical;

impl Spherical {
    /// `X_J(q)`.
    #[inline]
    pub fn transform(&self, q: &[f64]) -> PlueckerTransform {
        PlueckerTransform::from_rotation(DMat3::from_quat(DQuat::from_xyzw(q[0], q[1], q[2], q[3])))
    }

    /// `q ⊕ v dt = q · exp(ω dt)`, renormalised.
    pub fn integrate(q: &[f64], v: &[f64], dt: f64, out: &mut [f64]) {
        let q0 = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
        let dq = DQuat::from_scaled_axis(DVec3::new(v[0], v[1], v[2]) * dt);
        let r = (q0 * dq).normalize();
        out[..4].copy_from_slice(&[r.x, r.y, r.z, r.w]);
    }
}
