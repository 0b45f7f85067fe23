//! The preallocated workspace every algorithm writes into.

use glam::{DMat3, DVec3};

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

/// A dense `n × n` matrix in the leading block of a fixed-capacity `[[f64; N]; N]`, row-major:
/// element `(r, c)` is [`get`](Self::get)`(r, c)`, row `r` is [`row`](Self::row)`(r)` (`n`
/// elements). The derivative algorithms return their results as such views.
#[derive(Clone, Copy, Debug)]
pub struct MatrixView<'a, const N: usize> {
    rows: &'a [[f64; N]],
}

impl<'a, const N: usize> MatrixView<'a, N> {
    /// The leading `n × n` block of `m`.
    #[inline]
    pub(crate) fn new(m: &'a [[f64; N]; N], n: usize) -> Self {
        Self { rows: &m[..n] }
    }

    /// The number of rows (and of columns).
    #[inline]
    pub fn dim(&self) -> usize {
        self.rows.len()
    }

    /// Element `(r, c)`.
    #[inline]
    pub fn get(&self, r: usize, c: usize) -> f64 {
        self.rows[r][..self.rows.len()][c]
    }

    /// Row `r` (`dim()` elements).
    #[inline]
    pub fn row(&self, r: usize) -> &'a [f64] {
        &self.rows[r][..self.rows.len()]
    }

    /// The rows, first to last.
    pub fn rows(&self) -> impl Iterator<Item = &'a [f64]> + 'a {
        let n = self.rows.len();
        self.rows.iter().map(move |r| &r[..n])
    }
}

/// Workspace and results of the derivative algorithms
/// ([`crate::algo::rnea_derivatives`], [`crate::algo::aba_derivatives`],
/// [`crate::algo::static_torque_derivatives`]) for a model of capacity `N`, used beside a
/// [`Data`].
///
/// Kept apart from [`Data`] because of its size: six `N × N` matrices, 32 KB each at `N = 64`
/// and 512 KB each at `N = 256` (about 3.2 MB in all there), which programs that never
/// differentiate should not carry. Create one per thread, on the heap for large `N`
/// (`Box::new(DerivativeData::new())`); it never grows. Results stay valid until the next
/// derivative call.
#[derive(Clone, Debug)]
pub struct DerivativeData<const N: usize> {
    /// `∂τ/∂q` (RNEA derivatives; also what the ABA derivatives computed at their `q̈`).
    pub(crate) dtau_dq: [[f64; N]; N],
    /// `∂τ/∂q̇`.
    pub(crate) dtau_dv: [[f64; N]; N],
    /// `∂τ/∂q̈ = M`, both triangles.
    pub(crate) mass_matrix: [[f64; N]; N],
    /// `∂q̈/∂q` (ABA derivatives); scratch for the mimic contraction otherwise.
    pub(crate) ddq_dq: [[f64; N]; N],
    /// `∂q̈/∂q̇`; scratch for the mimic contraction otherwise.
    pub(crate) ddq_dv: [[f64; N]; N],
    /// `∂q̈/∂τ = M⁻¹`, both triangles; scratch for the mimic contraction otherwise.
    pub(crate) minv: [[f64; N]; N],
    /// `q̈` of the last ABA derivative call.
    pub(crate) qdd: [f64; N],
    /// The number of degrees of freedom of the last call (the views' dimension).
    pub(crate) n: usize,
    /// Per internal coordinate and per body, the recursions' intermediate quantities.
    pub(crate) ws: DerivativeWorkspace<N>,
}

