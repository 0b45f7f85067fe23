//! Rotations as unit quaternions ([`glam::DQuat`], stored x, y, z, w): the quaternion exponential
//! and logarithm, powers, angular velocity and acceleration from quaternion derivatives and back,
//! spherical linear interpolation with its derivatives, squad with its control points, and the
//! `Z-Y'-X''` Euler angles robot controllers use on the wire.
//!
//! Conventions: angular velocities and accelerations are in the world (fixed) frame unless a
//! function's name says `body`; `q̇ = ½ ω q`. The exponential takes a pure quaternion (a vector
//! `v`), so `exp(v)` rotates by the angle `2|v|` about `v` — as RL's `Quaternion::exp`. Nothing
//! here allocates or panics.

pub mod euler;
pub mod quaternion;
pub mod slerp;
pub mod squad;

pub use quaternion::{
    angular_acceleration, angular_acceleration_body, angular_velocity, angular_velocity_body, exp,
    log, pow, pure, quaternion_derivative, quaternion_second_derivative,
};
pub use slerp::Slerp;
pub use squad::{squad, squad_control_point};
