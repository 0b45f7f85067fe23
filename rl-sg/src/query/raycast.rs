//! Raycasts: the first shape along a ray (a laser scanner's beam, a line-of-sight check).

use std::cell::Cell;

use glam::DVec3;
use parry3d_f64::query::Ray;

use super::RayHit;
use crate::error::SgError;
use crate::scene::{ModelId, Scene, ShapeId};

impl Scene {
    /// The first shape hit by the ray from `origin` along `direction` (normalised here) within
    /// `max_distance` m, over every model. A ray starting inside a solid shape hits it at
    /// distance 0; triangle meshes are surfaces and are hit where the ray crosses them.
    pub fn raycast(
        &self,
        origin: DVec3,
        direction: DVec3,
        max_distance: f64,
    ) -> Result<Option<RayHit>, SgError> {
        self.raycast_models(origin, direction, max_distance, None)
    }

    /// [`Scene::raycast`] over one model.
    pub fn raycast_model(
        &self,
        model: ModelId,
        origin: DVec3,
        direction: DVec3,
        max_distance: f64,
    ) -> Result<Option<RayHit>, SgError> {
        self.raycast_models(origin, direction, max_distance, Some(model))
    }

    fn raycast_models(
        &self,
        origin: DVec3,
        direction: DVec3,
        max_distance: f64,
        only: Option<ModelId>,
    ) -> Result<Option<RayHit>, SgError> {
        if !origin.is_finite() {
            return Err(SgError::invalid(
                "ray origin",
                format!("{origin:?}"),
                "not finite",
            ));
        }
        let len = direction.length();
        if !(len.is_finite() && len > 0.0) {
            return Err(SgError::invalid(
                "ray direction",
                format!("{direction:?}"),
                "zero or not finite",
            ));
        }
        if max_distance.is_nan() || max_distance < 0.0 {
            return Err(SgError::invalid(
                "ray length",
                max_distance,
                "negative or NaN",
            ));
        }
        let ray = Ray::new(origin, direction / len);
        let mut best: Option<RayHit> = None;
        for (im, m) in self.models.iter().enumerate() {
            if only.is_some_and(|o| o.0 != im) || m.shape_count() == 0 {
                continue;
            }
            let limit = best.map_or(max_distance, |b| b.distance);
            let tree = m.bvh();
            // The tree keeps a leaf only when it beats the best so far, so the last normal
            // recorded is the winner's.
            let normal = Cell::new(DVec3::ZERO);
            let hit = tree.tree.cast_ray(&ray, limit, |leaf, best_toi| {
                let (b, s) = tree.leaves[leaf as usize];
                let s = &m.bodies()[b as usize].shapes()[s as usize];
                let i = s
                    .parry
                    .cast_ray_and_get_normal(&s.world, &ray, best_toi, true)?;
                if i.time_of_impact < best_toi {
                    normal.set(i.normal);
                }
                Some(i.time_of_impact)
            });
            if let Some((leaf, toi)) = hit {
                if best.is_none_or(|b| toi < b.distance) {
                    let (b, s) = tree.leaves[leaf as usize];
                    best = Some(RayHit {
                        shape: ShapeId {
                            model: im,
                            body: b as usize,
                            shape: s as usize,
                        },
                        distance: toi,
                        point: ray.point_at(toi),
                        normal: normal.get(),
                    });
                }
            }
        }
        Ok(best)
    }
}
