//! `rl model info | eval | bench` end to end: the JSON of `eval` carries RL's Puma 560 values,
//! bad arguments exit with code 2 and a message naming the argument.

mod cli;

use cli::{rl, rl_json};
use serde_json::Value;

const PUMA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/rlmdl/unimation-puma560.xml"
);

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

#[test]
fn eval_prints_rls_puma_values() {
    let v = rl_json(&[
        "model",
        "eval",
        PUMA,
        "--q",
        "0.2,0.3,0.4,0.5,0.6,0.7",
        "--qd",
        "-0.1,-0.05,0,0.05,0.1,0.15",
        "--qdd",
        "0.3,0.28,0.26,0.24,0.22,0.2",
        "--gravity",
        "0,0,-9.80665",
    ]);
    assert_eq!(v["dof"], 6);
    assert_eq!(v["nq"], 6);
    let f = |x: &Value| x.as_f64().unwrap();
    // RL's values (shared/reference/rl-models.md).
    assert!(close(f(&v["tau"][1]), -38.3359212354, 1e-9));
    assert!(close(f(&v["gravity"][1]), -39.1083348355, 1e-9));
    assert!(close(f(&v["coriolis"][0]), 0.00149693788723, 1e-9));
    let tool = &v["tools"][0];
    assert!(close(f(&tool["position"][0]), 0.671474225622, 1e-9));
    // x, y, z, w: the order of every quaternion the tool prints.
    let qw = f(&tool["quat_xyzw"][3]).abs();
    assert!(close(qw, 0.587069090875, 1e-9));
    assert_eq!(tool["jacobian"].as_array().unwrap().len(), 6);
    assert!(close(f(&tool["jacobian"][1][0]), 0.671474226, 1e-8));
    assert!(close(f(&v["mass_matrix"][0][0]), 4.68283594, 1e-8));
    // qdd = ABA(q, q̇, τ = 0) as RL printed it.
    assert!(close(f(&v["qdd"][0]), -0.918422292327, 1e-9));
}

