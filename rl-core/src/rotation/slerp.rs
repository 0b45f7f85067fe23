//! Spherical linear interpolation and its exact first and second derivatives.

use glam::{DQuat, DVec3};

use super::quaternion::{exp, log, pure};

/// Spherical linear interpolation from `q0` to `q1` over the parameter `s ∈ [0, 1]`:
/// `q(s) = q0 exp(s v)` with `v = log(q0* q1)`, so `q'(s) = q(s) v` and `q''(s) = q(s) v²`.
///
/// The angular velocity per unit `s` is constant, `2 q0 v q0*` in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slerp {
    q0: DQuat,
    v: DVec3,
}

impl Slerp {
    /// Interpolates along the shorter arc (flips `q1` to the hemisphere of `q0`).
    pub fn new(q0: DQuat, q1: DQuat) -> Self {
        let q1 = if q0.dot(q1) < 0.0 { -q1 } else { q1 };
        Self::new_unflipped(q0, q1)
    }

    /// Interpolates from `q0` to exactly `q1` without choosing the shorter arc (as squad needs).
    pub fn new_unflipped(q0: DQuat, q1: DQuat) -> Self {
        Self {
            q0,
            v: log(q0.conjugate() * q1),
        }
    }

    /// The orientation at `s`.
    pub fn value(&self, s: f64) -> DQuat {
        self.q0 * exp(self.v * s)
    }

    /// `dq/ds` at `s`.
    pub fn derivative(&self, s: f64) -> DQuat {
        self.value(s) * pure(self.v)
    }

    /// `d²q/ds²` at `s` (`v² = -|v|²`).
    pub fn second_derivative(&self, s: f64) -> DQuat {
        self.value(s) * (-self.v.length_squared())
    }

    /// World-frame angular velocity per unit `s` (constant along the arc).
    pub fn angular_velocity(&self) -> DVec3 {
        self.q0.mul_vec3(self.v) * 2.0
    }

    /// The rotation angle from start to end in radians.
    pub fn angle(&self) -> f64 {
        2.0 * self.v.length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints() {
        let q0 = DQuat::from_rotation_x(0.3);
        let q1 = DQuat::from_rotation_y(-1.2) * q0;
        let s = Slerp::new(q0, q1);
        assert!(s.value(0.0).abs_diff_eq(q0, 1e-15));
        assert!(s.value(1.0).abs_diff_eq(q1, 1e-14));
        assert!((s.angle() - 1.2).abs() < 1e-14);
    }
}
