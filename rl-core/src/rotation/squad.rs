//! Spherical quadrangle interpolation (squad, Shoemake 1987) and its control points.

use glam::DQuat;

use super::{
    quaternion::{exp, log},
    slerp::Slerp,
};

/// The inner control point of `q` between `q_prev` and `q_next`:
/// `a = q exp(-(log(q* q_next) + log(q* q_prev)) / 4)`, which makes squad C¹ at `q`.
///
/// Inputs should be sign-consistent (`q_prev·q ≥ 0`, `q·q_next ≥ 0`).
pub fn squad_control_point(q_prev: DQuat, q: DQuat, q_next: DQuat) -> DQuat {
    let qc = q.conjugate();
    q * exp((log(qc * q_next) + log(qc * q_prev)) * -0.25)
}

/// Squad between `q0` and `q1` with control points `a0` and `a1` at `s ∈ [0, 1]`:
/// `slerp(slerp(q0, q1, s), slerp(a0, a1, s), 2s(1-s))`, all slerps without arc flipping.
pub fn squad(q0: DQuat, q1: DQuat, a0: DQuat, a1: DQuat, s: f64) -> DQuat {
    let outer = Slerp::new_unflipped(q0, q1).value(s);
    let inner = Slerp::new_unflipped(a0, a1).value(s);
    Slerp::new_unflipped(outer, inner).value(2.0 * s * (1.0 - s))
}
