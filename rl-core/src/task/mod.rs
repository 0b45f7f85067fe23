//! Task-space control mathematics: the torques that make a tool follow a pose while the
//! remaining freedom of a redundant arm holds a posture, for the laws of a torque-controlled
//! arm (the controller's task-space laws build on these).
//!
//! - [`impedance`]: operational-space impedance (Khatib) with a dynamically consistent
//!   nullspace: the tool's acceleration is commanded, the posture and joint-limit avoidance act
//!   only where the task leaves the arm free, and a clamped (or damped) operational inertia
//!   keeps the torques bounded through singularities.
//! - [`repulsion`]: distance-based repulsion from obstacles at the robot's points nearest to
//!   them, in the nullspace of what must not yield ([`Priority`]).
//! - [`limit_rate`]: a torque-rate limit, as a torque-controlled arm enforces on its input
//!   (Franka: 1 N·m per ms).
//!
//! Like the algorithms, these write into a [`Data`](crate::Data) (and the task's own
//! [`TaskData`]), allocate nothing and never panic; [`operational_impedance`] checks its
//! arguments' lengths and values.

pub mod impedance;
mod rate;
pub mod repulsion;

pub use impedance::{
    ImpedanceGains, Orientation, Priority, Singularity, TaskData, TaskError, TaskReport,
    TaskTarget, operational_impedance,
};
pub use rate::limit_rate;
pub use repulsion::{MAX_PROXIMITIES, Proximity, Repulsion};
