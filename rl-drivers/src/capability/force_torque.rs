use glam::DVec3;
use rl_core::spatial::{ForceVector, PlueckerTransform};

use crate::Device;

/// A six-axis force-torque sensor (RL's `SixAxisForceTorqueSensor`).
///
/// The wrench is the one the sensor measures, in the sensor's own frame (its calibration
/// frame). [`wrench_in`](Self::wrench_in) gives it in any frame whose pose relative to the
/// sensor is known: the flange's or the tool's from the model's fixed transforms, the base's
/// from forward kinematics (e.g. `ati::SensorMount` does both from a loaded model).
pub trait SixAxisForceTorqueSensor: Device {
    /// The last received wrench in the sensor's frame: forces `fx, fy, fz` in N then torques
    /// `tx, ty, tz` in N·m.
    fn forces_torques(&self) -> Result<[f64; 6], Self::Error>;

    /// The same as a spatial force vector (moment about the sensor's origin, force), sensor
    /// frame.
    fn wrench(&self) -> Result<ForceVector, Self::Error> {
        let w = self.forces_torques()?;
        Ok(ForceVector::new(
            DVec3::new(w[3], w[4], w[5]),
            DVec3::new(w[0], w[1], w[2]),
        ))
    }

    /// The wrench in frame A, given `x_a_sensor`, the sensor frame's pose in A: forces rotated
    /// into A, moments taken about A's origin (`A_X_S* f`).
    fn wrench_in(&self, x_a_sensor: &PlueckerTransform) -> Result<ForceVector, Self::Error> {
        Ok(x_a_sensor.act_force(&self.wrench()?))
    }
}
