//! Models, bodies and shapes: RL's `rl::sg::Model`, `Body`, `Shape`.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::OnceLock;

use glam::DVec3;
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::math::Pose;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry3d_f64::shape::SharedShape;
use rl_core::spatial::PlueckerTransform;

use super::KinematicLink;
use crate::acm::AllowedCollisions;
use crate::error::SgError;
use crate::geometry::Geometry;
use crate::pose;

/// A shape: geometry at a fixed pose in its body's frame.
#[derive(Clone)]
pub struct Shape {
    name: String,
    geometry: Geometry,
    source: Option<(PathBuf, DVec3)>,
    local: PlueckerTransform,
    pub(crate) parry: SharedShape,
    /// parry's shape in the body frame (`local` · the geometry's parry offset).
    local_parry: Pose,
    /// parry's shape in the world.
    pub(crate) world: Pose,
    /// World bounding box.
    pub(crate) aabb: Aabb,
}

impl std::fmt::Debug for Shape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Shape")
            .field("name", &self.name)
            .field("geometry", &self.geometry.kind())
            .field("source", &self.source)
            .field("local", &self.local)
            .finish()
    }
}

impl Shape {
    /// A shape of `geometry` at `local` in its body's frame (checked: finite, a rotation).
    pub fn new(
        name: impl Into<String>,
        geometry: Geometry,
        local: PlueckerTransform,
    ) -> Result<Self, SgError> {
        let name = name.into();
        pose::check("shape pose", &local).map_err(|e| e.at(format!("shape \"{name}\"")))?;
        let parry = geometry
            .to_parry()
            .map_err(|e| e.at(format!("shape \"{name}\"")))?;
        let local_parry = pose::to_parry(&local) * geometry.parry_offset();
        let aabb = parry.compute_aabb(&local_parry);
        Ok(Self {
            name,
            geometry,
            source: None,
            local,
            parry,
            local_parry,
            world: local_parry,
            aabb,
        })
    }

    /// The same shape, noting the file its geometry came from and the scale applied to it.
    pub fn with_source(mut self, source: impl Into<PathBuf>, scale: DVec3) -> Self {
        self.source = Some((source.into(), scale));
        self
    }

    /// Its name (may be empty: URDF collision elements often have none).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Its geometry.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// The mesh file it was loaded from, if any.
    pub fn source(&self) -> Option<&std::path::Path> {
        self.source.as_ref().map(|s| s.0.as_path())
    }

    /// The scale applied to the mesh file's vertices (1 when none, or not from a file).
    pub fn source_scale(&self) -> DVec3 {
        self.source.as_ref().map_or(DVec3::ONE, |s| s.1)
    }

    /// Its pose in the body's frame.
    pub fn local_pose(&self) -> &PlueckerTransform {
        &self.local
    }

    /// Its pose in the world (as of the body's last pose).
    pub fn world_pose(&self) -> PlueckerTransform {
        pose::from_parry(&(self.world * self.geometry.parry_offset().inverse()))
    }

    /// Its world-frame bounding box, `(min, max)`.
    pub fn world_aabb(&self) -> (DVec3, DVec3) {
        (self.aabb.mins, self.aabb.maxs)
    }

    #[inline]
    pub(crate) fn place(&mut self, body: &Pose) {
        self.world = *body * self.local_parry;
        self.aabb = self.parry.compute_aabb(&self.world);
    }
}

/// A rigid body: shapes at fixed poses in its frame, the frame placed in the world.
#[derive(Clone, Debug)]
pub struct Body {
    name: String,
    pose: PlueckerTransform,
    shapes: Vec<Shape>,
    /// Whether the body is checked against other models (RL's `<ignore/>` turns it off).
    pub(crate) collision: bool,
    pub(crate) aabb: Option<Aabb>,
}

