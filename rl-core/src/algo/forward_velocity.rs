//! Forward velocity kinematics: every body's spatial velocity.
//!
//! `q`: `nq`, `qd`: `dof` elements. Results: [`Data::world_pose`], [`Data::velocity`]
//! (body coordinates). O(n). Does not allocate.

use crate::error::{Error, check_len};
use crate::model::{Data, Model, ROOT};
use crate::spatial::MotionVector;

use super::forward_position::body_pose;

/// Computes poses and spatial velocities of all bodies.
pub fn forward_velocity<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: &[f64],
) -> Result<(), Error> {
    check_len("q", q, model.nq)?;
    check_len("qd", qd, model.nv)?;
    if model.has_mimic {
        sweep_mimic(model, data, q, qd);
    } else {
        sweep::<false, N>(model, data, q, qd);
    }
    Ok(())
}

/// The sweep for models with mimic joints (out of line: the common path stays as it was).
#[cold]
#[inline(never)]
fn sweep_mimic<const N: usize>(model: &Model<N>, data: &mut Data<N>, q: &[f64], qd: &[f64]) {
    let qd = super::mimic::expand(model, qd);
    sweep::<true, N>(model, data, q, &qd);
}

/// The sweep over internal coordinates.
#[inline]
fn sweep<const MIMIC: bool, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: &[f64],
) {
    for i in 0..model.nbodies {
        body_pose::<MIMIC, N>(model, data, q, i);
        let sv = model.idx_v[i];
        let mut vj = MotionVector::ZERO;
        for k in sv..sv + model.joints[i].nv() {
            vj += model.subspace[k] * qd[k];
        }
        let p = model.parents[i];
        data.v[i] = if p == ROOT {
            vj
        } else {
            data.parent_pose[i].inv_act_motion(&data.v[p]) + vj
        };
    }
}

/// Tool `tool`'s velocity in world coordinates at the tool's origin, `[linear; angular]`
/// (RL's order), from the last velocity sweep.
pub fn tool_velocity<const N: usize>(
    model: &Model<N>,
    data: &Data<N>,
    tool: usize,
) -> Result<[f64; 6], Error> {
    let t = model.tools().get(tool).ok_or(Error::UnknownTool { tool })?;
    if t.body == ROOT {
        return Ok([0.0; 6]);
    }
    let v = t.placement.inv_act_motion(&data.v[t.body]);
    let r = (data.world_pose[t.body] * t.placement).rotation;
    let (l, a) = (r * v.linear, r * v.angular);
    Ok([l.x, l.y, l.z, a.x, a.y, a.z])
}
