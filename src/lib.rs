//! rl-rs: one consistent API from spatial mathematics to real-time control of robot hardware.
//!
//! This facade re-exports the three crates of the workspace:
//! - [`core`] (`rl-core`): spatial algebra, models, kinematics, dynamics, trajectories;
//! - [`rt`] (`rl-rt`): Linux real-time threads and absolute-deadline loops;
//! - [`drivers`] (`rl-drivers`): cyclic devices, protocol codecs and fake robots.

pub mod controller;
pub use rl_core as core;
pub use rl_drivers as drivers;
pub use rl_rt as rt;

/// The README's examples, compiled and run as doc tests so they cannot rot.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
