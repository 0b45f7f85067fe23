//! A complete, supervised joint-space controller: the program behind `rl run`, as a library so
//! tests, benchmarks and users' own programs get everything it does.
//!
//! [`ControlRun`] is the whole run in a few lines (see [`runtime`]): open the device, check the
//! model against it, plan before the servo goes on (or let a law of one's own prepare), run the
//! loop in a real-time thread, stop the device safely, report. Underneath, one control cycle
//! ([`Controller::cycle`]) reads the measured joints from any device with the [`JointRobot`]
//! capabilities, supervises them ([`supervise`]), takes the inputs other threads sent
//! ([`input`]), runs the control law ([`law`]) and checks, sends and steps its position,
//! velocity or torque command. The law `rl run` executes is the [`TrajectoryFollower`]: a
//! jerk-limited trajectory with inverse-dynamics feed-forward torques (RNEA, sent to a device
//! that takes them). It allocates nothing. Capacities are the user's choice:
//! `Controller<R, B, J, L>` for up to `B` moving bodies and `J` joints. Around it:
//!
//! - [`law`]: the [`ControlLaw`] trait — what a law gets each cycle, what it commands, how it
//!   brakes — and [`ControlRun::start_law`] to run one's own;
//! - [`input`]: targets and a law's own inputs from other threads, lock-free, checked, counted,
//!   with a staleness bound;
//! - [`plan`]: limits derived from the model, default waypoints, and a [`Plan`] that is checked
//!   against the model's position, speed and effort limits before anything moves;
//! - [`planned`] (feature `plan`): a collision-free path from rl-plan, made a trajectory the
//!   run follows ([`Motion::Trajectory`], [`ControlRun::start_with`]), blended through its
//!   waypoints (checked for collisions where it leaves the path) or stopping at each;
//! - [`supervise`]: the per-cycle checks and the [`Fault`]s that end a run;
//! - [`clock`]: trajectory time, slowed to rest along the path when a stop is asked for;
//! - [`tracking`]: tracking error, feed-forward peaks and limit checks of the measured motion;
//! - [`telemetry`]: one `Copy` record per cycle for a lock-free queue, and its CSV form (with
//!   the run's state each cycle);
//! - [`report`]: the end-of-run report as text and JSON (when a fault happened, too);
//! - [`lateness`]: who was late — the loop, the device's side (an in-process fake measures its
//!   own cycle), the delivery of the replies — and a run's likely cause when it failed on
//!   timing.
//! - `view` (feature `view`): the run's motion and tracking error, live in rl-view's page.
//!
//! A caller who wants its own loop steps a [`Controller`] itself:
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
//! let limits = MotionLimits::<8>::from_model(&model, 0.25)?;
//! let plan = Plan::new(&model, &start, &default_waypoints(&model, &start), &limits)?;
//! let mut control: Controller<_> =
//!     Controller::new(robot, model, plan, std::time::Duration::from_micros(7110))?;
//! while !control.cycle().finished {
//!     std::thread::sleep(std::time::Duration::from_micros(7110)); // use rl::rt::CyclicLoop
//! }
//! println!("{}", control.tracking().max_error());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod clock;
mod control;
mod follower;
pub mod input;
pub mod lateness;
pub mod law;
pub mod plan;
#[cfg(feature = "plan")]
pub mod planned;
pub mod report;
mod robot;
pub mod runtime;
pub mod safety;
pub mod stream;
pub mod supervise;
mod target_follower;
pub mod task_space;
pub mod telemetry;
pub mod tracking;
#[cfg(feature = "view")]
pub mod view;

pub use clock::TrajectoryClock;
pub use control::{Controller, CycleResult, CycleTiming, DEFAULT_MAX_BRAKING, FaultAt, RunEnd};
pub use follower::TrajectoryFollower;
pub use input::{InputError, InputSender, Target};
pub use lateness::{HostActivity, Lateness, OtherRtThread, PeerLateness};
pub use law::{
    BrakeReason, Command, CommandMode, Context, ControlLaw, LawError, LawStatus, LawSummary,
    Measured, Start,
};
pub use plan::{
    FollowTrajectory, Motion, MotionLimits, Plan, PlanBudget, PlanError, PlanTrajectory,
    default_waypoints,
};
pub use report::RunReport;
pub use robot::JointRobot;
pub use runtime::{ControlRun, Progress, RunError, RunOptions};
pub use supervise::{Fault, Supervision};
pub use target_follower::{DEFAULT_INPUT_TIMEOUT, FollowCounts, TargetFollower};
pub use telemetry::{CycleRecord, RunState, TelemetryFile};
pub use tracking::Tracking;
#[cfg(feature = "view")]
pub use view::{ViewHook, ViewPublisher};

use rl_core::loader::{self, LoadError, LoadedModel};

/// Default model capacity: most moving bodies (the embedded RV-6SL and RL's arms fit).
pub const DEFAULT_BODIES: usize = 16;
/// Default joint capacity (the H7 protocol carries 8 axes).
pub const DEFAULT_JOINTS: usize = 8;
/// Most waypoints of a plan (besides the start, which the plan returns to at the end); a
/// planned path may have `MAX_WAYPOINTS + 1` segments ([`plan::MOVE_SEGMENTS`] moves when it
/// stops at every waypoint, at most [`plan::BLENDED_SEGMENTS`] lines, blends and moves when it
/// is blended). More is a typed error before anything moves.
pub const MAX_WAYPOINTS: usize = 32;

/// The Mitsubishi RV-6SL (RL's `mitsubishi-rv6sl.xml`, BSD-2-Clause, see
/// `tests/data/rlmdl/LICENSE.md`), embedded so the default run needs no file.
pub const RV6SL_XML: &str = include_str!("../../tests/data/rlmdl/mitsubishi-rv6sl.xml");

/// Loads the embedded Mitsubishi RV-6SL at the default capacity (for another, load
/// [`RV6SL_XML`] with [`loader::load_str`]).
pub fn rv6sl() -> Result<LoadedModel<DEFAULT_BODIES>, LoadError> {
    loader::load_str(RV6SL_XML, &loader::UrdfOptions::default())
}
