//! rl-rs: one consistent API from spatial mathematics to real-time control of robot hardware.
//!
//! This facade re-exports the crates of the workspace:
//! - [`core`] (`rl-core`): spatial algebra, models, kinematics, dynamics, trajectories;
//! - [`rt`] (`rl-rt`): Linux real-time threads and absolute-deadline loops;
//! - [`drivers`] (`rl-drivers`): cyclic devices, protocol codecs and fake robots;
//! - [`sg`] (`rl-sg`): the scene graph — geometry, collision, distance, raycasts;
//! - `plan` (`rl-plan`, feature `plan`): motion planning — planners, collision checkers,
//!   path simplification and certification;
//! - `view` (`rl-view`, feature `view`): the browser viewer.

#![recursion_limit = "256"]

pub mod controller;
pub mod devices;
pub mod json;
// Inlined, so that `cargo doc --no-deps` documents the three crates as modules of this one and
// every link from here lands on a page that exists.
#[doc(inline)]
pub use rl_core as core;
#[doc(inline)]
pub use rl_drivers as drivers;
#[cfg(feature = "plan")]
pub use rl_plan as plan;
#[doc(inline)]
pub use rl_rt as rt;
pub use rl_sg as sg;
#[cfg(feature = "view")]
pub use rl_view as view;

/// The README's examples, compiled and run as doc tests so they cannot rot.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
