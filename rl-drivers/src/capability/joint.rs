use crate::{
    Device, JointLimitSensor, JointTorqueActuator, JointTorqueFeedForward, JointTorqueSensor,
    JointVelocityActuator, JointVelocitySensor,
};

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

    /// The device's joint velocity command, if it takes one (in its configured mode).
    fn joint_velocity_actuator(
        &mut self,
    ) -> Option<&mut dyn JointVelocityActuator<Error = Self::Error>> {
        None
    }

    /// The device's joint torque command, if it takes one (in its configured mode).
    fn joint_torque_actuator(
        &mut self,
    ) -> Option<&mut dyn JointTorqueActuator<Error = Self::Error>> {
        None
    }

    /// The device's measured joint velocities, if it reports them.
    fn joint_velocity_sensor(&self) -> Option<&dyn JointVelocitySensor<Error = Self::Error>> {
        None
    }

    /// The device's measured joint torques, if it reports them.
    fn joint_torque_sensor(&self) -> Option<&dyn JointTorqueSensor<Error = Self::Error>> {
        None
    }
}
