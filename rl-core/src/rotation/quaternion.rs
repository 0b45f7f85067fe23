//! Quaternion exponential, logarithm and power; angular velocity and acceleration from the first
//! and second time derivatives of a unit quaternion, and the inverse maps.

use glam::{DQuat, DVec3};

/// Below this angle `sin(x)/x` uses its Taylor series, which is exact to f64 there.
const SMALL_ANGLE: f64 = 1e-4;

/// `sin(x)/x` without the 0/0 at zero.
pub(crate) fn sinc(x: f64) -> f64 {
    if libm::fabs(x) < SMALL_ANGLE {
        let x2 = x * x;
        1.0 - x2 / 6.0 + x2 * x2 / 120.0
    } else {
        libm::sin(x) / x
    }
}

/// The pure quaternion `(v, 0)`: how a vector enters quaternion products.
#[inline]
pub fn pure(v: DVec3) -> DQuat {
    DQuat::from_xyzw(v.x, v.y, v.z, 0.0)
}

/// Quaternion exponential of the pure quaternion `v`: `(v/|v| sin|v|, cos|v|)`, a unit
/// quaternion rotating by `2|v|` about `v`.
#[doc(alias = "expmap")]
pub fn exp(v: DVec3) -> DQuat {
    let angle = v.length();
    let s = sinc(angle);
    DQuat::from_xyzw(v.x * s, v.y * s, v.z * s, libm::cos(angle))
}

/// Quaternion logarithm of a unit quaternion: the vector `v` with `exp(v) = q`, `|v| ≤ π`.
///
/// `q` and `-q` give different logarithms (the same rotation reached the long or short way);
/// callers wanting the shortest rotation flip `q` to `w ≥ 0` first.
#[doc(alias = "logmap")]
pub fn log(q: DQuat) -> DVec3 {
    let v = q.xyz();
    let s = v.length();
    let angle = libm::atan2(s, q.w);
    // angle / s, continuous through s = 0 (angle ≈ s / w there).
    let scale = if s < SMALL_ANGLE * libm::fabs(q.w) {
        // atan2(s, w)/s = (1/w)(1 - s²/(3w²) + ...)
        let r = s / q.w;
        (1.0 - r * r / 3.0) / q.w
    } else {
        angle / s
    };
    v * scale
}

/// Real power of a unit quaternion, `exp(t log q)`: the rotation `t` times as far.
pub fn pow(q: DQuat, t: f64) -> DQuat {
    exp(log(q) * t)
}

/// World-frame angular velocity from a unit quaternion and its time derivative: `ω = 2 q̇ q*`.
pub fn angular_velocity(q: DQuat, qd: DQuat) -> DVec3 {
    (qd * q.conjugate()).xyz() * 2.0
}

/// Body-frame angular velocity: `ω_b = 2 q* q̇`.
pub fn angular_velocity_body(q: DQuat, qd: DQuat) -> DVec3 {
    (q.conjugate() * qd).xyz() * 2.0
}

/// World-frame angular acceleration from a unit quaternion and its first two derivatives:
/// `α = 2 (q̈ q* + q̇ q̇*)`, whose second term is real, so `α = vec(2 q̈ q*)`.
pub fn angular_acceleration(q: DQuat, _qd: DQuat, qdd: DQuat) -> DVec3 {
    (qdd * q.conjugate()).xyz() * 2.0
}

/// Body-frame angular acceleration: `α_b = vec(2 q* q̈)`.
pub fn angular_acceleration_body(q: DQuat, _qd: DQuat, qdd: DQuat) -> DVec3 {
    (q.conjugate() * qdd).xyz() * 2.0
}

/// Time derivative of a unit quaternion rotating with world-frame angular velocity `ω`:
/// `q̇ = ½ ω q`.
pub fn quaternion_derivative(q: DQuat, omega: DVec3) -> DQuat {
    pure(omega * 0.5) * q
}

/// Second time derivative of a unit quaternion for world-frame `ω` and `α`:
/// `q̈ = ½ α q + ½ ω q̇ = ½ α q - ¼ |ω|² q`.
pub fn quaternion_second_derivative(q: DQuat, omega: DVec3, alpha: DVec3) -> DQuat {
    pure(alpha * 0.5) * q + q * (-0.25 * omega.length_squared())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_log_round_trip_and_small_angles() {
        for v in [
            DVec3::new(0.3, -0.2, 0.9),
            DVec3::new(1e-9, 0.0, -2e-9),
            DVec3::ZERO,
        ] {
            let q = exp(v);
            assert!((q.length() - 1.0).abs() < 1e-15);
            assert!((log(q) - v).length() < 1e-15);
        }
        let q = DQuat::from_axis_angle(DVec3::Z, 1.0);
        assert!(pow(q, 0.5).abs_diff_eq(DQuat::from_axis_angle(DVec3::Z, 0.5), 1e-15));
    }
}
