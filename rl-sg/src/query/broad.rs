//! Broad phase: which shape pairs are worth a narrow-phase call.

use std::ops::ControlFlow;

use glam::DVec3;
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};

use crate::scene::{Model, Shape, ShapeId};

/// A lower bound of the signed distance between anything in `a` and anything in `b`: the gap
/// between the boxes, or −∞ when they overlap (then the shapes may penetrate by any depth).
#[inline]
pub(crate) fn aabb_lower_bound(a: &Aabb, b: &Aabb) -> f64 {
    let gap = (a.mins - b.maxs).max(b.mins - a.maxs).max(DVec3::ZERO);
    if gap == DVec3::ZERO {
        f64::NEG_INFINITY
    } else {
        gap.length()
    }
}

/// A shape of a model with its id.
pub(crate) type Item<'a> = (ShapeId, &'a Shape);

/// A model with its index in the scene.
pub(crate) type Indexed<'a> = (usize, &'a Model);

/// The two models with the one with fewer shapes first (it is iterated, the other's tree is
/// searched), and whether they were swapped.
pub(crate) fn smaller_first<'a>(
    a: Indexed<'a>,
    b: Indexed<'a>,
) -> (bool, Indexed<'a>, Indexed<'a>) {
    if a.1.shape_count() > b.1.shape_count() {
        (true, b, a)
    } else {
        (false, a, b)
    }
}

/// The shapes of model `m` (index `im`) whose bodies are checked against other models.
pub(crate) fn checked_shapes(im: usize, m: &Model) -> impl Iterator<Item = Item<'_>> {
    m.bodies()
        .iter()
        .enumerate()
        .filter(|(_, b)| b.collision_enabled())
        .flat_map(move |(bi, b)| {
            b.shapes().iter().enumerate().map(move |(si, s)| {
                let id = ShapeId {
                    model: im,
                    body: bi,
                    shape: si,
                };
                (id, s)
            })
        })
}

/// Calls `f` for every shape pair of models `a` and `b` (indices `ia`, `ib`) whose boxes
/// overlap, bodies with collision off skipped; the pair comes as `(shape of a, shape of b)`.
/// The model with fewer shapes is iterated, the other's tree queried.
pub(crate) fn between_models<'s>(
    a: Indexed<'s>,
    b: Indexed<'s>,
    mut f: impl FnMut(Item<'s>, Item<'s>) -> ControlFlow<()>,
) -> ControlFlow<()> {
    let (swap, (is, small), (ig, big)) = smaller_first(a, b);
    let tree = big.bvh();
    for (bi, body) in small.bodies().iter().enumerate() {
        if !body.collision_enabled() {
            continue;
        }
        let Some(body_box) = body.aabb else { continue };
        // Cull the whole body first: one tree query per body, then per shape.
        if tree.tree.intersect_aabb(&body_box).next().is_none() {
            continue;
        }
        for (si, s) in body.shapes().iter().enumerate() {
            let sid = ShapeId {
                model: is,
                body: bi,
                shape: si,
            };
            for leaf in tree.tree.intersect_aabb(&s.aabb) {
                let (ob, os) = tree.leaves[leaf as usize];
                let other_body = &big.bodies()[ob as usize];
                if !other_body.collision_enabled() {
                    continue;
                }
                let o = &other_body.shapes()[os as usize];
                let oid = ShapeId {
                    model: ig,
                    body: ob as usize,
                    shape: os as usize,
                };
                let flow = if swap {
                    f((oid, o), (sid, s))
                } else {
                    f((sid, s), (oid, o))
                };
                flow?;
            }
        }
    }
    ControlFlow::Continue(())
}

/// Calls `f` for every shape pair of two bodies of model `m` (index `im`) that are checked for
/// self-collision and whose boxes overlap.
pub(crate) fn within_model<'s>(
    im: usize,
    m: &'s Model,
    mut f: impl FnMut(Item<'s>, Item<'s>) -> ControlFlow<()>,
) -> ControlFlow<()> {
    let bodies = m.bodies();
    for &(i, j) in m.self_collision_pairs() {
        let (i, j) = (i as usize, j as usize);
        let (bi, bj) = (&bodies[i], &bodies[j]);
        match (bi.aabb, bj.aabb) {
            (Some(x), Some(y)) if x.intersects(&y) => {}
            _ => continue,
        }
        for (si, s) in bi.shapes().iter().enumerate() {
            for (sj, t) in bj.shapes().iter().enumerate() {
                if !s.aabb.intersects(&t.aabb) {
                    continue;
                }
                let a = ShapeId {
                    model: im,
                    body: i,
                    shape: si,
                };
                let b = ShapeId {
                    model: im,
                    body: j,
                    shape: sj,
                };
                f((a, s), (b, t))?;
            }
        }
    }
    ControlFlow::Continue(())
}
