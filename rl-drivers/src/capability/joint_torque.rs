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

    /// The torques the device applies from the last command it received, as it reports them
    /// (a Franka arm: the state's `tau_J_d`), into `tau` (length [`JointDevice::dof`]); `false`
    /// (the default) when it does not report them. A torque-rate limit against these — as
    /// libfranka's `limitRate` does — keeps each step the device sees within its limit even
    /// after commands were lost on the way.
    fn applied_joint_torque(&self, tau: &mut [f64]) -> bool {
        let _ = tau;
        false
    }
}

/// Measures joint torques (RL's `JointTorqueSensor`).
pub trait JointTorqueSensor: JointDevice {
    /// Writes the last received joint torques in N·m (or N) into `q` (length [`JointDevice::dof`]).
    fn joint_torque(&self, q: &mut [f64]) -> Result<(), Self::Error>;
}
