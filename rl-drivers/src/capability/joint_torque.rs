use crate::JointDevice;

/// Commands joint torques (RL's `JointTorqueActuator`).
pub trait JointTorqueActuator: JointDevice {
    /// Buffers the joint torques in N·m (or N) for the next step; `q.len()` must be [`JointDevice::dof`].
    fn set_joint_torque(&mut self, q: &[f64]) -> Result<(), Self::Error>;

    /// Whether the device adds the gravity torque to what it is given (a Franka arm: its
    /// `tau_J_d` are the torques beyond gravity). `false` (the default): the torques given
    /// are the joints' torques.
    fn adds_gravity(&self) -> bool {
        false
    }
}

/// Measures joint torques (RL's `JointTorqueSensor`).
pub trait JointTorqueSensor: JointDevice {
    /// Writes the last received joint torques in N·m (or N) into `q` (length [`JointDevice::dof`]).
    fn joint_torque(&self, q: &mut [f64]) -> Result<(), Self::Error>;
}
