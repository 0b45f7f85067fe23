//! Circular arcs in 2-D and 3-D (all derivative orders against finite differences and the
//! closed form) and Cartesian pose trajectories.

mod traj_support;

use core::f64::consts::{PI, TAU};

use glam::{DQuat, DVec3};
use rl_core::traj::{
    Circular, Limits, Polynomial, PoseTrajectory, RotationTrajectory, SlerpTrajectory, Trajectory,
    TrajectoryError,
};
use traj_support::{assert_close, check_finite_differences, check_sample_matches};

#[test]
fn arc_2d_through_three_points() {
    // Unit circle around (1, 1): start (2, 1), via (1, 2), to (0, 1): a half turn.
    let c = Circular::<2>::through([2.0, 1.0], [1.0, 2.0], [0.0, 1.0], 2.0).unwrap();
    assert_close("center", c.center(), [1.0, 1.0], 1e-15);
    assert!((c.radius() - 1.0).abs() < 1e-15);
    assert!((c.angle() - PI).abs() < 1e-15);
    assert_close("start", c.position(0.0), [2.0, 1.0], 1e-15);
    assert_close("via", c.position(1.0), [1.0, 2.0], 1e-15);
    assert_close("end", c.position(2.0), [0.0, 1.0], 1e-15);
    // Clockwise the other way round: through (1, 0) to (0, 1) is also a half turn.
    let c = Circular::<2>::through([2.0, 1.0], [1.0, 0.0], [0.0, 1.0], 1.0).unwrap();
    assert_close("via cw", c.position(0.5), [1.0, 0.0], 1e-15);
    // Speed is constant: |v| = r ω.
    let v = c.derivative(0.3, 1);
    assert!(((v[0] * v[0] + v[1] * v[1]).sqrt() - PI).abs() < 1e-14);
    check_finite_differences(&c, 6, 41, &[]);
    check_sample_matches(&c, 10);
}

#[test]
fn arc_3d_through_three_points_and_full_circle() {
    let p0 = [1.0, 0.0, 0.0];
    let p1 = [0.0, 1.0, 0.0];
    let p2 = [0.0, 0.0, 1.0];
    let c = Circular::<3>::through(p0, p1, p2, 3.0).unwrap();
    let third = 1.0 / 3.0;
    assert_close("center", c.center(), [third; 3], 1e-15);
    assert!((c.angle() - 4.0 * PI / 3.0).abs() < 1e-14, "{}", c.angle());
    assert_close("via", c.position(1.5), p1, 1e-14);
    assert_close("end", c.position(3.0), p2, 1e-14);
    for k in 0..=20 {
        let p = c.position(3.0 * k as f64 / 20.0);
        let r: f64 = p
            .iter()
            .zip(c.center())
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        assert!((r - c.radius()).abs() < 1e-14);
        assert!(
            (p.iter().sum::<f64>() - 1.0).abs() < 1e-14,
            "leaves the plane"
        );
    }
    check_finite_differences(&c, 6, 41, &[]);
    let full = Circular::<3>::through_with_angle(p0, p1, p2, TAU, 1.0).unwrap();
    assert_close("closed", full.position(1.0), p0, 1e-14);
    assert_close("p1 first", full.position(1.0 / 3.0), p1, 1e-14);
    // Derivative n: ωⁿ r for every n.
    for n in 0..8 {
        let d = full.derivative(0.123, n);
        let norm = d
            .iter()
            .zip(if n == 0 { full.center() } else { [0.0; 3] })
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        assert!((norm - TAU.powi(n as i32) * full.radius()).abs() < 1e-10 * TAU.powi(n as i32));
    }
}

#[test]
fn arc_errors() {
    assert_eq!(
        Circular::<2>::through([0.0, 0.0], [1.0, 1.0], [2.0, 2.0], 1.0).unwrap_err(),
        TrajectoryError::Degenerate
    );
    assert_eq!(
        Circular::<3>::through([0.0; 3], [0.0; 3], [1.0, 0.0, 0.0], 1.0).unwrap_err(),
        TrajectoryError::Degenerate
    );
    assert_eq!(
        Circular::<2>::through([2.0, 1.0], [1.0, 2.0], [0.0, 1.0], 0.0).unwrap_err(),
        TrajectoryError::BadDuration
    );
    assert_eq!(
        Circular::<2>::through_with_angle([2.0, 1.0], [1.0, 2.0], [0.0, 1.0], 7.0, 1.0)
            .unwrap_err(),
        TrajectoryError::Degenerate
    );
    assert!(matches!(
        Circular::<3>::through([0.0, f64::NAN, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 1.0),
        Err(TrajectoryError::NotFinite { index: 1, .. })
    ));
}

#[test]
fn pose_trajectory_joins_position_and_rotation() {
    let limits = Limits::uniform(1.0, 2.0, 10.0);
    let pos = Polynomial::quintic_at_rest([0.0, 0.0, 0.5], [0.3, -0.2, 0.7], &limits).unwrap();
    let q0 = DQuat::IDENTITY;
    let q1 = DQuat::from_rotation_y(0.5);
    let rot = SlerpTrajectory::new(q0, q1, pos.duration()).unwrap();
    let pose = PoseTrajectory::new(pos, rot).unwrap();
    let t = 0.4 * pose.duration();
    let s = pose.sample(t);
    assert_close("position", s.position.to_array(), pos.position(t), 1e-14);
    let tw = s.twist();
    assert_close(
        "linear velocity",
        [tw[0], tw[1], tw[2]],
        pos.derivative(t, 1),
        1e-14,
    );
    assert!(
        (DVec3::from_slice(&s.twist()[3..]) - rot.rotation(t).angular_velocity).length() == 0.0
    );
    let acc = s.acceleration();
    assert_close(
        "linear acceleration",
        [acc[0], acc[1], acc[2]],
        pos.derivative(t, 2),
        1e-14,
    );
    assert!(s.orientation.abs_diff_eq(rot.rotation(t).orientation, 0.0));
    // Spatial = classical minus ω × v.
    let sp = s.spatial_acceleration();
    let expect = s.linear_acceleration - s.angular_velocity.cross(s.linear_velocity);
    assert_close("spatial", [sp[0], sp[1], sp[2]], expect.to_array(), 0.0);
    let short = SlerpTrajectory::new(q0, q1, 0.5 * pos.duration()).unwrap();
    assert_eq!(
        PoseTrajectory::new(pos, short).unwrap_err(),
        TrajectoryError::DurationMismatch
    );
}
