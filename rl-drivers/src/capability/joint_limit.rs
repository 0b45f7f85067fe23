use crate::JointDevice;

/// Reports joints the device stopped at a limit: it refused or clamped the last command
/// because it lay beyond a joint limit, or a limit switch is active (CiA 402 "internal limit
/// active"; a controller that clamps the commanded position). A controller finds this
/// capability at run time through [`JointDevice::joint_limit_sensor`] and treats a reported
/// limit as a fault.
pub trait JointLimitSensor: JointDevice {
    /// Writes `true` for each joint the device reported at a limit in the last step (length
    /// [`JointDevice::dof`]).
    fn joint_limit_reached(&self, reached: &mut [bool]) -> Result<(), Self::Error>;
}
