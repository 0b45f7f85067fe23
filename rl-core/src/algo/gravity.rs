//! The generalized gravity vector `G(q)`: the joint forces that hold the robot still.
//!
//! RNEA with `q̇ = q̈ = 0` reduces to statics: each joint carries the weight of the bodies
//! beyond it. So only the gravity vector goes down the tree (rotated into each body's
//! coordinates) and only the subtree mass `m` and first moment `h = m c` come back up; the
//! wrench at body `i`'s origin is `(h × (−g), −m g)`, and `τ = Sᵀ` of it. About half the
//! arithmetic of the full RNEA, whose spatial inertia products and force transforms the
//! static case does not need. `q`: `nq`; result: `dof`. O(n). Does not allocate.

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
    // Down: −g in each body's coordinates, kept as the RNEA acceleration of a robot at rest;
    // the composites start as each body's own mass and first moment.
    for i in 0..model.nbodies {
        local_pose(model, data, q, i);
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
    Ok(&data.tau[..model.nv])
}
