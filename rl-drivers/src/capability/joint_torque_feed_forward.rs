use crate::JointDevice;

/// Accepts a feed-forward torque added to the device's own position or velocity control (a
/// servo drive's torque offset, CiA 402 object 0x60B2; a visualiser shows it). A controller
/// that computes inverse-dynamics torques finds this capability at run time through
/// [`JointDevice::torque_feed_forward`] and sends them where it is present.
pub trait JointTorqueFeedForward: JointDevice {
    /// Buffers the feed-forward torques in N·m (or N) for the next step; `tau.len()` must be
    /// [`JointDevice::dof`].
    fn set_joint_torque_feed_forward(&mut self, tau: &[f64]) -> Result<(), Self::Error>;
}
