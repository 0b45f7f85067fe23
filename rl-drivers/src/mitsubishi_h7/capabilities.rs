//! The capabilities the H7 offers the application: joint and Cartesian positions, limits, the
//! gripper, and the link's statistics.

use crate::capability::{
    CartesianPositionActuator, CartesianPositionSensor, Gripper, JointDevice, JointLimitSensor,
    JointPositionActuator, JointPositionSensor, LinkStatistics, LinkStatisticsSensor, Pose,
};
use crate::device::{Error, Operation};
use crate::proto::h7::{Command, Data, DataShape, DataView, MAX_AXES, Mode, MxtType, PoseData};
use glam::DVec3;
use rl_core::rotation::euler;

use super::{Measured, MitsubishiH7};

impl LinkStatisticsSensor for MitsubishiH7 {
    fn link_statistics(&self) -> LinkStatistics {
        let c = self.counters();
        LinkStatistics {
            sent: c.sent,
            received: c.replies,
            lost: c.timeouts,
            late: c.late,
            rejected: c.foreign,
            corrupt: c.wrong_length + c.corrupt + c.replayed,
            consecutive_failures: c.consecutive_failures,
            delivery: c.delivery,
        }
    }
}

impl JointDevice for MitsubishiH7 {
    /// The axes the controller reported at `open` (or the configured count; 0 before `open`
    /// when none is configured).
    fn dof(&self) -> usize {
        self.axes
    }

    fn joint_limit_sensor(&self) -> Option<&dyn JointLimitSensor<Error = Error>> {
        Some(self)
    }
}

impl JointLimitSensor for MitsubishiH7 {
    /// A joint whose command value in the last reply (type 2, the value the controller took)
    /// differs from the last joint command sent by more than an `f32` unit in the last place:
    /// the controller clamped it at a position or speed limit. Always `false` when the reply
    /// types hold no joint command or no joint command was sent yet.
    fn joint_limit_reached(&self, reached: &mut [bool]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", self.axes, reached.len())?;
        reached.copy_from_slice(&self.limit[..self.axes]);
        Ok(())
    }
}

impl JointPositionActuator for MitsubishiH7 {
    /// Buffers `q` for the axes the device has; any other slot of the packet carries the last
    /// measured value, never a made-up one.
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Error> {
        self.check_command(Mode::Joint, q.len())?;
        let mut j = [0f32; MAX_AXES];
        for (i, d) in j.iter_mut().enumerate() {
            *d = q.get(i).copied().unwrap_or(self.measured[i]) as f32;
        }
        self.request.dat = Data::from_joints(&j);
        self.request.command = Command::Move;
        self.request.send_type = MxtType::Joint;
        Ok(())
    }
}

impl JointPositionSensor for MitsubishiH7 {
    /// The joints of the last reply (encoder feedback when requested, else the filtered or
    /// commanded joints), or, before the first reply, where `JPOSF` said the arm stood at
    /// `open`.
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", self.axes, q.len())?;
        match self.measured_from {
            Measured::None => Err(Error::protocol(
                Operation::Get,
                "H7 packet",
                &"no joint position known yet (no JPOSF answer, no reply)",
            )),
            _ => {
                q.copy_from_slice(&self.measured[..self.axes]);
                Ok(())
            }
        }
    }

    /// Joints travel as `f32`: half a unit in the last place at `q`; before the first reply,
    /// half the last digit `JPOSF` printed (0.005° for two decimals) where that is coarser.
    fn joint_position_resolution(&self, q: f64) -> f64 {
        let printed = match &self.measured_from {
            Measured::Report(r) => (0..r.axes)
                .map(|i| {
                    let d = r.resolution(i);
                    if self.config.linear_axes[i] {
                        d
                    } else {
                        d.to_radians()
                    }
                })
                .fold(0.0, f64::max),
            _ => 0.0,
        };
        f32_half_ulp(q).max(printed)
    }
}

/// The spacing of `f32` values at `x`.
pub(super) fn f32_ulp(x: f32) -> f32 {
    let a = x.abs();
    if !a.is_finite() {
        return 0.0;
    }
    f32::from_bits(a.to_bits() + 1) - a
}

/// Half the spacing of `f32` values at `x`: how far a value rounded to `f32` can be off.
fn f32_half_ulp(x: f64) -> f64 {
    let f = (x as f32).abs();
    if !f.is_finite() {
        return 0.0;
    }
    let next = f32::from_bits(f.to_bits() + 1);
    0.5 * f64::from(next - f)
}

impl CartesianPositionActuator for MitsubishiH7 {
    fn set_cartesian_position(&mut self, pose: &Pose) -> Result<(), Error> {
        self.check_command(Mode::Pose, self.axes)?;
        // Keep the arm configuration (structure flags) the controller last reported.
        let (sflg1, sflg2) = match self.find_shape(DataShape::Pose, "") {
            Ok(DataView::Pose(p)) => (p.sflg1, p.sflg2),
            _ => (0, 0),
        };
        let data = PoseData {
            xyz_mm: pose.translation.to_array().map(|v| (v * 1000.0) as f32),
            abc_rad: euler::to_zyx(&pose.rotation).map(|v| v as f32),
            additional: [0.0; 2],
            sflg1,
            sflg2,
        };
        self.request.dat = Data::from_pose(&data);
        self.request.command = Command::Move;
        self.request.send_type = MxtType::Pose;
        Ok(())
    }
}

impl CartesianPositionSensor for MitsubishiH7 {
    fn cartesian_position(&self) -> Result<Pose, Error> {
        match self.find_shape(DataShape::Pose, "no pose data in the last reply")? {
            DataView::Pose(p) => Ok(Pose::new(
                euler::from_zyx(p.abc_rad.map(f64::from)),
                DVec3::from_array(p.xyz_mm.map(|v| f64::from(v) / 1000.0)),
            )),
            _ => Err(Error::protocol(
                Operation::Get,
                "H7 packet",
                &"no pose data in the last reply",
            )),
        }
    }
}

impl Gripper for MitsubishiH7 {
    fn halt(&mut self) -> Result<(), Error> {
        let g = self.config.gripper;
        self.set_output(g.bit_top, g.mask, g.halt)
    }

    fn release(&mut self) -> Result<(), Error> {
        let g = self.config.gripper;
        self.set_output(g.bit_top, g.mask, g.release)
    }

    fn shut(&mut self) -> Result<(), Error> {
        let g = self.config.gripper;
        self.set_output(g.bit_top, g.mask, g.shut)
    }
}

#[cfg(test)]
mod tests {
    use super::f32_half_ulp;

    #[test]
    fn the_resolution_covers_the_rounding_to_f32() {
        // kinova's joint limit, as a MELFA controller would report a joint standing on it.
        let limit = 0.331_612_557_879_f64;
        let reported = f64::from(limit as f32);
        assert_ne!(reported, limit);
        assert!((reported - limit).abs() <= f32_half_ulp(limit));
        assert!(f32_half_ulp(limit) < 2e-8);
        assert_eq!(f32_half_ulp(0.0), 0.5 * f64::from(f32::from_bits(1)));
        assert_eq!(f32_half_ulp(f64::NAN), 0.0);
    }
}
