//! A counting global allocator proves that the algorithms allocate nothing: every call in the
//! measured section below is counted, and the count must stay zero.

mod support;

use rl_core::Data;
use rl_core::algo;
use rl_core::spatial::ForceVector;
use rl_testkit::{CountingAllocator, allocations};
use support::{Rng, every_joint_type, mimic_tree, random_chain, random_state};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn dynamics_and_kinematics_allocate_nothing() {
    run_all(&every_joint_type::<32>(9));
}

/// With mimic joints every call maps between public and internal coordinates (on the stack).
#[test]
fn with_mimic_joints_too() {
    run_all(&mimic_tree::<32>(4));
}

fn run_all(model: &rl_core::Model<32>) {
    let model = model.clone();
    let mut data = Box::new(Data::<32>::new());
    let mut deriv = Box::new(rl_core::model::DerivativeData::<32>::new());
    let mut r = Rng(1);
    let states: Vec<_> = (0..20).map(|_| random_state(&model, &mut r)).collect();
    let fext = vec![ForceVector::ZERO; model.body_count()];
    let mut jac = Box::new([[[0.0; 32]; 6]; 4]);
    let mut sink = 0.0;

    let (n, ()) = allocations(|| {
        for (q, qd, qdd) in &states {
            algo::forward_position(&model, &mut data, q).unwrap();
            sink += algo::tool_pose(&model, &data, 0).unwrap().translation.x;
            algo::forward_velocity(&model, &mut data, q, qd).unwrap();
            algo::forward_acceleration(&model, &mut data, q, qd, qdd).unwrap();
            algo::jacobian(&model, &mut data, q, 0, &mut jac[0]).unwrap();
            algo::jacobians(&model, &mut data, q, &mut jac[..]).unwrap();
            sink += algo::jacobian_derivative_times_qd(&model, &mut data, q, qd, 1).unwrap()[0];
            let tau: [f64; 32] = {
                let t = algo::rnea(&model, &mut data, q, qd, qdd).unwrap();
                let mut a = [0.0; 32];
                a[..t.len()].copy_from_slice(t);
                a
            };
            sink +=
                algo::rnea_with_external_forces(&model, &mut data, q, qd, qdd, &fext).unwrap()[0];
            sink += algo::gravity(&model, &mut data, q).unwrap()[0];
            sink += algo::coriolis(&model, &mut data, q, qd).unwrap()[0];
            sink += algo::nonlinear_effects(&model, &mut data, q, qd).unwrap()[0];
            algo::crba(&model, &mut data, q).unwrap();
            algo::factor_mass_matrix(&model, &mut data).unwrap();
            let mut b = tau;
            algo::solve_mass_matrix(&model, &data, &mut b[..model.dof()]).unwrap();
            sink += algo::aba(&model, &mut data, q, qd, &tau[..model.dof()]).unwrap()[0];
            let nv = model.dof();
            sink += algo::rnea_derivatives(&model, &mut data, &mut deriv, q, qd, qdd)
                .unwrap()
                .dtau_dq
                .get(0, 0);
            sink += algo::rnea_derivatives_with_external_forces(
                &model, &mut data, &mut deriv, q, qd, qdd, &fext,
            )
            .unwrap()
            .dtau_dv
            .get(0, 0);
            sink += algo::aba_derivatives(&model, &mut data, &mut deriv, q, qd, &tau[..nv])
                .unwrap()
                .ddq_dq
                .get(0, 0);
            sink += algo::aba_derivatives_with_external_forces(
                &model,
                &mut data,
                &mut deriv,
                q,
                qd,
                &tau[..nv],
                &fext,
            )
            .unwrap()
            .minv
            .get(0, 0);
            sink += algo::static_torque_derivatives(&model, &mut data, &mut deriv, q)
                .unwrap()
                .get(0, 0);
            sink += algo::static_torque_derivatives_with_external_forces(
                &model, &mut data, &mut deriv, q, &fext,
            )
            .unwrap()
            .get(0, 0);
            sink += algo::operational_inverse_inertia(&model, &mut data, q, 0, &mut jac[0])
                .unwrap()[0][0];
        }
    });

    assert!(sink.is_finite());
    assert_eq!(n, 0, "the algorithms allocated");
}

/// The task-space law (fixed-base models only: a chain of seven).
#[test]
fn the_operational_impedance_allocates_nothing() {
    use rl_core::task::{ImpedanceGains, TaskData, TaskTarget, limit_rate, operational_impedance};
    let model = random_chain::<32>(7, 5);
    let mut data = Box::new(Data::<32>::new());
    let mut task = Box::new(TaskData::<32>::new());
    let mut r = Rng(2);
    let states: Vec<_> = (0..20).map(|_| random_state(&model, &mut r)).collect();
    let target = TaskTarget::at(r.pose());
    // The default bound, and one so large that the clamp acts (its eigen-decomposition runs).
    let gains = ImpedanceGains::default();
    let clamping = ImpedanceGains {
        singularity: rl_core::task::Singularity::Clamped([1e3, 1e3]),
        ..gains
    };
    // Two levels with obstacles near two links (their point Jacobians and solves).
    let levels = ImpedanceGains {
        priority: rl_core::task::Priority::OrientationFirst,
        ..gains
    };
    let near = [
        rl_core::task::Proximity::at_rest(3, r.vec3(0.3), glam::DVec3::Z, 0.08),
        rl_core::task::Proximity::at_rest(6, r.vec3(0.3), glam::DVec3::X, 0.12),
    ];
    let mut tau = [0.0; 7];
    let mut previous = [0.0; 7];
    let mut sink = 0.0;
    let mut clamped = 0;
    let mut repelled = 0;
    let (n, ()) = allocations(|| {
        for (q, qd, posture) in &states {
            for g in [&gains, &clamping, &levels] {
                let obstacles = if *g == levels { &near[..] } else { &[] };
                task.set_proximities(obstacles).unwrap();
                let report = operational_impedance(
                    &model, &mut data, &mut task, 0, g, &target, q, qd, posture, &mut tau,
                )
                .unwrap();
                clamped += report.bounded_directions;
                repelled += report.repelling;
                sink += report.position_error + limit_rate(&previous, &mut tau, 1.0) as f64;
                previous = tau;
            }
        }
    });
    assert!(clamped > 0, "the clamp never acted");
    assert!(repelled > 0, "no obstacle repelled");
    assert!(sink.is_finite() && previous.iter().any(|t| *t != 0.0));
    assert_eq!(n, 0, "the task-space law allocated");
}

#[test]
fn the_counter_counts() {
    // The allocator must see allocations, or the test above proves nothing.
    let (n, v) = allocations(|| Vec::<u8>::with_capacity(16));
    drop(v);
    assert!(n > 0);
}
