//! What the generator is asked: the current and target state of `N` axes, their limits, the
//! interface, the synchronisation, waypoints and a minimum duration; and its validation.

use super::error::{Limit, OtgError, Quantity};

/// Most intermediate waypoints one input holds.
pub const MAX_WAYPOINTS: usize = 8;

/// Position, velocity and acceleration of `N` axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State<const N: usize> {
    /// Position of each axis.
    pub position: [f64; N],
    /// Velocity of each axis.
    pub velocity: [f64; N],
    /// Acceleration of each axis.
    pub acceleration: [f64; N],
}

impl<const N: usize> State<N> {
    /// At rest at `position`.
    pub const fn at_rest(position: [f64; N]) -> Self {
        Self {
            position,
            velocity: [0.0; N],
            acceleration: [0.0; N],
        }
    }
}

/// Kinematic limits of `N` axes. Velocity, acceleration and jerk limits may be
/// `f64::INFINITY` (that derivative is then free: an infinite jerk limit lets the acceleration
/// jump, an infinite acceleration limit the velocity) or zero (see the module docs). Position
/// limits default to `±∞`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits<const N: usize> {
    /// Largest velocity (≥ 0).
    pub max_velocity: [f64; N],
    /// Smallest velocity (≤ 0).
    pub min_velocity: [f64; N],
    /// Largest acceleration (≥ 0).
    pub max_acceleration: [f64; N],
    /// Smallest acceleration (≤ 0).
    pub min_acceleration: [f64; N],
    /// Largest jerk magnitude (≥ 0).
    pub max_jerk: [f64; N],
    /// Smallest position.
    pub min_position: [f64; N],
    /// Largest position.
    pub max_position: [f64; N],
}

impl<const N: usize> Limits<N> {
    /// Symmetric limits `|v| ≤ velocity`, `|a| ≤ acceleration`, `|j| ≤ jerk` per axis, no
    /// position limits.
    pub const fn new(velocity: [f64; N], acceleration: [f64; N], jerk: [f64; N]) -> Self {
        let mut min_velocity = [0.0; N];
        let mut min_acceleration = [0.0; N];
        let mut i = 0;
        while i < N {
            min_velocity[i] = -velocity[i];
            min_acceleration[i] = -acceleration[i];
            i += 1;
        }
        Self {
            max_velocity: velocity,
            min_velocity,
            max_acceleration: acceleration,
            min_acceleration,
            max_jerk: jerk,
            min_position: [f64::NEG_INFINITY; N],
            max_position: [f64::INFINITY; N],
        }
    }

    /// The same symmetric limits on every axis.
    pub const fn uniform(velocity: f64, acceleration: f64, jerk: f64) -> Self {
        Self::new([velocity; N], [acceleration; N], [jerk; N])
    }

    /// These limits with position limits `[min, max]` per axis.
    pub const fn with_positions(mut self, min: [f64; N], max: [f64; N]) -> Self {
        self.min_position = min;
        self.max_position = max;
        self
    }
}

/// What the target prescribes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Interface {
    /// Reach the target position, velocity and acceleration.
    #[default]
    Position,
    /// Reach the target velocity and acceleration; the position is free (and the velocity
    /// limits do not apply: this is how an axis stops or follows a velocity).
    Velocity,
}

/// How the axes share one duration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Synchronization {
    /// All axes reach their targets at the same time, the earliest time all of them can.
    #[default]
    Time,
    /// As `Time`, but axes whose target is at rest may arrive earlier (their own shortest time).
    TimeIfNecessary,
    /// As `Time`, and where the axes' start and target are collinear (straight lines in joint
    /// space), every axis follows the same profile scaled: the motion stays on the line.
    /// Otherwise the same as `Time`.
    Phase,
    /// Every axis takes its own shortest time.
    None,
}

/// Up to [`MAX_WAYPOINTS`] intermediate positions to pass through, in order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Waypoints<const N: usize> {
    points: [[f64; N]; MAX_WAYPOINTS],
    len: usize,
}

impl<const N: usize> Default for Waypoints<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Waypoints<N> {
    /// None.
    pub const fn new() -> Self {
        Self {
            points: [[0.0; N]; MAX_WAYPOINTS],
            len: 0,
        }
    }

    /// Appends a waypoint; hands it back when full.
    pub fn push(&mut self, point: [f64; N]) -> Result<(), [f64; N]> {
        if self.len == MAX_WAYPOINTS {
            return Err(point);
        }
        self.points[self.len] = point;
        self.len += 1;
        Ok(())
    }

    /// The waypoints in order.
    pub fn as_slice(&self) -> &[[f64; N]] {
        &self.points[..self.len]
    }

