//! Tool Jacobians in the world frame, and `J̇ q̇`.
//!
//! `J` maps `q̇` to the tool's velocity in world coordinates at the tool's origin, rows
//! `[linear xyz; angular xyz]` (RL's layout, Pinocchio's `LOCAL_WORLD_ALIGNED`). One forward
//! sweep computes every DOF's motion subspace in world coordinates; each tool then fills its
//! columns from its own ancestors only — one sweep for all tools, where RL runs `n` velocity
//! sweeps. `q`: `nq`. O(n + tools·depth). Does not allocate.
//!
//! Columns are the public DOFs: a mimic joint's column is added to its leader's, times the
//! multiplier (`J = J_int G`, [`crate::model::mimic`]).

use glam::DVec3;

use crate::error::{Error, check_len};
use crate::joint::Joint;
use crate::model::{Data, Model, ROOT};

use super::forward_position::world_pose;

/// A 6 × `N` Jacobian, rows `[linear xyz; angular xyz]`; columns past `model.dof()` unused.
pub type Jacobian<const N: usize> = [[f64; N]; 6];

/// Fills `out` with tool `tool`'s Jacobian from the world poses of its ancestors in `data`
/// (the last forward sweep). Every column is written once: the ancestors' from their world
/// motion subspaces, the others zero. (With mimic joints, [`super::mimic::fill_jacobian`]
/// adds each internal column to the public column it follows: `J = J_int G`.)
fn fill<const N: usize>(
    model: &Model<N>,
    data: &Data<N>,
    tool: usize,
    out: &mut Jacobian<N>,
) -> Result<(), Error> {
    // Only the tool's origin is needed, not its orientation.
    let t = model.tools().get(tool).ok_or(Error::UnknownTool { tool })?;
    let p = if t.body == ROOT {
        t.placement.translation
    } else {
        data.world_pose[t.body].transform_point(t.placement.translation)
    };
    fill_at(model, data, t.body, p, out);
    Ok(())
}

/// The Jacobian of the point `p` (world) moving with body `body` (its ancestors' columns from
/// the world poses in `data`, the others zero).
fn fill_at<const N: usize>(
    model: &Model<N>,
    data: &Data<N>,
    body: usize,
    p: DVec3,
    out: &mut Jacobian<N>,
) {
    let mut zero_from = model.nv;
    let mut set = |k: usize, lin: DVec3, ang: DVec3| {
        for (row, v) in out
            .iter_mut()
            .zip([lin.x, lin.y, lin.z, ang.x, ang.y, ang.z])
        {
            row[k] = v;
        }
    };
    // Leaf to root, so DOF indices fall; the gap above each ancestor's DOFs is zero.
    let mut b = body;
    while b != ROOT {
        let sv = model.idx_v[b];
        let end = sv + model.joints[b].nv();
        for k in end..zero_from {
            set(k, DVec3::ZERO, DVec3::ZERO);
        }
        let x = &data.world_pose[b];
        match model.joints[b] {
            // Columns that are unit vectors in body coordinates are columns of the rotation:
            // translations along x, y, z, then rotations about them.
            Joint::SixDof(_) => {
                for j in 0..3 {
                    let w = x.rotation.col(j);
                    set(sv + j, w, DVec3::ZERO);
                    set(sv + 3 + j, w.cross(p - x.translation), w);
                }
            }
            _ => {
                for k in sv..end {
                    let s = model.act_subspace(b, k, x);
                    set(k, s.linear + s.angular.cross(p), s.angular);
                }
            }
        }
        zero_from = sv;
        b = model.parents[b];
    }
    for k in 0..zero_from {
        set(k, DVec3::ZERO, DVec3::ZERO);
    }
}

/// The world Jacobian of the point `point` (world coordinates) moving with body `body` — e.g.
/// the point of a link closest to an obstacle — from the world poses of the body's ancestors in
/// `data` (those of the last [`super::forward_position`] or [`jacobian`] through that body), in
/// [`jacobian`]'s convention: rows `[linear; angular]`, the linear rows the point's velocity.
/// [`ROOT`] gives zeros. O(depth). Does not allocate.
pub fn point_jacobian<const N: usize>(
    model: &Model<N>,
    data: &Data<N>,
    body: usize,
    point: DVec3,
    out: &mut Jacobian<N>,
) -> Result<(), Error> {
    if body != ROOT && body >= model.nbodies {
        return Err(Error::UnknownBody { body });
    }
    if model.has_mimic {
        super::mimic::fill_jacobian(model, data, body, point, out);
    } else {
        fill_at(model, data, body, point, out);
    }
    Ok(())
}

