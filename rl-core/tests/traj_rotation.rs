//! Rotation trajectories: unit quaternions, end conditions, world angular velocity and
//! acceleration against finite differences of the orientation, continuity at waypoints.

mod traj_support;

use glam::{DQuat, DVec3};
use rl_core::{
    rotation::{exp, log},
    traj::{
        CubicQuaternionSpline, JerkLimitedRotation, RotationTrajectory, SlerpTrajectory,
        TrajectoryError,
    },
};
use traj_support::Rng;

fn random_quat(rng: &mut Rng) -> DQuat {
    exp(DVec3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    ) * 1.4)
}

fn same_rotation(a: DQuat, b: DQuat, tol: f64) -> bool {
    (a - b).length() <= tol || (a + b).length() <= tol
}

/// ω against log(q(t+h) q(t-h)*)/h and α against central differences of ω, at interior times
/// away from `avoid`.
fn check_rates<R: RotationTrajectory>(r: &R, avoid: &[f64]) {
    let d = r.duration();
    let h = 1e-6 * d;
    for k in 1..60 {
        let t = d * k as f64 / 60.0 + 0.31 * h;
        if avoid.iter().any(|b| (t - b).abs() < 4.0 * h) {
            continue;
        }
        let s = r.rotation(t);
        assert!(
            (s.orientation.length() - 1.0).abs() < 1e-13,
            "not unit at {t}"
        );
        let rel = r.rotation(t + h).orientation * r.rotation(t - h).orientation.conjugate();
        let rel = if rel.w < 0.0 { -rel } else { rel };
        let omega_fd = log(rel) * (1.0 / h);
        assert!(
            (omega_fd - s.angular_velocity).length() < 1e-6 * (1.0 + s.angular_velocity.length()),
            "ω at {t}: {} vs fd {omega_fd}",
            s.angular_velocity
        );
        let alpha_fd =
            (r.rotation(t + h).angular_velocity - r.rotation(t - h).angular_velocity) / (2.0 * h);
        assert!(
            (alpha_fd - s.angular_acceleration).length()
                < 1e-5 * (1.0 + s.angular_acceleration.length()),
            "α at {t}: {} vs fd {alpha_fd}",
            s.angular_acceleration
        );
    }
}

#[test]
fn slerp_trajectory_has_constant_angular_velocity() {
    let q0 = DQuat::from_rotation_z(0.2);
    let q1 = DQuat::from_rotation_x(1.0) * q0;
    let r = SlerpTrajectory::new(q0, q1, 2.0).unwrap();
    assert!(same_rotation(r.rotation(2.0).orientation, q1, 1e-14));
    assert!((r.rotation(0.7).angular_velocity - DVec3::X * 0.5).length() < 1e-14);
    check_rates(&r, &[]);
    assert_eq!(
        SlerpTrajectory::new(q0, q1, 0.0).unwrap_err(),
        TrajectoryError::BadDuration
    );
}

#[test]
fn jerk_limited_rotation_reaches_the_goal_at_rest_within_limits() {
    let mut rng = Rng(23);
    for _ in 0..50 {
        let (q0, q1) = (random_quat(&mut rng), random_quat(&mut rng));
        let (v, a, j) = (
            rng.range(0.2, 3.0),
            rng.range(0.5, 10.0),
            rng.range(1.0, 100.0),
        );
        let r = JerkLimitedRotation::new(q0, q1, v, a, j).unwrap();
        let d = r.duration();
        assert!(same_rotation(r.rotation(0.0).orientation, q0, 1e-14));
        assert!(same_rotation(r.rotation(d).orientation, q1, 1e-9));
        assert!(r.rotation(d).angular_velocity.length() < 1e-9);
        assert!(r.rotation(d).angular_acceleration.length() < 1e-9);
        for k in 0..=400 {
            let s = r.rotation(d * k as f64 / 400.0);
            assert!(s.angular_velocity.length() <= v * (1.0 + 1e-9));
            assert!(s.angular_acceleration.length() <= a * (1.0 + 1e-9));
        }
        check_rates(&r, &[]);
    }
}

