//! Trajectory benchmarks, 7 axes (issue 4): evaluation of position, velocity, acceleration and
//! jerk, and construction of a quintic at rest, a cubic spline through 6 waypoints and a
//! jerk-limited profile at rest. `scripts/bench-ruckig` runs this and Ruckig in one go.

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DQuat, DVec3};
use rl_core::traj::{
    CubicQuaternionSpline, JerkLimited, Limits, Piecewise, Polynomial, RotationTrajectory,
    Trajectory, spline,
};

#[path = "../tests/support/waypoints.rs"]
mod waypoints;
use waypoints::{POINTS, TIMES};

/// Walks `t` through the trajectory at 1 kHz so every call evaluates a different time. The
/// result goes to `black_box` by reference: it must exist in memory, but returning it by
/// value would time one more copy of it (criterion's), not the evaluation.
fn eval<const D: usize, T: Trajectory<D>>(c: &mut Criterion, name: &str, traj: &T) {
    let end = traj.duration();
    let mut t = 0.0;
    c.bench_function(name, |b| {
        b.iter(|| {
            t += 0.001;
            if t > end {
                t = 0.0;
            }
            let s = traj.sample(black_box(t));
            black_box(&s);
        })
    });
}

fn evaluation(c: &mut Criterion) {
    let limits = Limits::<7>::uniform(1.0, 2.0, 10.0);
    let quintic = Polynomial::quintic_at_rest(POINTS[0], POINTS[1], &limits).unwrap();
    eval(c, "eval/quintic_7", &quintic);
    let cubic: Piecewise<Polynomial<7, 4>, 8> = spline::natural_cubic(&TIMES, &POINTS).unwrap();
    eval(c, "eval/cubic_spline_6wp_7", &cubic);
    let jerk = JerkLimited::new(POINTS[0], POINTS[1], &limits).unwrap();
    eval(c, "eval/jerk_limited_7", &jerk);
    let sextic: Piecewise<Polynomial<7, 7>, 15> =
        spline::six_one_six_at_rest(&POINTS, &limits).unwrap();
    eval(c, "eval/six_one_six_6wp_7", &sextic);
    let q = [
        DQuat::IDENTITY,
        DQuat::from_rotation_x(1.0),
        DQuat::from_rotation_y(0.5),
        DQuat::from_rotation_z(-0.7),
    ];
    let rot: CubicQuaternionSpline<4> =
        CubicQuaternionSpline::new(&TIMES[..4], &q, DVec3::ZERO, DVec3::ZERO).unwrap();
    let mut t = 0.0;
    c.bench_function("eval/quaternion_spline", |b| {
        b.iter(|| {
            t += 0.001;
            if t > 2.0 {
                t = 0.0;
            }
            let r = rot.rotation(black_box(t));
            black_box(&r);
        })
    });
}

/// Results by reference to `black_box`, as in [`eval`].
fn construction(c: &mut Criterion) {
    let limits = Limits::<7>::uniform(1.0, 2.0, 10.0);
    c.bench_function("build/quintic_at_rest_7", |b| {
        b.iter(|| {
            let p = Polynomial::quintic_at_rest(
                black_box(POINTS[0]),
                black_box(POINTS[1]),
                black_box(&limits),
            );
            black_box(&p);
        })
    });
    c.bench_function("build/cubic_spline_6wp_7", |b| {
        b.iter(|| {
            let s: Result<Piecewise<Polynomial<7, 4>, 8>, _> =
                spline::natural_cubic(black_box(&TIMES), black_box(&POINTS));
            black_box(&s);
        })
    });
    c.bench_function("build/jerk_limited_7", |b| {
        b.iter(|| {
            let j = JerkLimited::new(
                black_box(POINTS[0]),
                black_box(POINTS[1]),
                black_box(&limits),
            );
            black_box(&j);
        })
    });
}

criterion_group!(benches, evaluation, construction);
criterion_main!(benches);
