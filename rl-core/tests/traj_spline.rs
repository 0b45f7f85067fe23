//! Splines through waypoints: interpolation and end conditions to 1e-12, continuity up to the
//! promised order at every boundary, limits of the at-rest moves.

mod traj_support;

use rl_core::traj::{
    BlendShape, BlendTime, Limits, Piecewise, Polynomial, Trajectory, TrajectoryError, spline,
};
use traj_support::{assert_close, check_finite_differences, check_sample_matches};

const TIMES: [f64; 6] = [0.0, 0.7, 1.5, 2.0, 3.1, 4.0];
const POINTS: [[f64; 2]; 6] = [
    [0.0, 1.0],
    [1.0, -0.5],
    [0.5, 0.25],
    [2.0, 0.0],
    [1.0, 3.0],
    [-1.0, 2.0],
];
const TOL: f64 = 1e-12;

fn max_abs_over_segments<const D: usize, const C: usize, const M: usize>(
    s: &Piecewise<Polynomial<D, C>, M>,
    order: usize,
) -> [f64; D] {
    let mut out = [0.0; D];
    for seg in s.segments() {
        for (o, m) in out.iter_mut().zip(seg.max_abs_derivative(order)) {
            *o = f64::max(*o, m);
        }
    }
    out
}

#[test]
fn natural_cubic_interpolates_with_zero_end_acceleration_and_is_c2() {
    let s: Piecewise<Polynomial<2, 4>, 8> = spline::natural_cubic(&TIMES, &POINTS).unwrap();
    assert_eq!(s.len(), 5);
    for (t, p) in TIMES.iter().zip(POINTS) {
        assert_close("waypoint", s.position(t - TIMES[0]), p, TOL);
    }
    assert_close("start acc", s.derivative(0.0, 2), [0.0; 2], TOL);
    assert_close("end acc", s.derivative(4.0, 2), [0.0; 2], TOL);
    s.check_continuity(2, 1e-12).unwrap();
    // The jerk does jump: the check must see it (at some boundary, not just the first).
    assert!(s.check_continuity(3, 1e-12).is_err());
    check_finite_differences(&s, 3, 97, &TIMES);
    check_sample_matches(&s, 40);
}

#[test]
fn clamped_cubic_meets_end_velocities() {
    let v0 = [0.5, -1.0];
    let v1 = [0.0, 2.0];
    let s: Piecewise<Polynomial<2, 4>, 5> = spline::clamped_cubic(&TIMES, &POINTS, v0, v1).unwrap();
    for (t, p) in TIMES.iter().zip(POINTS) {
        assert_close("waypoint", s.position(*t), p, TOL);
    }
    assert_close("v0", s.derivative(0.0, 1), v0, TOL);
    assert_close("v1", s.derivative(4.0, 1), v1, TOL);
    s.check_continuity(2, 1e-12).unwrap();
    check_finite_differences(&s, 3, 97, &TIMES);
}

#[test]
fn two_waypoints_natural_is_a_line() {
    let s: Piecewise<Polynomial<1, 4>, 1> =
        spline::natural_cubic(&[1.0, 3.0], &[[0.0], [4.0]]).unwrap();
    assert_close("mid", s.position(1.0), [2.0], TOL);
    assert_close("vel", s.derivative(0.3, 1), [2.0], TOL);
}

#[test]
fn continuity_check_reports_a_jump_at_a_later_boundary() {
    // RL's check stops after the first boundary; ours must find a jump at the third.
    let mut s: Piecewise<Polynomial<1, 2>, 4> = Piecewise::new();
    s.push(Polynomial::linear([0.0], [1.0], 1.0).unwrap())
        .unwrap();
    s.push(Polynomial::linear([1.0], [2.0], 1.0).unwrap())
        .unwrap();
    s.push(Polynomial::linear([2.0], [3.0], 1.0).unwrap())
        .unwrap();
    s.push(Polynomial::linear([3.5], [4.0], 1.0).unwrap())
        .unwrap();
    let err = s.check_continuity(0, 1e-12).unwrap_err();
    assert_eq!((err.boundary, err.order, err.axis), (2, 0, 0));
    assert!((err.jump - 0.5).abs() < 1e-15);
    assert!(matches!(
        s.push(Polynomial::linear([4.0], [5.0], 1.0).unwrap()),
        Err(TrajectoryError::Capacity {
            capacity: 4,
            requested: 5
        })
    ));
}

