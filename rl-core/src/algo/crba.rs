//! The joint-space mass matrix `M(q)` by the composite rigid-body algorithm (CRBA).
//!
//! Featherstone, *Rigid Body Dynamics Algorithms*, Table 6.2: composite inertias are
//! accumulated from the leaves, and each column's force is carried up the body's ancestors
//! only (the matrix is as sparse as the tree). `q`: `nq`; result: the full symmetric
//! `dof × dof` matrix in [`Data::mass_matrix`]. O(n·depth). Does not allocate.

use crate::error::{Error, check_len};
use crate::model::{Data, Model, ROOT};

use super::forward_position::body_pose;

/// Computes `M(q)` into `data` (read it with [`Data::mass_matrix`]).
pub fn crba<const N: usize>(model: &Model<N>, data: &mut Data<N>, q: &[f64]) -> Result<(), Error> {
    check_len("q", q, model.nq)?;
    // Entries between DOFs on different branches are zero and never written below.
    for row in &mut data.mass_matrix[..model.nv] {
        row[..model.nv].fill(0.0);
    }
    for i in 0..model.nbodies {
        body_pose(model, data, q, i);
        data.composite[i] = model.inertias[i];
    }
    for i in (0..model.nbodies).rev() {
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        let ic = data.composite[i];
        for k in sv..sv + nv {
            let mut f = ic.mul_motion(&model.subspace[k]);
            for l in sv..=k {
                let m = model.subspace[l].dot(&f);
                data.mass_matrix[k][l] = m;
                data.mass_matrix[l][k] = m;
            }
            let mut j = i;
            while model.parents[j] != ROOT {
                f = data.parent_pose[j].act_force(&f);
                j = model.parents[j];
                let sj = model.idx_v[j];
                for l in sj..sj + model.joints[j].nv() {
                    let m = model.subspace[l].dot(&f);
                    data.mass_matrix[k][l] = m;
                    data.mass_matrix[l][k] = m;
                }
            }
        }
        let p = model.parents[i];
        if p != ROOT {
            let ic_parent = ic.transform_to_parent(&data.parent_pose[i]);
            data.composite[p] += ic_parent;
        }
    }
    Ok(())
}
