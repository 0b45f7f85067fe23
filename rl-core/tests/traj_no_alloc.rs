//! A counting global allocator proves that constructing and evaluating every trajectory type
//! allocates nothing. The counter is per thread (rl-testkit), so tests running in parallel do
//! not see each other's allocations.

use std::hint::black_box;

use glam::{DQuat, DVec3};
use rl_core::traj::{
    BlendShape, BlendTime, Circular, CubicQuaternionSpline, JerkLimited, JerkLimitedRotation,
    Limits, Piecewise, Polynomial, PoseTrajectory, RotationTrajectory, SlerpTrajectory, Trajectory,
    spline,
};
use rl_testkit::{CountingAllocator, allocations as count};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[path = "support/waypoints.rs"]
mod waypoints;
use waypoints::{POINTS, TIMES};

fn sample_all<const D: usize, T: Trajectory<D>>(t: &T) -> f64 {
    let mut acc = 0.0;
    for k in 0..=100 {
        let s = t.sample(t.duration() * k as f64 / 100.0);
        acc += s.position[0] + s.velocity[0] + s.acceleration[0] + s.jerk[0];
        acc += t.derivative(0.3, 4)[0];
    }
    acc
}

#[test]
fn construction_and_evaluation_allocate_nothing() {
    let limits = Limits::<7>::uniform(1.0, 2.0, 10.0);
    // Warm up lazily initialised runtime state (thread-locals) outside the measurement.
    black_box(Polynomial::quintic_at_rest(POINTS[0], POINTS[1], &limits).unwrap());

    let mut report: Vec<(&str, u64)> = Vec::with_capacity(32);
    let mut total = 0.0;
    let mut step = |name: &'static str, f: &mut dyn FnMut() -> f64| {
        let (n, v) = count(f);
        total += v;
        report.push((name, n));
    };
    step("quintic at rest", &mut || {
        let p = Polynomial::quintic_at_rest(POINTS[0], POINTS[1], &limits).unwrap();
        sample_all(&p)
    });
    step("septic, extrema", &mut || {
        let p = Polynomial::septic(
            POINTS[0], POINTS[1], POINTS[2], POINTS[3], POINTS[4], POINTS[5], POINTS[0], POINTS[1],
            1.5,
        )
        .unwrap();
        sample_all(&p) + p.extrema().max[0] + p.max_abs_derivative(2)[0]
    });
    step("natural cubic", &mut || {
        let s: Piecewise<Polynomial<7, 4>, 8> = spline::natural_cubic(&TIMES, &POINTS).unwrap();
        s.check_continuity(2, 1e-9).unwrap();
        sample_all(&s)
    });
    step("clamped cubic", &mut || {
        let s: Piecewise<Polynomial<7, 4>, 8> =
            spline::clamped_cubic(&TIMES, &POINTS, [0.0; 7], [0.0; 7]).unwrap();
        sample_all(&s)
    });
    step("linear with sextic blends", &mut || {
        let s: Piecewise<Polynomial<7, 7>, 11> = spline::linear_with_blends(
            &TIMES,
            &POINTS,
            BlendShape::Sextic,
            BlendTime::Fraction(0.3),
        )
        .unwrap();
        sample_all(&s)
    });
    step("6-1-6 at rest", &mut || {
        let s: Piecewise<Polynomial<7, 7>, 15> =
            spline::six_one_six_at_rest(&POINTS, &limits).unwrap();
        sample_all(&s)
    });
    step("quintics through waypoints", &mut || {
        let s: Piecewise<Polynomial<7, 6>, 5> = spline::at_rest_through(&POINTS, &limits).unwrap();
        sample_all(&s)
    });
    step("jerk-limited", &mut || {
        let j = JerkLimited::new(POINTS[0], POINTS[1], &limits).unwrap();
        sample_all(&j)
    });
    step("jerk-limited through waypoints", &mut || {
        let s: Piecewise<JerkLimited<7>, 5> =
            spline::jerk_limited_through(&POINTS, &limits).unwrap();
        sample_all(&s)
    });
    step("circular arc", &mut || {
        let c =
            Circular::<3>::through([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], 2.0).unwrap();
        sample_all(&c)
    });
    let q = [
        DQuat::IDENTITY,
        DQuat::from_rotation_x(1.0),
        DQuat::from_rotation_y(0.5),
    ];
    step("quaternion spline", &mut || {
        let r: CubicQuaternionSpline<4> =
            CubicQuaternionSpline::new(&TIMES[..3], &q, DVec3::ZERO, DVec3::X).unwrap();
        r.rotation(0.7).angular_acceleration.x
    });
    step("jerk-limited rotation", &mut || {
        let jr = JerkLimitedRotation::new(q[0], q[1], 1.0, 2.0, 10.0).unwrap();
        jr.rotation(0.3).orientation.x
    });
    step("pose", &mut || {
        let pos = Polynomial::quintic_at_rest([0.0; 3], [1.0; 3], &Limits::uniform(1.0, 1.0, 1.0))
            .unwrap();
        let pose = PoseTrajectory::new(
            pos,
            SlerpTrajectory::new(q[0], q[2], pos.duration()).unwrap(),
        )
        .unwrap();
        pose.sample(0.5).twist()[4]
    });
    step("error path", &mut || {
        spline::natural_cubic::<7, 2>(&TIMES, &POINTS).is_err() as u8 as f64
    });
    assert!(total.is_finite());
    let bad: Vec<_> = report.iter().filter(|(_, n)| *n > 0).collect();
    assert!(bad.is_empty(), "allocations: {bad:?}");
    assert_eq!(report.len(), 14);
}

#[test]
fn the_counter_does_count() {
    // Guards against a counter that cannot fail.
    let (n, v) = count(|| black_box(vec![1u8, 2, 3]));
    assert_eq!(v.len(), 3);
    assert!(n >= 1);
}
