//! The limits the robot checks a client's commands against, as libfranka 0.21.2 states them
//! (`include/franka/rate_limiting.h`, `src/joint_velocity_limits.cpp`) and the FR3's URDF gives
//! them per joint (`<limit>` and `<position_based_velocity_limits>`, which the robot hands
//! the client with `GetRobotModel`).
//!
//! Joint velocity limits depend on the position: near a joint limit the joint may only move
//! as fast as it can still stop, `v ≤ −offset + √(2 · deceleration · (upper − q))` towards the
//! upper limit (and mirrored towards the lower one), never more than the joint's maximum.

use super::DOF;

/// The interface's cycle in s.
pub const DELTA_T: f64 = 1e-3;
/// Largest joint acceleration, rad/s² (a larger jump of the commanded velocity in one cycle is
/// a `velocity_discontinuity`).
pub const MAX_JOINT_ACCELERATION: f64 = 10.0;
/// Largest joint jerk, rad/s³ (a larger jump of the commanded acceleration is an
/// `acceleration_discontinuity`).
pub const MAX_JOINT_JERK: f64 = 5000.0;
/// Largest rate of the commanded torque, N·m/s (`controller_torque_discontinuity`): 1 N·m per
/// millisecond.
pub const MAX_TORQUE_RATE: f64 = 1000.0;

/// One joint's limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointLimits {
    /// Lower position, rad.
    pub lower: f64,
    /// Upper position, rad.
    pub upper: f64,
    /// Largest speed, rad/s.
    pub velocity: f64,
    /// Position-based velocity limit: offset, rad/s.
    pub velocity_offset: f64,
    /// Position-based velocity limit: deceleration, rad/s².
    pub deceleration: f64,
    /// Largest torque, N·m.
    pub effort: f64,
}

impl JointLimits {
    /// The largest velocity towards the upper limit at `q` (libfranka's
    /// `getUpperJointVelocityLimits` without its tolerance).
    pub fn upper_velocity(&self, q: f64) -> f64 {
        let room = (2.0 * self.deceleration * (self.upper - q)).max(0.0);
        self.velocity
            .min((-self.velocity_offset + libm::sqrt(room)).max(0.0))
    }

    /// The largest velocity towards the lower limit at `q`, as a negative number.
    pub fn lower_velocity(&self, q: f64) -> f64 {
        let room = (2.0 * self.deceleration * (q - self.lower)).max(0.0);
        (-self.velocity).max((self.velocity_offset - libm::sqrt(room)).min(0.0))
    }
}

/// The FR3's joint limits (its URDF in franka_description, as franky-sim 1.0.4 ships it).
pub const FR3: [JointLimits; DOF] = [
    JointLimits {
        lower: -2.9007,
        upper: 2.9007,
        velocity: 2.62,
        velocity_offset: 0.652,
        deceleration: 6.0,
        effort: 87.0,
    },
    JointLimits {
        lower: -1.8361,
        upper: 1.8361,
        velocity: 2.62,
        velocity_offset: 0.25,
        deceleration: 2.585,
        effort: 87.0,
    },
    JointLimits {
        lower: -2.9007,
        upper: 2.9007,
        velocity: 2.62,
        velocity_offset: 0.2005,
        deceleration: 3.5,
        effort: 87.0,
    },
    JointLimits {
        lower: -3.077,
        upper: -0.1169,
        velocity: 2.62,
        velocity_offset: 0.3542,
        deceleration: 4.0,
        effort: 87.0,
    },
    JointLimits {
        lower: -2.8763,
        upper: 2.8763,
        velocity: 5.26,
        velocity_offset: 0.5738,
        deceleration: 17.0,
        effort: 12.0,
    },
    JointLimits {
        lower: 0.4398,
        upper: 4.6216,
        velocity: 4.18,
        velocity_offset: 0.4885,
        deceleration: 5.5,
        effort: 12.0,
    },
    JointLimits {
        lower: -3.0508,
        upper: 3.0508,
        velocity: 5.26,
        velocity_offset: 0.4592,
        deceleration: 17.0,
        effort: 12.0,
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_limits_shrink_towards_the_position_limits() {
        let j = FR3[0];
        // Mid-range: the joint's maximum.
        assert_eq!(j.upper_velocity(0.0), 2.62);
        assert_eq!(j.lower_velocity(0.0), -2.62);
        // At the upper limit it may not move up at all, but down at full speed.
        assert_eq!(j.upper_velocity(j.upper), 0.0);
        assert_eq!(j.lower_velocity(j.upper), -2.62);
        // 0.1 rad before the limit: √(2·6·0.1) − 0.652 = 0.4434.
        let v = j.upper_velocity(j.upper - 0.1);
        assert!((v - (1.2f64.sqrt() - 0.652)).abs() < 1e-12, "{v}");
        assert!((j.lower_velocity(j.lower + 0.1) + v).abs() < 1e-12);
    }
}
