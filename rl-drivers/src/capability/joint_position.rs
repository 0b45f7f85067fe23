use crate::JointDevice;

/// Commands joint positions (RL's `JointPositionActuator`).
pub trait JointPositionActuator: JointDevice {
    /// Buffers the joint positions in rad (or m for prismatic joints) for the next step; `q.len()` must be [`JointDevice::dof`].
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Self::Error>;
}

/// Measures joint positions (RL's `JointPositionSensor`).
pub trait JointPositionSensor: JointDevice {
    /// Writes the last received joint positions in rad (or m for prismatic joints) into `q` (length [`JointDevice::dof`]).
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Self::Error>;
}
