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
