use crate::Device;

/// A six-axis force-torque sensor (RL's `SixAxisForceTorqueSensor`).
pub trait SixAxisForceTorqueSensor: Device {
    /// The last received wrench: forces `fx, fy, fz` in N then torques `tx, ty, tz` in N·m.
    fn forces_torques(&self) -> Result<[f64; 6], Self::Error>;
}
