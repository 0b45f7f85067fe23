//! Polynomials: every boundary-condition constructor to 1e-12, derivative and integral,
//! extrema, at-rest constructors within their limits (exact maxima) and synchronised.

mod traj_support;

use rl_core::traj::{Limits, Polynomial, Trajectory, TrajectoryError};
use traj_support::{assert_close, check_finite_differences, check_sample_matches};

const X0: [f64; 3] = [0.5, -1.0, 2.0];
const X1: [f64; 3] = [1.5, 0.25, -3.0];
const V0: [f64; 3] = [0.1, -0.4, 0.0];
const V1: [f64; 3] = [-0.3, 0.2, 1.0];
const A0: [f64; 3] = [1.0, 0.0, -2.0];
const A1: [f64; 3] = [0.5, -1.5, 0.25];
const J0: [f64; 3] = [3.0, -1.0, 0.0];
const J1: [f64; 3] = [-2.0, 0.5, 4.0];
const T: f64 = 1.7;
const TOL: f64 = 1e-12;

fn check<const C: usize>(
    p: &Polynomial<3, C>,
    start: &[(usize, [f64; 3])],
    end: &[(usize, [f64; 3])],
) {
    for &(order, value) in start {
        assert_close("start", p.derivative(0.0, order), value, TOL);
    }
    for &(order, value) in end {
        assert_close("end", p.derivative(T, order), value, TOL);
    }
    check_finite_differences(p, 4, 23, &[]);
    check_sample_matches(p, 9);
}

#[test]
fn boundary_conditions_of_every_constructor() {
    let p = Polynomial::linear(X0, X1, T).unwrap();
    check(&p, &[(0, X0)], &[(0, X1)]);
    let p = Polynomial::quadratic(X0, X1, V0, T).unwrap();
    check(&p, &[(0, X0), (1, V0)], &[(0, X1)]);
    let p = Polynomial::cubic(X0, X1, V0, V1, T).unwrap();
    check(&p, &[(0, X0), (1, V0)], &[(0, X1), (1, V1)]);
    let p = Polynomial::cubic_from_accelerations(X0, X1, A0, A1, T).unwrap();
    check(&p, &[(0, X0), (2, A0)], &[(0, X1), (2, A1)]);
    let p = Polynomial::quartic(X0, X1, V0, V1, A0, T).unwrap();
    check(&p, &[(0, X0), (1, V0), (2, A0)], &[(0, X1), (1, V1)]);
    let p = Polynomial::quintic(X0, X1, V0, V1, A0, A1, T).unwrap();
    check(
        &p,
        &[(0, X0), (1, V0), (2, A0)],
        &[(0, X1), (1, V1), (2, A1)],
    );
    let p = Polynomial::sextic(X0, X1, V0, V1, A0, A1, J0, T).unwrap();
    check(
        &p,
        &[(0, X0), (1, V0), (2, A0), (3, J0)],
        &[(0, X1), (1, V1), (2, A1)],
    );
    let p = Polynomial::septic(X0, X1, V0, V1, A0, A1, J0, J1, T).unwrap();
    check(
        &p,
        &[(0, X0), (1, V0), (2, A0), (3, J0)],
        &[(0, X1), (1, V1), (2, A1), (3, J1)],
    );
}

#[test]
fn derivative_and_integral_are_exact_inverses() {
    let p = Polynomial::quintic(X0, X1, V0, V1, A0, A1, T).unwrap();
    let d: Polynomial<3, 5> = p.derivative_polynomial();
    let back: Polynomial<3, 6> = d.integral(X0);
    for k in 0..=10 {
        let t = T * k as f64 / 10.0;
        assert_close("derivative", d.position(t), p.derivative(t, 1), TOL);
        assert_close("d'' ", d.derivative(t, 1), p.derivative(t, 2), TOL);
        assert_close("integral", back.position(t), p.position(t), TOL);
    }
    // Beyond the degree every derivative is zero.
    assert_eq!(p.derivative(0.3, 6), [0.0; 3]);
    assert_eq!(p.degree(), 5);
}

