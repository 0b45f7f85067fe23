//! Agreement with Pinocchio 4.1 to 1e-9 on robots from `example-robot-data`.
//!
//! The fixtures in `tests/data/pinocchio/` (made by `scripts/gen-pinocchio-fixtures`, see the
//! README there) hold Pinocchio's own model description (joint types, placements, inertias,
//! frames) and, for random states, its RNEA, ABA, CRBA, gravity, nonlinear effects, joint
//! placements and frame Jacobians, velocities and classical accelerations. Here the model is
//! built from that description, so these tests check the algorithms independently of the
//! URDF loader (whose own comparison is in `loader_*` tests).

mod support;

use rl_core::Data;
use rl_core::algo;
use support::assert_close;
use support::fixture::{build, f64s, fixture, pose};

const N: usize = 64;
/// For the model over 64 bodies (tiago_dual, 101).
const BIG: usize = 128;
const TOL: f64 = 1e-9;

fn check(robot: &str) {
    check_n::<N>(robot, 10);
}

/// `min_states`: the fixture must have at least this many (10; 3 for the 101-DOF model, whose
/// mass matrices make a state 160 KB).
fn check_n<const N: usize>(robot: &str, min_states: usize) {
    let fx = fixture(robot);
    let model = build::<N>(&fx);
    assert_eq!(model.dof(), fx["nv"].as_u64().unwrap() as usize);
    let mut d = Box::new(Data::<N>::new());
    let n = model.dof();
    let mut jac = [[0.0; N]; 6];
    let states = fx["states"].as_array().unwrap();
    assert!(states.len() >= min_states);
    for (k, s) in states.iter().enumerate() {
        let what = |x: &str| format!("{robot} state {k}: {x}");
        let q = f64s(s.get("q_angles").unwrap_or(&s["q"]));
        let (v, a, tau_in) = (f64s(&s["v"]), f64s(&s["a"]), f64s(&s["tau_in"]));
        let tau = algo::rnea(&model, &mut d, &q, &v, &a).unwrap().to_vec();
        assert_close(&what("rnea"), &tau, &f64s(&s["tau"]), TOL);
        let g = algo::gravity(&model, &mut d, &q).unwrap().to_vec();
        assert_close(&what("gravity"), &g, &f64s(&s["gravity"]), TOL);
        let nle = algo::nonlinear_effects(&model, &mut d, &q, &v)
            .unwrap()
            .to_vec();
        assert_close(&what("nle"), &nle, &f64s(&s["nonlinear_effects"]), TOL);
        let c = algo::coriolis(&model, &mut d, &q, &v).unwrap().to_vec();
        assert_close(&what("coriolis"), &c, &f64s(&s["coriolis"]), TOL);
        let qdd = algo::aba(&model, &mut d, &q, &v, &tau_in).unwrap().to_vec();
        assert_close(&what("aba"), &qdd, &f64s(&s["qdd"]), TOL);
        algo::crba(&model, &mut d, &q).unwrap();
        for (r, row) in s["mass_matrix"].as_array().unwrap().iter().enumerate() {
            let ours: Vec<f64> = (0..n).map(|c| d.mass_matrix(r, c)).collect();
            assert_close(&what("crba"), &ours, &f64s(row), TOL);
        }
        algo::forward_position(&model, &mut d, &q).unwrap();
        for (i, p) in s["joint_placements"].as_array().unwrap().iter().enumerate() {
            let x = d.world_pose(i);
            let expected = pose(p);
            assert_close(
                &what("oMi.p"),
                &x.translation.to_array(),
                &expected.translation.to_array(),
                TOL,
            );
            assert_close(
                &what("oMi.R"),
                &x.rotation.to_cols_array(),
                &expected.rotation.to_cols_array(),
                TOL,
            );
        }
        algo::forward_acceleration(&model, &mut d, &q, &v, &a).unwrap();
        for (t, f) in s["frames"].as_array().unwrap().iter().enumerate() {
            assert_eq!(model.tools()[t].name.as_str(), f["name"].as_str().unwrap());
            let x = algo::tool_pose(&model, &d, t).unwrap();
            let expected = pose(&f["placement"]);
            assert_close(
                &what("oMf.p"),
                &x.translation.to_array(),
                &expected.translation.to_array(),
                TOL,
            );
            assert_close(
                &what("oMf.R"),
                &x.rotation.to_cols_array(),
                &expected.rotation.to_cols_array(),
                TOL,
            );
            let vel = algo::tool_velocity(&model, &d, t).unwrap();
            assert_close(&what("frame velocity"), &vel, &f64s(&f["velocity"]), TOL);
            let acc = algo::tool_acceleration(&model, &d, t).unwrap();
            assert_close(
                &what("frame acceleration"),
                &acc,
                &f64s(&f["classical_acceleration"]),
                TOL,
            );
        }
        for (t, f) in s["frames"].as_array().unwrap().iter().enumerate() {
            algo::jacobian(&model, &mut d, &q, t, &mut jac).unwrap();
            for (r, row) in f["jacobian"].as_array().unwrap().iter().enumerate() {
                assert_close(&what("jacobian"), &jac[r][..n], &f64s(row), TOL);
            }
        }
    }
}

#[test]
fn ur5() {
    check("ur5");
}

#[test]
fn panda() {
    check("panda");
}

#[test]
fn panda_arm() {
    check("panda_arm");
}

#[test]
fn xarm7() {
    check("xarm7");
}

#[test]
fn kinova_continuous_joints() {
    check("kinova");
}

#[test]
fn solo12_floating_base() {
    check("solo12");
}

#[test]
fn anymal_c_floating_base() {
    check("anymal_c");
}

#[test]
fn talos_reduced_floating_base() {
    check("talos_reduced");
}

#[test]
fn panda_mimic_finger() {
    check("panda_mimic");
}

#[test]
fn panda_collision_mimic_finger() {
    check("panda_collision_mimic");
}

#[test]
fn baxter_mimic_grippers() {
    check("baxter_mimic");
}

#[test]
fn tiago_pro_mimic_grippers() {
    check("tiago_pro_mimic");
}

/// Mimic joints that are descendants of their leader, and mimic joints below mimic joints.
#[test]
fn pr2_mimic_grippers() {
    check("pr2_mimic");
}

/// 101 bodies.
#[test]
fn tiago_dual_over_64_bodies() {
    check_n::<BIG>("tiago_dual", 3);
}

/// The KUKA LBR iiwa of pybullet's data (rl-core/tests/data/urdf/).
#[test]
fn iiwa() {
    check("iiwa");
}

/// Unitree G1, 29 joints on a floating base (35 DOF).
#[test]
fn g1_floating_base() {
    check("g1");
}

/// The Panda arm with the FR3's armature (franky-sim's MuJoCo values): RNEA adds `armature ·
/// q̈`, CRBA its diagonal, ABA inverts both.
#[test]
fn panda_arm_with_armature() {
    check("panda_arm_armature");
}

/// Armature on a floating base's legs and (not physical, for the code path) on its six-DOF
/// joint, whose ABA block `D` gains it.
#[test]
fn solo12_with_armature() {
    check("solo12_armature");
}

/// Armature on a model with a mimic joint (ABA through the mass matrix).
#[test]
fn panda_mimic_with_armature() {
    check("panda_mimic_armature");
}
