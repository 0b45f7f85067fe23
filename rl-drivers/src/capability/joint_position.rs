use crate::JointDevice;

/// Commands joint positions (RL's `JointPositionActuator`).
pub trait JointPositionActuator: JointDevice {
    /// Buffers the joint positions in rad (or m for prismatic joints) for the next step;
    /// `q.len()` must be [`JointDevice::dof`].
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Self::Error>;
}

/// Measures joint positions (RL's `JointPositionSensor`).
pub trait JointPositionSensor: JointDevice {
    /// Writes the last received joint positions in rad (or m for prismatic joints) into `q`
    /// (length [`JointDevice::dof`]).
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Self::Error>;

    /// The resolution of a reported position near `q` (rad or m): the largest difference
    /// between the true value and the reported one that the device's own representation
    /// explains (half a unit in the last place of an `f32` on the wire, half an encoder
    /// count). A check against a limit tolerates this much. 0 when exact.
    fn joint_position_resolution(&self, q: f64) -> f64 {
        let _ = q;
        0.0
    }

    /// The device's own count of its measurements, where its protocol numbers them (the
    /// Franka's `message_id`): consecutive measurements are one apart, a lost one shows as a
    /// jump. A check of the measured speed divides by the measurements actually between two
    /// readings instead of assuming one. `None` when the protocol does not number them.
    fn joint_position_sample(&self) -> Option<u64> {
        None
    }
}
