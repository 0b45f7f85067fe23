//! Distance queries: the closest (or deepest) pair with its witness points.
//!
//! Branch and bound: a pair is measured only when the lower bound of its boxes
//! ([`super::broad::aabb_lower_bound`]) is below the best distance found so far; between
//! models, each shape of the smaller model searches the other's tree best-first.

use super::broad::{self, aabb_lower_bound};
use super::{CollisionFilter, Distance, shapes_distance};
use crate::scene::{BodyId, Model, ModelId, Scene, Shape, ShapeId};

/// Keeps the smaller of two optional distances.
fn keep(best: &mut Option<Distance>, d: Option<Distance>) {
    if let Some(d) = d {
        if best.is_none_or(|b| d.distance < b.distance) {
            *best = Some(d);
        }
    }
}

fn bound(best: &Option<Distance>) -> f64 {
    best.map_or(f64::INFINITY, |d| d.distance)
}

impl Scene {
    /// Signed distance between two shapes, with witness points; `None` if an id is unknown or
    /// parry cannot measure the pair (two half-spaces).
    pub fn shape_distance(&self, a: ShapeId, b: ShapeId) -> Option<Distance> {
        shapes_distance(self.shape(a)?, a, self.shape(b)?, b)
    }

    /// The closest pair of shapes of two bodies.
    pub fn body_distance(&self, a: BodyId, b: BodyId) -> Option<Distance> {
        let mut best = None;
        self.body_pair_distance(a, b, &mut best);
        best
    }

    fn body_pair_distance(&self, a: BodyId, b: BodyId, best: &mut Option<Distance>) {
        let (Some(ba), Some(bb)) = (self.body(a), self.body(b)) else {
            return;
        };
        if let (Some(x), Some(y)) = (ba.aabb, bb.aabb) {
            if aabb_lower_bound(&x, &y) >= bound(best) {
                return;
            }
        }
        for (i, s) in ba.shapes().iter().enumerate() {
            for (j, t) in bb.shapes().iter().enumerate() {
                if aabb_lower_bound(&s.aabb, &t.aabb) >= bound(best) {
                    continue;
                }
                let ia = ShapeId {
                    model: a.model,
                    body: a.body,
                    shape: i,
                };
                let ib = ShapeId {
                    model: b.model,
                    body: b.body,
                    shape: j,
                };
                keep(best, shapes_distance(s, ia, t, ib));
            }
        }
    }

    /// The closest pair between two models (bodies with collision off skipped); the same model
    /// twice means its self-distance.
    pub fn model_distance(&self, a: ModelId, b: ModelId) -> Option<Distance> {
        self.min_distance(&CollisionFilter::Between(a, b))
    }

    /// The closest pair of a model's self-collision pairs (its allowed set excepted).
    pub fn self_distance(&self, m: ModelId) -> Option<Distance> {
        self.min_distance(&CollisionFilter::SelfCollision(m))
    }

    /// The closest pair among the pairs `filter` selects (the pairs a collision query with the
    /// same filter tests): negative when some pair penetrates, the deepest then.
    pub fn min_distance(&self, filter: &CollisionFilter) -> Option<Distance> {
        let mut best = None;
        let n = self.models.len();
        match *filter {
            CollisionFilter::All => {
                for i in 0..n {
                    if self.models[i].self_collision() {
                        self.within(i, &mut best);
                    }
                }
                for i in 0..n {
                    for j in i + 1..n {
                        self.between(i, j, &mut best);
                    }
                }
            }
            CollisionFilter::SelfCollision(m) => self.within(m.0, &mut best),
            CollisionFilter::Between(a, b) if a == b => self.within(a.0, &mut best),
            CollisionFilter::Between(a, b) => self.between(a.0, b.0, &mut best),
            CollisionFilter::Against(a) => {
                for j in (0..n).filter(|&j| j != a.0) {
                    self.between(a.0, j, &mut best);
                }
            }
        }
        best
    }

    fn within(&self, im: usize, best: &mut Option<Distance>) {
        let Some(m) = self.models.get(im) else { return };
        for &(i, j) in m.self_collision_pairs() {
            let a = BodyId {
                model: im,
                body: i as usize,
            };
            let b = BodyId {
                model: im,
                body: j as usize,
            };
            self.body_pair_distance(a, b, best);
        }
    }

    fn between(&self, ia: usize, ib: usize, best: &mut Option<Distance>) {
        let (Some(a), Some(b)) = (self.models.get(ia), self.models.get(ib)) else {
            return;
        };
        if ia == ib {
            return self.within(ia, best);
        }
        // Iterate the smaller model; search the other's tree.
        let (swap, (is, small), (ig, big)) = broad::smaller_first((ia, a), (ib, b));
        for (sid, s) in broad::checked_shapes(is, small) {
            if let Some(d) = nearest_in(big, ig, s, sid, bound(best)) {
                keep(best, Some(if swap { d.swapped() } else { d }));
            }
        }
    }
}

/// The shape of model `m` (index `im`) nearest to `s`, if nearer than `limit`.
fn nearest_in(m: &Model, im: usize, s: &Shape, sid: ShapeId, limit: f64) -> Option<Distance> {
    let tree = m.bvh();
    tree.tree
        .find_best(
            limit,
            |node, _| aabb_lower_bound(&node.aabb(), &s.aabb),
            |leaf, _| {
                let (ob, os) = tree.leaves[leaf as usize];
                let body = &m.bodies()[ob as usize];
                if !body.collision_enabled() {
                    return None;
                }
                let oid = ShapeId {
                    model: im,
                    body: ob as usize,
                    shape: os as usize,
                };
                shapes_distance(s, sid, &body.shapes()[os as usize], oid).map(|d| (d.distance, d))
            },
        )
        .map(|(_, (_, d))| d)
}
