use crate::JointDevice;

/// Commands joint velocitys (RL's `JointVelocityActuator`).
pub trait JointVelocityActuator: JointDevice {
    /// Buffers the joint velocitys in rad/s (or m/s) for the next step; `q.len()` must be [`JointDevice::dof`].
    fn set_joint_velocity(&mut self, q: &[f64]) -> Result<(), Self::Error>;
}

/// Measures joint velocitys (RL's `JointVelocitySensor`).
pub trait JointVelocitySensor: JointDevice {
    /// Writes the last received joint velocitys in rad/s (or m/s) into `q` (length [`JointDevice::dof`]).
    fn joint_velocity(&self, q: &mut [f64]) -> Result<(), Self::Error>;
}
