//! The task-space law's cycle with obstacle avoidance for a 7-axis arm (RL's KUKA LBR iiwa 7
//! R800): forward kinematics, 30 capsules on the arm moved to the world, each capsule's
//! nearest of 50 obstacle spheres, the 8 nearest proximities, and rl-core's operational-space
//! impedance with the orientation first, the position and the repulsion in its nullspace and
//! the posture last (`rl_core::task::operational_impedance`). Issue 27's goal: ≤ 10 µs per
//! cycle on the machine the controller runs on; `scripts/bench-task-space` compares the same
//! law on Pinocchio.
//!
//! `cargo bench -p rl-sg --bench task_avoidance`

#![allow(missing_docs)] // criterion_group! generates an undocumented function

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use rl_core::spatial::PlueckerTransform;
use rl_core::task::{
    ImpedanceGains, MAX_PROXIMITIES, Priority, Proximity, TaskData, TaskTarget,
    operational_impedance,
};
use rl_core::{Data, algo, loader};
use rl_sg::capsule::{Capsule, CapsuleModel, LinkCapsule};

/// The arm, and 30 capsules: four along each body's link (two on the last), radius 6–8 cm.
fn arm() -> (rl_core::Model<16>, CapsuleModel<32>) {
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/rlmdl/kuka-lbr-iiwa-7-r800.xml");
    let model = loader::load_file::<16>(&file)
        .expect("the iiwa model")
        .model;
    let mut data = Data::<16>::new();
    let q = vec![0.0; model.nq()];
    algo::forward_position(&model, &mut data, &q).expect("fk");
    let mut caps = CapsuleModel::<32>::new();
    let bodies = model.body_count();
    for b in 0..bodies {
        let x = *data.world_pose(b);
        let next = if b + 1 < bodies {
            data.world_pose(b + 1).translation
        } else {
            x.translation + x.rotation * DVec3::Z * 0.12
        };
        let end = x.rotation.transpose() * (next - x.translation);
        let pieces = if b + 1 < bodies {
            4
        } else {
            30 - 4 * (bodies - 1)
        };
        let radius = 0.08 - 0.003 * b as f64;
        for k in 0..pieces {
            let (s, e) = (k as f64 / pieces as f64, (k + 1) as f64 / pieces as f64);
            caps.push(LinkCapsule::new(
                b,
                b as u16,
                Capsule::new(end * s, end * e, radius),
            ))
            .unwrap();
        }
    }
    (model, caps)
}

fn task_avoidance(c: &mut Criterion) {
    let (model, mut caps) = arm();
    let n = model.dof();
    let mut data = Box::new(Data::<16>::new());
    let mut task = Box::new(TaskData::<16>::new());
    let mut s = 11u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    // States near a working pose, and obstacles around the arm's reach.
    let home = [0.0, 0.6, 0.0, -1.2, 0.0, 0.9, 0.0];
    let states: Vec<(Vec<f64>, Vec<f64>)> = (0..64)
        .map(|_| {
            (
                home.iter().map(|h| h + (rnd() - 0.5) * 0.6).collect(),
                (0..n).map(|_| (rnd() - 0.5) * 2.0).collect(),
            )
        })
        .collect();
    let spheres: Vec<Capsule> = (0..50)
        .map(|_| {
            Capsule::sphere(
                DVec3::new(rnd() * 1.2 - 0.3, rnd() * 1.2 - 0.6, rnd() * 1.3),
                0.03 + 0.07 * rnd(),
            )
        })
        .collect();
    let velocities = [DVec3::ZERO; 0];
    algo::forward_position(&model, &mut data, &home).unwrap();
    let x = algo::tool_pose(&model, &data, 0).unwrap();
    let target = TaskTarget::at(PlueckerTransform::new(
        x.rotation,
        x.translation + DVec3::new(0.05, 0.0, 0.0),
    ));
    let gains = ImpedanceGains {
        priority: Priority::OrientationFirst,
        ..ImpedanceGains::default()
    };
    let mut near = [Proximity::at_rest(0, DVec3::ZERO, DVec3::X, 0.0); MAX_PROXIMITIES];
    let mut tau = vec![0.0; n];
    // How many proximities repel per state (printed, so the row's work is known).
    let mut repelling = 0;
    for (q, qd) in &states {
        algo::forward_position(&model, &mut data, q).unwrap();
        caps.update(&data);
        let k = caps.proximities(&spheres, &velocities, gains.repulsion.influence, &mut near);
        task.set_proximities(&near[..k]).unwrap();
        let r = operational_impedance(
            &model, &mut data, &mut task, 0, &gains, &target, q, qd, &home, &mut tau,
        )
        .unwrap();
        repelling += r.repelling;
    }
    println!(
        "{} capsules × {} spheres; {:.2} proximities inside the influence distance per state",
        caps.len(),
        spheres.len(),
        repelling as f64 / states.len() as f64
    );
    let mut i = 0;
    c.bench_function(
        "task_avoidance: fk + 30 capsules × 50 spheres + law",
        |b| {
            b.iter(|| {
                i = (i + 1) % states.len();
                let (q, qd) = &states[i];
                algo::forward_position(&model, &mut data, black_box(q)).unwrap();
                caps.update(&data);
                let k = caps.proximities(
                    black_box(&spheres),
                    &velocities,
                    gains.repulsion.influence,
                    &mut near,
                );
                task.set_proximities(&near[..k]).unwrap();
                black_box(
                    operational_impedance(
                        &model, &mut data, &mut task, 0, &gains, &target, q, qd, &home, &mut tau,
                    )
                    .unwrap(),
                )
            })
        },
    );
    c.bench_function(
        "task_avoidance: proximities 30 capsules × 50 spheres",
        |b| {
            b.iter(|| {
                black_box(caps.proximities(
                    black_box(&spheres),
                    &velocities,
                    gains.repulsion.influence,
                    &mut near,
                ))
            })
        },
    );
    task.set_proximities(&[]).unwrap();
    c.bench_function("task_avoidance: law without obstacles", |b| {
        b.iter(|| {
            i = (i + 1) % states.len();
            let (q, qd) = &states[i];
            black_box(
                operational_impedance(
                    &model, &mut data, &mut task, 0, &gains, &target, q, qd, &home, &mut tau,
                )
                .unwrap(),
            )
        })
    });
}

criterion_group!(benches, task_avoidance);
criterion_main!(benches);