#[test]
fn extrema_of_a_known_polynomial() {
    // p(t) = (t - 1)² on [0, 3]: min 0 at 1, max 4 at 3.  q(t) = -(t-2)^3 + 3t: critical t = 1, 3.
    let p = Polynomial::<2, 4>::new(
        [
            [1.0, -8.0 + 0.0],
            [-2.0, 12.0 + 3.0],
            [1.0, -6.0],
            [0.0, 1.0],
        ],
        3.0,
    )
    .unwrap();
    // axis 1: (t-2)³ + 3t = t³ - 6t² + 15t - 8, p' = 3t² - 12t + 15 > 0: monotonic.
    let e = p.extrema();
    assert!((e.min[0] - 0.0).abs() < 1e-15 && (e.time_of_min[0] - 1.0).abs() < 1e-12);
    assert!((e.max[0] - 4.0).abs() < 1e-15 && e.time_of_max[0] == 3.0);
    assert_eq!((e.time_of_min[1], e.time_of_max[1]), (0.0, 3.0));
    // A cubic with an interior max and min: p = t³ - 1.5 t² on [-.., 2]: critical 0 and 1.
    let q = Polynomial::<1, 4>::new([[0.5], [0.0], [-1.5], [1.0]], 2.0).unwrap();
    let e = q.extrema();
    // p(0)=0.5, p(1)=0, p(2)=2.5.
    assert!((e.min[0] - 0.0).abs() < 1e-15 && (e.time_of_min[0] - 1.0).abs() < 1e-12);
    assert!((e.max[0] - 2.5).abs() < 1e-15);
}

#[test]
fn at_rest_constructors_reach_the_goal_at_rest_within_limits() {
    let limits = Limits {
        velocity: [1.0, 2.0, 0.5],
        acceleration: [3.0, 1.0, 4.0],
        jerk: [20.0, 5.0, 9.0],
    };
    let check =
        |d: f64, p1: [f64; 3], pos: [f64; 3], vel: [f64; 3], acc: [f64; 3], jerk: [f64; 3]| {
            assert_close("goal", pos, p1, TOL);
            for (what, peak, lim) in [
                ("velocity", vel, limits.velocity),
                ("acceleration", acc, limits.acceleration),
                ("jerk", jerk, limits.jerk),
            ] {
                for i in 0..3 {
                    assert!(
                        peak[i] <= lim[i] * (1.0 + 1e-9),
                        "{what} axis {i}: {} > {}",
                        peak[i],
                        lim[i]
                    );
                }
            }
            assert!(d > 0.0);
        };
    let p = Polynomial::cubic_at_rest(X0, X1, &limits).unwrap();
    check(
        p.duration(),
        X1,
        p.position(p.duration()),
        p.max_abs_derivative(1),
        p.max_abs_derivative(2),
        p.max_abs_derivative(3),
    );
    assert_close("rest", p.derivative(p.duration(), 1), [0.0; 3], TOL);
    let p = Polynomial::quintic_at_rest(X0, X1, &limits).unwrap();
    check(
        p.duration(),
        X1,
        p.position(p.duration()),
        p.max_abs_derivative(1),
        p.max_abs_derivative(2),
        p.max_abs_derivative(3),
    );
    for order in 1..=2 {
        assert_close("rest start", p.derivative(0.0, order), [0.0; 3], TOL);
        assert_close("rest end", p.derivative(p.duration(), order), [0.0; 3], TOL);
    }
    let p = Polynomial::septic_at_rest(X0, X1, &limits).unwrap();
    check(
        p.duration(),
        X1,
        p.position(p.duration()),
        p.max_abs_derivative(1),
        p.max_abs_derivative(2),
        p.max_abs_derivative(3),
    );
    for order in 1..=3 {
        assert_close("rest start", p.derivative(0.0, order), [0.0; 3], TOL);
        assert_close("rest end", p.derivative(p.duration(), order), [0.0; 3], TOL);
    }
}

