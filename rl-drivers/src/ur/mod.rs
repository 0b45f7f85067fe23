//! Universal Robots arms (e-Series, CB3) over RTDE, with a program on the controller that
//! follows RTDE input registers, the dashboard server, and the real-time interface (RL's
//! `UniversalRobotsRtde`, `UniversalRobotsDashboard` and `UniversalRobotsRealtime`).
//!
//! - [`crate::proto::rtde`]: the RTDE codec (messages, types, variables, recipes), `no_std`;
//! - [`program`]: the URScript program sent at `start` ([`FollowerProgram`]);
//! - [`dashboard`]: the dashboard client ([`Dashboard`]);
//! - `device`: the cyclic device, [`UniversalRobot`];
//! - `realtime`: the real-time interface's stream (30003, 30013) as a cyclic device that
//!   reads the arm's state and sends URScript, [`UrRealtime`].
//!
//! A session: `open` (RTDE version 2, the controller's version, one output recipe at 500 Hz
//! and two input recipes; the dashboard), `start` (optionally power on and release the brakes;
//! start the outputs; the program follows the registers once its handshake reads 1), one
//! exchange a step (the joints written, the controller's next package read, safety and the
//! program checked), `stop` (the program ends with `stopj`; RTDE paused), `close`.
//!
//! Not built: analog I/O through the device, and the primary and secondary interfaces'
//! messages (a program that does not compile is seen only as one that does not start).

mod convert;
pub mod dashboard;
mod device;
mod link;
pub mod program;
mod realtime;

pub use dashboard::{Dashboard, DashboardError};
pub use device::{
    DOF, UniversalRobot, UrConfig, UrCounters, UrState, robot_mode, robot_mode_name,
    safety_stop_name,
};
pub use program::{FollowerProgram, MODE_POSITION, MODE_VELOCITY};
pub use realtime::{SCRIPT_CAPACITY, UrRealtime, UrRealtimeConfig, UrRealtimeCounters};
