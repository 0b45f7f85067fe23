//! A complete joint-space position controller: the program behind `rl run`, as a library so
//! tests, benchmarks and users' own programs can drive it.
//!
//! One control cycle ([`Controller::cycle`]) reads the measured joints from a cyclic device,
//! evaluates a jerk-limited trajectory, computes inverse-dynamics feed-forward torques (RNEA),
//! commands the next position and steps the device. It allocates nothing. Around it:
//!
//! - [`plan`]: limits derived from the model, default waypoints, and a [`Plan`] that is checked
//!   against the model's position, speed and effort limits before anything moves;
//! - [`clock`]: trajectory time, slowed to rest along the path when a stop is asked for;
//! - [`tracking`]: tracking error, feed-forward peaks and limit checks of the measured motion;
//! - [`telemetry`]: one `Copy` record per cycle for a lock-free queue, and its CSV form;
//! - [`report`]: the end-of-run report as text and JSON.
//!
//! The real-time loop, the thread and the device's life cycle stay with the caller (the `rl`
//! tool's `run` command shows the whole program).
//!
//! ```no_run
//! use rl::controller::{Controller, MotionLimits, Plan, default_waypoints, rv6sl};
//! use rl::drivers::fake::h7_controller::{FakeH7, FakeH7Config};
//! use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
//! use rl::drivers::{CyclicDevice, Device, JointPositionSensor};
//!
//! let model = rv6sl()?.model;
//! let fake = FakeH7::spawn(FakeH7Config::loopback(6))?;
//! let mut robot = MitsubishiH7::new(MitsubishiH7Config::new(6, fake.udp_addr(), fake.r3_addr()))?;
//! robot.open()?;
//! robot.start()?;
//! robot.step()?; // the first reply tells where the arm is
//! let mut start = [0.0; 6];
//! robot.joint_position(&mut start)?;
//! let limits = MotionLimits::from_model(&model, 0.25)?;
//! let plan = Plan::new(&model, &start, &default_waypoints(&model, &start), &limits)?;
//! let mut control = Controller::new(robot, model, plan, std::time::Duration::from_micros(7110))?;
//! while !control.cycle().finished {
//!     std::thread::sleep(std::time::Duration::from_micros(7110)); // use rl::rt::CyclicLoop
//! }
//! println!("{}", control.tracking().max_error());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod clock;
mod control;
pub mod plan;
pub mod report;
pub mod telemetry;
pub mod tracking;

pub use clock::TrajectoryClock;
pub use control::{Controller, CycleResult, JointRobot, RunEnd};
pub use plan::{MotionLimits, Plan, PlanError, default_waypoints};
pub use telemetry::CycleRecord;
pub use tracking::Tracking;

use rl_core::loader::{self, LoadError, LoadedModel};

/// Most joints the controller drives (the H7 protocol carries 8 axes).
pub const MAX_JOINTS: usize = 8;
/// Model capacity: most moving bodies a model may have.
pub const MAX_BODIES: usize = 16;
/// Most waypoints of a plan (besides the start, which the plan returns to at the end).
pub const MAX_WAYPOINTS: usize = 32;

/// The model every controller type is built for.
pub type RobotModel = rl_core::Model<MAX_BODIES>;

/// The Mitsubishi RV-6SL (RL's `mitsubishi-rv6sl.xml`, BSD-2-Clause, see
/// `tests/data/rlmdl/LICENSE.md`), embedded so the default run needs no file.
pub const RV6SL_XML: &str = include_str!("../../tests/data/rlmdl/mitsubishi-rv6sl.xml");

/// Loads the embedded Mitsubishi RV-6SL.
pub fn rv6sl() -> Result<LoadedModel<MAX_BODIES>, LoadError> {
    loader::load_str(RV6SL_XML, &loader::UrdfOptions::default())
}
