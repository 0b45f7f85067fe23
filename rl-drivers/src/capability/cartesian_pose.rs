use rl_core::spatial::PlueckerTransform;

use crate::Device;

/// A tool pose: rl-core's [`PlueckerTransform`] (rotation matrix and translation in m), the
/// type forward kinematics returns, so a pose from [`rl_core::algo::tool_pose`] can be
/// commanded as it is. Drivers convert to their protocol's form on the wire (for MELFA and
/// Coach: millimetres or metres and the `Z-Y'-X''` angles of [`rl_core::rotation::euler`]).
pub type Pose = PlueckerTransform;

/// Commands the tool pose (RL's `CartesianPositionActuator`).
pub trait CartesianPositionActuator: Device {
    /// Buffers the pose for the next step.
    fn set_cartesian_position(&mut self, pose: &Pose) -> Result<(), Self::Error>;
}

/// Measures the tool pose (RL's `CartesianPositionSensor`).
pub trait CartesianPositionSensor: Device {
    /// The last received pose.
    fn cartesian_position(&self) -> Result<Pose, Self::Error>;
}
