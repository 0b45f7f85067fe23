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
pub use rigid_inertia::{InertiaProblem, RigidBodyInertia};
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

/// `R S Rᵀ` for a symmetric `S` (only the upper triangle is computed).
#[inline]
pub fn rotate_symmetric(r: &DMat3, s: &DMat3) -> DMat3 {
    symmetric_from_upper(rotate_symmetric_upper(r, s))
}

/// The upper triangle `[m00, m01, m02, m11, m12, m22]` of `R S Rᵀ` for a symmetric `S` and a
/// rotation `R`, in 33 multiplications instead of the 45 of `(R S) Rᵀ`.
///
/// With `S = s₂₂ 1 + U + Uᵀ`, where `U` keeps the first two rows of `S − s₂₂ 1` above the
/// diagonal and half of their diagonal, `R S Rᵀ = s₂₂ 1 + N + Nᵀ` (as `R Rᵀ = 1`), and
/// `N = R U Rᵀ = r₀ (R u₀)ᵀ + r₁ (R u₁)ᵀ` with `rᵢ` the columns of `R` and `uᵢ` the rows of `U`.
#[inline]
pub(crate) fn rotate_symmetric_upper(r: &DMat3, s: &DMat3) -> [f64; 6] {
    let s22 = s.z_axis.z;
    let u0 = DVec3::new(0.5 * (s.x_axis.x - s22), s.y_axis.x, s.z_axis.x);
    let u1 = DVec3::new(0.0, 0.5 * (s.y_axis.y - s22), s.z_axis.y);
    let (w0, w1) = (*r * u0, *r * u1);
    let (r0, r1) = (r.x_axis, r.y_axis);
    // Columns of N.
    let n0 = r0 * w0.x + r1 * w1.x;
    let n1 = r0 * w0.y + r1 * w1.y;
    let n2 = r0 * w0.z + r1 * w1.z;
    [
        2.0 * n0.x + s22,
        n1.x + n0.y,
        n2.x + n0.z,
        2.0 * n1.y + s22,
        n2.y + n1.z,
        2.0 * n2.z + s22,
    ]
}

/// The symmetric matrix with upper triangle `[m00, m01, m02, m11, m12, m22]`.
#[inline]
pub(crate) fn symmetric_from_upper(m: [f64; 6]) -> DMat3 {
    let [m00, m01, m02, m11, m12, m22] = m;
    DMat3::from_cols(
        DVec3::new(m00, m01, m02),
        DVec3::new(m01, m11, m12),
        DVec3::new(m02, m12, m22),
    )
}

/// `S − (a bᵀ + b aᵀ) + d 1` on an upper triangle (the parallel-axis shifts of an inertia).
#[inline]
pub(crate) fn shift_upper(s: [f64; 6], a: DVec3, b: DVec3, d: f64) -> [f64; 6] {
    [
        s[0] - 2.0 * a.x * b.x + d,
        s[1] - (a.x * b.y + b.x * a.y),
        s[2] - (a.x * b.z + b.x * a.z),
        s[3] - 2.0 * a.y * b.y + d,
        s[4] - (a.y * b.z + b.y * a.z),
        s[5] - 2.0 * a.z * b.z + d,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotate_symmetric_matches_the_dense_product() {
        let s = DMat3::from_cols(
            DVec3::new(0.31, -0.02, 0.05),
            DVec3::new(-0.02, 0.27, 0.011),
            DVec3::new(0.05, 0.011, 0.12),
        );
        for (axis, angle) in [
            (DVec3::new(1.0, 2.0, -0.5), 0.7),
            (DVec3::Z, -2.9),
            (DVec3::new(-0.3, 0.1, 0.9), 3.1),
            (DVec3::X, 0.0),
        ] {
            let r = DMat3::from_axis_angle(axis.normalize(), angle);
            let dense = r * s * r.transpose();
            let fast = rotate_symmetric(&r, &s);
            assert!(
                (dense - fast)
                    .abs()
                    .to_cols_array()
                    .iter()
                    .all(|e| *e < 1e-15),
                "{dense} vs {fast}"
            );
        }
    }
}
