//! Six-DOF joint: free motion in space (a floating base, Pinocchio's free-flyer).

use glam::{DMat3, DQuat, DVec3};

use crate::spatial::{PlueckerTransform, skew};

/// `q = [x, y, z, qx, qy, qz, qw]` (position of the child frame in the parent frame and a unit
/// quaternion); `v = [linear; angular]` velocity of the child frame in child coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SixDof;

impl SixDof {
    /// `X_J(q)`.
    #[inline]
    pub fn transform(&self, q: &[f64]) -> PlueckerTransform {
        PlueckerTransform::new(
            DMat3::from_quat(DQuat::from_xyzw(q[3], q[4], q[5], q[6])),
            DVec3::new(q[0], q[1], q[2]),
        )
    }

    /// `q ⊕ v dt = X(q) · exp(v dt)` with the SE(3) exponential (constant body twist).
    pub fn integrate(q: &[f64], v: &[f64], dt: f64, out: &mut [f64]) {
        let lin = DVec3::new(v[0], v[1], v[2]) * dt;
        let w = DVec3::new(v[3], v[4], v[5]) * dt;
        let th2 = w.length_squared();
        let th = libm::sqrt(th2);
        let (b, c) = if th < 1e-6 {
            (0.5 - th2 / 24.0, 1.0 / 6.0 - th2 / 120.0)
        } else {
            (
                (1.0 - libm::cos(th)) / th2,
                (th - libm::sin(th)) / (th2 * th),
            )
        };
        let wx = skew(w);
        let local = lin + wx * lin * b + wx * (wx * lin) * c;
        let q0 = DQuat::from_xyzw(q[3], q[4], q[5], q[6]);
        let p = DVec3::new(q[0], q[1], q[2]) + q0 * local;
        let r = (q0 * DQuat::from_scaled_axis(w)).normalize();
        out[..7].copy_from_slice(&[p.x, p.y, p.z, r.x, r.y, r.z, r.w]);
    }
}
