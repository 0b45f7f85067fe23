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
        "--duration",
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
    let out = rl(&["fake-robot", "h7", "--model", model, "--duration", "1"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("quaternion"));
}

/// `rl fake-robot h7 --model planar2`: a client (our driver, over the network to another
/// process) finds the model's two axes with JPOSF, its pose replies are the model's forward
/// kinematics, and the status lines show what the fake saw (end packet, servo, limit hits).
#[test]
fn h7_fake_with_a_model_answers_poses_from_its_kinematics() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    use std::time::Duration;

    use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
    use rl::drivers::{
        CartesianPositionSensor, CyclicDevice, Device, JointDevice, JointPositionActuator,
    };

    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/rlmdl/planar2.xml");
    let mut child = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args([
            "fake-robot",
            "h7",
            "--model",
            model,
            "--bind",
            "127.0.0.1:0",
            "--r3-bind",
            "127.0.0.1:0",
            "--duration",
            "3",
        ])
        .stdout(Stdio::piped())
        .spawn()
        .expect("run rl");
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let first = lines.next().unwrap().unwrap();
    // "fake H7 controller (2 joints): real-time UDP on A, R3 on B; Ctrl-C to stop"
    let addr = |after: &str| -> std::net::SocketAddr {
        let rest = &first[first.find(after).unwrap() + after.len()..];
        rest.split([',', ';'])
            .next()
            .unwrap()
            .trim()
            .parse()
            .unwrap()
    };
    let (udp, r3) = (addr("UDP on "), addr("R3 on "));
    let mut config = MitsubishiH7Config::at(udp, r3);
    config.reply_timeout = Duration::from_millis(50);
    let mut robot = MitsubishiH7::new(config).unwrap();
    robot.open().unwrap();
    assert_eq!(robot.dof(), 2);
    robot.start().unwrap();
    // planar2's limits are ±360°: 7 rad on joint 1 is beyond them (a limit hit).
    robot.set_joint_position(&[0.4, 7.0]).unwrap();
    robot.step().unwrap();
    robot.set_joint_position(&[0.4, -1.1]).unwrap();
    // The arm follows its command with a servo lag of two cycles: 60 cycles settle it.
    for _ in 0..60 {
        robot.step().unwrap();
    }
    let pose = robot.cartesian_position().unwrap();
    let (a, b) = (0.4f32 as f64, -1.1f32 as f64);
    assert!((pose.translation.x - (a.cos() + (a + b).cos())).abs() < 1e-5);
    assert!((pose.translation.y - (a.sin() + (a + b).sin())).abs() < 1e-5);
    robot.stop().unwrap();
    robot.close().unwrap();
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let _ = child.wait();
    let last = rest
        .iter()
        .rev()
        .find(|l| l.starts_with("t="))
        .expect("a status line");
    for field in [
        "ends=1",
        "servo=off",
        "limit_hits=1",
        "program=stopped",
        "rejected=0",
    ] {
        assert!(last.contains(field), "{field} missing in: {last}");
    }
}