    /// Number of waypoints.
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` without waypoints.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Removes all.
    pub fn clear(&mut self) {
        self.len = 0;
    }
}

/// One request to the generator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Input<const N: usize> {
    /// Where the axes are.
    pub current: State<N>,
    /// Where they should be (for [`Interface::Velocity`] the position is ignored).
    pub target: State<N>,
    /// Kinematic and position limits.
    pub limits: Limits<N>,
    /// Position or velocity target.
    pub interface: Interface,
    /// How the axes share the duration.
    pub synchronization: Synchronization,
    /// The trajectory takes at least this long (seconds).
    pub minimum_duration: Option<f64>,
    /// Positions to pass through on the way (position interface).
    pub waypoints: Waypoints<N>,
}

impl<const N: usize> Input<N> {
    /// From `current` to `target` under `limits`, time-synchronised, position interface.
    pub const fn new(current: State<N>, target: State<N>, limits: Limits<N>) -> Self {
        Self {
            current,
            target,
            limits,
            interface: Interface::Position,
            synchronization: Synchronization::Time,
            minimum_duration: None,
            waypoints: Waypoints::new(),
        }
    }

    /// Checks every value; the first problem found is returned (axis order, then quantity).
    ///
    /// The current state may be beyond the velocity and acceleration limits (the trajectory
    /// brakes back within them first). The target must be within them, and for a position
    /// target with an acceleration the velocity while that acceleration is taken away at full
    /// jerk must be within them too (otherwise no profile can arrive there inside the limits).
    pub fn validate(&self) -> Result<(), OtgError> {
        let l = &self.limits;
        let velocity_interface = self.interface == Interface::Velocity;
        if let Some(d) = self.minimum_duration
            && !(d >= 0.0 && d.is_finite())
        {
            return Err(OtgError::NotFinite {
                quantity: Quantity::MinimumDuration,
                axis: 0,
            });
        }
        for axis in 0..N {
            let bad = |limit| Err(OtgError::BadLimit { limit, axis });
            let (v_max, v_min) = (l.max_velocity[axis], l.min_velocity[axis]);
            let (a_max, a_min) = (l.max_acceleration[axis], l.min_acceleration[axis]);
            let j = l.max_jerk[axis];
            if !(j >= 0.0) {
                return bad(Limit::MaxJerk);
            }
            if !(a_max >= 0.0) {
                return bad(Limit::MaxAcceleration);
            }
            if !(a_min <= 0.0) {
                return bad(Limit::MinAcceleration);
            }
            if !(v_max >= 0.0) {
                return bad(Limit::MaxVelocity);
            }
            if !(v_min <= 0.0) {
                return bad(Limit::MinVelocity);
            }
            let (p_min, p_max) = (l.min_position[axis], l.max_position[axis]);
            if !(p_min <= p_max) {
                return bad(Limit::Position);
            }
            let values = [
                (self.current.position[axis], Quantity::CurrentPosition),
                (self.current.velocity[axis], Quantity::CurrentVelocity),
                (
                    self.current.acceleration[axis],
                    Quantity::CurrentAcceleration,
                ),
                (self.target.position[axis], Quantity::TargetPosition),
                (self.target.velocity[axis], Quantity::TargetVelocity),
                (self.target.acceleration[axis], Quantity::TargetAcceleration),
            ];
            for (value, quantity) in values {
                let ignored = velocity_interface && quantity == Quantity::TargetPosition;
                if !ignored && !value.is_finite() {
                    return Err(OtgError::NotFinite { quantity, axis });
                }
            }
            let (vf, af) = (self.target.velocity[axis], self.target.acceleration[axis]);
            let outside = |quantity| Err(OtgError::TargetOutsideLimits { quantity, axis });
            if af > a_max || af < a_min {
                return outside(Quantity::TargetAcceleration);
            }
            if !velocity_interface {
                if vf > v_max || vf < v_min {
                    return outside(Quantity::TargetVelocity);
                }
                // Arriving with acceleration af ≠ 0 at full jerk, the velocity before was
                // vf + af²/(2j) (af < 0) or vf − af²/(2j) (af > 0).
                if j > 0.0 && j.is_finite() {
                    let swing = af * af / (2.0 * j);
                    if (af < 0.0 && vf + swing > v_max) || (af > 0.0 && vf - swing < v_min) {
                        return outside(Quantity::TargetAcceleration);
                    }
                }
            }
        }
        for point in self.waypoints.as_slice() {
            for (axis, value) in point.iter().enumerate() {
                if !value.is_finite() {
                    return Err(OtgError::NotFinite {
                        quantity: Quantity::Waypoint,
                        axis,
                    });
                }
            }
        }
        Ok(())
    }
}
