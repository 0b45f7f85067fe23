//! The preallocated workspace every algorithm writes into.

use crate::spatial::{
    ArticulatedBodyInertia, ForceVector, MotionVector, PlueckerTransform, RigidBodyInertia,
};

/// Workspace and results for a [`super::Model`] of the same capacity `N`.
///
/// Create one per thread (it is large but never grows); the algorithms fill it and return
/// views of their results. Results stay valid until the next algorithm call.
#[derive(Clone, Debug)]
pub struct Data<const N: usize> {
    /// Pose of each body in its parent's frame (`placement · X_J(q)`).
    pub(crate) parent_pose: [PlueckerTransform; N],
    /// Pose of each body in the world frame.
    pub(crate) world_pose: [PlueckerTransform; N],
    /// Spatial velocity of each body, in body coordinates.
    pub(crate) v: [MotionVector; N],
    /// Spatial acceleration of each body, in body coordinates.
    pub(crate) a: [MotionVector; N],
    /// Bias acceleration `v × S q̇` (ABA) of each body.
    pub(crate) c: [MotionVector; N],
    /// Spatial force on each body (RNEA) or articulated bias force (ABA), body coordinates.
    pub(crate) f: [ForceVector; N],
    /// Composite rigid-body inertia (CRBA).
    pub(crate) composite: [RigidBodyInertia; N],
    /// Articulated-body inertia (ABA).
    pub(crate) articulated: [ArticulatedBodyInertia; N],
    /// `U = I^A S` per DOF (ABA).
    pub(crate) u: [ForceVector; N],
    /// `D⁻¹` per body, the joint's `nv × nv` block stored row-major in 6×6 (ABA).
    pub(crate) d_inv: [[[f64; 6]; 6]; N],
    /// `u = τ − Sᵀ p^A` per DOF (ABA).
    pub(crate) u_bias: [f64; N],
    /// Motion subspace columns in world coordinates at the world origin, one per DOF.
    pub(crate) world_subspace: [MotionVector; N],
    /// Joint torques (RNEA and friends).
    pub(crate) tau: [f64; N],
    /// A path of bodies (the Jacobian's branch, leaf first), kept here so that no call has to
    /// zero an `N`-long array of its own.
    pub(crate) chain: [usize; N],
    /// Joint accelerations (ABA).
    pub(crate) qdd: [f64; N],
    /// Joint-space mass matrix (CRBA): the upper triangle `[r][c]`, `r ≤ c`, is kept (the lower
    /// one is not written; read through [`Data::mass_matrix`]).
    pub(crate) mass_matrix: [[f64; N]; N],
    /// Scratch matrix for factorisations.
    pub(crate) factor: [[f64; N]; N],
}

impl<const N: usize> Default for Data<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Data<N> {
    /// A zeroed workspace.
    pub fn new() -> Self {
        Self {
            parent_pose: [PlueckerTransform::IDENTITY; N],
            world_pose: [PlueckerTransform::IDENTITY; N],
            v: [MotionVector::ZERO; N],
            a: [MotionVector::ZERO; N],
            c: [MotionVector::ZERO; N],
            f: [ForceVector::ZERO; N],
            composite: [RigidBodyInertia::ZERO; N],
            articulated: [ArticulatedBodyInertia::ZERO; N],
            u: [ForceVector::ZERO; N],
            d_inv: [[[0.0; 6]; 6]; N],
            u_bias: [0.0; N],
            world_subspace: [MotionVector::ZERO; N],
            tau: [0.0; N],
            chain: [0; N],
            qdd: [0.0; N],
            mass_matrix: [[0.0; N]; N],
            factor: [[0.0; N]; N],
        }
    }

    /// Pose of body `i` in the world frame, from the last sweep that computes world poses:
    /// [`crate::algo::forward_position`], [`crate::algo::forward_velocity`],
    /// [`crate::algo::forward_acceleration`] and [`crate::algo::aba`] (every body),
    /// [`crate::algo::jacobian`] (the tool's branch). RNEA, gravity and CRBA work in body
    /// coordinates and leave it as it was.
    pub fn world_pose(&self, i: usize) -> &PlueckerTransform {
        &self.world_pose[i]
    }

    /// Spatial velocity of body `i` in its own coordinates, from the last
    /// [`crate::algo::forward_velocity`], [`crate::algo::forward_acceleration`] or RNEA call
    /// (ABA reuses this storage for world-frame velocities).
    pub fn velocity(&self, i: usize) -> &MotionVector {
        &self.v[i]
    }

    /// Spatial acceleration of body `i` in its own coordinates, from the last
    /// [`crate::algo::forward_acceleration`] (without gravity); RNEA and ABA reuse this storage
    /// (with gravity as a base acceleration, ABA in world coordinates).
    pub fn acceleration(&self, i: usize) -> &MotionVector {
        &self.a[i]
    }

    /// Row `r` of the mass matrix from the last [`crate::algo::crba`] call, into `out[..n]`.
    pub fn mass_matrix_row(&self, r: usize, out: &mut [f64]) {
        for (c, x) in out.iter_mut().enumerate() {
            *x = self.mass_matrix(r, c);
        }
    }

    /// Element `(r, c)` of the mass matrix from the last [`crate::algo::crba`] call.
    pub fn mass_matrix(&self, r: usize, c: usize) -> f64 {
        if r <= c {
            self.mass_matrix[r][c]
        } else {
            self.mass_matrix[c][r]
        }
    }
}