#[test]
fn wrong_lengths_and_non_numbers_name_the_argument() {
    let out = rl(&["model", "eval", PUMA, "--q", "0,0,0"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--q") && err.contains('6'), "{err}");
    let out = rl(&[
        "model",
        "eval",
        PUMA,
        "--q",
        "0,0,0,0,0,0",
        "--qd",
        "0,x,0,0,0,0",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--qd") && err.contains("\"x\""), "{err}");
    let out = rl(&["model", "info", "/nonexistent/model.urdf"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn info_lists_joints_and_tools() {
    let v = rl_json(&["model", "info", PUMA, "--json"]);
    assert_eq!(v["dof"], 6);
    assert_eq!(v["joints"].as_array().unwrap().len(), 6);
    assert_eq!(v["joints"][0]["type"], "revolute");
    assert_eq!(v["tools"].as_array().unwrap().len(), 1);
    assert!(v["mass_kg"].as_f64().unwrap() > 20.0);
}

#[test]
fn bench_reports_every_algorithm() {
    let v = rl_json(&[
        "model", "bench", PUMA, "--json", "--states", "4", "--rounds", "3",
    ]);
    for k in [
        "fk_ns",
        "jacobian_ns",
        "rnea_ns",
        "nle_ns",
        "gravity_ns",
        "crba_ns",
        "aba_ns",
    ] {
        let ns = v[k].as_f64().unwrap_or_else(|| panic!("{k} missing: {v}"));
        assert!(ns > 0.0 && ns.is_finite(), "{k} = {ns}");
    }
}

// ---------------------------------------------------------------------------------------------
// Issue 13: mimic joints, any size, zero-DOF models, physical checks, quaternions, limits.

const BOX6D: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/rlmdl/box-6d-300505.sixDof.xml"
);

/// example-robot-data's `robots/` folder, or `None` (the test prints SKIPPED).
fn robots() -> Option<std::path::PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    match rl::core::loader::example_robot_data_dir(root) {
        Ok(d) => Some(d.join("robots")),
        Err(e) => {
            println!("SKIPPED: example-robot-data is not available: {e}");
            None
        }
    }
}

fn robot(rel: &str) -> Option<String> {
    robots().map(|r| r.join(rel).to_string_lossy().into_owned())
}

/// Exit code 2 and a message containing every one of `needles`.
fn refused(args: &[&str], needles: &[&str]) -> String {
    let out = rl(args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "rl {args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "rl {args:?}: {n:?} not in\n{err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    err
}

#[test]
fn a_mimic_error_names_the_tools_flag() {
    let path = std::env::temp_dir().join(format!("rl-mimic-loop-{}.urdf", std::process::id()));
    let joint = |name: &str, parent: &str, child: &str, leader: &str| {
        format!(
            "<joint name=\"{name}\" type=\"revolute\"><parent link=\"{parent}\"/><child \
             link=\"{child}\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" \
             velocity=\"1\" effort=\"1\"/><mimic joint=\"{leader}\"/></joint>"
        )
    };
    let text = format!(
        "<robot name=\"loop\"><link name=\"b\"/><link name=\"l1\"/><link name=\"l2\"/>{}{}</robot>",
        joint("a", "b", "l1", "c"),
        joint("c", "l1", "l2", "a")
    );
    std::fs::write(&path, text).unwrap();
    let file = path.to_str().unwrap();
    let err = refused(
        &["model", "info", file],
        &["mimic joint \"a\"", "loops", "--mimic-independent"],
    );
    assert!(!err.contains("MimicJoints"), "a Rust API named: {err}");
    // The flag does what the message says.
    let v = rl_json(&["model", "info", file, "--json", "--mimic-independent"]);
    assert_eq!(v["dof"], 2);
    let _ = std::fs::remove_file(&path);
}

#[test]
fn mimic_joints_follow_their_leaders_or_are_independent() {
    let Some(panda) = robot("panda_description/urdf/panda.urdf") else {
        return;
    };
    let v = rl_json(&["model", "info", &panda, "--json"]);
    assert_eq!(v["dof"], 8);
    let finger2 = &v["joints"][8];
    assert_eq!(finger2["name"], "panda_finger_joint2");
    assert_eq!(finger2["nv"], 0);
    assert_eq!(finger2["mimic"]["leader"], "panda_finger_joint1");
    let v = rl_json(&["model", "info", &panda, "--json", "--mimic-independent"]);
    assert_eq!(v["dof"], 9);
    assert!(v["warnings"][0].as_str().unwrap().contains("independent"));
    // Eval: the finger's torque reaches its leader; 8 values in, 8 out.
    let v = rl_json(&["model", "eval", &panda, "--q", "0,0,0,-1,0,1,0,0.02"]);
    assert_eq!(v["tau"].as_array().unwrap().len(), 8);
    assert_eq!(v["mass_matrix"].as_array().unwrap().len(), 8);
}

#[test]
fn models_over_64_bodies_load() {
    let Some(tiago) = robot("tiago_description/robots/tiago_dual.urdf") else {
        return;
    };
    let v = rl_json(&["model", "eval", &tiago]);
    assert_eq!(v["dof"], 101);
    assert_eq!(v["mass_matrix"][100].as_array().unwrap().len(), 101);
    assert!(v["qdd"][100].as_f64().unwrap().is_finite());
    // rl run takes the same capacity: the model loads and reaches the device, whose joint
    // count is what refuses it (tests/run_capacity.rs runs 101 joints at that capacity).
    let out = rl(&["run", "--model", &tiago, "--duration", "1s"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("the model has 101 joints; the fake H7 simulates 1 to 8 axes"),
        "{err}"
    );
}

#[test]
fn over_the_largest_capacity_the_message_says_which_and_how() {
    let dir = std::env::temp_dir().join(format!("rl-capacity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("chain300.urdf");
    let mut text = String::from("<robot name=\"chain\"><link name=\"l0\"/>");
    for k in 1..=300 {
        text += &format!(
            "<link name=\"l{k}\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" \
             izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link><joint name=\"j{k}\" \
             type=\"continuous\"><parent link=\"l{}\"/><child link=\"l{k}\"/></joint>",
            k - 1
        );
    }
    text += "</robot>";
    std::fs::write(&path, text).unwrap();
    let file = path.to_str().unwrap();
    let said = [
        "capacity of 256",
        "<joint \"j257\">",
        "src/cli/capacity.rs",
        "CAPACITIES",
        "load_file::<512>",
    ];
    refused(&["model", "info", file], &said);
    // The run loop, its planner and the fake robots take the same capacity choice.
    let err = refused(&["run", "--model", file, "--duration", "1s"], &said);
    assert!(err.contains("--model: "), "{err}");
    refused(
        &["fake-robot", "h7", "--model", file, "--duration", "1"],
        &said,
    );
}

#[test]
fn a_model_without_moving_joints_evaluates_and_benches() {
    let Some(quad) = robot("hector_description/robots/quadrotor_base.urdf") else {
        return;
    };
    let v = rl_json(&["model", "eval", &quad]);
    assert_eq!((v["dof"].as_u64(), v["nq"].as_u64()), (Some(0), Some(0)));
    assert_eq!(v["tau"].as_array().unwrap().len(), 0);
    let v = rl_json(&[
        "model", "bench", &quad, "--json", "--states", "2", "--rounds", "1",
    ]);
    assert_eq!(v["dof"], 0);
    assert!(v["rnea_ns"].as_f64().unwrap() >= 0.0);
    // As a floating base it has six DOF and evaluates too.
    let v = rl_json(&["model", "eval", &quad, "--floating-base"]);
    assert_eq!(v["dof"], 6);
}

#[test]
fn quaternions_must_be_of_unit_norm_or_normalised_on_request() {
    // q = [x y z qx qy qz qw].
    refused(
        &["model", "eval", BOX6D, "--q", "0,0,0,0,0,0,0.5"],
        &[
            "--q: elements 3..6",
            "\"joint0\"",
            "norm 0.5",
            "--normalize",
        ],
    );
    let err = refused(
        &["model", "eval", BOX6D, "--q", "0,0,0,0,0,0,0"],
        &["norm 0"],
    );
    assert!(
        !err.contains("--normalize"),
        "a zero quaternion has no direction: {err}"
    );
    let v = rl_json(&[
        "model",
        "eval",
        BOX6D,
        "--q",
        "0,0,0,0,0,0,0.5",
        "--normalize",
    ]);
    assert_eq!(v["q"][6], 1.0);
    // A unit quaternion typed with enough digits passes as it is.
    rl_json(&[
        "model",
        "eval",
        BOX6D,
        "--q",
        "1,2,3,0,0,0.7071067811865476,0.7071067811865476",
    ]);
}

#[test]
fn a_massless_subtree_is_named() {
    let Some(romeo) = robot("romeo_description/urdf/romeo.urdf") else {
        return;
    };
    let out = rl(&["model", "eval", &romeo]);
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["qdd"].is_null());
    let why = v["qdd_error"].as_str().unwrap();
    assert!(
        why.contains("\"RHand\"") && why.contains("massless"),
        "{why}"
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("joint \"LHand\" (DOF 24) moves no mass"),
        "{err}"
    );
    let out = rl(&["model", "bench", &romeo, "--states", "2", "--rounds", "1"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("ABA not timed"));
}

#[test]
fn unphysical_inertias_are_refused_or_loaded_with_a_flag() {
    // RL's Puma: body3's moments break the triangle inequality (a warning by default).
    let out = rl(&["model", "info", PUMA]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("link \"body3\": inertia not physical"));
    refused(
        &["model", "info", PUMA, "--inertia-check", "strict"],
        &[
            "\"body3\"",
            "triangle inequality",
            "--inertia-check definite",
        ],
    );
    let Some(romeo) = robot("romeo_description/urdf/romeo_laas_small.urdf") else {
        return;
    };
    refused(
        &["model", "info", &romeo],
        &["not positive semi-definite", "--inertia-check lenient"],
    );
    rl_json(&[
        "model",
        "info",
        &romeo,
        "--json",
        "--inertia-check",
        "lenient",
    ]);
}

#[test]
fn a_zero_speed_or_effort_limit_means_not_given() {
    let Some(pendulum) = robot("double_pendulum_description/urdf/double_pendulum_continuous.urdf")
    else {
        return;
    };
    let v = rl_json(&["model", "info", &pendulum, "--json"]);
    for j in v["joints"].as_array().unwrap() {
        let l = &j["limits"][0];
        assert!(l["velocity"].is_null() && l["effort"].is_null(), "{j}");
    }
    // The fake H7 takes such a model (unlimited speed) instead of refusing it.
    let out = rl(&[
        "fake-robot",
        "h7",
        "--model",
        &pendulum,
        "--bind",
        "127.0.0.1:0",
        "--r3-bind",
        "127.0.0.1:0",
        "--duration",
        "1",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // So does rl run, which plans with an assumed speed for such joints and says so.
    let out = rl(&["run", "--model", &pendulum, "--duration", "1s", "--json"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let v: Value = serde_json::from_slice(&out.stdout).expect("JSON report");
    assert_eq!(v["failed"], false, "{v}");
    assert!(
        v["assumed_speed"].is_object(),
        "no assumed speed reported: {v}"
    );
}

#[test]
fn bench_refuses_a_huge_number_of_states() {
    refused(
        &["model", "bench", PUMA, "--states", "100000000"],
        &["--states 100000000", "1 to 100000"],
    );
    refused(&["model", "bench", PUMA, "--rounds", "0"], &["--rounds 0"]);
}
