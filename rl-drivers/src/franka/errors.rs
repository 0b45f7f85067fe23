//! The robot's errors and reflexes: 41 flags in every state record, `errors` (active now) and
//! `reflex_reason` (why the last motion was stopped, libfranka's `last_motion_errors`), in the
//! order of libfranka-common's `research_interface::robot::Error` (`error.h`), named as
//! libfranka names them (`getErrorName`).
//!
//! [`ErrorSet`] holds one record's flags in a `u64`; [`ReflexCounts`] counts, per error, how
//! often it was raised (a flag that goes from clear to set), so a report can say what stopped
//! the arm and how often.

use core::fmt;

/// Number of error flags in a state record.
pub const ERROR_COUNT: usize = 41;

macro_rules! robot_errors {
    ($($(#[$meta:meta])* $variant:ident = $index:literal => $name:literal),+ $(,)?) => {
        /// One of the robot's errors (the index of its flag).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum RobotError {
            $($(#[$meta])* $variant = $index),+
        }

        impl RobotError {
            /// Every error, in flag order.
            pub const ALL: [RobotError; ERROR_COUNT] = [$(RobotError::$variant),+];

            /// libfranka's name (`getErrorName`).
            pub const fn name(self) -> &'static str {
                match self {
                    $(RobotError::$variant => $name),+
                }
            }
        }
    };
}

robot_errors! {
    /// The robot moved past the joint limits.
    JointPositionLimitsViolation = 0 => "joint_position_limits_violation",
    /// The robot moved past a virtual wall.
    CartesianPositionLimitsViolation = 1 => "cartesian_position_limits_violation",
    /// The robot would have collided with itself.
    SelfCollisionAvoidanceViolation = 2 => "self_collision_avoidance_violation",
    /// The robot exceeded the joint velocity limits.
    JointVelocityViolation = 3 => "joint_velocity_violation",
    /// The robot exceeded the Cartesian velocity limits.
    CartesianVelocityViolation = 4 => "cartesian_velocity_violation",
    /// The robot exceeded a safety threshold during force control.
    ForceControlSafetyViolation = 5 => "force_control_safety_violation",
    /// A collision: a joint torque threshold was exceeded.
    JointReflex = 6 => "joint_reflex",
    /// A collision: a Cartesian force threshold was exceeded.
    CartesianReflex = 7 => "cartesian_reflex",
    /// The internal motion generator did not reach the goal pose.
    MaxGoalPoseDeviationViolation = 8 => "max_goal_pose_deviation_violation",
    /// The internal motion generator deviated from the path.
    MaxPathPoseDeviationViolation = 9 => "max_path_pose_deviation_violation",
    /// The Cartesian velocity profile was violated.
    CartesianVelocityProfileSafetyViolation = 10 => "cartesian_velocity_profile_safety_violation",
    /// The joint position motion generator's first command was not the robot's position.
    JointPositionMotionGeneratorStartPoseInvalid = 11 => "joint_position_motion_generator_start_pose_invalid",
    /// The joint motion generator commanded a position beyond the limits.
    JointMotionGeneratorPositionLimitsViolation = 12 => "joint_motion_generator_position_limits_violation",
    /// The joint motion generator commanded a velocity beyond the limits.
    JointMotionGeneratorVelocityLimitsViolation = 13 => "joint_motion_generator_velocity_limits_violation",
    /// The joint motion generator's velocity jumped (acceleration beyond the limits).
    JointMotionGeneratorVelocityDiscontinuity = 14 => "joint_motion_generator_velocity_discontinuity",
    /// The joint motion generator's acceleration jumped (jerk beyond the limits).
    JointMotionGeneratorAccelerationDiscontinuity = 15 => "joint_motion_generator_acceleration_discontinuity",
    /// The Cartesian position motion generator's first command was not the robot's pose.
    CartesianPositionMotionGeneratorStartPoseInvalid = 16 => "cartesian_position_motion_generator_start_pose_invalid",
    /// The Cartesian motion generator commanded an elbow beyond its limits.
    CartesianMotionGeneratorElbowLimitViolation = 17 => "cartesian_motion_generator_elbow_limit_violation",
    /// The Cartesian motion generator commanded a velocity beyond the limits.
    CartesianMotionGeneratorVelocityLimitsViolation = 18 => "cartesian_motion_generator_velocity_limits_violation",
    /// The Cartesian motion generator's velocity jumped.
    CartesianMotionGeneratorVelocityDiscontinuity = 19 => "cartesian_motion_generator_velocity_discontinuity",
    /// The Cartesian motion generator's acceleration jumped.
    CartesianMotionGeneratorAccelerationDiscontinuity = 20 => "cartesian_motion_generator_acceleration_discontinuity",
    /// The commanded elbow sign changed.
    CartesianMotionGeneratorElbowSignInconsistent = 21 => "cartesian_motion_generator_elbow_sign_inconsistent",
    /// The first elbow command was not the robot's elbow.
    CartesianMotionGeneratorStartElbowInvalid = 22 => "cartesian_motion_generator_start_elbow_invalid",
    /// The force controller's desired force was not held.
    ForceControllerDesiredForceToleranceViolation = 23 => "force_controller_desired_force_tolerance_violation",
    /// The elbow sign at the start was inconsistent.
    StartElbowSignInconsistent = 24 => "start_elbow_sign_inconsistent",
    /// Commands were lost: too many in a row missed their cycle.
    CommunicationConstraintsViolation = 25 => "communication_constraints_violation",
    /// The robot exceeded its power limit.
    PowerLimitViolation = 26 => "power_limit_violation",
    /// The Cartesian motion generator's inverse kinematics left the joint limits.
    CartesianMotionGeneratorJointPositionLimitsViolation = 27 => "cartesian_motion_generator_joint_position_limits_violation",
    /// The Cartesian motion generator's joint velocities exceeded the limits.
    CartesianMotionGeneratorJointVelocityLimitsViolation = 28 => "cartesian_motion_generator_joint_velocity_limits_violation",
    /// The Cartesian motion generator's joint velocities jumped.
    CartesianMotionGeneratorJointVelocityDiscontinuity = 29 => "cartesian_motion_generator_joint_velocity_discontinuity",
    /// The Cartesian motion generator's joint accelerations jumped.
    CartesianMotionGeneratorJointAccelerationDiscontinuity = 30 => "cartesian_motion_generator_joint_acceleration_discontinuity",
    /// The Cartesian pose command is not a valid homogeneous transform.
    CartesianPositionMotionGeneratorInvalidFrame = 31 => "cartesian_position_motion_generator_invalid_frame_flag",
    /// The commanded torque jumped (torque rate beyond the limit).
    ControllerTorqueDiscontinuity = 32 => "controller_torque_discontinuity",
    /// The joint point-to-point motion lacked the torque to plan.
    JointP2PInsufficientTorqueForPlanning = 33 => "joint_p2p_insufficient_torque_for_planning",
    /// A measured joint torque left its range.
    TauJRangeViolation = 34 => "tau_J_range_violation",
    /// An instability was detected.
    InstabilityDetection = 35 => "instability_detected",
    /// A joint moved in the wrong direction.
    JointMoveInWrongDirection = 36 => "joint_move_in_wrong_direction",
    /// The Cartesian spline motion generator failed.
    CartesianSplineViolation = 37 => "cartesian_spline_motion_generator_violation",
    /// The joint via-point planner hit a joint limit.
    JointViaPlanLimitViolation = 38 => "joint_via_motion_generator_planning_joint_limit_violation",
    /// The base accelerometer did not initialise in time.
    BaseAccelerationInitializationTimeout = 39 => "base_acceleration_initialization_timeout",
    /// The base accelerometer reading is invalid.
    BaseAccelerationInvalidReading = 40 => "base_acceleration_invalid_reading",
}

impl RobotError {
    /// The error of flag `index`.
    pub const fn from_index(index: usize) -> Option<Self> {
        if index < ERROR_COUNT {
            Some(Self::ALL[index])
        } else {
            None
        }
    }

    /// Its flag's index.
    pub const fn index(self) -> usize {
        self as usize
    }

    /// Whether it is a communication error (the client's loop or the network, not the arm).
    pub const fn is_communication(self) -> bool {
        matches!(self, Self::CommunicationConstraintsViolation)
    }

    /// Whether it says the commanded signal jumped (a discontinuity in position, velocity or
    /// torque), which a client's motion generator or a lost packet causes.
    pub const fn is_discontinuity(self) -> bool {
        matches!(
            self,
            Self::JointMotionGeneratorVelocityDiscontinuity
                | Self::JointMotionGeneratorAccelerationDiscontinuity
                | Self::CartesianMotionGeneratorVelocityDiscontinuity
                | Self::CartesianMotionGeneratorAccelerationDiscontinuity
                | Self::CartesianMotionGeneratorJointVelocityDiscontinuity
                | Self::CartesianMotionGeneratorJointAccelerationDiscontinuity
                | Self::ControllerTorqueDiscontinuity
        )
    }

    /// Whether it is a limit violation (position, velocity, torque, power).
    pub const fn is_limit_violation(self) -> bool {
        matches!(
            self,
            Self::JointPositionLimitsViolation
                | Self::CartesianPositionLimitsViolation
                | Self::JointVelocityViolation
                | Self::CartesianVelocityViolation
                | Self::JointMotionGeneratorPositionLimitsViolation
                | Self::JointMotionGeneratorVelocityLimitsViolation
                | Self::CartesianMotionGeneratorElbowLimitViolation
                | Self::CartesianMotionGeneratorVelocityLimitsViolation
                | Self::PowerLimitViolation
                | Self::CartesianMotionGeneratorJointPositionLimitsViolation
                | Self::CartesianMotionGeneratorJointVelocityLimitsViolation
                | Self::TauJRangeViolation
        )
    }
}

impl fmt::Display for RobotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A record's 41 flags.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ErrorSet(u64);

impl ErrorSet {
    /// No error.
    pub const EMPTY: Self = Self(0);

    /// The set of the flags in `flags`.
    pub fn from_flags(flags: &[bool; ERROR_COUNT]) -> Self {
        Self(
            flags
                .iter()
                .enumerate()
                .filter(|(_, on)| **on)
                .fold(0, |bits, (i, _)| bits | (1 << i)),
        )
    }

    /// The flags.
    pub fn to_flags(self) -> [bool; ERROR_COUNT] {
        core::array::from_fn(|i| self.0 & (1 << i) != 0)
    }

    /// This set with `e` added.
    #[must_use]
    pub const fn with(self, e: RobotError) -> Self {
        Self(self.0 | (1 << e as u64))
    }

    /// Both sets' flags.
    #[must_use]
    pub const fn union(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// Whether `e` is set.
    pub const fn contains(self, e: RobotError) -> bool {
        self.0 & (1 << e as u64) != 0
    }

    /// Whether no flag is set.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Number of flags set.
    pub const fn len(self) -> u32 {
        self.0.count_ones()
    }

    /// The flags set in `self` but not in `before`.
    #[must_use]
    pub const fn raised_since(self, before: Self) -> Self {
        Self(self.0 & !before.0)
    }

    /// The errors set, in flag order.
    pub fn iter(self) -> impl Iterator<Item = RobotError> {
        RobotError::ALL
            .into_iter()
            .filter(move |e| self.contains(*e))
    }

    /// The first error set, if any.
    pub fn first(self) -> Option<RobotError> {
        self.iter().next()
    }
}

impl fmt::Display for ErrorSet {
    /// libfranka's form: `["joint_reflex", "communication_constraints_violation"]`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("[")?;
        for (k, e) in self.iter().enumerate() {
            if k > 0 {
                f.write_str(", ")?;
            }
            write!(f, "\"{}\"", e.name())?;
        }
        f.write_str("]")
    }
}

/// How often each error was raised (a flag going from clear to set in consecutive records).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReflexCounts {
    counts: [u32; ERROR_COUNT],
    last: ErrorSet,
}

impl Default for ReflexCounts {
    fn default() -> Self {
        Self {
            counts: [0; ERROR_COUNT],
            last: ErrorSet::EMPTY,
        }
    }
}

impl ReflexCounts {
    /// Takes one record's flags; returns the errors raised by it.
    pub fn record(&mut self, now: ErrorSet) -> ErrorSet {
        let raised = now.raised_since(self.last);
        for e in raised.iter() {
            self.counts[e.index()] = self.counts[e.index()].saturating_add(1);
        }
        self.last = now;
        raised
    }

    /// How often `e` was raised.
    pub const fn count(&self, e: RobotError) -> u32 {
        self.counts[e as usize]
    }

    /// Raisings of every error together.
    pub fn total(&self) -> u64 {
        self.counts.iter().map(|&c| u64::from(c)).sum()
    }

    /// Each error raised at least once, with its count.
    pub fn iter(&self) -> impl Iterator<Item = (RobotError, u32)> + '_ {
        RobotError::ALL
            .into_iter()
            .map(|e| (e, self.counts[e.index()]))
            .filter(|(_, c)| *c > 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_map_to_libfrankas_names_and_order() {
        assert_eq!(RobotError::ALL.len(), 41);
        for (i, e) in RobotError::ALL.iter().enumerate() {
            assert_eq!(e.index(), i);
        }
        assert_eq!(
            RobotError::from_index(25),
            Some(RobotError::CommunicationConstraintsViolation)
        );
        assert_eq!(RobotError::from_index(41), None);
        let mut flags = [false; ERROR_COUNT];
        flags[6] = true;
        flags[25] = true;
        let s = ErrorSet::from_flags(&flags);
        assert_eq!(s.to_flags(), flags);
        assert_eq!(
            s.to_string(),
            "[\"joint_reflex\", \"communication_constraints_violation\"]"
        );
        assert_eq!(ErrorSet::EMPTY.to_string(), "[]");
    }

    #[test]
    fn raisings_are_counted_once_per_rising_edge() {
        let mut c = ReflexCounts::default();
        let reflex = ErrorSet::EMPTY.with(RobotError::JointReflex);
        assert_eq!(c.record(reflex), reflex);
        assert_eq!(
            c.record(reflex),
            ErrorSet::EMPTY,
            "still set: not raised again"
        );
        c.record(ErrorSet::EMPTY);
        c.record(reflex.with(RobotError::PowerLimitViolation));
        assert_eq!(c.count(RobotError::JointReflex), 2);
        assert_eq!(c.count(RobotError::PowerLimitViolation), 1);
        assert_eq!(c.total(), 3);
        assert_eq!(c.iter().count(), 2);
    }
}
