//! Sensor and actuator interfaces, one per file, mirroring RL's `rl::hal` capability classes.
//!
//! They work on buffered values: setters store a command for the next [`step`], getters return
//! what the last step received. Joint vectors are caller-provided slices whose length must equal
//! [`JointDevice::dof`] (a wrong length is [`Error::InvalidArgument`]); nothing allocates.
//!
//! [`step`]: crate::CyclicDevice::step
//! [`Error::InvalidArgument`]: crate::Error::InvalidArgument

mod analog_io;
mod cartesian_pose;
mod digital_io;
mod force_torque;
mod gripper;
mod joint;
mod joint_limit;
mod joint_position;
mod joint_torque;
mod joint_torque_feed_forward;
mod joint_velocity;
mod link_statistics;
mod range_sensor;

pub use analog_io::{AnalogInputReader, AnalogOutputWriter};
pub use cartesian_pose::{CartesianPositionActuator, CartesianPositionSensor, Pose};
pub use digital_io::{DigitalInputReader, DigitalOutputWriter};
pub use force_torque::SixAxisForceTorqueSensor;
pub use gripper::Gripper;
pub use joint::JointDevice;
pub use joint_limit::JointLimitSensor;
pub use joint_position::{JointPositionActuator, JointPositionSensor};
pub use joint_torque::{JointTorqueActuator, JointTorqueSensor};
pub use joint_torque_feed_forward::JointTorqueFeedForward;
pub use joint_velocity::{JointVelocityActuator, JointVelocitySensor};
pub use link_statistics::{Delivery, LinkStatistics, LinkStatisticsSensor};
pub use range_sensor::RangeSensor;
