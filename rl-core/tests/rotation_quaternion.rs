//! Quaternion extensions: exp/log/pow identities, angular velocity and acceleration from
//! quaternion derivatives and back (against finite differences), slerp derivatives, squad.

mod traj_support;

use glam::{DQuat, DVec3};
use rl_core::rotation::{
    Slerp, angular_acceleration, angular_acceleration_body, angular_velocity,
    angular_velocity_body, exp, log, pow, quaternion_derivative, quaternion_second_derivative,
    squad, squad_control_point,
};
use traj_support::Rng;

fn random_quat(rng: &mut Rng) -> DQuat {
    let v = DVec3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    );
    exp(v * 1.5)
}

fn close(a: DQuat, b: DQuat, tol: f64) -> bool {
    (a - b).length() <= tol
}

#[test]
fn exp_log_pow_identities() {
    let mut rng = Rng(7);
    for _ in 0..500 {
        let q = random_quat(&mut rng);
        assert!((q.length() - 1.0).abs() < 1e-15);
        assert!(close(exp(log(q)), q, 1e-15));
        assert!(close(pow(q, 1.0), q, 1e-15));
        assert!(close(pow(q, 0.5) * pow(q, 0.5), q, 1e-14));
        assert!(close(pow(q, 0.0), DQuat::IDENTITY, 0.0));
        // Agrees with glam's axis-angle: exp(v) rotates by 2|v|.
        let v = log(q);
        assert!(
            close(DQuat::from_scaled_axis(v * 2.0), q, 1e-14)
                || close(DQuat::from_scaled_axis(v * 2.0), -q, 1e-14)
        );
    }
}

/// q(t) = exp(a t + b t²) q0: derivatives by central differences.
#[test]
fn angular_velocity_and_acceleration_round_trip_and_match_finite_differences() {
    let mut rng = Rng(11);
    for _ in 0..100 {
        let q0 = random_quat(&mut rng);
        let a = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let b = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let c = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let q = |t: f64| exp(a * t + b * t * t) * exp(c * t) * q0;
        let t = rng.range(-0.5, 0.5);
        let h = 1e-4;
        let qd = (q(t + h) - q(t - h)) * (0.5 / h);
        let qdd = (q(t + h) + q(t - h) - q(t) * 2.0) * (1.0 / (h * h));
        let omega = angular_velocity(q(t), qd);
        let alpha = angular_acceleration(q(t), qd, qdd);
        // Back to quaternion derivatives.
        let qd_exact = quaternion_derivative(q(t), omega);
        let qdd_exact = quaternion_second_derivative(q(t), omega, alpha);
        assert!(close(qd_exact, qd, 1e-7));
        assert!(close(qdd_exact, qdd, 1e-5));
        // Exact round trips.
        assert!((angular_velocity(q(t), qd_exact) - omega).length() < 1e-14);
        assert!((angular_acceleration(q(t), qd_exact, qdd_exact) - alpha).length() < 1e-13);
        // q̇ is tangent to the unit sphere: q·q̇ = 0.
        assert!(q(t).dot(qd_exact).abs() < 1e-15);
        // ω from finite differences of the rotation: R(t+h) R(t-h)ᵀ ≈ exp(ω 2h).
        let rel = q(t + h) * q(t - h).conjugate();
        let omega_fd = log(rel) * (2.0 / (2.0 * h));
        assert!((omega_fd - omega).length() < 1e-7 * (1.0 + omega.length()));
        // Body frame = world rotated back.
        let qc = q(t).conjugate();
        assert!((angular_velocity_body(q(t), qd) - qc.mul_vec3(omega)).length() < 1e-12);
        assert!((angular_acceleration_body(q(t), qd, qdd) - qc.mul_vec3(alpha)).length() < 1e-12);
        // α is the derivative of ω.
        let w = |t: f64| {
            let qd = (q(t + 1e-5) - q(t - 1e-5)) * (0.5 / 1e-5);
            angular_velocity(q(t), qd)
        };
        let alpha_fd = (w(t + h) - w(t - h)) / (2.0 * h);
        assert!(
            (alpha_fd - alpha).length() < 1e-5 * (1.0 + alpha.length()),
            "{alpha_fd} vs {alpha}"
        );
    }
}

#[test]
fn slerp_endpoints_derivatives_and_unit_norm() {
    let mut rng = Rng(13);
    for _ in 0..200 {
        let (q0, q1) = (random_quat(&mut rng), random_quat(&mut rng));
        let s = Slerp::new(q0, q1);
        assert!(close(s.value(0.0), q0, 1e-15));
        let end = s.value(1.0);
        assert!(close(end, q1, 1e-13) || close(end, -q1, 1e-13));
        for k in 0..=10 {
            let u = k as f64 / 10.0;
            assert!((s.value(u).length() - 1.0).abs() < 1e-14);
            let h = 1e-5;
            let d_fd = (s.value(u + h) - s.value(u - h)) * (0.5 / h);
            let dd_fd = (s.derivative(u + h) - s.derivative(u - h)) * (0.5 / h);
            assert!(close(s.derivative(u), d_fd, 1e-9));
            assert!(close(s.second_derivative(u), dd_fd, 1e-9));
            // Constant world angular velocity along the arc.
            assert!(
                (angular_velocity(s.value(u), s.derivative(u)) - s.angular_velocity()).length()
                    < 1e-13
            );
        }
        assert!(s.angle() <= core::f64::consts::PI + 1e-15);
    }
}

#[test]
fn squad_interpolates_and_is_smooth_at_waypoints() {
    let mut rng = Rng(17);
    for _ in 0..50 {
        let mut q = [DQuat::IDENTITY; 4];
        for qi in q.iter_mut() {
            *qi = random_quat(&mut rng);
        }
        for i in 1..4 {
            if q[i].dot(q[i - 1]) < 0.0 {
                q[i] = -q[i];
            }
        }
        let a1 = squad_control_point(q[0], q[1], q[2]);
        let a2 = squad_control_point(q[1], q[2], q[3]);
        // Segment 1-2 with its neighbours' control points.
        let a0 = squad_control_point(q[0], q[0], q[1]);
        let f = |s: f64| squad(q[1], q[2], a1, a2, s);
        assert!(close(f(0.0), q[1], 1e-14));
        assert!(close(f(1.0), q[2], 1e-13));
        for k in 0..=20 {
            assert!((f(k as f64 / 20.0).length() - 1.0).abs() < 1e-14);
        }
        // C¹ at q1: the derivative leaving segment 0-1 equals the one entering 1-2.
        let g = |s: f64| squad(q[0], q[1], a0, a1, s);
        let h = 1e-6;
        let left = (g(1.0) - g(1.0 - h)) * (1.0 / h);
        let right = (f(h) - f(0.0)) * (1.0 / h);
        assert!(close(left, right, 1e-4), "{left} vs {right}");
    }
}
