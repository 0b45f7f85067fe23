//! rl-cell: a running rl-rs controller in a cell of machines, over Zenoh — the engine ROS 2's
//! Tier-1 `rmw_zenoh` middleware uses — never on the real-time thread.
//!
//! - [`Cell`] ([`bridge`]): a Zenoh session and a bridge thread. Out: measured and commanded
//!   joint states (`sensor_msgs/JointState`) at the loop's rate or decimated, the run state,
//!   faults and the report at the end, and liveliness tokens so peers see the controller come
//!   and go. In: streamed targets (`trajectory_msgs/JointTrajectory`), obstacle poses
//!   (`geometry_msgs/PoseStamped` or `PointStamped`) and stop requests, each checked
//!   ([`inbound`]: stale, out of order, out of limits are refused and counted) before it is
//!   handed to an [`Inbound`] (the controller's input channel) or the run's stop flag.
//! - [`ros2`]: what ROS 2 sees: rmw_zenoh's key expressions, liveliness tokens and attachments,
//!   CDR bytes and RIHS01 type hashes (ROS 2 Jazzy's wire format; the tests check the bytes
//!   against PyPI `rosbags` and the hashes against Jazzy's).
//! - [`watch`]: what a cell publishes, decoded, for `rl cell watch`.
//! - [`config`]: endpoints (loopback unless told), domain, namespace, decimation, bounds.
//!
//! The real-time loop is not touched: it hands its per-cycle records to the run's telemetry
//! queue as it does without a cell; the caller that drains that queue passes each record on
//! with [`Cell::forward`] (wait-free, allocation-free).

pub mod bridge;
pub mod config;
pub mod inbound;
pub mod ros2;
pub mod watch;

pub use bridge::{Cell, CellReport, OutboundCounts, Sample};
pub use config::{CellConfig, CellError};
pub use inbound::{
    Arrival, FnInbound, Inbound, InboundCounts, JointLimits, Limits, Obstacle, Refusal, Refuse,
    Target,
};
