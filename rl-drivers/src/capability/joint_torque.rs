use crate::JointDevice;

/// Commands joint torques (RL's `JointTorqueActuator`).
pub trait JointTorqueActuator: JointDevice {
    /// Buffers the joint torques in N·m (or N) for the next step; `q.len()` must be [`JointDevice::dof`].
    fn set_joint_torque(&mut self, q: &[f64]) -> Result<(), Self::Error>;
}

/// Measures joint torques (RL's `JointTorqueSensor`).
pub trait JointTorqueSensor: JointDevice {
    /// Writes the last received joint torques in N·m (or N) into `q` (length [`JointDevice::dof`]).
    fn joint_torque(&self, q: &mut [f64]) -> Result<(), Self::Error>;
}