#[test]
fn at_rest_duration_is_the_shortest_one_limit_is_reached() {
    // Shortest means some axis touches some limit exactly.
    let limits = Limits {
        velocity: [1.0, 2.0, 0.5],
        acceleration: [3.0, 1.0, 4.0],
        jerk: [20.0, 5.0, 9.0],
    };
    let p = Polynomial::quintic_at_rest(X0, X1, &limits).unwrap();
    let ratios = [
        p.max_abs_derivative(1)
            .iter()
            .zip(limits.velocity)
            .map(|(a, b)| a / b)
            .fold(0.0f64, f64::max),
        p.max_abs_derivative(2)
            .iter()
            .zip(limits.acceleration)
            .map(|(a, b)| a / b)
            .fold(0.0f64, f64::max),
        p.max_abs_derivative(3)
            .iter()
            .zip(limits.jerk)
            .map(|(a, b)| a / b)
            .fold(0.0f64, f64::max),
    ];
    let max = ratios.iter().copied().fold(0.0f64, f64::max);
    assert!((max - 1.0).abs() < 1e-9, "peak usage {ratios:?}");
    // Unlimited jerk and acceleration: velocity alone decides, T = 1.875 h / v.
    let inf = f64::INFINITY;
    let p = Polynomial::<1, 6>::quintic_at_rest(
        [0.0],
        [2.0],
        &Limits {
            velocity: [1.0],
            acceleration: [inf],
            jerk: [inf],
        },
    )
    .unwrap();
    assert!((p.duration() - 3.75).abs() < 1e-15);
}

#[test]
fn no_motion_gives_a_constant_of_zero_duration() {
    let p = Polynomial::quintic_at_rest(X0, X0, &Limits::uniform(1.0, 1.0, 1.0)).unwrap();
    assert_eq!(p.duration(), 0.0);
    assert_eq!(p.position(5.0), X0);
    assert_eq!(p.derivative(0.0, 1), [0.0; 3]);
}

#[test]
fn bad_inputs_are_typed_errors() {
    assert_eq!(
        Polynomial::linear(X0, X1, 0.0),
        Err(TrajectoryError::BadDuration)
    );
    assert_eq!(
        Polynomial::linear(X0, X1, f64::NAN),
        Err(TrajectoryError::BadDuration)
    );
    assert_eq!(
        Polynomial::linear(X0, X1, -1.0),
        Err(TrajectoryError::BadDuration)
    );
    assert!(matches!(
        Polynomial::cubic([f64::NAN, 0.0, 0.0], X1, V0, V1, 1.0),
        Err(TrajectoryError::NotFinite {
            what: "boundary condition",
            index: 0
        })
    ));
    let mut bad = Limits::uniform(1.0, 1.0, 1.0);
    bad.acceleration[2] = 0.0;
    assert_eq!(
        Polynomial::quintic_at_rest(X0, X1, &bad),
        Err(TrajectoryError::BadLimit {
            axis: 2,
            kind: rl_core::traj::LimitKind::Acceleration
        })
    );
    bad.acceleration[2] = f64::NAN;
    assert!(matches!(
        Polynomial::quintic_at_rest(X0, X1, &bad),
        Err(TrajectoryError::BadLimit { axis: 2, .. })
    ));
    bad = Limits::uniform(1.0, -2.0, 1.0);
    assert!(matches!(
        Polynomial::cubic_at_rest(X0, X1, &bad),
        Err(TrajectoryError::BadLimit { axis: 0, .. })
    ));
    let inf = f64::INFINITY;
    assert_eq!(
        Polynomial::quintic_at_rest(X0, X1, &Limits::uniform(inf, inf, inf)),
        Err(TrajectoryError::Unreachable)
    );
    assert!(matches!(
        Polynomial::quintic_at_rest(X0, [0.0, inf, 0.0], &Limits::uniform(1.0, 1.0, 1.0)),
        Err(TrajectoryError::NotFinite { index: 1, .. })
    ));
}

#[test]
fn evaluation_outside_the_interval_holds_the_ends_and_nan_does_not_panic() {
    let p = Polynomial::quintic(X0, X1, V0, V1, A0, A1, T).unwrap();
    assert_eq!(p.position(-1.0), p.position(0.0));
    assert_eq!(p.position(T + 5.0), p.position(T));
    assert!(p.position(f64::NAN)[0].is_nan());
}
