use crate::{Device, JointLimitSensor, JointTorqueFeedForward};

/// A device with joints (RL's `rl::hal::Joint`): the length every joint vector must have.
///
/// Optional capabilities are found at run time through the provided methods (RL finds them
/// with a `dynamic_cast`): a driver that implements one returns itself.
pub trait JointDevice: Device {
    /// Number of joints (degrees of freedom) the device has.
    fn dof(&self) -> usize;

    /// The device's feed-forward torque input, if it has one.
    fn torque_feed_forward(
        &mut self,
    ) -> Option<&mut dyn JointTorqueFeedForward<Error = Self::Error>> {
        None
    }

    /// The device's report of joints stopped at a limit, if it gives one.
    fn joint_limit_sensor(&self) -> Option<&dyn JointLimitSensor<Error = Self::Error>> {
        None
    }
}