/// The recursions' intermediate quantities, in world coordinates (see the module docs of
/// `algo::rnea_derivatives` for the symbols).
#[derive(Clone, Debug)]
pub(crate) struct DerivativeWorkspace<const N: usize> {
    /// Per internal coordinate: `∂v/∂q` of the coordinate's own body beyond the transport
    /// term, `v_λ × S`.
    pub(crate) dv: [MotionVector; N],
    /// `∂a/∂q` beyond transport, `a_λ × S + v_λ × (v_λ × S)`.
    pub(crate) da: [MotionVector; N],
    /// `∂a/∂q̇` beyond transport, `(v_λ + v) × S`.
    pub(crate) dadv: [MotionVector; N],
    /// `∂F/∂q` of the subtree force of the coordinate's body (with `S ×* F` once the body's
    /// own rows are written).
    pub(crate) dfdq: [ForceVector; N],
    /// `∂F/∂q̇`.
    pub(crate) dfdv: [ForceVector; N],
    /// `∂F/∂q̈ = I^c S`.
    pub(crate) dfda: [ForceVector; N],
    /// Per coordinate `a`, packed for the pairs with its descendants' rows: `[dA_a, dAv_a]`
    /// component by component, then `[ω(dV_a), ω(S_a)]`.
    pub(crate) lower: [[[f64; 2]; 9]; N],
    /// Per coordinate: its world subspace column `S` as `[angular; linear]`.
    pub(crate) subspace: [[f64; 6]; N],
    /// Per body: the velocity-dependent force `v ×* I v − fext` (ABA derivatives).
    pub(crate) bias: [ForceVector; N],
    /// Per body: the angular block of the composite `B` operator (`∂f/∂ω` of a velocity
    /// variation).
    pub(crate) bn: [DMat3; N],
    /// Per body: the composite linear momentum (the linear block of `B` is `2 ω × h_lin`).
    pub(crate) hf: [DVec3; N],
}

impl<const N: usize> Default for DerivativeData<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> DerivativeData<N> {
    /// A zeroed workspace.
    pub fn new() -> Self {
        Self {
            dtau_dq: [[0.0; N]; N],
            dtau_dv: [[0.0; N]; N],
            mass_matrix: [[0.0; N]; N],
            ddq_dq: [[0.0; N]; N],
            ddq_dv: [[0.0; N]; N],
            minv: [[0.0; N]; N],
            qdd: [0.0; N],
            n: 0,
            ws: DerivativeWorkspace {
                dv: [MotionVector::ZERO; N],
                da: [MotionVector::ZERO; N],
                dadv: [MotionVector::ZERO; N],
                dfdq: [ForceVector::ZERO; N],
                dfdv: [ForceVector::ZERO; N],
                dfda: [ForceVector::ZERO; N],
                lower: [[[0.0; 2]; 9]; N],
                subspace: [[0.0; 6]; N],
                bias: [ForceVector::ZERO; N],
                bn: [DMat3::ZERO; N],
                hf: [DVec3::ZERO; N],
            },
        }
    }

    /// `∂τ/∂q` from the last [`crate::algo::rnea_derivatives`] (or, at the computed `q̈`,
    /// [`crate::algo::aba_derivatives`]; or the static torque's from
    /// [`crate::algo::static_torque_derivatives`]).
    pub fn dtau_dq(&self) -> MatrixView<'_, N> {
        MatrixView::new(&self.dtau_dq, self.n)
    }

    /// `∂τ/∂q̇` from the last [`crate::algo::rnea_derivatives`] or
    /// [`crate::algo::aba_derivatives`].
    pub fn dtau_dv(&self) -> MatrixView<'_, N> {
        MatrixView::new(&self.dtau_dv, self.n)
    }

    /// `M = ∂τ/∂q̈` from the last [`crate::algo::rnea_derivatives`].
    pub fn mass_matrix(&self) -> MatrixView<'_, N> {
        MatrixView::new(&self.mass_matrix, self.n)
    }

    /// `∂q̈/∂q` from the last [`crate::algo::aba_derivatives`].
    pub fn ddq_dq(&self) -> MatrixView<'_, N> {
        MatrixView::new(&self.ddq_dq, self.n)
    }

    /// `∂q̈/∂q̇` from the last [`crate::algo::aba_derivatives`].
    pub fn ddq_dv(&self) -> MatrixView<'_, N> {
        MatrixView::new(&self.ddq_dv, self.n)
    }

    /// `M⁻¹ = ∂q̈/∂τ` from the last [`crate::algo::aba_derivatives`].
    pub fn minv(&self) -> MatrixView<'_, N> {
        MatrixView::new(&self.minv, self.n)
    }

    /// `q̈` from the last [`crate::algo::aba_derivatives`].
    pub fn qdd(&self) -> &[f64] {
        &self.qdd[..self.n]
    }
}