#[test]
fn cubic_quaternion_spline_meets_orientations_and_end_angular_velocities() {
    let mut rng = Rng(29);
    for _ in 0..30 {
        let times = [0.0, 0.8, 1.5, 2.7, 3.0];
        let q: Vec<DQuat> = (0..5).map(|_| random_quat(&mut rng)).collect();
        let w0 = DVec3::new(0.3, -0.2, 0.5);
        let w1 = DVec3::new(-0.1, 0.0, 0.4);
        let s: CubicQuaternionSpline<4> = CubicQuaternionSpline::new(&times, &q, w0, w1).unwrap();
        assert!((s.duration() - 3.0).abs() < 1e-15);
        for (t, qi) in times.iter().zip(&q) {
            assert!(
                same_rotation(s.rotation(*t).orientation, *qi, 1e-13),
                "waypoint at {t}"
            );
        }
        assert!((s.rotation(0.0).angular_velocity - w0).length() < 1e-13);
        assert!((s.rotation(3.0).angular_velocity - w1).length() < 1e-13);
        // C¹ at every interior waypoint: ω from the left equals ω from the right.
        for &t in &times[1..4] {
            let left = s.rotation(t - 1e-9).angular_velocity;
            let right = s.rotation(t).angular_velocity;
            assert!(
                (left - right).length() < 1e-6 * (1.0 + right.length()),
                "ω jumps at {t}"
            );
            let ql = s.rotation(t - 1e-12).orientation;
            assert!(
                (ql - s.rotation(t).orientation).length() < 1e-9,
                "q jumps (sign) at {t}"
            );
        }
        check_rates(&s, &times);
    }
}

#[test]
fn cubic_quaternion_spline_is_c2_at_interior_waypoints() {
    let mut rng = Rng(31);
    for _ in 0..30 {
        let times = [0.0, 0.6, 1.5, 2.1, 3.0, 3.4];
        // Neighbouring orientations up to ~1 rad apart.
        let mut q = vec![random_quat(&mut rng)];
        for _ in 1..6 {
            let step = DVec3::new(
                rng.range(-0.3, 0.3),
                rng.range(-0.3, 0.3),
                rng.range(-0.3, 0.3),
            );
            q.push(exp(step) * *q.last().unwrap());
        }
        let w0 = DVec3::new(0.2, 0.0, -0.1);
        let s: CubicQuaternionSpline<5> =
            CubicQuaternionSpline::new(&times, &q, w0, DVec3::ZERO).unwrap();
        assert!(
            s.acceleration_jump() < 1e-12,
            "not C²: {}",
            s.acceleration_jump()
        );
        for &t in &times[1..5] {
            let i = s.starts().partition_point(|&x| x <= t) - 1;
            let left_start = s.starts()[i - 1];
            // Left limit via the previous segment's end, right value at the knot.
            let left = s.rotation(t - 1e-7).angular_acceleration;
            let right = s.rotation(t).angular_acceleration;
            assert!(
                (left - right).length() < 1e-5 * (1.0 + right.length()),
                "α jumps at {t} ({left_start})"
            );
        }
        assert!((s.rotation(0.0).angular_velocity - w0).length() < 1e-13);
        assert!(s.rotation(3.4).angular_velocity.length() < 1e-13);
        for (t, qi) in times.iter().zip(&q) {
            assert!(same_rotation(s.rotation(*t).orientation, *qi, 1e-13));
        }
        check_rates(&s, &times);
    }
}

#[test]
fn quaternion_spline_errors() {
    let q = [DQuat::IDENTITY; 3];
    let r: Result<CubicQuaternionSpline<1>, _> =
        CubicQuaternionSpline::new(&[0.0, 1.0, 2.0], &q, DVec3::ZERO, DVec3::ZERO);
    assert_eq!(
        r.unwrap_err(),
        TrajectoryError::Capacity {
            capacity: 1,
            requested: 2
        }
    );
    let r: Result<CubicQuaternionSpline<4>, _> =
        CubicQuaternionSpline::new(&[0.0, 1.0, 1.0], &q, DVec3::ZERO, DVec3::ZERO);
    assert_eq!(
        r.unwrap_err(),
        TrajectoryError::NonIncreasingTime { index: 2 }
    );
    let bad = [DQuat::IDENTITY, DQuat::from_xyzw(0.0, f64::NAN, 0.0, 1.0)];
    let r: Result<CubicQuaternionSpline<4>, _> =
        CubicQuaternionSpline::new(&[0.0, 1.0], &bad, DVec3::ZERO, DVec3::ZERO);
    assert!(matches!(
        r,
        Err(TrajectoryError::NotFinite { index: 1, .. })
    ));
}
