//! Mimic joints: a joint that follows another one instead of moving on its own (URDF's
//! `<mimic joint= multiplier= offset=>`, Pinocchio's `JointModelMimic`).
//!
//! A mimic joint `j` following the leader `l` has the configuration `q_j = m q_l + o` and the
//! velocity `q̇_j = m q̇_l`. It adds no degree of freedom: `q`, `q̇`, `q̈` and `τ` have no entry
//! for it. Its body still moves and carries mass, so it appears in kinematics and dynamics:
//! inside the sweeps every joint, mimic or not, keeps its own coordinate (the *internal*
//! coordinates, Pinocchio's "extended" ones), and the public vectors map onto them by the
//! constant matrix `G` (one row per internal coordinate, with `1` at its own column or `m` at
//! its leader's):
//!
//! ```text
//! q̇_int = G q̇,   q̈_int = G q̈,   τ = Gᵀ τ_int,   M = Gᵀ M_int G,   J = J_int G.
//! ```
//!
//! These are the equations of the constrained system by virtual work (the coupling does no
//! work), and they are what Pinocchio 4 computes: a mimic joint's torque maps back to its
//! leader through the multiplier, and the leader's row and column of `M` collect the mimic's
//! contributions. Unlike Pinocchio 4.1, the leader may come anywhere in the tree, before or
//! after its mimic, on the same branch or another.
//!
//! A model without mimic joints has `G = 1`: the algorithms then run without any of this (one
//! test per call, see [`super::Model::has_mimic`]).

use super::{Model, ROOT};

/// How a joint follows another: `q = multiplier · q_leader + offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mimic {
    /// The body whose joint is followed (a one-coordinate joint that is not a mimic itself).
    pub leader: usize,
    /// The factor on the leader's position and velocity.
    pub multiplier: f64,
    /// Added to the position, rad or m.
    pub offset: f64,
}

impl<const N: usize> Model<N> {
    /// The parent of internal coordinate `k` on the path to the root (the coordinate before it
    /// in the same joint, or the last one of the parent body's joint), or [`ROOT`].
    pub(crate) fn internal_dof_parent(&self, k: usize) -> usize {
        let b = self.dof_body[k];
        if k > self.idx_v[b] {
            return k - 1;
        }
        match self.parents[b] {
            ROOT => ROOT,
            p => self.idx_v[p] + self.joints[p].nv() - 1,
        }
    }

    /// After the last body: numbers the public coordinates (mimic joints have none), moves the
    /// limits to them, and works out the factorisation tree of `M`.
    pub(crate) fn finish_coordinates(&mut self) {
        // Public q and v indices, in body order, skipping the mimic joints.
        let (mut nq, mut nv) = (0, 0);
        for i in 0..self.nbodies {
            if self.mimic[i].is_some() {
                continue;
            }
            let (iv, j) = (self.idx_v[i], self.joints[i]);
            self.idx_q[i] = nq;
            for k in 0..j.nv() {
                self.ext_v[iv + k] = nv + k;
                self.ext_scale[iv + k] = 1.0;
                self.v_ext[nv + k] = iv + k;
                // Limits were set at internal indices; public ones are never above them.
                self.limits[nv + k] = self.limits[iv + k];
            }
            nq += j.nq();
            nv += j.nv();
        }
        for i in 0..self.nbodies {
            if let Some(m) = self.mimic[i] {
                let l = m.leader;
                self.idx_q[i] = self.idx_q[l];
                self.ext_v[self.idx_v[i]] = self.ext_v[self.idx_v[l]];
                self.ext_scale[self.idx_v[i]] = m.multiplier;
            }
        }
        for k in nv..self.nv_ext {
            self.limits[k] = super::JointLimits::UNLIMITED;
        }
        self.nq = nq;
        self.nv = nv;
        self.has_mimic = nv != self.nv_ext;
        if self.has_mimic {
            self.elimination_tree();
        } else {
            for k in 0..nv {
                self.dof_parent[k] = self.internal_dof_parent(k);
            }
        }
    }

    /// The parents of the sparse `LᵀDL` factorisation of `M = Gᵀ M_int G` (eliminating the
    /// last coordinate first, Featherstone's order): `dof_parent[k]` is the highest `i < k`
    /// with `L[k][i] ≠ 0` after fill-in, so every nonzero of row `k` lies on the path
    /// `dof_parent[k], dof_parent[dof_parent[k]], …`. Without mimic joints this is the tree of
    /// the degrees of freedom itself; a mimic joint on another branch than its leader couples
    /// the branches and the path grows to cover the fill-in.
    ///
    /// Liu's algorithm with path compression over the nonzeros of `M`: public coordinates `a`
    /// and `b` interact where an internal coordinate of one is an ancestor of an internal
    /// coordinate of the other. O(n · n_int · depth), at load time; no allocation.
    fn elimination_tree(&mut self) {
        let n = self.nv;
        let mut ancestor = [ROOT; N];
        for k in 0..n {
            self.dof_parent[k] = ROOT;
        }
        // Eliminate n-1, n-2, …, 0: at step k, join the trees of the already eliminated
        // neighbours i > k of k under k.
        for k in (0..n).rev() {
            for e in 0..self.nv_ext {
                let mut f = self.internal_dof_parent(e);
                while f != ROOT {
                    let (a, b) = (self.ext_v[e], self.ext_v[f]);
                    let other = if a == k && b > k {
                        Some(b)
                    } else if b == k && a > k {
                        Some(a)
                    } else {
                        None
                    };
                    if let Some(mut r) = other {
                        while ancestor[r] != ROOT && ancestor[r] != k {
                            let next = ancestor[r];
                            ancestor[r] = k;
                            r = next;
                        }
                        if ancestor[r] == ROOT {
                            ancestor[r] = k;
                            self.dof_parent[r] = k;
                        }
                    }
                    f = self.internal_dof_parent(f);
                }
            }
        }
    }
}
