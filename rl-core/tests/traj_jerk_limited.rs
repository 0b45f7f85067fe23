//! The 7-segment jerk-limited profile: hand-computed durations (Biagiotti & Melchiorri §3.4),
//! limits respected at every phase boundary and in between, goal reached at rest, axes
//! synchronised to the slowest, continuity of position, velocity and acceleration.

mod traj_support;

use rl_core::traj::{JerkLimited, Limits, Piecewise, Trajectory, TrajectoryError, spline};
use traj_support::{Rng, assert_close, check_finite_differences, check_sample_matches};

/// Checks limits at every phase boundary of every axis (where |v| and |a| peak for this
/// profile) and on a dense grid, and the goal at rest.
fn check_profile<const D: usize>(
    p: &JerkLimited<D>,
    start: [f64; D],
    goal: [f64; D],
    limits: &Limits<D>,
) {
    let t_end = p.duration();
    assert_close("start", p.position(0.0), start, 1e-12);
    assert_close("goal", p.position(t_end), goal, 1e-9);
    for order in 1..=2 {
        assert_close("rest start", p.derivative(0.0, order), [0.0; D], 1e-12);
        assert_close("rest end", p.derivative(t_end, order), [0.0; D], 1e-9);
    }
    let mut times: Vec<f64> = (0..=2000).map(|k| t_end * k as f64 / 2000.0).collect();
    for axis in 0..D {
        times.extend(p.phase_ends(axis).unwrap());
    }
    for t in times {
        let s = p.sample(t);
        for i in 0..D {
            assert!(
                s.velocity[i].abs() <= limits.velocity[i] * (1.0 + 1e-9),
                "v{i} {} at {t}",
                s.velocity[i]
            );
            assert!(
                s.acceleration[i].abs() <= limits.acceleration[i] * (1.0 + 1e-9),
                "a{i} {} at {t}",
                s.acceleration[i]
            );
            assert!(
                s.jerk[i].abs() <= limits.jerk[i] * (1.0 + 1e-9),
                "j{i} {} at {t}",
                s.jerk[i]
            );
            // Never overshoots the goal (monotonic motion).
            let (lo, hi) = (start[i].min(goal[i]), start[i].max(goal[i]));
            assert!(
                s.position[i] >= lo - 1e-9 && s.position[i] <= hi + 1e-9,
                "overshoot axis {i}"
            );
        }
    }
}

#[test]
fn hand_computed_cases() {
    // h = 10, v = 5, a = 10, j = 30: vj ≥ a², Tj = 1/3, Ta = 1/3 + 1/2, Tv = 10/5 - Ta.
    let l = Limits::uniform(5.0, 10.0, 30.0);
    let p = JerkLimited::new([0.0], [10.0], &l).unwrap();
    let (tj, ta) = (1.0 / 3.0, 1.0 / 3.0 + 0.5);
    let tv = 2.0 - ta;
    assert!(
        (p.duration() - (2.0 * ta + tv)).abs() < 1e-14,
        "{}",
        p.duration()
    );
    let ends = p.phase_ends(0).unwrap();
    assert!((ends[0] - tj).abs() < 1e-14 && (ends[2] - ta).abs() < 1e-14);
    // Velocity limit reached in the cruise, acceleration limit in phase 2, jerk in phase 1.
    assert!((p.derivative(ta + 0.5 * tv, 1)[0] - 5.0).abs() < 1e-12);
    assert!((p.derivative(0.5, 2)[0] - 10.0).abs() < 1e-12);
    assert_eq!(p.derivative(0.1, 3)[0], 30.0);
    check_profile(&p, [0.0], [10.0], &l);

    // Short move: neither v nor a reached, Tj = (h / 2j)^(1/3), T = 4 Tj.
    let p = JerkLimited::new([1.0], [1.0 - 0.002], &l).unwrap();
    let tj = (0.002f64 / 60.0).cbrt();
    assert!((p.duration() - 4.0 * tj).abs() < 1e-14);
    check_profile(&p, [1.0], [0.998], &l);

    // Acceleration reached, velocity not: h = 3 ≥ 2a³/j² = 2.2 and h < v·Ta.
    let p = JerkLimited::new([0.0], [3.0], &l).unwrap();
    let tj: f64 = 1.0 / 3.0;
    let ta = 0.5 * tj + (0.25 * tj * tj + 0.3).sqrt();
    assert!((p.duration() - 2.0 * ta).abs() < 1e-14);
    check_profile(&p, [0.0], [3.0], &l);
}

