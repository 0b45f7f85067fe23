//! Dynamics benchmarks (issue 3): every algorithm of `rl model bench` — fk (all body poses),
//! jacobian (world Jacobian of the first tool, FK included), rnea, nle (C + G), gravity, crba
//! (mass matrix), aba, and the analytical derivatives (drnea: ∂τ/∂q, ∂τ/∂q̇, M; daba: ∂q̈/∂q,
//! ∂q̈/∂q̇, M⁻¹; dstatic: ∂g/∂q), and the task-space law (`task_impedance`:
//! `rl_core::task::operational_impedance`, 6-D task, clamped operational inertia, posture and
//! joint-limit avoidance in the nullspace, default gains, toward a pose 5 cm and 0.2 rad from
//! the tool) — on RL's UR5 (6 axes) and KUKA LBR iiwa 7 R800 (7 axes) models, in
//! fixed-size models of capacity 8, cycling through 16 random states so no call sees the
//! state of the one before. `scripts/bench-pinocchio` compares the same algorithms with
//! Pinocchio and dynibo.

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use rl_core::algo::{self, Jacobian};
use rl_core::loader;
use rl_core::model::DerivativeData;
use rl_core::{Data, Model};

/// Bodies and DOF of the benchmark models: enough for a 7-axis arm.
const N: usize = 8;
/// States cycled through.
const STATES: usize = 16;

/// The arms, by file in the workspace's tests/data/rlmdl.
const ARMS: [(&str, &str); 2] = [
    ("ur5", "universal-robots-ur5.xml"),
    ("iiwa7", "kuka-lbr-iiwa-7-r800.xml"),
];

/// Random states: positions within the limits, velocities and accelerations in [-1, 1].
struct States {
    q: Vec<[f64; N]>,
    qd: Vec<[f64; N]>,
    qdd: Vec<[f64; N]>,
    tau: Vec<[f64; N]>,
}

/// A SplitMix64 stream of uniform numbers in [0, 1).
fn splitmix(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

fn states(model: &Model<N>) -> States {
    let mut seed = 0x5EED;
    let (nq, nv) = (model.nq(), model.dof());
    let mut s = States {
        q: vec![[0.0; N]; STATES],
        qd: vec![[0.0; N]; STATES],
        qdd: vec![[0.0; N]; STATES],
        tau: vec![[0.0; N]; STATES],
    };
    let mut data = Data::<N>::new();
    for i in 0..STATES {
        model.random_configuration(&mut s.q[i][..nq], || splitmix(&mut seed));
        for k in 0..nv {
            s.qd[i][k] = 2.0 * splitmix(&mut seed) - 1.0;
            s.qdd[i][k] = 2.0 * splitmix(&mut seed) - 1.0;
        }
        let tau = algo::rnea(
            model,
            &mut data,
            &s.q[i][..nq],
            &s.qd[i][..nv],
            &s.qdd[i][..nv],
        )
        .expect("RNEA of a valid state");
        s.tau[i][..nv].copy_from_slice(tau);
    }
    s
}

fn load(file: &str) -> Model<N> {
    let path: PathBuf = [
        env!("CARGO_MANIFEST_DIR"),
        "..",
        "tests",
        "data",
        "rlmdl",
        file,
    ]
    .iter()
    .collect();
    match loader::load_file::<N>(&path) {
        Ok(loaded) => loaded.model,
        Err(e) => panic!("{}: {e}", path.display()),
    }
}

fn dynamics(c: &mut Criterion) {
    for (arm, file) in ARMS {
        let model = load(file);
        let s = states(&model);
        let (nq, nv) = (model.nq(), model.dof());
        let mut data = Data::<N>::new();
        let mut deriv = DerivativeData::<N>::new();
        let mut jac: Jacobian<N> = [[0.0; N]; 6];
        let mut group = c.benchmark_group("dynamics");
        // Runs `f` on the next state at every iteration.
        macro_rules! bench {
            ($name:literal, |$i:ident| $call:expr) => {{
                let mut next = 0;
                group.bench_function(BenchmarkId::new($name, arm), |b| {
                    b.iter(|| {
                        let $i = next;
                        next = (next + 1) % STATES;
                        black_box($call)
                    })
                });
            }};
        }
        bench!("fk", |i| algo::forward_position(
            &model,
            &mut data,
            black_box(&s.q[i][..nq])
        )
        .is_ok());
        bench!("jacobian", |i| algo::jacobian(
            &model,
            &mut data,
            black_box(&s.q[i][..nq]),
            0,
            &mut jac
        )
        .is_ok());
        bench!("rnea", |i| algo::rnea(
            &model,
            &mut data,
            black_box(&s.q[i][..nq]),
            &s.qd[i][..nv],
            &s.qdd[i][..nv]
        )
        .map(|t| t[0]));
        bench!("nle", |i| algo::nonlinear_effects(
            &model,
            &mut data,
            black_box(&s.q[i][..nq]),
            &s.qd[i][..nv]
        )
        .map(|t| t[0]));
        bench!("gravity", |i| algo::gravity(
            &model,
            &mut data,
            black_box(&s.q[i][..nq])
        )
        .map(|t| t[0]));
        bench!("crba", |i| algo::crba(
            &model,
            &mut data,
            black_box(&s.q[i][..nq])
        )
        .is_ok());
        bench!("aba", |i| algo::aba(
            &model,
            &mut data,
            black_box(&s.q[i][..nq]),
            &s.qd[i][..nv],
            &s.tau[i][..nv]
        )
        .map(|t| t[0]));
        bench!("drnea", |i| algo::rnea_derivatives(
            &model,
            &mut data,
            &mut deriv,
            black_box(&s.q[i][..nq]),
            &s.qd[i][..nv],
            &s.qdd[i][..nv]
        )
        .map(|r| r.dtau_dq.get(0, 0)));
        bench!("daba", |i| algo::aba_derivatives(
            &model,
            &mut data,
            &mut deriv,
            black_box(&s.q[i][..nq]),
            &s.qd[i][..nv],
            &s.tau[i][..nv]
        )
        .map(|r| r.ddq_dq.get(0, 0)));
        bench!("dstatic", |i| algo::static_torque_derivatives(
            &model,
            &mut data,
            &mut deriv,
            black_box(&s.q[i][..nq])
        )
        .map(|m| m.get(0, 0)));
        let gains = rl_core::task::ImpedanceGains::default();
        let mut task = Box::new(rl_core::task::TaskData::<N>::new());
        let mut tau = [0.0; N];
        algo::forward_position(&model, &mut data, &s.q[0][..nq]).expect("fk");
        let x = algo::tool_pose(&model, &data, 0).expect("tool");
        let target = rl_core::task::TaskTarget::at(rl_core::spatial::PlueckerTransform::new(
            glam::DMat3::from_rotation_x(0.2) * x.rotation,
            x.translation + glam::DVec3::new(0.05, 0.0, 0.0),
        ));
        bench!("task_impedance", |i| rl_core::task::operational_impedance(
            &model,
            &mut data,
            &mut task,
            0,
            &gains,
            &target,
            black_box(&s.q[i][..nq]),
            &s.qd[i][..nv],
            &s.q[(i + 1) % STATES][..nq],
            &mut tau[..nv]
        )
        .map(|r| r.position_error));
        group.finish();
    }
}

criterion_group!(benches, dynamics);
criterion_main!(benches);
