//! Franka robots (FR3, Panda) over the Franka Control Interface (FCI): the libfranka network
//! protocol of research-interface version 10, which libfranka 0.21.2 and franky-sim 1.0.4 speak.
//!
//! One file per protocol concept:
//! - [`message`]: the TCP command messages (header, commands, requests, status codes);
//! - [`connect`]: the connection handshake and its version check;
//! - [`state`]: the robot-state record the robot sends over UDP every millisecond;
//! - [`command`]: the robot-command record the client answers it with;
//! - [`errors`]: the robot's errors and reflexes (41 flags), typed and counted;
//! - [`limits`]: the interface's limits (what the robot checks a command against);
//! - `device` (feature `std`): the cyclic device, [`FrankaArm`].
//!
//! The codecs are `no_std`, allocation-free and never panic on any input: every decode returns
//! a typed error that says what and where. Layouts are the packed C structs of libfranka-common
//! (`include/research_interface/robot/{service_types,rbk_types,error}.h`, Apache-2.0), little
//! endian; the lengths were checked against franky-sim's Python encoders (1377 and 371 bytes)
//! and, through the tests, against libfranka 0.21.2 itself.
//!
//! The session, as the robot runs it:
//! 1. The client opens TCP to port 1337 and sends `Connect` with its version and the UDP port
//!    it listens on; the robot answers with its status and version, refusing another version
//!    (`IncompatibleLibraryVersion`).
//! 2. From then on the robot sends a [`state::RobotState`] every millisecond to that UDP port,
//!    `message_id` counting up by one per millisecond.
//! 3. `Move` (TCP) starts a motion with a controller mode and a motion generator mode; the robot
//!    answers `MotionStarted` at once and a second time (same command id) when the motion ends:
//!    `Success`, or why it ended (`ReflexAborted`, `Preempted`, …).
//! 4. While a motion runs the client answers each state with a [`command::RobotCommand`] that
//!    carries the state's `message_id`; a command that misses its millisecond is lost, and the
//!    robot stops with `communication_constraints_violation` after 20 lost in a row.
//! 5. The client ends a motion by setting `motion_generation_finished` (or
//!    `torque_command_finished`) in its commands until the robot reports idle, or by `StopMove`.
#![forbid(unsafe_code)]

pub mod command;
pub mod connect;
pub mod errors;
pub mod limits;
pub mod message;
pub mod state;
mod wire;

#[cfg(feature = "std")]
mod device;
#[cfg(feature = "std")]
mod link;

#[cfg(feature = "std")]
pub use device::{
    ControlMode, FrankaArm, FrankaConfig, FrankaCounters, FrankaSettings, MotionEnd,
    RECOMMENDED_STATE_WAIT,
};

/// The TCP port of the robot's command server.
pub const COMMAND_PORT: u16 = 1337;
/// Joints of a Franka arm.
pub const DOF: usize = 7;
/// The robot's cycle: one state a millisecond.
pub const CYCLE: core::time::Duration = core::time::Duration::from_millis(1);
/// Lost commands in a row after which the robot stops the motion with
/// `communication_constraints_violation` (Franka's FCI documentation; Polymetis' troubleshooting
/// page: "fails to receive a command packet in time for 20 steps in a row").
pub const MAX_LOST_IN_A_ROW: u32 = 20;
