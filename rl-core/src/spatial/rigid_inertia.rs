//! Rigid-body spatial inertia.

use core::ops::{Add, AddAssign};

use glam::{DMat3, DVec3};

use super::{
    ForceVector, MotionVector, PlueckerTransform, rotate_symmetric_upper, shift_upper, skew,
    symmetric_from_upper,
};

/// The spatial inertia of a rigid body about a frame's origin, in that frame's coordinates.
///
/// Stored as Featherstone's `(m, h, Ī)`: mass, first moment `h = m c` (c: centre of mass) and
/// the rotational inertia `Ī` about the frame's origin, so `I·v` costs two 3×3 products and
/// a sum of inertias is a sum of fields.
#[doc(alias = "Inertia")]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidBodyInertia {
    /// Mass, kg.
    pub mass: f64,
    /// First moment of mass `m c`, kg·m.
    pub first_moment: DVec3,
    /// Rotational inertia about the frame's origin, kg·m².
    pub rotational: DMat3,
}

impl Default for RigidBodyInertia {
    fn default() -> Self {
        Self::ZERO
    }
}

impl RigidBodyInertia {
    /// No mass at all.
    pub const ZERO: Self = Self {
        mass: 0.0,
        first_moment: DVec3::ZERO,
        rotational: DMat3::ZERO,
    };

    /// The inertia of a body of mass `mass` with centre of mass `com` and rotational inertia
    /// `inertia_com` about the centre of mass (axes of the frame).
    pub fn from_com(mass: f64, com: DVec3, inertia_com: DMat3) -> Self {
        let c = skew(com);
        Self {
            mass,
            first_moment: com * mass,
            rotational: inertia_com - c * c * mass,
        }
    }

    /// The centre of mass (the origin if there is no mass).
    pub fn com(&self) -> DVec3 {
        if self.mass > 0.0 {
            self.first_moment / self.mass
        } else {
            DVec3::ZERO
        }
    }

    /// The rotational inertia about the centre of mass.
    pub fn inertia_com(&self) -> DMat3 {
        let c = skew(self.com());
        self.rotational + c * c * self.mass
    }

    /// The principal moments of inertia about the centre of mass, ascending, kg·m².
    pub fn principal_moments(&self) -> [f64; 3] {
        crate::math::symmetric_eigenvalues(&self.inertia_com())
    }

    /// Whether a rigid body can have this inertia: finite, mass ≥ 0, the rotational inertia
    /// about the centre of mass positive semi-definite (no principal moment below 0) and, for a
    /// body with mass, its principal moments satisfying the triangle inequality
    /// `I₁ + I₂ ≥ I₃` (both follow from `I = ∫ ρ (|r|² 1 − r rᵀ) dV` with `ρ ≥ 0`).
    ///
    /// A massless inertia is held to positive semi-definiteness only: no rigid body is
    /// massless, so such an inertia stands for something else, e.g. a motor's rotor inertia
    /// about the joint axis lumped into the link (RL's Puma 560 body 1: `m = 0`,
    /// `I = diag(0, 0.35, 0)`, where only that inertia was identified).
    ///
    /// Tolerance: `1e-9` of the largest moment, plus `1e-12` kg·m² for files that write an
    /// inertia of a few ulps of noise (a rounded rotation of zero).
    pub fn check_physical(&self) -> Result<(), InertiaProblem> {
        let finite = self.mass.is_finite()
            && self.first_moment.is_finite()
            && self
                .rotational
                .to_cols_array()
                .iter()
                .all(|x| x.is_finite());
        if !finite {
            return Err(InertiaProblem::NotFinite);
        }
        if self.mass < 0.0 {
            return Err(InertiaProblem::NegativeMass { mass: self.mass });
        }
        let moments = self.principal_moments();
        let tol = 1e-9 * moments[2].abs().max(moments[0].abs()) + 1e-12;
        if moments[0] < -tol {
            return Err(InertiaProblem::NotPositiveSemiDefinite { moments });
        }
        if self.mass > 0.0 && moments[0] + moments[1] < moments[2] - tol {
            return Err(InertiaProblem::TriangleInequality { moments });
        }
        Ok(())
    }

