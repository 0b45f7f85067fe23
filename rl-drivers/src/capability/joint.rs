use crate::{Device, JointTorqueFeedForward};

/// A device with joints (RL's `rl::hal::Joint`): the length every joint vector must have.
pub trait JointDevice: Device {
    /// Number of joints (degrees of freedom).
    fn dof(&self) -> usize;

    /// The device's feed-forward torque input, if it has one (RL finds capabilities with a
    /// `dynamic_cast`; a driver that implements [`JointTorqueFeedForward`] returns itself).
    fn torque_feed_forward(
        &mut self,
    ) -> Option<&mut dyn JointTorqueFeedForward<Error = Self::Error>> {
        None
    }
}
