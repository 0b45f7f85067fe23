//! rl-core: spatial algebra, models, kinematics, dynamics and trajectories for robots.
//!
//! `#![no_std]`, no allocator, no panics on the hot path. Model loading (URDF, RL's XML model
//! format) is behind the `std` feature.
#![no_std]
#![forbid(unsafe_code)]
// Index loops over DOFs and matrix entries read as the equations do.
#![allow(clippy::needless_range_loop)]

#[cfg(feature = "std")]
extern crate std;

pub mod rotation;
pub mod traj;

pub mod algo;
mod error;
pub mod joint;
#[cfg(feature = "std")]
pub mod loader;
pub mod math;
pub mod model;
pub mod spatial;
pub mod task;

pub use error::Error;
pub use model::{Data, Model, ModelBuilder};
