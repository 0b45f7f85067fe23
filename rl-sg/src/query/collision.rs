//! Collision queries: is anything colliding, and which shape pairs.

use std::ops::ControlFlow;

use super::broad::{self, Item};
use super::{CollisionFilter, CollisionPair, shapes_intersect};
use crate::scene::{Scene, ShapeId};

impl Scene {
    /// Calls `f` for every candidate shape pair of `filter` (boxes overlap, pair checked).
    pub(crate) fn for_each_candidate<'s>(
        &'s self,
        filter: &CollisionFilter,
        mut f: impl FnMut(Item<'s>, Item<'s>) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        let models = &self.models;
        let get = |i: usize| models.get(i).map(|m| (i, m));
        match *filter {
            CollisionFilter::All => {
                for (i, m) in models.iter().enumerate() {
                    if m.self_collision() {
                        broad::within_model(i, m, &mut f)?;
                    }
                }
                for i in 0..models.len() {
                    for j in i + 1..models.len() {
                        broad::between_models((i, &models[i]), (j, &models[j]), &mut f)?;
                    }
                }
            }
            CollisionFilter::SelfCollision(m) => {
                if let Some((i, m)) = get(m.0) {
                    broad::within_model(i, m, &mut f)?;
                }
            }
            CollisionFilter::Between(a, b) if a == b => {
                if let Some((i, m)) = get(a.0) {
                    broad::within_model(i, m, &mut f)?;
                }
            }
            CollisionFilter::Between(a, b) => {
                if let (Some(x), Some(y)) = (get(a.0), get(b.0)) {
                    broad::between_models(x, y, &mut f)?;
                }
            }
            CollisionFilter::Against(a) => {
                if let Some(x) = get(a.0) {
                    for j in (0..models.len()).filter(|&j| j != a.0) {
                        broad::between_models(x, (j, &models[j]), &mut f)?;
                    }
                }
            }
        }
        ControlFlow::Continue(())
    }

    /// Every shape pair `filter` selects, before any bounding-box culling (for exporting a
    /// problem to another collision library, or counting the work a broad phase saves): self
    /// pairs of the bodies checked, then pairs of different models, bodies with collision off
    /// skipped.
    pub fn pairs_checked(&self, filter: &CollisionFilter) -> Vec<(ShapeId, ShapeId)> {
        let mut out = Vec::new();
        let shapes = |m: usize, b: usize| -> Vec<ShapeId> {
            let n = self.models[m].bodies()[b].shapes().len();
            (0..n)
                .map(|shape| ShapeId {
                    model: m,
                    body: b,
                    shape,
                })
                .collect()
        };
        let within = |m: usize, out: &mut Vec<(ShapeId, ShapeId)>| {
            if let Some(model) = self.models.get(m) {
                for &(i, j) in model.self_collision_pairs() {
                    for a in shapes(m, i as usize) {
                        for b in shapes(m, j as usize) {
                            out.push((a, b));
                        }
                    }
                }
            }
        };
        let between = |ma: usize, mb: usize, out: &mut Vec<(ShapeId, ShapeId)>| {
            let (Some(x), Some(y)) = (self.models.get(ma), self.models.get(mb)) else {
                return;
            };
            for (i, _) in x
                .bodies()
                .iter()
                .enumerate()
                .filter(|(_, b)| b.collision_enabled())
            {
                for (j, _) in y
                    .bodies()
                    .iter()
                    .enumerate()
                    .filter(|(_, b)| b.collision_enabled())
                {
                    for a in shapes(ma, i) {
                        for b in shapes(mb, j) {
                            out.push((a, b));
                        }
                    }
                }
            }
        };
        let n = self.models.len();
        match *filter {
            CollisionFilter::All => {
                for m in 0..n {
                    if self.models[m].self_collision() {
                        within(m, &mut out);
                    }
                }
                for a in 0..n {
                    for b in a + 1..n {
                        between(a, b, &mut out);
                    }
                }
            }
            CollisionFilter::SelfCollision(m) => within(m.0, &mut out),
            CollisionFilter::Between(a, b) if a == b => within(a.0, &mut out),
            CollisionFilter::Between(a, b) => between(a.0, b.0, &mut out),
            CollisionFilter::Against(a) => {
                for b in (0..n).filter(|&b| b != a.0) {
                    between(a.0, b, &mut out);
                }
            }
        }
        out
    }

    /// The shape pairs of `filter` that survive the broad phase (boxes overlap): the pairs a
    /// collision query hands to the narrow phase.
    pub fn broad_phase_pairs(&self, filter: &CollisionFilter) -> Vec<(ShapeId, ShapeId)> {
        let mut out = Vec::new();
        let _ = self.for_each_candidate(filter, |(a, _), (b, _)| {
            out.push((a, b));
            ControlFlow::Continue(())
        });
        out
    }

    /// Whether two shapes are in contact (`None` if an id is unknown).
    pub fn shapes_collide(&self, a: ShapeId, b: ShapeId) -> Option<bool> {
        Some(shapes_intersect(self.shape(a)?, self.shape(b)?))
    }

    /// Every pair of shapes in contact among the pairs `filter` selects, in a deterministic
    /// order (by model, body, shape of the first, then of the second).
    pub fn collisions(&self, filter: &CollisionFilter) -> Vec<CollisionPair> {
        let mut out = Vec::new();
        let _ = self.for_each_candidate(filter, |(a, sa), (b, sb)| {
            if shapes_intersect(sa, sb) {
                out.push(CollisionPair { a, b });
            }
            ControlFlow::Continue(())
        });
        out.sort_unstable();
        out
    }

    /// Whether any pair `filter` selects is in contact; stops at the first.
    pub fn is_colliding(&self, filter: &CollisionFilter) -> bool {
        self.for_each_candidate(filter, |(_, sa), (_, sb)| {
            if shapes_intersect(sa, sb) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .is_break()
    }

    /// The body pairs in contact (each once, as `(model/body, model/body)` ids), from
    /// [`Scene::collisions`].
    pub fn colliding_bodies(
        &self,
        filter: &CollisionFilter,
    ) -> Vec<(crate::BodyId, crate::BodyId)> {
        let mut v: Vec<_> = self
            .collisions(filter)
            .into_iter()
            .map(|p| (p.a.body_id(), p.b.body_id()))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }
}
