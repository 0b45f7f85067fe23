//! Typed, `Copy` errors of trajectory construction.

use core::fmt;

/// Which kinematic limit was bad.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitKind {
    /// Velocity limit.
    Velocity,
    /// Acceleration limit.
    Acceleration,
    /// Jerk limit.
    Jerk,
}

/// Why a trajectory could not be built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrajectoryError {
    /// `times[index]` is not greater than the time before it.
    NonIncreasingTime {
        /// Index of the offending time.
        index: usize,
    },
    /// A limit is zero, negative or NaN (or infinite where the profile needs a finite one).
    BadLimit {
        /// Axis of the limit.
        axis: usize,
        /// Which limit.
        kind: LimitKind,
    },
    /// An input value is NaN or infinite.
    NotFinite {
        /// What the value is (`"waypoint"`, `"time"`, `"duration"`, ...).
        what: &'static str,
        /// Index of the waypoint, time or axis.
        index: usize,
    },
    /// More segments (or waypoints) than the fixed capacity holds.
    Capacity {
        /// The capacity of the type.
        capacity: usize,
        /// What the input needs.
        requested: usize,
    },
    /// Fewer waypoints than the construction needs.
    TooFewWaypoints {
        /// Minimum number.
        required: usize,
        /// Number given.
        given: usize,
    },
    /// The constraints cannot be met (e.g. a motion with no finite limit to bound its speed).
    Unreachable,
    /// A duration is negative, zero where motion is required, or not finite.
    BadDuration,
    /// Blends around waypoint `waypoint` overlap their neighbours or exceed the segment.
    BlendTooLong {
        /// The waypoint whose blend does not fit.
        waypoint: usize,
    },
    /// Geometry without a unique answer (collinear arc points, coincident points).
    Degenerate,
    /// Position and rotation parts of a pose trajectory have different durations.
    DurationMismatch,
}

impl fmt::Display for TrajectoryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NonIncreasingTime { index } => {
                write!(f, "time {index} is not greater than the time before it")
            }
            Self::BadLimit { axis, kind } => {
                write!(
                    f,
                    "{kind:?} limit of axis {axis} must be finite and positive"
                )
            }
            Self::NotFinite { what, index } => write!(f, "{what} {index} is not finite"),
            Self::Capacity {
                capacity,
                requested,
            } => {
                write!(
                    f,
                    "needs {requested} segments but the capacity is {capacity}"
                )
            }
            Self::TooFewWaypoints { required, given } => {
                write!(f, "needs at least {required} waypoints, got {given}")
            }
            Self::Unreachable => f.write_str("the constraints cannot be met"),
            Self::BadDuration => f.write_str("duration must be finite and positive"),
            Self::BlendTooLong { waypoint } => {
                write!(
                    f,
                    "blend at waypoint {waypoint} does not fit between its neighbours"
                )
            }
            Self::Degenerate => f.write_str("degenerate geometry (collinear or coincident points)"),
            Self::DurationMismatch => {
                f.write_str("position and rotation trajectories have different durations")
            }
        }
    }
}

/// A jump found by a continuity check.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Discontinuity {
    /// Index of the boundary (between segment `boundary` and `boundary + 1`).
    pub boundary: usize,
    /// Derivative order that jumps.
    pub order: usize,
    /// Axis that jumps.
    pub axis: usize,
    /// Size of the jump (right minus left).
    pub jump: f64,
}

impl fmt::Display for Discontinuity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "derivative {} of axis {} jumps by {} at boundary {}",
            self.order, self.axis, self.jump, self.boundary
        )
    }
}

impl core::error::Error for TrajectoryError {}

impl core::error::Error for Discontinuity {}
