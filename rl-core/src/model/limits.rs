//! Joint limits, per degree of freedom.

/// Limits of one degree of freedom, in SI units (rad or m, rad/s or m/s, N·m or N).
///
/// Missing limits are infinite, as RL makes them. Position limits apply to coordinates that
/// are a plain number (not to the quaternion part of spherical and six-DOF joints).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointLimits {
    /// Lowest position.
    pub lower: f64,
    /// Highest position.
    pub upper: f64,
    /// Largest speed (absolute value); infinite when unknown.
    pub velocity: f64,
    /// Largest effort (absolute value); infinite when unknown.
    pub effort: f64,
    /// The coordinate is an angle that wraps around (a continuous joint); position limits do
    /// not apply.
    pub wraparound: bool,
}

impl Default for JointLimits {
    fn default() -> Self {
        Self::UNLIMITED
    }
}

impl JointLimits {
    /// No limits at all.
    pub const UNLIMITED: Self = Self {
        lower: f64::NEG_INFINITY,
        upper: f64::INFINITY,
        velocity: f64::INFINITY,
        effort: f64::INFINITY,
        wraparound: false,
    };

    /// Whether position `x` is within `[lower, upper]` (always for wraparound joints).
    pub fn contains(&self, x: f64) -> bool {
        self.wraparound || (x >= self.lower && x <= self.upper)
    }

    /// `x` clamped into `[lower, upper]`, or wrapped into `[-π, π)` for wraparound joints.
    pub fn clamp(&self, x: f64) -> f64 {
        if self.wraparound {
            let two_pi = 2.0 * core::f64::consts::PI;
            x - two_pi * libm::floor((x + core::f64::consts::PI) / two_pi)
        } else {
            x.clamp(self.lower, self.upper)
        }
    }

    /// Whether both position limits are finite.
    pub fn is_bounded(&self) -> bool {
        !self.wraparound && self.lower.is_finite() && self.upper.is_finite()
    }
}
