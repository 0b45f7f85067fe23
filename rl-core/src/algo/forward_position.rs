//! Forward position kinematics: the world pose of every body and tool.
//!
//! `q` has `model.nq()` elements. Results: [`Data::world_pose`]. O(n). Does not allocate.
//!
//! The pose helpers here are shared by every sweep. Their `MIMIC` parameter says whether the
//! model may have mimic joints ([`crate::model::mimic`]): each algorithm tests
//! [`Model::has_mimic`] once and runs a copy of its sweeps without the per-body test when the
//! answer is no.

use crate::error::{Error, check_len};
use crate::model::{Data, Model, ROOT};
use crate::spatial::PlueckerTransform;

/// Computes every body's pose relative to its parent and to the world.
pub fn forward_position<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
) -> Result<(), Error> {
    check_len("q", q, model.nq)?;
    if model.has_mimic {
        sweep_mimic(model, data, q);
    } else {
        sweep::<false, N>(model, data, q);
    }
    Ok(())
}

/// The sweep for models with mimic joints, out of line so that the common path stays as it
/// was without them.
#[cold]
#[inline(never)]
fn sweep_mimic<const N: usize>(model: &Model<N>, data: &mut Data<N>, q: &[f64]) {
    sweep::<true, N>(model, data, q);
}

#[inline]
fn sweep<const MIMIC: bool, const N: usize>(model: &Model<N>, data: &mut Data<N>, q: &[f64]) {
    for i in 0..model.nbodies {
        world_pose::<MIMIC, N>(model, data, q, i);
    }
}

/// Body `i`'s pose in its parent, `placement · X_J(q)` (a mimic joint at `m q_leader + o`).
#[inline(always)]
fn joint_pose<const MIMIC: bool, const N: usize>(
    model: &Model<N>,
    q: &[f64],
    i: usize,
) -> PlueckerTransform {
    let joint = &model.joints[i];
    let sq = model.idx_q[i];
    if MIMIC {
        if let Some(m) = &model.mimic[i] {
            let x = m.multiplier * q[sq] + m.offset;
            return joint.placed_transform(&model.placements[i], &[x]);
        }
    }
    joint.placed_transform(&model.placements[i], &q[sq..sq + joint.nq()])
}

/// Body `i`'s pose in its parent into `data` (for the sweeps that work in body coordinates).
#[inline]
pub(crate) fn local_pose<const MIMIC: bool, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    i: usize,
) {
    data.parent_pose[i] = joint_pose::<MIMIC, N>(model, q, i);
}

/// Body `i`'s pose in the world into `data` (its parent's must be there), returned too. The
/// pose in the parent is not kept: the world-frame algorithms do not need it.
#[inline]
pub(crate) fn world_pose<const MIMIC: bool, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    i: usize,
) -> PlueckerTransform {
    let x = joint_pose::<MIMIC, N>(model, q, i);
    let p = model.parents[i];
    let w = if p == ROOT { x } else { data.world_pose[p] * x };
    data.world_pose[i] = w;
    w
}

/// Body `i`'s pose in its parent and in the world, into `data`.
#[inline]
pub(crate) fn body_pose<const MIMIC: bool, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    i: usize,
) {
    local_pose::<MIMIC, N>(model, data, q, i);
    let x = data.parent_pose[i];
    let p = model.parents[i];
    data.world_pose[i] = if p == ROOT { x } else { data.world_pose[p] * x };
}

/// The world pose of tool `tool`, from the body poses of the last forward sweep.
pub fn tool_pose<const N: usize>(
    model: &Model<N>,
    data: &Data<N>,
    tool: usize,
) -> Result<PlueckerTransform, Error> {
    let t = model.tools().get(tool).ok_or(Error::UnknownTool { tool })?;
    Ok(if t.body == ROOT {
        t.placement
    } else {
        data.world_pose[t.body] * t.placement
    })
}