#[test]
fn axes_synchronise_to_the_slowest_and_keep_their_limits() {
    let l = Limits {
        velocity: [1.0, 3.0, 0.5, 2.0],
        acceleration: [2.0, 1.0, 5.0, 2.0],
        jerk: [10.0, 4.0, 50.0, 1.0],
    };
    let (a, b) = ([0.0, 1.0, -2.0, 0.3], [2.0, -1.0, -1.0, 0.3]);
    let p = JerkLimited::new(a, b, &l).unwrap();
    let alone = JerkLimited::axis_durations(a, b, &l);
    let slowest = alone.iter().copied().fold(0.0, f64::max);
    assert_eq!(p.duration(), slowest);
    for (axis, own) in alone.iter().enumerate() {
        // Every moving axis ends when the slowest does.
        assert!((p.phase_ends(axis).unwrap()[6] - slowest).abs() < 1e-12 || *own == 0.0);
    }
    check_profile(&p, a, b, &l);
    // Jerk against differences of acceleration too, away from phase boundaries.
    let boundaries: Vec<f64> = (0..4)
        .flat_map(|axis| p.phase_ends(axis).unwrap())
        .collect();
    check_finite_differences(&p, 3, 211, &boundaries);
    check_sample_matches(&p, 50);
}

#[test]
fn random_moves_respect_limits() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for _ in 0..300 {
        let l = Limits {
            velocity: core::array::from_fn(|_| rng.range(0.05, 5.0)),
            acceleration: core::array::from_fn(|_| rng.range(0.05, 20.0)),
            jerk: core::array::from_fn(|_| rng.range(0.05, 500.0)),
        };
        let a: [f64; 3] = core::array::from_fn(|_| rng.range(-3.0, 3.0));
        let b: [f64; 3] = core::array::from_fn(|_| rng.range(-3.0, 3.0));
        let p = JerkLimited::new(a, b, &l).unwrap();
        check_profile(&p, a, b, &l);
    }
}

#[test]
fn through_waypoints_is_continuous_in_acceleration() {
    let points = [[0.0, 0.0], [1.0, 0.5], [1.0, -0.5], [-2.0, 0.0]];
    let l = Limits::uniform(1.0, 2.0, 8.0);
    let s: Piecewise<JerkLimited<2>, 3> = spline::jerk_limited_through(&points, &l).unwrap();
    s.check_continuity(2, 1e-9).unwrap();
    let mut t = 0.0;
    for (i, seg) in s.segments().iter().enumerate() {
        assert_close("waypoint", s.position(t), points[i], 1e-9);
        t += seg.duration();
    }
    assert_close("last", s.position(s.duration()), points[3], 1e-9);
}

#[test]
fn bad_limits_are_typed_errors() {
    let mut l = Limits::uniform(1.0, 1.0, 1.0);
    l.jerk[1] = f64::INFINITY;
    assert!(matches!(
        JerkLimited::new([0.0; 2], [1.0; 2], &l),
        Err(TrajectoryError::BadLimit { axis: 1, .. })
    ));
    l = Limits::uniform(1.0, -1.0, 1.0);
    assert!(matches!(
        JerkLimited::new([0.0; 2], [1.0; 2], &l),
        Err(TrajectoryError::BadLimit { axis: 0, .. })
    ));
    l = Limits::uniform(1.0, 1.0, 1.0);
    assert!(matches!(
        JerkLimited::new([0.0; 2], [1.0, f64::NAN], &l),
        Err(TrajectoryError::NotFinite { .. })
    ));
    let r: Result<Piecewise<JerkLimited<2>, 1>, _> =
        spline::jerk_limited_through(&[[0.0; 2], [1.0; 2], [2.0; 2]], &l);
    assert_eq!(
        r.unwrap_err(),
        TrajectoryError::Capacity {
            capacity: 1,
            requested: 2
        }
    );
}
