//! rl-core: spatial algebra, models, kinematics, dynamics and trajectories for robots.
//!
//! `#![no_std]`, no allocator, no panics on the hot path. Model loading (URDF, RL's XML model
//! format) is behind the `std` feature.
#![no_std]
#![forbid(unsafe_code)]

#[cfg(feature = "std")]
extern crate std;

pub mod rotation;
pub mod traj;
