use crate::Device;

/// A Cartesian pose as the robot protocols carry it: position in m and rotation as the angles
/// `a, b, c` in rad with `R = Rz(c)·Ry(b)·Rx(a)` (the convention of MELFA and RL's Coach).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose {
    /// `x, y, z` in m.
    pub position_m: [f64; 3],
    /// `a, b, c` in rad, `R = Rz(c)·Ry(b)·Rx(a)`.
    pub abc_rad: [f64; 3],
}

/// Commands the tool pose (RL's `CartesianPositionActuator`).
pub trait CartesianPositionActuator: Device {
    /// Buffers the pose for the next step.
    fn set_cartesian_position(&mut self, pose: &Pose) -> Result<(), Self::Error>;
}

/// Measures the tool pose (RL's `CartesianPositionSensor`).
pub trait CartesianPositionSensor: Device {
    /// The last received pose.
    fn cartesian_position(&self) -> Result<Pose, Self::Error>;
}
