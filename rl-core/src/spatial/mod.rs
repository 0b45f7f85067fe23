//! Spatial vector algebra after Featherstone (*Rigid Body Dynamics Algorithms*, 2008, ch. 2).
//!
//! Motion and force vectors are kept as two 3-vectors with named parts, so the order question
//! (Featherstone's `[angular; linear]` against Pinocchio's `[linear; angular]`) never arises
//! inside the library; only the outside conventions (RL's Jacobian rows `[linear; angular]`)
//! pick an order. Transforms store a rotation and a translation, never a dense 6×6 matrix.

mod articulated_inertia;
mod force;
mod motion;
mod rigid_inertia;
mod transform;

pub use articulated_inertia::ArticulatedBodyInertia;
pub use force::ForceVector;
pub use motion::MotionVector;
pub use rigid_inertia::RigidBodyInertia;
pub use transform::PlueckerTransform;

use glam::{DMat3, DVec3};

/// The skew-symmetric matrix `[v]×` with `[v]× w = v × w`.
#[inline]
pub fn skew(v: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, v.z, -v.y),
        DVec3::new(-v.z, 0.0, v.x),
        DVec3::new(v.y, -v.x, 0.0),
    )
}

/// `[p]× M`: the cross product of `p` with each column of `M`.
#[inline]
pub(crate) fn skew_mul(p: DVec3, m: &DMat3) -> DMat3 {
    DMat3::from_cols(p.cross(m.x_axis), p.cross(m.y_axis), p.cross(m.z_axis))
}

/// `a bᵀ + b aᵀ`, symmetric.
#[inline]
pub(crate) fn sym_outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x + b * a.x, a * b.y + b * a.y, a * b.z + b * a.z)
}

/// `R S Rᵀ` for a symmetric `S` (only the upper triangle is computed).
#[inline]
pub fn rotate_symmetric(r: &DMat3, s: &DMat3) -> DMat3 {
    // A = R S, then only the upper triangle of A Rᵀ: (A Rᵀ)ᵢⱼ = Σₖ Aᵢₖ Rⱼₖ (column-major arrays).
    let a = (*r * *s).to_cols_array();
    let r = r.to_cols_array();
    let e = |i: usize, j: usize| a[i] * r[j] + a[3 + i] * r[3 + j] + a[6 + i] * r[6 + j];
    let (m00, m01, m02) = (e(0, 0), e(0, 1), e(0, 2));
    let (m11, m12, m22) = (e(1, 1), e(1, 2), e(2, 2));
    DMat3::from_cols(
        DVec3::new(m00, m01, m02),
        DVec3::new(m01, m11, m12),
        DVec3::new(m02, m12, m22),
    )
}