/// The world Jacobian of tool `tool` at configuration `q` (forward position included). Only the
/// bodies between the root and the tool are visited, so on a branched robot this costs one
/// branch, not the whole tree; the world poses of the other bodies in `data` are left as they
/// were.
pub fn jacobian<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    tool: usize,
    out: &mut Jacobian<N>,
) -> Result<(), Error> {
    if model.has_mimic {
        return jacobian_mimic(model, data, q, tool, out);
    }
    check_len("q", q, model.nq)?;
    if tool >= model.ntools {
        return Err(Error::UnknownTool { tool });
    }
    // The tool's ancestors, leaf first.
    let mut len = 0;
    let mut b = model.tools[tool].body;
    while b != ROOT {
        data.chain[len] = b;
        len += 1;
        b = model.parents[b];
    }
    for c in (0..len).rev() {
        world_pose::<false, N>(model, data, q, data.chain[c]);
    }
    fill(model, data, tool, out)
}

/// [`jacobian`] for models with mimic joints (out of line: the common path stays as it was).
#[cold]
#[inline(never)]
fn jacobian_mimic<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    tool: usize,
    out: &mut Jacobian<N>,
) -> Result<(), Error> {
    check_len("q", q, model.nq)?;
    if tool >= model.ntools {
        return Err(Error::UnknownTool { tool });
    }
    let mut len = 0;
    let mut b = model.tools[tool].body;
    while b != ROOT {
        data.chain[len] = b;
        len += 1;
        b = model.parents[b];
    }
    for c in (0..len).rev() {
        world_pose::<true, N>(model, data, q, data.chain[c]);
    }
    fill_mimic(model, data, tool, out)
}

/// Tool `tool`'s Jacobian with mimic columns added to their leaders' ([`fill`]'s convention).
fn fill_mimic<const N: usize>(
    model: &Model<N>,
    data: &Data<N>,
    tool: usize,
    out: &mut Jacobian<N>,
) -> Result<(), Error> {
    let t = model.tools().get(tool).ok_or(Error::UnknownTool { tool })?;
    let p = if t.body == ROOT {
        t.placement.translation
    } else {
        data.world_pose[t.body].transform_point(t.placement.translation)
    };
    super::mimic::fill_jacobian(model, data, t.body, p, out);
    Ok(())
}

/// The world Jacobians of all tools in one sweep; `out` needs at least `tools().len()`
/// elements (tool `t` goes to `out[t]`).
pub fn jacobians<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    out: &mut [Jacobian<N>],
) -> Result<(), Error> {
    check_len("q", q, model.nq)?;
    if out.len() < model.ntools {
        return Err(Error::Dimension {
            argument: "out",
            expected: model.ntools,
            got: out.len(),
        });
    }
    super::forward_position(model, data, q)?;
    for (t, j) in out.iter_mut().enumerate().take(model.ntools) {
        if model.has_mimic {
            fill_mimic(model, data, t, j)?;
        } else {
            fill(model, data, t, j)?;
        }
    }
    Ok(())
}

/// `J̇ q̇` of tool `tool` in the Jacobian's convention: the tool's classical acceleration
/// when `q̈ = 0`, so that `ẍ = J q̈ + J̇ q̇`. Runs forward acceleration with `q̈ = 0`
/// (overwriting `data`'s velocities and accelerations).
pub fn jacobian_derivative_times_qd<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: &[f64],
    tool: usize,
) -> Result<[f64; 6], Error> {
    check_len("q", q, model.nq)?;
    check_len("qd", qd, model.nv)?;
    let zeros = [0.0; N];
    super::forward_acceleration(model, data, q, qd, &zeros[..model.nv])?;
    super::tool_acceleration(model, data, tool)
}
