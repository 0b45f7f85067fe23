//! The generalized gravity vector `G(q)`: the joint forces that hold the robot still.
//!
//! RNEA with `q̇ = q̈ = 0` reduces to statics: each joint carries the weight of the bodies
//! beyond it. So only the gravity vector goes down the tree (rotated into each body's
//! coordinates) and only the subtree mass `m` and first moment `h = m c` come back up; the
//! wrench at body `i`'s origin is `(h × (−g), −m g)`, and `τ = Sᵀ` of it. About half the
//! arithmetic of the full RNEA, whose spatial inertia products and force transforms the
//! static case does not need. `q`: `nq`; result: `dof` (with mimic joints `Gᵀ` of the
//! internal torques, as RNEA). O(n). Does not allocate.

use glam::DVec3;

use crate::error::{Error, check_len};
use crate::model::{Data, Model, ROOT};
use crate::spatial::{ForceVector, MotionVector};

use super::forward_position::local_pose;

/// `G(q)`.
pub fn gravity<'d, const N: usize>(
    model: &Model<N>,
    data: &'d mut Data<N>,
    q: &[f64],
) -> Result<&'d [f64], Error> {
    check_len("q", q, model.nq)?;
    if model.has_mimic {
        run_mimic(model, data, q);
    } else {
        run::<false, N>(model, data, q);
    }
    Ok(&data.tau[..model.nv])
}

/// `Gᵀ` of the internal sweeps, for models with mimic joints (out of line: the common path
/// stays as it was).
#[cold]
#[inline(never)]
fn run_mimic<const N: usize>(model: &Model<N>, data: &mut Data<N>, q: &[f64]) {
    run::<true, N>(model, data, q);
    super::mimic::contract_tau(model, data);
}

/// The two sweeps, over internal coordinates.
#[inline]
fn run<const MIMIC: bool, const N: usize>(model: &Model<N>, data: &mut Data<N>, q: &[f64]) {
    // Down: −g in each body's coordinates, kept as the RNEA acceleration of a robot at rest;
    // the composites start as each body's own mass and first moment.
    for i in 0..model.nbodies {
        local_pose::<MIMIC, N>(model, data, q, i);
        let p = model.parents[i];
        let up = if p == ROOT {
            -model.gravity
        } else {
            data.a[p].linear
        };
        data.a[i] = MotionVector::new(DVec3::ZERO, data.parent_pose[i].inv_rotate(up));
        data.composite[i].mass = model.inertias[i].mass;
        data.composite[i].first_moment = model.inertias[i].first_moment;
    }
    // Up: each joint holds its subtree; mass and first moment move to the parent.
    for i in (0..model.nbodies).rev() {
        let (m, h) = (data.composite[i].mass, data.composite[i].first_moment);
        let up = data.a[i].linear;
        let f = ForceVector {
            moment: h.cross(up),
            force: up * m,
        };
        model.joint_force(i, &f, &mut data.tau);
        let p = model.parents[i];
        if p != ROOT {
            let x = &data.parent_pose[i];
            data.composite[p].mass += m;
            data.composite[p].first_moment += x.rotation * h + x.translation * m;
        }
    }
}
