//! Cartesian pose trajectories: a position trajectory and a rotation trajectory over the same
//! time, giving the pose with its twist and acceleration in the world frame.

use glam::{DQuat, DVec3};

use super::{RotationTrajectory, Trajectory, TrajectoryError};

/// Pose, twist and acceleration at one time, all in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseSample {
    /// Position of the frame origin.
    pub position: DVec3,
    /// Orientation (world from frame).
    pub orientation: DQuat,
    /// Velocity of the frame origin.
    pub linear_velocity: DVec3,
    /// Angular velocity.
    pub angular_velocity: DVec3,
    /// Acceleration of the frame origin (classical, the second derivative of the position).
    pub linear_acceleration: DVec3,
    /// Angular acceleration.
    pub angular_acceleration: DVec3,
}

impl PoseSample {
    /// Twist `[v; ω]` (RL's Jacobian row order: linear then angular).
    pub fn twist(&self) -> [f64; 6] {
        let (v, w) = (self.linear_velocity, self.angular_velocity);
        [v.x, v.y, v.z, w.x, w.y, w.z]
    }

    /// Spatial acceleration (Featherstone) of the moving frame at its origin, world-aligned
    /// axes, `[a - ω × v; α]` (linear first, as RL): the classical acceleration minus the
    /// velocity-product term.
    pub fn spatial_acceleration(&self) -> [f64; 6] {
        let a = self.linear_acceleration - self.angular_velocity.cross(self.linear_velocity);
        let b = self.angular_acceleration;
        [a.x, a.y, a.z, b.x, b.y, b.z]
    }

    /// Classical acceleration `[a; α]` of the frame origin, the target of `J q̈ + J̇ q̇`.
    pub fn acceleration(&self) -> [f64; 6] {
        let (a, b) = (self.linear_acceleration, self.angular_acceleration);
        [a.x, a.y, a.z, b.x, b.y, b.z]
    }
}

/// A position trajectory `P` and a rotation trajectory `R` of equal duration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseTrajectory<P, R> {
    position: P,
    rotation: R,
}

impl<P: Trajectory<3>, R: RotationTrajectory> PoseTrajectory<P, R> {
    /// Joins the two parts; their durations must agree to 1e-9 relative.
    pub fn new(position: P, rotation: R) -> Result<Self, TrajectoryError> {
        let (a, b) = (position.duration(), rotation.duration());
        if !(libm::fabs(a - b) <= 1e-9 * a.max(b).max(1e-9)) {
            return Err(TrajectoryError::DurationMismatch);
        }
        Ok(Self { position, rotation })
    }

    /// Duration in seconds.
    pub fn duration(&self) -> f64 {
        self.position.duration()
    }

    /// The position part.
    pub fn position_part(&self) -> &P {
        &self.position
    }

    /// The rotation part.
    pub fn rotation_part(&self) -> &R {
        &self.rotation
    }

    /// Pose, twist and acceleration at `t`.
    pub fn sample(&self, t: f64) -> PoseSample {
        let p = self.position.sample(t);
        let r = self.rotation.rotation(t);
        PoseSample {
            position: DVec3::from_array(p.position),
            orientation: r.orientation,
            linear_velocity: DVec3::from_array(p.velocity),
            angular_velocity: r.angular_velocity,
            linear_acceleration: DVec3::from_array(p.acceleration),
            angular_acceleration: r.angular_acceleration,
        }
    }
}
