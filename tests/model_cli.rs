//! `rl model info | eval | bench` end to end: the JSON of `eval` carries RL's Puma 560 values,
//! bad arguments exit with code 2 and a message naming the argument.

use std::process::Command;

use serde_json::Value;

const PUMA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/rlmdl/unimation-puma560.xml"
);

fn rl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(args)
        .output()
        .expect("run rl")
}

/// Runs `rl` with `args`, which must succeed, and parses its JSON output.
fn rl_json(args: &[&str]) -> Value {
    let out = rl(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

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
    let qw = f(&tool["quaternion_wxyz"][0]).abs();
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
    assert!(v["mass"].as_f64().unwrap() > 20.0);
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
