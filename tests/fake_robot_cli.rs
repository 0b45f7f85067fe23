//! `rl fake-robot h7 --model FILE`: the simulated arm takes the model's joints and limits;
//! a model the fake cannot simulate is refused with exit code 2.

use std::process::Command;

fn rl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(args)
        .output()
        .expect("run rl")
}

#[test]
fn h7_fake_takes_the_models_joints() {
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/rlmdl/planar3.xml");
    let out = rl(&[
        "fake-robot",
        "h7",
        "--model",
        model,
        "--bind",
        "127.0.0.1:0",
        "--r3-bind",
        "127.0.0.1:0",
        "--seconds",
        "1",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("(3 joints)"), "{text}");
}

#[test]
fn h7_fake_refuses_quaternion_joints() {
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/rlmdl/box-6d-300505.sixDof.xml"
    );
    let out = rl(&["fake-robot", "h7", "--model", model, "--seconds", "1"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("quaternion"));
}
