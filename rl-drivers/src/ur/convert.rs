//! The controller's representations as the capabilities take them, shared by the RTDE device
//! and the real-time interface's: the tool vector (x, y, z in m, a rotation vector in rad) as
//! a pose, and one of the 18 digital inputs (standard 0–7, configurable 8–15, tool 16–17) of
//! the controller's bit set.

use glam::{DMat3, DVec3};

use crate::capability::Pose;
use crate::device::Error;

/// Digital inputs a UR controller reports.
pub(crate) const DIGITAL_INPUTS: usize = 18;

/// The tool vector as a pose: the rotation vector's angle about its axis.
pub(crate) fn tool_pose(p: &[f64; 6]) -> Pose {
    let v = DVec3::new(p[3], p[4], p[5]);
    let angle = v.length();
    let rotation = if angle > 0.0 {
        DMat3::from_axis_angle(v / angle, angle)
    } else {
        DMat3::IDENTITY
    };
    Pose::new(rotation, DVec3::new(p[0], p[1], p[2]))
}

/// Digital input `index` of the controller's bit set.
pub(crate) fn digital_input(bits: u64, index: usize) -> Result<bool, Error> {
    if index >= DIGITAL_INPUTS {
        return Err(Error::InvalidArgument {
            what: "UR digital input",
            expected: DIGITAL_INPUTS - 1,
            got: index,
        });
    }
    Ok(bits & (1 << index) != 0)
}
