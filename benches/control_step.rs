//! Cost of one full control step of `rl run` for the 6-axis RV-6SL: read the measured joints,
//! evaluate the jerk-limited trajectory, inverse dynamics (RNEA) feed-forward, command the next
//! position, and step the H7 device against the in-process fake on loopback (one UDP round
//! trip). The parts are measured alone too, so the network's share is visible. This is the
//! number that tells how fast a loop the library supports on a machine.
//!
//! A planned path's trajectory is sampled alone too: blended through its waypoints, and the same
//! path retimed with bounded jerk (`rl run --plan`'s default, whose sample finds the path's own
//! time by Newton steps on its arc length).
//!
//! `cargo bench --bench control_step`

#![allow(missing_docs)] // criterion_group! generates an undocumented function
#[path = "../tests/common/mod.rs"]
mod common;

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use rl::controller::{Controller, MotionLimits, Plan, default_waypoints, rv6sl};
use rl::core::traj::Trajectory;
use rl::core::{Data, algo};
use rl::drivers::{CyclicDevice, Device, JointPositionSensor};

fn control_step(c: &mut Criterion) {
    let loaded = rv6sl().expect("embedded model");
    let model = loaded.model;
    let dof = model.dof();
    let fake = common::immediate_fake(dof);
    let robot = common::started_h7(&fake, dof);
    let mut start = vec![0.0; dof];
    robot.joint_position(&mut start).expect("joints");
    let limits = MotionLimits::<8>::from_model(&model, 0.25).expect("limits");
    let plan =
        Plan::new(&model, &start, &default_waypoints(&model, &start), &limits).expect("plan");
    let trajectory = plan.trajectory().clone();
    let duration = plan.duration_s();
    let mut control =
        Box::new(Controller::new(robot, model.clone(), plan, common::PERIOD).expect("controller"));

    let mut group = c.benchmark_group("control_step");
    group.measurement_time(Duration::from_secs(3));
    group.bench_function("full cycle, 6 axes, H7 fake on loopback", |b| {
        b.iter(|| {
            let out = control.cycle();
            if out.finished {
                // The tour returns to its start, so restarting keeps the command continuous.
                control.rewind();
            }
            black_box(out.record.feed_forward)
        })
    });
    assert_eq!(
        control.failed_steps(),
        0,
        "lost replies during the benchmark"
    );

    let mut t = 0.0;
    group.bench_function("trajectory sample", |b| {
        b.iter(|| {
            t = if t > duration { 0.0 } else { t + 0.00711 };
            black_box(trajectory.sample(black_box(t)))
        })
    });
    let blended = common::tour_as_planned_path(&model, &start, &limits, false);
    let retimed = common::tour_as_planned_path(&model, &start, &limits, true);
    for (name, tr) in [
        ("planned path sample, blended", &blended),
        ("planned path sample, retimed with bounded jerk", &retimed),
    ] {
        let duration = tr.duration();
        let mut t = 0.0;
        group.bench_function(name, |b| {
            b.iter(|| {
                t = if t > duration { 0.0 } else { t + 0.00711 };
                black_box(tr.sample(black_box(t)))
            })
        });
    }
    let mut data = Box::new(Data::new());
    let s = trajectory.sample(0.3 * duration);
    group.bench_function("RNEA feed-forward", |b| {
        b.iter(|| {
            let tau = algo::rnea(
                &model,
                &mut data,
                black_box(&s.position[..dof]),
                black_box(&s.velocity[..dof]),
                black_box(&s.acceleration[..dof]),
            )
            .expect("lengths");
            black_box(tau[0])
        })
    });
    let mut robot = control.into_robot();
    group.bench_function("H7 device step (UDP round trip)", |b| {
        b.iter(|| robot.step().expect("step"))
    });
    group.finish();
    robot.stop().expect("stop");
    robot.close().expect("close");
}

criterion_group!(benches, control_step);
criterion_main!(benches);
