//! The obstacles of the fast checker, exact primitives in `f32`: spheres, boxes (oriented),
//! cylinders, capsules and half-spaces, taken from rl-sg scene models.
//!
//! Each robot sphere is tested against every obstacle with the exact sphere–primitive test
//! (touching counts as collision): box by clamping to the box in its frame, cylinder by its
//! radial and axial gaps, capsule by the closest point of its segment. A cone is replaced by
//! the cylinder around it (conservative). Meshes and convex hulls are not supported here (an
//! error says so; the exact [`crate::scene::SceneValidity`] handles them).
//!
//! Obstacles are sorted by their distance from a reference point (the robot's base); a robot
//! sphere whose farthest reach from that point is below an obstacle's distance in every lane
//! skips it and all farther ones (VAMP's cull).

use glam::{DMat3, DVec3};
use rl_sg::{Geometry, Scene};

use crate::error::PlanError;

/// One obstacle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Shape {
    /// Centre and radius.
    Sphere { c: [f32; 3], r: f32 },
    /// Centre, axes (rows: the box's x, y, z axes in the world) and half extents.
    Cuboid {
        c: [f32; 3],
        axes: [[f32; 3]; 3],
        half: [f32; 3],
    },
    /// Centre, unit axis, half length, radius.
    Cylinder {
        c: [f32; 3],
        u: [f32; 3],
        h: f32,
        r: f32,
    },
    /// Segment start, unit direction, length, radius.
    Capsule {
        a: [f32; 3],
        u: [f32; 3],
        len: f32,
        r: f32,
    },
    /// Points with `n · p ≤ d` (unit outward normal `n`).
    HalfSpace { n: [f32; 3], d: f32 },
}

/// An obstacle with its distance from the reference point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Obstacle {
    pub(crate) shape: Shape,
    /// A lower bound of the distance from the reference point to the obstacle.
    pub(crate) min_distance: f32,
}

/// The obstacles, sorted by distance from `origin`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Environment {
    pub(crate) origin: [f32; 3],
    pub(crate) obstacles: Vec<Obstacle>,
}

fn f3(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

impl Environment {
    /// An empty environment measured from `origin` (the robot's base).
    pub fn new(origin: DVec3) -> Self {
        Self {
            origin: f3(origin),
            obstacles: Vec::new(),
        }
    }

    /// The number of obstacles.
    pub fn len(&self) -> usize {
        self.obstacles.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.obstacles.is_empty()
    }

    /// Adds every shape of every body of the models of `scene` except `skip` (the robot), in
    /// their current world poses. Bodies with collision switched off are left out.
    pub fn add_scene(
        &mut self,
        scene: &Scene,
        skip: Option<rl_sg::ModelId>,
    ) -> Result<(), PlanError> {
        for (mi, m) in scene.models().iter().enumerate() {
            if Some(rl_sg::ModelId(mi)) == skip {
                continue;
            }
            for b in m.bodies() {
                if !b.collision_enabled() {
                    continue;
                }
                for s in b.shapes() {
                    let x = s.world_pose();
                    self.add(s.geometry(), x.rotation, x.translation)
                        .map_err(|e| match e {
                            PlanError::Unsupported(w) => PlanError::Unsupported(format!(
                                "{w} (shape \"{}\" of {}/{})",
                                s.name(),
                                m.name(),
                                b.name()
                            )),
                            e => e,
                        })?;
                }
            }
        }
        Ok(())
    }

    /// Adds one shape of `geometry` with rotation `r` and centre `t` in the world.
    pub fn add(&mut self, geometry: &Geometry, r: DMat3, t: DVec3) -> Result<(), PlanError> {
        let o = DVec3::new(
            self.origin[0] as f64,
            self.origin[1] as f64,
            self.origin[2] as f64,
        );
        let (shape, min_distance) = match geometry {
            Geometry::Sphere { radius } => (
                Shape::Sphere {
                    c: f3(t),
                    r: *radius as f32,
                },
                (t - o).length() - radius,
            ),
            Geometry::Box { size } => {
                let half = *size * 0.5;
                // Distance from the origin to the box, in the box's frame.
                let l = r.transpose() * (o - t);
                let gap = (l.abs() - half).max(DVec3::ZERO);
                (
                    Shape::Cuboid {
                        c: f3(t),
                        axes: [f3(r.x_axis), f3(r.y_axis), f3(r.z_axis)],
                        half: f3(half),
                    },
                    gap.length(),
                )
            }
            Geometry::Cylinder { radius, length } | Geometry::Cone { radius, length } => (
                Shape::Cylinder {
                    c: f3(t),
                    u: f3(r.z_axis),
                    h: (*length * 0.5) as f32,
                    r: *radius as f32,
                },
                (t - o).length() - (radius * radius + length * length * 0.25).sqrt(),
            ),
            Geometry::Capsule { radius, length } => {
                let a = t - r.z_axis * (*length * 0.5);
                (
                    Shape::Capsule {
                        a: f3(a),
                        u: f3(r.z_axis),
                        len: *length as f32,
                        r: *radius as f32,
                    },
                    (t - o).length() - length * 0.5 - radius,
                )
            }
            Geometry::HalfSpace { normal, offset } => {
                // In the world: n_w · p ≤ offset + n_w · t.
                let n = r * *normal;
                let d = offset + n.dot(t);
                (
                    Shape::HalfSpace {
                        n: f3(n),
                        d: d as f32,
                    },
                    (n.dot(o) - d).max(0.0),
                )
            }
            other => {
                return Err(PlanError::Unsupported(format!(
                    "{} obstacles in the sphere checker (boxes, spheres, cylinders, cones, \
                     capsules and half-spaces are)",
                    other.kind()
                )));
            }
        };
        // Rounding to f32 and the bound itself: keep the cull conservative.
        let min_distance = (min_distance.max(0.0) as f32) * (1.0 - 1e-5) - 1e-5;
        let at = self
            .obstacles
            .partition_point(|x| x.min_distance <= min_distance);
        self.obstacles.insert(
            at,
            Obstacle {
                shape,
                min_distance: min_distance.max(0.0),
            },
        );
        Ok(())
    }
}
