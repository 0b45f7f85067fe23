//! Why a trajectory could not be generated: what, and which axis.

use core::fmt;

/// A quantity of the input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Current position.
    CurrentPosition,
    /// Current velocity.
    CurrentVelocity,
    /// Current acceleration.
    CurrentAcceleration,
    /// Target position.
    TargetPosition,
    /// Target velocity.
    TargetVelocity,
    /// Target acceleration.
    TargetAcceleration,
    /// An intermediate waypoint's position.
    Waypoint,
    /// The minimum duration.
    MinimumDuration,
}

/// A limit of the input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// Maximum velocity (must be ≥ 0).
    MaxVelocity,
    /// Minimum velocity (must be ≤ 0).
    MinVelocity,
    /// Maximum acceleration (must be ≥ 0).
    MaxAcceleration,
    /// Minimum acceleration (must be ≤ 0).
    MinAcceleration,
    /// Maximum jerk (must be ≥ 0).
    MaxJerk,
    /// Position limits (minimum ≤ maximum, not NaN).
    Position,
}

/// Why the generator could not produce a trajectory. Every variant names the axis (or waypoint)
/// at fault; none leaves a NaN behind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OtgError {
    /// A state value is NaN or infinite.
    NotFinite {
        /// Which value.
        quantity: Quantity,
        /// Axis.
        axis: usize,
    },
    /// A limit has the wrong sign or is NaN.
    BadLimit {
        /// Which limit.
        limit: Limit,
        /// Axis.
        axis: usize,
    },
    /// The target velocity or acceleration is beyond the limits, or the target cannot be
    /// approached within them (its acceleration implies a velocity beyond the limits).
    TargetOutsideLimits {
        /// Which value.
        quantity: Quantity,
        /// Axis.
        axis: usize,
    },
    /// A zero jerk or acceleration limit leaves the axis with its current acceleration, which
    /// does not reach the target (or conflicts with the other axes' duration).
    ZeroLimits {
        /// Axis.
        axis: usize,
    },
    /// No time-optimal profile was found for the axis (a numerical failure: please report the
    /// input).
    NoProfile {
        /// Axis.
        axis: usize,
    },
    /// No profile of the synchronised duration was found for the axis (numerical failure:
    /// please report the input).
    NoSynchronization {
        /// Axis.
        axis: usize,
        /// The duration in seconds.
        duration: f64,
    },
    /// No duration suits all axes (only possible with zero limits on some axis).
    NoCommonDuration,
    /// The current position is outside the position limits.
    CurrentOutsidePositionLimits {
        /// Axis.
        axis: usize,
    },
    /// The target (or a waypoint) is outside the position limits.
    TargetOutsidePositionLimits {
        /// Axis.
        axis: usize,
    },
    /// The axis moves too fast to stop before its position limit.
    CannotStopBeforePositionLimit {
        /// Axis.
        axis: usize,
    },
    /// The target state cannot be reached without crossing a position limit (its velocity
    /// cannot be built up or taken away inside them).
    PositionLimitsUnreachable {
        /// Axis.
        axis: usize,
    },
    /// More intermediate waypoints than the capacity.
    TooManyWaypoints {
        /// Capacity.
        capacity: usize,
    },
    /// Waypoints are for [`super::calculate_waypoints`] (not [`super::calculate`] nor the
    /// online [`super::Otg`]), with the position interface and no minimum duration.
    WaypointsUnsupported,
    /// The duration is not finite (limits too small for the distance).
    DurationNotFinite,
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::CurrentPosition => "current position",
            Self::CurrentVelocity => "current velocity",
            Self::CurrentAcceleration => "current acceleration",
            Self::TargetPosition => "target position",
            Self::TargetVelocity => "target velocity",
            Self::TargetAcceleration => "target acceleration",
            Self::Waypoint => "waypoint",
            Self::MinimumDuration => "minimum duration",
        })
    }
}

impl fmt::Display for Limit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::MaxVelocity => "maximum velocity must be >= 0",
            Self::MinVelocity => "minimum velocity must be <= 0",
            Self::MaxAcceleration => "maximum acceleration must be >= 0",
            Self::MinAcceleration => "minimum acceleration must be <= 0",
            Self::MaxJerk => "maximum jerk must be >= 0",
            Self::Position => "position limits must satisfy min <= max",
        })
    }
}

impl fmt::Display for OtgError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NotFinite { quantity, axis } => {
                write!(f, "{quantity} of axis {axis} is not finite")
            }
            Self::BadLimit { limit, axis } => write!(f, "axis {axis}: {limit}"),
            Self::TargetOutsideLimits { quantity, axis } => {
                write!(f, "{quantity} of axis {axis} is outside its limits")
            }
            Self::ZeroLimits { axis } => write!(
                f,
                "axis {axis}: a zero jerk or acceleration limit keeps the current acceleration, which does not reach the target"
            ),
            Self::NoProfile { axis } => write!(f, "axis {axis}: no time-optimal profile found"),
            Self::NoSynchronization { axis, duration } => {
                write!(
                    f,
                    "axis {axis}: no profile of the synchronised duration {duration} s"
                )
            }
            Self::NoCommonDuration => f.write_str("no duration suits every axis"),
            Self::CurrentOutsidePositionLimits { axis } => {
                write!(
                    f,
                    "current position of axis {axis} is outside its position limits"
                )
            }
            Self::TargetOutsidePositionLimits { axis } => {
                write!(f, "target of axis {axis} is outside its position limits")
            }
            Self::CannotStopBeforePositionLimit { axis } => {
                write!(f, "axis {axis} cannot stop before its position limit")
            }
            Self::PositionLimitsUnreachable { axis } => write!(
                f,
                "axis {axis}: the target state cannot be reached inside the position limits"
            ),
            Self::TooManyWaypoints { capacity } => {
                write!(f, "more than {capacity} intermediate waypoints")
            }
            Self::WaypointsUnsupported => f.write_str(
                "waypoints need calculate_waypoints, the position interface and no minimum duration",
            ),
            Self::DurationNotFinite => f.write_str("the trajectory duration is not finite"),
        }
    }
}

impl core::error::Error for OtgError {}