impl Body {
    /// An empty body at the world origin.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            pose: PlueckerTransform::IDENTITY,
            shapes: Vec::new(),
            collision: true,
            aabb: None,
        }
    }

    /// Adds a shape of `geometry` at `local` in the body's frame; a pose that is not a rigid
    /// transform is refused.
    pub fn add_shape(
        &mut self,
        name: impl Into<String>,
        geometry: Geometry,
        local: PlueckerTransform,
    ) -> Result<&mut Self, SgError> {
        let s = Shape::new(name, geometry, local)?;
        self.push_shape(s);
        Ok(self)
    }

    /// Adds a shape built elsewhere.
    pub fn push_shape(&mut self, mut shape: Shape) {
        shape.place(&pose::to_parry(&self.pose));
        self.aabb = Some(match self.aabb {
            Some(a) => a.merged(&shape.aabb),
            None => shape.aabb,
        });
        self.shapes.push(shape);
    }

    /// Its name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Its shapes.
    pub fn shapes(&self) -> &[Shape] {
        &self.shapes
    }

    /// Its pose in the world.
    pub fn pose(&self) -> &PlueckerTransform {
        &self.pose
    }

    /// Whether it is checked against other models.
    pub fn collision_enabled(&self) -> bool {
        self.collision
    }

    /// Checks it against other models, or not (RL's `<ignore/>`: a robot's base on the floor).
    pub fn set_collision_enabled(&mut self, on: bool) {
        self.collision = on;
    }

    /// World bounding box of all its shapes, `(min, max)`; `None` without shapes.
    pub fn world_aabb(&self) -> Option<(DVec3, DVec3)> {
        self.aabb.map(|a| (a.mins, a.maxs))
    }

    /// Places the body (pose checked by the caller). Does not allocate.
    #[inline]
    pub(crate) fn place(&mut self, x: &PlueckerTransform) {
        self.pose = *x;
        let p = pose::to_parry(x);
        let mut aabb: Option<Aabb> = None;
        for s in &mut self.shapes {
            s.place(&p);
            aabb = Some(match aabb {
                Some(a) => a.merged(&s.aabb),
                None => s.aabb,
            });
        }
        self.aabb = aabb;
    }
}

/// A model: a robot or an environment, a list of bodies.
#[derive(Clone, Debug)]
pub struct Model {
    name: String,
    pub(crate) bodies: Vec<Body>,
    /// The first body of each name (a hash map: a scene of 100 000 objects looked every name
    /// up in a list, 50 s).
    body_names: HashMap<String, usize>,
    pub(crate) allowed: AllowedCollisions,
    pub(crate) self_collision: bool,
    pub(crate) kinematics: Option<KinematicLink>,
    /// Notes from loading (dropped degenerate triangles, ignored elements).
    pub(crate) warnings: Vec<String>,
    /// Broad phase over the model's shapes, built on first use after the model last moved.
    pub(crate) bvh: OnceLock<ModelBvh>,
    /// The body pairs checked for self-collision (not allowed, both with shapes), built on first
    /// use after the bodies or the allowed set last changed.
    pub(crate) self_pairs: OnceLock<Vec<(u32, u32)>>,
}

/// A bounding-volume tree over a model's shapes.
#[derive(Clone, Debug)]
pub(crate) struct ModelBvh {
    pub(crate) tree: Bvh,
    /// Leaf `k` is shape `leaves[k].1` of body `leaves[k].0`.
    pub(crate) leaves: Vec<(u32, u32)>,
}