#[test]
fn blends_start_and_end_at_rest_and_are_as_smooth_as_their_shape() {
    for (shape, order) in [
        (BlendShape::Parabolic, 1),
        (BlendShape::Quartic, 2),
        (BlendShape::Sextic, 3),
    ] {
        for blend in [BlendTime::Seconds(0.2), BlendTime::Fraction(0.4)] {
            let s: Piecewise<Polynomial<2, 7>, 11> =
                spline::linear_with_blends(&TIMES, &POINTS, shape, blend).unwrap();
            assert!(
                (s.duration() - 4.0).abs() < 1e-12,
                "{shape:?} {}",
                s.duration()
            );
            assert_close("start", s.position(0.0), POINTS[0], TOL);
            assert_close("end", s.position(4.0), POINTS[5], TOL);
            for o in 1..=order {
                assert_close("rest start", s.derivative(0.0, o), [0.0; 2], TOL);
                assert_close("rest end", s.derivative(4.0, o), [0.0; 2], TOL);
            }
            s.check_continuity(order, 1e-9)
                .unwrap_or_else(|e| panic!("{shape:?}: {e}"));
            assert!(
                s.check_continuity(order + 1, 1e-9).is_err(),
                "{shape:?} is smoother than claimed"
            );
            let boundaries: Vec<f64> = s.starts().to_vec();
            check_finite_differences(&s, order + 1, 101, &boundaries);
        }
    }
}

#[test]
fn blend_lines_pass_through_interior_waypoints() {
    // Between blends the trajectory is the line through neighbouring waypoints.
    let tb = 0.1;
    let s: Piecewise<Polynomial<2, 7>, 11> =
        spline::linear_with_blends(&TIMES, &POINTS, BlendShape::Quartic, BlendTime::Seconds(tb))
            .unwrap();
    // Segment between waypoints 2 and 3 (both interior): velocity = chord slope.
    let t = 0.5 * (TIMES[2] + TIMES[3]);
    let slope = [
        (POINTS[3][0] - POINTS[2][0]) / 0.5,
        (POINTS[3][1] - POINTS[2][1]) / 0.5,
    ];
    assert_close("chord velocity", s.derivative(t, 1), slope, TOL);
    let expect = [
        POINTS[2][0] + slope[0] * (t - TIMES[2]),
        POINTS[2][1] + slope[1] * (t - TIMES[2]),
    ];
    assert_close("on the line", s.position(t), expect, TOL);
}

#[test]
fn blends_that_do_not_fit_are_errors() {
    let r: Result<Piecewise<Polynomial<2, 7>, 11>, _> = spline::linear_with_blends(
        &TIMES,
        &POINTS,
        BlendShape::Parabolic,
        BlendTime::Seconds(0.5),
    );
    assert!(matches!(r, Err(TrajectoryError::BlendTooLong { .. })));
    let r: Result<Piecewise<Polynomial<2, 7>, 10>, _> = spline::linear_with_blends(
        &TIMES,
        &POINTS,
        BlendShape::Parabolic,
        BlendTime::Seconds(0.1),
    );
    assert_eq!(
        r.unwrap_err(),
        TrajectoryError::Capacity {
            capacity: 10,
            requested: 11
        }
    );
}

#[test]
fn smooth_trapezoids_at_rest_respect_limits_and_synchronise() {
    let limits = Limits {
        velocity: [1.0, 0.5],
        acceleration: [2.0, 4.0],
        jerk: [f64::INFINITY; 2],
    };
    for (shape, order) in [
        (BlendShape::Parabolic, 1),
        (BlendShape::Quartic, 2),
        (BlendShape::Sextic, 3),
    ] {
        let s: Piecewise<Polynomial<2, 7>, 15> =
            spline::smooth_trapezoid_at_rest(&POINTS, &limits, shape).unwrap();
        let v = max_abs_over_segments(&s, 1);
        let a = max_abs_over_segments(&s, 2);
        for i in 0..2 {
            assert!(
                v[i] <= limits.velocity[i] * (1.0 + 1e-9),
                "{shape:?} v{i} {}",
                v[i]
            );
            assert!(
                a[i] <= limits.acceleration[i] * (1.0 + 1e-9),
                "{shape:?} a{i} {}",
                a[i]
            );
        }
        s.check_continuity(order, 1e-9).unwrap();
        // Every move ends exactly at its waypoint at rest, and each is as short as possible:
        // within each move one axis reaches its velocity or acceleration limit.
        for (m, seg) in s.segments().chunks(3).enumerate() {
            assert_close(
                "move end",
                seg[2].position(seg[2].duration()),
                POINTS[m + 1],
                TOL,
            );
            for o in 1..=order {
                assert_close(
                    "at rest",
                    seg[2].derivative(seg[2].duration(), o),
                    [0.0; 2],
                    TOL,
                );
            }
            let mut usage: f64 = 0.0;
            for p in seg {
                let (pv, pa) = (p.max_abs_derivative(1), p.max_abs_derivative(2));
                for i in 0..2 {
                    usage = usage
                        .max(pv[i] / limits.velocity[i])
                        .max(pa[i] / limits.acceleration[i]);
                }
            }
            assert!(
                (usage - 1.0).abs() < 1e-9,
                "{shape:?} move {m}: usage {usage}"
            );
        }
    }
    let r: Result<Piecewise<Polynomial<2, 7>, 15>, _> =
        spline::four_one_four_at_rest(&POINTS, &Limits::uniform(1.0, 0.0, 1.0));
    assert!(matches!(r, Err(TrajectoryError::BadLimit { axis: 0, .. })));
    let r: Result<Piecewise<Polynomial<2, 7>, 14>, _> =
        spline::six_one_six_at_rest(&POINTS, &limits);
    assert!(matches!(r, Err(TrajectoryError::Capacity { .. })));
}

