use crate::Device;

/// A device with joints (RL's `rl::hal::Joint`): the length every joint vector must have.
pub trait JointDevice: Device {
    /// Number of joints (degrees of freedom).
    fn dof(&self) -> usize;
}