impl Model {
    /// An empty model without self-collision checks (an environment); robots loaded from
    /// files have them on.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            bodies: Vec::new(),
            body_names: HashMap::new(),
            allowed: AllowedCollisions::default(),
            self_collision: false,
            kinematics: None,
            warnings: Vec::new(),
            bvh: OnceLock::new(),
            self_pairs: OnceLock::new(),
        }
    }

    /// Adds a body and returns it for adding shapes.
    pub fn add_body(&mut self, name: impl Into<String>) -> &mut Body {
        let body = Body::new(name);
        self.body_names
            .entry(body.name.clone())
            .or_insert(self.bodies.len());
        self.bodies.push(body);
        self.invalidate();
        self.self_pairs.take();
        self.bodies.last_mut().expect("just pushed")
    }

    /// Its name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Renames it.
    pub fn set_name(&mut self, name: impl Into<String>) {
        self.name = name.into();
    }

    /// Its bodies.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// Body `i`, mutable (shapes, collision flag; poses through the [`crate::Scene`]).
    pub fn body_mut(&mut self, i: usize) -> Option<&mut Body> {
        self.invalidate();
        self.self_pairs.take();
        self.bodies.get_mut(i)
    }

    /// The index of the (first) body called `name`.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.body_names.get(name).copied()
    }

    /// The pairs of its bodies not checked against each other.
    pub fn allowed_collisions(&self) -> &AllowedCollisions {
        &self.allowed
    }

    /// The allowed pairs, to change.
    pub fn allowed_collisions_mut(&mut self) -> &mut AllowedCollisions {
        self.self_pairs.take();
        &mut self.allowed
    }

    /// Whether its bodies are checked against each other (pairs in the allowed set excepted).
    pub fn self_collision(&self) -> bool {
        self.self_collision
    }

    /// Checks its bodies against each other, or not.
    pub fn set_self_collision(&mut self, on: bool) {
        self.self_collision = on;
    }

    /// How its bodies follow a kinematic model, if they do.
    pub fn kinematics(&self) -> Option<&KinematicLink> {
        self.kinematics.as_ref()
    }

    /// Sets how its bodies follow a kinematic model.
    pub fn set_kinematics(&mut self, link: KinematicLink) {
        self.kinematics = Some(link);
    }

    /// Allows every pair of bodies that ride on one kinematic body (links joined by fixed
    /// joints): they cannot move against each other, so their contact is no collision.
    pub fn allow_rigidly_joined(&mut self) {
        let Some(k) = self.kinematics.as_ref() else {
            return;
        };
        let n = self.bodies.len();
        let mut pairs = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                if let (Some((a, _)), Some((b, _))) = (k.frame(i), k.frame(j)) {
                    if a == b {
                        pairs.push((i, j));
                    }
                }
            }
        }
        for (i, j) in pairs {
            self.allowed_collisions_mut().allow(i, j);
        }
    }

    /// Notes from loading: dropped degenerate triangles, elements ignored, and so on.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Adds a note.
    pub fn warn(&mut self, note: impl Into<String>) {
        self.warnings.push(note.into());
    }

    /// The number of shapes in all bodies.
    pub fn shape_count(&self) -> usize {
        self.bodies.iter().map(|b| b.shapes.len()).sum()
    }

    /// Forgets the broad phase (the model moved): frees it if one was built, allocates nothing.
    #[inline]
    pub(crate) fn invalidate(&mut self) {
        drop(self.bvh.take());
    }

    /// The broad phase, built if needed.
    pub(crate) fn bvh(&self) -> &ModelBvh {
        self.bvh.get_or_init(|| {
            let mut leaves = Vec::with_capacity(self.shape_count());
            let mut boxes = Vec::with_capacity(self.shape_count());
            for (bi, b) in self.bodies.iter().enumerate() {
                for (si, s) in b.shapes.iter().enumerate() {
                    leaves.push((bi as u32, si as u32));
                    boxes.push(s.aabb);
                }
            }
            ModelBvh {
                tree: Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes),
                leaves,
            }
        })
    }

    /// The body pairs checked for self-collision: not in the allowed set, both with shapes.
    pub fn self_collision_pairs(&self) -> &[(u32, u32)] {
        self.self_pairs.get_or_init(|| {
            let n = self.bodies.len();
            let mut v = Vec::new();
            for i in 0..n {
                for j in i + 1..n {
                    if !self.bodies[i].shapes.is_empty()
                        && !self.bodies[j].shapes.is_empty()
                        && !self.allowed.is_allowed(i, j)
                    {
                        v.push((i as u32, j as u32));
                    }
                }
            }
            v
        })
    }
}