#[test]
fn at_rest_polynomials_through_waypoints() {
    let limits = Limits::uniform(1.0, 2.0, 10.0);
    let s: Piecewise<Polynomial<2, 6>, 5> = spline::at_rest_through(&POINTS, &limits).unwrap();
    s.check_continuity(2, 1e-12).unwrap();
    let mut t = 0.0;
    for (i, seg) in s.segments().iter().enumerate() {
        assert_close("waypoint", s.position(t), POINTS[i], TOL);
        t += seg.duration();
    }
    assert_close("last", s.position(t), POINTS[5], TOL);
    let r: Result<Piecewise<Polynomial<2, 5>, 5>, _> = spline::at_rest_through(&POINTS, &limits);
    assert_eq!(r.unwrap_err(), TrajectoryError::Degenerate);
}

#[test]
fn bad_waypoints_are_typed_errors() {
    let mut times = TIMES;
    times[3] = times[2];
    let r: Result<Piecewise<Polynomial<2, 4>, 8>, _> = spline::natural_cubic(&times, &POINTS);
    assert_eq!(
        r.unwrap_err(),
        TrajectoryError::NonIncreasingTime { index: 3 }
    );
    let mut points = POINTS;
    points[4][1] = f64::NAN;
    let r: Result<Piecewise<Polynomial<2, 4>, 8>, _> = spline::natural_cubic(&TIMES, &points);
    assert_eq!(
        r.unwrap_err(),
        TrajectoryError::NotFinite {
            what: "waypoint",
            index: 4
        }
    );
    let r: Result<Piecewise<Polynomial<2, 4>, 4>, _> = spline::natural_cubic(&TIMES, &POINTS);
    assert_eq!(
        r.unwrap_err(),
        TrajectoryError::Capacity {
            capacity: 4,
            requested: 5
        }
    );
    let r: Result<Piecewise<Polynomial<2, 4>, 8>, _> =
        spline::natural_cubic(&TIMES[..1], &POINTS[..1]);
    assert_eq!(
        r.unwrap_err(),
        TrajectoryError::TooFewWaypoints {
            required: 2,
            given: 1
        }
    );
    let r: Result<Piecewise<Polynomial<2, 4>, 8>, _> = spline::natural_cubic(&TIMES[..3], &POINTS);
    assert!(matches!(r, Err(TrajectoryError::TooFewWaypoints { .. })));
}

#[test]
fn a_spline_of_splines_plays_them_in_order() {
    // Two natural cubic splines one after another: composition of piecewise functions.
    let first: Piecewise<Polynomial<2, 4>, 5> =
        spline::natural_cubic(&TIMES[..3], &POINTS[..3]).unwrap();
    let second: Piecewise<Polynomial<2, 4>, 5> =
        spline::natural_cubic(&TIMES[2..], &POINTS[2..]).unwrap();
    let mut both: Piecewise<Piecewise<Polynomial<2, 4>, 5>, 2> = Piecewise::new();
    both.push(first.clone()).unwrap();
    both.push(second.clone()).unwrap();
    assert!((both.duration() - 4.0).abs() < 1e-15);
    for k in 0..=40 {
        let t = 4.0 * k as f64 / 40.0;
        let expect = if t < 1.5 {
            first.sample(t)
        } else {
            second.sample(t - 1.5)
        };
        assert_close("composed", both.position(t), expect.position, 1e-15);
        assert_close(
            "composed v",
            both.sample(t).velocity,
            expect.velocity,
            1e-15,
        );
    }
    // Both end at rest in acceleration and meet at waypoint 2: C⁰ and C² there, velocity jumps.
    both.check_continuity(0, 1e-12).unwrap();
    let e = both.check_continuity(1, 1e-12).unwrap_err();
    assert_eq!((e.boundary, e.order), (0, 1));
}
