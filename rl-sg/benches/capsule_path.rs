//! The control-rate distance path for a 7-axis arm (RL's KUKA LBR iiwa 7 R800) against ten
//! obstacle spheres: capsules along every link (two per link, 6–8 cm radius, from each body's
//! origin to the next), moved by forward kinematics, distances to the spheres. Goal: ≤ 1 µs per
//! query (update + distance) on the machine the controller runs on.
//!
//! `cargo bench -p rl-sg --bench capsule_path`

#![allow(missing_docs)] // criterion_group! generates an undocumented function

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use rl_core::{Data, algo, loader};
use rl_sg::capsule::{Capsule, CapsuleModel, LinkCapsule};

fn arm() -> (rl_core::Model<16>, CapsuleModel<32>) {
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/rlmdl/kuka-lbr-iiwa-7-r800.xml");
    let loaded = loader::load_file::<16>(&file).expect("the iiwa model");
    let model = loaded.model;
    let mut data = Data::<16>::new();
    let q = vec![0.0; model.nq()];
    algo::forward_position(&model, &mut data, &q).expect("fk");
    let mut caps = CapsuleModel::<32>::new();
    for b in 0..model.body_count() {
        // From this body's origin towards the next body's (or 10 cm along z at the tip), in
        // this body's frame: two capsules covering the link.
        let x = *data.world_pose(b);
        let next = if b + 1 < model.body_count() {
            data.world_pose(b + 1).translation
        } else {
            x.translation + x.rotation * DVec3::Z * 0.1
        };
        let end = x.rotation.transpose() * (next - x.translation);
        let radius = 0.08 - 0.003 * b as f64;
        caps.push(LinkCapsule::new(
            b,
            b as u16,
            Capsule::new(DVec3::ZERO, end * 0.5, radius),
        ))
        .unwrap();
        caps.push(LinkCapsule::new(
            b,
            b as u16,
            Capsule::new(end * 0.5, end, radius),
        ))
        .unwrap();
    }
    (model, caps)
}

fn capsule_path(c: &mut Criterion) {
    let (model, mut caps) = arm();
    let mut data = Data::<16>::new();
    let mut s = 7u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let spheres: Vec<Capsule> = (0..10)
        .map(|_| {
            Capsule::sphere(
                DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() * 1.2) * 1.2,
                0.05 + 0.1 * rnd(),
            )
        })
        .collect();
    let qs: Vec<Vec<f64>> = (0..64)
        .map(|_| (0..model.nq()).map(|_| (rnd() - 0.5) * 5.0).collect())
        .collect();
    println!(
        "{} capsules on {} bodies, {} obstacle spheres",
        caps.len(),
        model.body_count(),
        spheres.len()
    );
    let mut k = 0;
    c.bench_function("fk + update + distance to 10 spheres", |b| {
        b.iter(|| {
            k = (k + 1) % qs.len();
            algo::forward_position(&model, &mut data, black_box(&qs[k])).unwrap();
            caps.update(&data);
            black_box(caps.min_distance(black_box(&spheres)))
        })
    });
    // The kernel alone, poses from the last FK of each configuration.
    let mut datas: Vec<Data<16>> = Vec::new();
    for q in &qs {
        let mut d = Data::<16>::new();
        algo::forward_position(&model, &mut d, q).unwrap();
        datas.push(d);
    }
    c.bench_function("update + distance to 10 spheres", |b| {
        b.iter(|| {
            k = (k + 1) % datas.len();
            caps.update(black_box(&datas[k]));
            black_box(caps.min_distance(black_box(&spheres)))
        })
    });
    c.bench_function("distance to 10 spheres", |b| {
        b.iter(|| black_box(caps.min_distance(black_box(&spheres))))
    });
}

criterion_group!(benches, capsule_path);
criterion_main!(benches);
