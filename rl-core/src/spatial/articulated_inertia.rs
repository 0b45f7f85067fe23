//! Articulated-body inertia (Featherstone ch. 7), the 6×6 symmetric operator of ABA.

use core::ops::{AddAssign, Sub};

use glam::{DMat3, DVec3};

use super::{
    ForceVector, MotionVector, PlueckerTransform, RigidBodyInertia, rotate_symmetric, skew,
    skew_mul,
};

/// A symmetric 6×6 spatial inertia kept as 3×3 blocks: `f = [I ω + H v; Hᵀ ω + M v]`.
///
/// Articulated-body inertias are not rigid-body inertias (the linear block is not a multiple of
/// the identity), so they need the full blocks; rigid ones convert losslessly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArticulatedBodyInertia {
    /// Angular–angular block (symmetric).
    pub angular: DMat3,
    /// Angular–linear coupling block.
    pub coupling: DMat3,
    /// Linear–linear block (symmetric).
    pub linear: DMat3,
}

impl Default for ArticulatedBodyInertia {
    fn default() -> Self {
        Self::ZERO
    }
}

impl From<RigidBodyInertia> for ArticulatedBodyInertia {
    #[inline]
    fn from(i: RigidBodyInertia) -> Self {
        Self {
            angular: i.rotational,
            coupling: skew(i.first_moment),
            linear: DMat3::from_diagonal(DVec3::splat(i.mass)),
        }
    }
}

impl ArticulatedBodyInertia {
    /// The zero operator.
    pub const ZERO: Self = Self {
        angular: DMat3::ZERO,
        coupling: DMat3::ZERO,
        linear: DMat3::ZERO,
    };

    /// `I v`.
    #[inline]
    pub fn mul_motion(&self, v: &MotionVector) -> ForceVector {
        ForceVector {
            moment: self.angular * v.angular + self.coupling * v.linear,
            force: self.coupling.transpose() * v.angular + self.linear * v.linear,
        }
    }

    /// Subtracts the symmetric rank-one term `u uᵀ / d` (one column of `U D⁻¹ Uᵀ`).
    #[inline]
    pub fn sub_rank_one(&mut self, u: &ForceVector, scale: f64) {
        let (n, f) = (u.moment, u.force);
        self.angular -= outer(n, n * scale);
        self.coupling -= outer(n, f * scale);
        self.linear -= outer(f, f * scale);
    }

    /// Subtracts `a bᵀ` symmetrised: used with `b = U D⁻¹` columns for multi-DOF joints.
    #[inline]
    pub fn sub_outer(&mut self, a: &ForceVector, b: &ForceVector) {
        self.angular -= outer(a.moment, b.moment);
        self.coupling -= outer(a.moment, b.force);
        self.linear -= outer(a.force, b.force);
    }

    /// This inertia, given in B coordinates, expressed in A coordinates by `a_b`:
    /// `A_X_B* I B_X_A`.
    #[inline]
    pub fn transform_to_parent(&self, a_b: &PlueckerTransform) -> Self {
        let r = &a_b.rotation;
        let p = a_b.translation;
        let i = rotate_symmetric(r, &self.angular);
        let h = *r * self.coupling * r.transpose();
        let m = rotate_symmetric(r, &self.linear);
        // With P = [p]×: I_A = I − H P − (H P)ᵀ − P M P, H_A = H + P M; and X P = −(P Xᵀ)ᵀ.
        let pm = skew_mul(p, &m);
        let hp = -skew_mul(p, &h.transpose()).transpose();
        let pmp = -skew_mul(p, &pm.transpose()).transpose();
        Self {
            angular: i - hp - hp.transpose() - pmp,
            coupling: h + pm,
            linear: m,
        }
    }
}

/// `a bᵀ` as a column-major 3×3 matrix.
#[inline]
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

impl AddAssign for ArticulatedBodyInertia {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        self.angular += o.angular;
        self.coupling += o.coupling;
        self.linear += o.linear;
    }
}

impl Sub for ArticulatedBodyInertia {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self {
            angular: self.angular - o.angular,
            coupling: self.coupling - o.coupling,
            linear: self.linear - o.linear,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn transform_matches_rigid_and_maps() {
        let rb = RigidBodyInertia::from_com(
            1.7,
            DVec3::new(-0.2, 0.05, 0.3),
            DMat3::from_diagonal(DVec3::new(0.2, 0.3, 0.25)),
        );
        let x = PlueckerTransform::from_quat_translation(
            DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.9),
            DVec3::new(-0.3, 0.8, 0.1),
        );
        let mut ab = ArticulatedBodyInertia::from(rb);
        // make it non-rigid
        ab.sub_rank_one(
            &ForceVector::new(DVec3::new(0.1, 0.2, 0.0), DVec3::new(0.3, -0.1, 0.2)),
            0.5,
        );
        let v = MotionVector::new(DVec3::new(0.3, -0.2, 0.9), DVec3::new(1.0, 0.4, -0.6));
        let direct = ab.transform_to_parent(&x).mul_motion(&v);
        let via = x.act_force(&ab.mul_motion(&x.inv_act_motion(&v)));
        assert!((direct - via).moment.length() < 1e-13);
        assert!((direct - via).force.length() < 1e-13);
        let rigid = ArticulatedBodyInertia::from(rb.transform_to_parent(&x));
        let conv = ArticulatedBodyInertia::from(rb).transform_to_parent(&x);
        assert!(
            (rigid.angular - conv.angular)
                .abs()
                .to_cols_array()
                .iter()
                .all(|e| *e < 1e-13)
        );
    }
}
