//! The joint-space mass matrix `M(q)` by the composite rigid-body algorithm (CRBA).
//!
//! Featherstone, *Rigid Body Dynamics Algorithms*, §6.2, in world coordinates (as Pinocchio
//! does it): each body's inertia and motion subspace are brought to the world frame once, the
//! composite inertias then add without transforms, and each matrix entry `M[k][l]` (DOF `l` an
//! ancestor of DOF `k`) is a single scalar product `S_lᵀ (I^c_k S_k)`. `q`: `nq`; result: the
//! full symmetric `dof × dof` matrix in [`Data::mass_matrix`]. O(n·depth). Does not allocate.

use crate::error::{Error, check_len};
use crate::model::{Data, Model, ROOT};

use super::forward_position::world_pose;

/// Computes `M(q)` into `data` (read it with [`Data::mass_matrix`]).
pub fn crba<const N: usize>(model: &Model<N>, data: &mut Data<N>, q: &[f64]) -> Result<(), Error> {
    check_len("q", q, model.nq)?;
    // Only the upper triangle is kept. Entries between DOFs on different branches are zero
    // and never written below.
    for (r, row) in data.mass_matrix[..model.nv].iter_mut().enumerate() {
        row[r..model.nv].fill(0.0);
    }
    for i in 0..model.nbodies {
        let x = world_pose(model, data, q, i);
        data.composite[i] = model.world_inertia(i, &x);
        let sv = model.idx_v[i];
        for k in sv..sv + model.joints[i].nv() {
            data.world_subspace[k] = model.act_subspace(i, k, &x);
        }
    }
    for i in (0..model.nbodies).rev() {
        let sv = model.idx_v[i];
        let ic = data.composite[i];
        for k in sv..sv + model.joints[i].nv() {
            let f = ic.mul_motion(&data.world_subspace[k]);
            // This joint's own block, then every ancestor's DOFs.
            for l in sv..=k {
                data.mass_matrix[l][k] = data.world_subspace[l].dot(&f);
            }
            let mut l = model.dof_parent[sv];
            while l != ROOT {
                data.mass_matrix[l][k] = data.world_subspace[l].dot(&f);
                l = model.dof_parent[l];
            }
        }
        let p = model.parents[i];
        if p != ROOT {
            data.composite[p] += ic;
        }
    }
    Ok(())
}
