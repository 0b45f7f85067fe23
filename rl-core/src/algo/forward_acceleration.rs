//! Forward acceleration kinematics: every body's spatial acceleration (without gravity).
//!
//! `q`: `nq`, `qd`, `qdd`: `dof` elements. Results: poses, [`Data::velocity`] and
//! [`Data::acceleration`] (body coordinates). O(n). Does not allocate.

use crate::error::{Error, check_len};
use crate::model::{Data, Model, ROOT};
use crate::spatial::MotionVector;

use super::forward_position::body_pose;

/// Computes poses, spatial velocities and spatial accelerations of all bodies.
pub fn forward_acceleration<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<(), Error> {
    check_len("q", q, model.nq)?;
    check_len("qd", qd, model.nv)?;
    check_len("qdd", qdd, model.nv)?;
    if model.has_mimic {
        sweep_mimic(model, data, q, qd, qdd);
    } else {
        sweep::<false, N>(model, data, q, qd, qdd);
    }
    Ok(())
}

/// The sweep for models with mimic joints (out of line: the common path stays as it was).
#[cold]
#[inline(never)]
fn sweep_mimic<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) {
    let (qd, qdd) = (
        super::mimic::expand(model, qd),
        super::mimic::expand(model, qdd),
    );
    sweep::<true, N>(model, data, q, &qd, &qdd);
}

/// The sweep over internal coordinates.
#[inline]
fn sweep<const MIMIC: bool, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) {
    for i in 0..model.nbodies {
        body_pose::<MIMIC, N>(model, data, q, i);
        let sv = model.idx_v[i];
        let mut vj = MotionVector::ZERO;
        let mut aj = MotionVector::ZERO;
        for k in sv..sv + model.joints[i].nv() {
            vj += model.subspace[k] * qd[k];
            aj += model.subspace[k] * qdd[k];
        }
        let p = model.parents[i];
        let x = &data.parent_pose[i];
        let (v, a) = if p == ROOT {
            (vj, aj)
        } else {
            let v = x.inv_act_motion(&data.v[p]) + vj;
            (v, x.inv_act_motion(&data.a[p]) + aj + v.cross_motion(&vj))
        };
        data.v[i] = v;
        data.a[i] = a;
    }
}

/// Tool `tool`'s classical acceleration (the second derivative of its origin's position and
/// its angular acceleration) in world coordinates, `[linear; angular]`, from the last
/// acceleration sweep.
pub fn tool_acceleration<const N: usize>(
    model: &Model<N>,
    data: &Data<N>,
    tool: usize,
) -> Result<[f64; 6], Error> {
    let t = model.tools().get(tool).ok_or(Error::UnknownTool { tool })?;
    if t.body == ROOT {
        return Ok([0.0; 6]);
    }
    let v = t.placement.inv_act_motion(&data.v[t.body]);
    let a = t.placement.inv_act_motion(&data.a[t.body]);
    let r = (data.world_pose[t.body] * t.placement).rotation;
    let l = r * (a.linear + v.angular.cross(v.linear));
    let w = r * a.angular;
    Ok([l.x, l.y, l.z, w.x, w.y, w.z])
}