    /// The momentum `I v` of a body moving with `v`.
    #[inline]
    pub fn mul_motion(&self, v: &MotionVector) -> ForceVector {
        ForceVector {
            moment: self.rotational * v.angular + self.first_moment.cross(v.linear),
            force: v.linear * self.mass - self.first_moment.cross(v.angular),
        }
    }

    /// This inertia, given in B coordinates, expressed in A coordinates by `a_b` (the pose of B
    /// in A): `A_X_B* I B_X_A`.
    #[inline]
    pub fn transform_to_parent(&self, a_b: &PlueckerTransform) -> Self {
        let r = &a_b.rotation;
        let p = a_b.translation;
        let h = *r * self.first_moment;
        // Ī_A = R Ī Rᵀ − ([h]×[p]× + [p]×[h]×) − m [p]×², with [a]×[b]× = b aᵀ − (a·b) 1,
        // = R Ī Rᵀ − (p gᵀ + g pᵀ) + 2 (g·p) 1 with g = h + m p / 2.
        let m = self.mass;
        let g = h + p * (0.5 * m);
        let e = rotate_symmetric_upper(r, &self.rotational);
        let rotational = symmetric_from_upper(shift_upper(e, p, g, 2.0 * g.dot(p)));
        Self {
            mass: m,
            first_moment: h + p * m,
            rotational,
        }
    }
}

impl Add for RigidBodyInertia {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self {
            mass: self.mass + o.mass,
            first_moment: self.first_moment + o.first_moment,
            rotational: self.rotational + o.rotational,
        }
    }
}

impl AddAssign for RigidBodyInertia {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn transform_agrees_with_force_and_motion_maps() {
        let i = RigidBodyInertia::from_com(
            2.5,
            DVec3::new(0.1, -0.05, 0.2),
            DMat3::from_cols(
                DVec3::new(0.3, 0.01, 0.02),
                DVec3::new(0.01, 0.4, -0.03),
                DVec3::new(0.02, -0.03, 0.5),
            ),
        );
        let x = PlueckerTransform::from_quat_translation(
            DQuat::from_rotation_arc(DVec3::X, DVec3::new(0.3, 0.5, 0.8).normalize()),
            DVec3::new(0.7, -0.2, 1.3),
        );
        let v_a = MotionVector::new(DVec3::new(0.3, -0.2, 0.9), DVec3::new(1.0, 0.4, -0.6));
        let direct = i.transform_to_parent(&x).mul_motion(&v_a);
        let via = x.act_force(&i.mul_motion(&x.inv_act_motion(&v_a)));
        assert!(
            (direct - via).moment.length() < 1e-13,
            "{direct:?} vs {via:?}"
        );
        assert!((direct - via).force.length() < 1e-13);
        assert!((i.com() - DVec3::new(0.1, -0.05, 0.2)).length() < 1e-15);
    }
}

/// Why an inertia is not one a rigid body can have ([`RigidBodyInertia::check_physical`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InertiaProblem {
    /// A value is not finite.
    NotFinite,
    /// The mass is negative.
    NegativeMass {
        /// The mass, kg.
        mass: f64,
    },
    /// A principal moment about the centre of mass is negative.
    NotPositiveSemiDefinite {
        /// The principal moments about the centre of mass, ascending, kg·m².
        moments: [f64; 3],
    },
    /// The two smaller principal moments add up to less than the largest.
    TriangleInequality {
        /// The principal moments about the centre of mass, ascending, kg·m².
        moments: [f64; 3],
    },
}

impl core::fmt::Display for InertiaProblem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            InertiaProblem::NotFinite => f.write_str("a mass or inertia value is not finite"),
            InertiaProblem::NegativeMass { mass } => write!(f, "the mass {mass} kg is negative"),
            InertiaProblem::NotPositiveSemiDefinite { moments: [a, b, c] } => write!(
                f,
                "its principal moments about the centre of mass ({a:.6e}, {b:.6e}, {c:.6e}) \
                 kg·m² are not all ≥ 0 (the tensor is not positive semi-definite)"
            ),
            InertiaProblem::TriangleInequality { moments: [a, b, c] } => write!(
                f,
                "its principal moments about the centre of mass ({a:.6e}, {b:.6e}, {c:.6e}) \
                 kg·m² break the triangle inequality I₁ + I₂ ≥ I₃"
            ),
        }
    }
}
