//! The capabilities a Coach viewer offers the application: joint positions, velocities and
//! torques out, the positions it shows back, and the link's statistics.

use crate::capability::{
    Delivery, JointDevice, JointPositionActuator, JointPositionSensor, JointTorqueActuator,
    JointTorqueFeedForward, JointVelocityActuator, LinkStatistics, LinkStatisticsSensor,
};
use crate::device::{Error, Operation};
use crate::proto::coach::Message;

use super::Coach;

impl LinkStatisticsSensor for Coach {
    /// `rejected` counts well-formed lines that were not ours; `corrupt` lines that did not
    /// parse, did not fit, or did not match the model.
    fn link_statistics(&self) -> LinkStatistics {
        let c = self.counters;
        LinkStatistics {
            sent: c.sent,
            received: c.replies,
            lost: c.timeouts,
            late: c.late,
            rejected: c.other_lines,
            corrupt: c.bad_lines,
            consecutive_failures: self.lifecycle.consecutive_failures(),
            delivery: Delivery::default(),
        }
    }
}

impl JointTorqueFeedForward for Coach {
    /// Shows the feed-forward torques in the visualiser (`5 <i> τ…`).
    fn set_joint_torque_feed_forward(&mut self, tau: &[f64]) -> Result<(), Error> {
        self.set_joint_torque(tau)
    }
}

impl JointDevice for Coach {
    fn dof(&self) -> usize {
        self.config.dof
    }

    fn torque_feed_forward(&mut self) -> Option<&mut dyn JointTorqueFeedForward<Error = Error>> {
        Some(self)
    }

    fn joint_velocity_actuator(&mut self) -> Option<&mut dyn JointVelocityActuator<Error = Error>> {
        Some(self)
    }

    fn joint_torque_actuator(&mut self) -> Option<&mut dyn JointTorqueActuator<Error = Error>> {
        Some(self)
    }
}

impl JointPositionActuator for Coach {
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Error> {
        let values = self.values(q)?;
        self.push(&Message::JointPosition {
            model: self.config.model,
            values,
        })
    }
}

impl JointVelocityActuator for Coach {
    fn set_joint_velocity(&mut self, qd: &[f64]) -> Result<(), Error> {
        let values = self.values(qd)?;
        self.push(&Message::JointVelocity {
            model: self.config.model,
            values,
        })
    }
}

impl JointTorqueActuator for Coach {
    fn set_joint_torque(&mut self, tau: &[f64]) -> Result<(), Error> {
        let values = self.values(tau)?;
        self.push(&Message::JointTorque {
            model: self.config.model,
            values,
        })
    }
}

impl JointPositionSensor for Coach {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", self.config.dof, q.len())?;
        if !self.have_joints {
            return Err(Error::protocol(
                Operation::Get,
                "Coach line",
                &"no joint reply received yet",
            ));
        }
        q.copy_from_slice(&self.joints[..self.config.dof]);
        Ok(())
    }

    /// The server prints six significant digits: half a unit in the sixth digit.
    fn joint_position_resolution(&self, q: f64) -> f64 {
        if q == 0.0 || !q.is_finite() {
            return 0.0;
        }
        let exponent = q.abs().log10().floor();
        0.5 * 10f64.powf(exponent - 5.0)
    }
}
