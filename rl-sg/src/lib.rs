//! rl-sg: the scene graph of rl-rs (RL's `rl::sg`) — robots and their surroundings as geometry,
//! with collision, distance, penetration depth and ray queries, linked to the kinematics.
//!
//! Features: `std` (default) builds everything below; without it only [`capsule`] is built,
//! `#![no_std]`, without an allocator (the control-rate distance path).
//!
//! # The model
//!
//! RL's shape of the data: a [`Scene`] holds [`Model`]s (a robot, the environment), a model
//! holds [`Body`]s, a body holds [`Shape`]s at fixed poses in the body's frame. Bodies live in
//! the world frame, not in a tree, so kinematics, a physics engine or a sensor can place them;
//! [`Scene::update`] places every body of a robot from rl-core's forward kinematics in one call,
//! without allocating. Shapes ([`Geometry`]): box, sphere, cylinder, capsule, cone, convex hull,
//! triangle mesh, half-space. Collision, distance, depth and ray queries run through
//! [parry3d](https://parry.rs) (f64), behind a bounding-volume-tree broad phase.
//!
//! # Loading
//!
//! - URDF `<collision>` or `<visual>` geometry with STL, OBJ and COLLADA meshes
//!   ([`load::urdf`]), `package://` and relative paths; SRDF `<disable_collisions>`
//!   ([`load::srdf`]); RL's `rlsg` XML with VRML97 geometry ([`load::rlsg`], [`load::vrml`]);
//!   MoveIt planning-scene YAML ([`load::moveit`]).
//! - Bad input gives an [`SgError`] naming the file, the element and the reason.
//!
//! # Example
//!
//! ```
//! use glam::DVec3;
//! use rl_core::spatial::PlueckerTransform;
//! use rl_sg::{Geometry, Model, Scene};
//!
//! let mut scene = Scene::new();
//! let mut a = Model::new("a");
//! a.add_body("box").add_shape("b", Geometry::cuboid(DVec3::splat(1.0))?, PlueckerTransform::IDENTITY)?;
//! let mut b = Model::new("b");
//! b.add_body("ball").add_shape("s", Geometry::sphere(0.5)?, PlueckerTransform::IDENTITY)?;
//! let (ia, ib) = (scene.add_model(a)?, scene.add_model(b)?);
//! let ball = scene.body_id(ib, "ball").unwrap();
//! scene.set_body_pose(ball, &PlueckerTransform::from_translation(DVec3::new(2.0, 0.0, 0.0)))?;
//! let d = scene.model_distance(ia, ib).unwrap();
//! assert!((d.distance - 1.0).abs() < 1e-12);
//! assert!(scene.collisions(&rl_sg::CollisionFilter::All).is_empty());
//! # Ok::<(), rl_sg::SgError>(())
//! ```
#![cfg_attr(not(feature = "std"), no_std)]
#![deny(missing_docs)]

pub mod capsule;

#[cfg(feature = "std")]
mod acm;
#[cfg(feature = "std")]
mod error;
#[cfg(feature = "std")]
pub mod fit;
#[cfg(feature = "std")]
mod geometry;
#[cfg(feature = "std")]
pub mod load;
#[cfg(feature = "std")]
mod pose;
#[cfg(feature = "std")]
mod query;
#[cfg(feature = "std")]
pub mod report;
#[cfg(feature = "std")]
mod scene;

#[cfg(feature = "std")]
pub use acm::AllowedCollisions;
#[cfg(feature = "std")]
pub use error::{SgError, SgErrorKind};
#[cfg(feature = "std")]
pub use geometry::{Geometry, MeshStats, TriangleMesh};
#[cfg(feature = "std")]
pub use query::{CollisionFilter, CollisionPair, Distance, RayHit};
#[cfg(feature = "std")]
pub use scene::{Body, BodyId, KinematicLink, Model, ModelId, Scene, Shape, ShapeId, UpdateError};
