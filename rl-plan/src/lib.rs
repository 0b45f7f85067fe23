//! rl-plan: collision-free motion planning for any robot model (RL's `rl::plan`), and the means
//! to execute the result.
//!
//! # The core (generic over a validity check)
//!
//! - [`space`]: configuration spaces with each joint's topology (intervals, circles that wrap,
//!   rotations), metric, interpolation and sampling, limits from the model, overridable.
//! - [`nn`]: nearest neighbours — linear, k-d tree (wrap-around aware), GNAT (any metric).
//! - [`sampler`]: uniform, Gaussian, bridge, Halton. [`verifier`]: sequential and recursive
//!   edge checks at a resolution. [`optimizer`]: shortcutting and RL's advanced optimiser.
//! - [`planner`]: PRM (k nearest or radius, A*), RRT, RRT with goal bias, bidirectional RRT,
//!   RRT-Connect (RL's `RrtConCon`, `RrtExtCon`, `RrtExtExt`); a seed and a time budget on
//!   every call, the same seed giving the same path.
//! - [`validity::Validity`]: what the planners ask; [`scene::SceneValidity`] answers with
//!   rl-sg's exact geometry (self-collision with the SRDF's pairs, and the environment).
//!
//! # The fast path
//!
//! [`fast`]: the robot as spheres (from a `*_spherized.urdf`, or fitted around its meshes),
//! forward kinematics and sphere tests for eight configurations at once in SIMD lanes (AVX2
//! with FMA when the CPU has it, a portable build otherwise), the points of an edge checked in
//! batches spread over it, with early exit. See `NOTES.md` for the design and the numbers
//! against VAMP.
//!
//! # Problems and execution
//!
//! [`problem`]: MoveIt planning scenes and motion plan requests (MotionBenchMaker), RL's
//! rlplan XML scenarios. [`bench`](mod@bench): OMPL's benchmark log and summary statistics.
//! [`execute`]: a path becomes a trajectory within per-joint velocity, acceleration and jerk
//! limits that a controller can follow — stopping at every waypoint, or
//! ([`execute::blend`]) blending through them, with the blends checked for collisions.
#![deny(missing_docs)]
// Index loops over coordinates, lanes and pivots read as the math does.
#![allow(clippy::needless_range_loop)]

pub mod bench;
pub mod budget;
pub mod error;
pub mod execute;
pub mod fast;
pub mod nn;
pub mod optimizer;
pub mod path;
pub mod planner;
pub mod problem;
pub mod rng;
pub mod sampler;
pub mod scene;
pub mod solve;
pub mod space;
pub mod validity;
pub mod verifier;

pub use budget::Budget;
pub use error::PlanError;
pub use path::Path;
pub use rng::Rng;
pub use solve::{PlanOptions, PlanResult, plan};
pub use space::{JointSpace, Topology};
pub use validity::Validity;
