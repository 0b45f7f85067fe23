//! Plücker transforms: rigid-body transforms acting on spatial vectors.

use core::ops::Mul;

use glam::{DMat3, DQuat, DVec3};

use super::{ForceVector, MotionVector};

/// The pose of a frame B relative to a frame A, stored as the rotation `R` (B's axes in A
/// coordinates) and the translation `p` (B's origin in A coordinates).
///
/// As a map it takes B coordinates to A coordinates: points `x_A = R x_B + p`, and spatial
/// vectors through [`act_motion`](Self::act_motion) and [`act_force`](Self::act_force) (the
/// 6×6 Plücker matrices `A_X_B` and `A_X_B*` of Featherstone, applied without forming them).
/// The inverse maps are the `inv_act_*` methods. Composition `a_b * b_c` gives `a_c`.
#[doc(alias = "SE3")]
#[doc(alias = "Transform")]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlueckerTransform {
    /// Rotation of B relative to A (columns: B's axes in A coordinates).
    pub rotation: DMat3,
    /// B's origin in A coordinates, m.
    pub translation: DVec3,
}

impl Default for PlueckerTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl PlueckerTransform {
    /// The identity transform.
    pub const IDENTITY: Self = Self {
        rotation: DMat3::IDENTITY,
        translation: DVec3::ZERO,
    };

    /// A transform from a rotation matrix and a translation.
    #[inline]
    pub const fn new(rotation: DMat3, translation: DVec3) -> Self {
        Self {
            rotation,
            translation,
        }
    }

    /// A pure translation.
    #[inline]
    pub const fn from_translation(translation: DVec3) -> Self {
        Self {
            rotation: DMat3::IDENTITY,
            translation,
        }
    }

    /// A pure rotation.
    #[inline]
    pub const fn from_rotation(rotation: DMat3) -> Self {
        Self {
            rotation,
            translation: DVec3::ZERO,
        }
    }

    /// A transform from a unit quaternion and a translation.
    #[inline]
    pub fn from_quat_translation(q: DQuat, translation: DVec3) -> Self {
        Self {
            rotation: DMat3::from_quat(q),
            translation,
        }
    }

    /// The rotation as a unit quaternion.
    #[inline]
    pub fn quaternion(&self) -> DQuat {
        DQuat::from_mat3(&self.rotation)
    }

    /// The inverse transform (pose of A relative to B).
    #[inline]
    pub fn inverse(&self) -> Self {
        let rt = self.rotation.transpose();
        Self {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }

    /// A point given in B coordinates, in A coordinates.
    #[inline]
    pub fn transform_point(&self, x: DVec3) -> DVec3 {
        self.rotation * x + self.translation
    }

    /// A motion vector given in B coordinates, in A coordinates (`A_X_B m`).
    #[inline]
    pub fn act_motion(&self, m: &MotionVector) -> MotionVector {
        let angular = self.rotation * m.angular;
        MotionVector {
            angular,
            linear: self.rotation * m.linear + self.translation.cross(angular),
        }
    }

    /// A motion vector given in A coordinates, in B coordinates (`B_X_A m`).
    #[inline]
    pub fn inv_act_motion(&self, m: &MotionVector) -> MotionVector {
        MotionVector {
            angular: self.inv_rotate(m.angular),
            linear: self.inv_rotate(m.linear - self.translation.cross(m.angular)),
        }
    }

    /// `Rᵀ v` without forming `Rᵀ`: three dot products with the columns.
    #[inline]
    pub fn inv_rotate(&self, v: DVec3) -> DVec3 {
        let r = &self.rotation;
        DVec3::new(r.x_axis.dot(v), r.y_axis.dot(v), r.z_axis.dot(v))
    }

    /// A force vector given in B coordinates, in A coordinates (`A_X_B* f`).
    #[inline]
    pub fn act_force(&self, f: &ForceVector) -> ForceVector {
        let force = self.rotation * f.force;
        ForceVector {
            moment: self.rotation * f.moment + self.translation.cross(force),
            force,
        }
    }

    /// A force vector given in A coordinates, in B coordinates (`B_X_A* f`).
    #[inline]
    pub fn inv_act_force(&self, f: &ForceVector) -> ForceVector {
        ForceVector {
            moment: self.inv_rotate(f.moment - self.translation.cross(f.force)),
            force: self.inv_rotate(f.force),
        }
    }

    /// The 6×6 motion transform matrix `A_X_B` in Featherstone's `[angular; linear]` order.
    /// For tests and printing only: the algorithms never form it.
    pub fn to_motion_matrix(&self) -> [[f64; 6]; 6] {
        let mut out = [[0.0; 6]; 6];
        let r = self.rotation;
        let pr = super::skew(self.translation) * r;
        for i in 0..3 {
            for j in 0..3 {
                out[i][j] = r.col(j)[i];
                out[i + 3][j + 3] = r.col(j)[i];
                out[i + 3][j] = pr.col(j)[i];
            }
        }
        out
    }
}

impl Mul for PlueckerTransform {
    type Output = Self;
    /// `a_b * b_c = a_c`.
    #[inline]
    fn mul(self, o: Self) -> Self {
        Self {
            rotation: self.rotation * o.rotation,
            translation: self.rotation * o.translation + self.translation,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> PlueckerTransform {
        PlueckerTransform::from_quat_translation(
            DQuat::from_euler(glam::EulerRot::ZYX, 0.3, -0.7, 1.1),
            DVec3::new(0.4, -1.2, 0.25),
        )
    }

    #[test]
    fn inverse_round_trips_and_matches_the_matrix() {
        let x = sample();
        let m = MotionVector::new(DVec3::new(0.1, 0.2, -0.3), DVec3::new(-1.0, 0.5, 2.0));
        let back = x.inv_act_motion(&x.act_motion(&m));
        assert!((back - m).angular.length() < 1e-14 && (back - m).linear.length() < 1e-14);
        let via_inverse = x.inverse().act_motion(&m);
        let direct = x.inv_act_motion(&m);
        assert!((via_inverse - direct).linear.length() < 1e-14);
        // the 6×6 matrix agrees with the action
        let mx = x.to_motion_matrix();
        let a = m.to_array();
        let y = x.act_motion(&m).to_array();
        for i in 0..6 {
            let yi: f64 = (0..6).map(|j| mx[i][j] * a[j]).sum();
            assert!((yi - y[i]).abs() < 1e-14);
        }
    }

    #[test]
    fn power_is_invariant() {
        let x = sample();
        let m = MotionVector::new(DVec3::new(0.1, 0.2, -0.3), DVec3::new(-1.0, 0.5, 2.0));
        let f = ForceVector::new(DVec3::new(0.7, -0.1, 0.3), DVec3::new(2.0, 1.0, -0.5));
        let p1 = m.dot(&f);
        let p2 = x.act_motion(&m).dot(&x.act_force(&f));
        assert!((p1 - p2).abs() < 1e-13);
        let f2 = x.inv_act_force(&x.act_force(&f));
        assert!((f2 - f).moment.length() < 1e-14 && (f2 - f).force.length() < 1e-14);
    }
}
