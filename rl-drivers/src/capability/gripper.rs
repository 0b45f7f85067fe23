use crate::Device;

/// A gripper (RL's `Gripper`): each call buffers the command for the next step.
pub trait Gripper: Device {
    /// Stops the gripper where it is.
    fn halt(&mut self) -> Result<(), Self::Error>;
    /// Opens the gripper.
    fn release(&mut self) -> Result<(), Self::Error>;
    /// Closes the gripper.
    fn shut(&mut self) -> Result<(), Self::Error>;
}
