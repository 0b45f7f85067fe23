//! Property tests over random waypoints, times and limits.

mod traj_support;

use glam::{DQuat, DVec3};
use proptest::prelude::*;
use rl_core::{
    rotation::exp,
    traj::{
        BlendShape, BlendTime, CubicQuaternionSpline, JerkLimited, Limits, Piecewise, Polynomial,
        RotationTrajectory, Trajectory, spline,
    },
};
use traj_support::assert_close;

const D: usize = 3;

fn waypoints() -> impl Strategy<Value = (Vec<f64>, Vec<[f64; D]>)> {
    (2usize..8).prop_flat_map(|n| {
        (
            prop::collection::vec(0.05f64..2.0, n),
            prop::collection::vec(prop::array::uniform3(-5.0f64..5.0), n),
        )
            .prop_map(|(gaps, points)| {
                let mut t = 0.0;
                let times = gaps
                    .iter()
                    .map(|g| {
                        let now = t;
                        t += g;
                        now
                    })
                    .collect();
                (times, points)
            })
    })
}

fn limits() -> impl Strategy<Value = Limits<D>> {
    (
        prop::array::uniform3(0.05f64..5.0),
        prop::array::uniform3(0.05f64..20.0),
        prop::array::uniform3(0.05f64..500.0),
    )
        .prop_map(|(velocity, acceleration, jerk)| Limits {
            velocity,
            acceleration,
            jerk,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn cubic_splines_interpolate_and_are_c2((times, points) in waypoints(), v0 in prop::array::uniform3(-2.0f64..2.0)) {
        let natural: Piecewise<Polynomial<D, 4>, 8> = spline::natural_cubic(&times, &points).unwrap();
        let clamped: Piecewise<Polynomial<D, 4>, 8> = spline::clamped_cubic(&times, &points, v0, [0.0; D]).unwrap();
        for s in [&natural, &clamped] {
            for (t, p) in times.iter().zip(&points) {
                assert_close("waypoint", s.position(*t), *p, 1e-9);
            }
            s.check_continuity(2, 1e-8).unwrap();
        }
        assert_close("v0", clamped.derivative(0.0, 1), v0, 1e-9);
    }

    #[test]
    fn jerk_limited_moves_respect_limits((_, points) in waypoints(), l in limits()) {
        let s: Piecewise<JerkLimited<D>, 8> = spline::jerk_limited_through(&points, &l).unwrap();
        s.check_continuity(2, 1e-9).unwrap();
        for (m, seg) in s.segments().iter().enumerate() {
            assert_close("goal", seg.position(seg.duration()), points[m + 1], 1e-9);
            assert_close("rest", seg.derivative(seg.duration(), 1), [0.0; D], 1e-9);
            let mut times: Vec<f64> = (0..=200).map(|k| seg.duration() * k as f64 / 200.0).collect();
            for axis in 0..D {
                times.extend(seg.phase_ends(axis).unwrap());
            }
            for t in times {
                let x = seg.sample(t);
                for i in 0..D {
                    prop_assert!(x.velocity[i].abs() <= l.velocity[i] * (1.0 + 1e-9));
                    prop_assert!(x.acceleration[i].abs() <= l.acceleration[i] * (1.0 + 1e-9));
                    prop_assert!(x.jerk[i].abs() <= l.jerk[i] * (1.0 + 1e-9));
                }
            }
            // The slowest axis is time-optimal: the move is as long as that axis needs alone.
            let alone = JerkLimited::axis_durations(points[m], points[m + 1], &l);
            prop_assert_eq!(seg.duration(), alone.iter().copied().fold(0.0, f64::max));
        }
    }

    #[test]
    fn at_rest_polynomials_respect_limits((_, points) in waypoints(), l in limits()) {
        let s: Piecewise<Polynomial<D, 8>, 8> = spline::at_rest_through(&points, &l).unwrap();
        s.check_continuity(3, 1e-9).unwrap();
        for seg in s.segments() {
            for (order, lim) in [(1, l.velocity), (2, l.acceleration), (3, l.jerk)] {
                let peak = seg.max_abs_derivative(order);
                for i in 0..D {
                    prop_assert!(peak[i] <= lim[i] * (1.0 + 1e-9), "order {} axis {}: {} > {}", order, i, peak[i], lim[i]);
                }
            }
        }
    }

    #[test]
    fn blends_are_continuous((times, points) in waypoints(), f in 0.05f64..=1.0) {
        let s: Piecewise<Polynomial<D, 7>, 15> = spline::linear_with_blends(&times, &points, BlendShape::Sextic, BlendTime::Fraction(f)).unwrap();
        s.check_continuity(3, 1e-9).unwrap();
        assert_close("end", s.position(s.duration()), *points.last().unwrap(), 1e-9);
    }

    #[test]
    fn quaternion_splines_stay_unit((times, points) in waypoints(), w in prop::array::uniform3(-1.0f64..1.0)) {
        let q: Vec<DQuat> = points.iter().map(|p| exp(DVec3::from_array(*p) * 0.3)).collect();
        let s: CubicQuaternionSpline<8> = CubicQuaternionSpline::new(&times, &q, DVec3::from_array(w), DVec3::ZERO).unwrap();
        for k in 0..=100 {
            let r = s.rotation(s.duration() * k as f64 / 100.0);
            prop_assert!((r.orientation.length() - 1.0).abs() < 1e-12);
            prop_assert!(r.angular_velocity.is_finite() && r.angular_acceleration.is_finite());
        }
    }
}
