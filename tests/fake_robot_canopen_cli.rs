//! `rl fake-robot canopen`: fake CiA 402 drives from the command line, driven by our master
//! over cannelloni UDP; the model's joint count sets the nodes; bad arguments exit with 2.

mod pairs;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::Duration;

use rl::drivers::canopen::{Cia402, Cia402Config};
use rl::drivers::transport::can::CanAddress;
use rl::drivers::{CyclicDevice, Device, JointPositionActuator, JointPositionSensor};

fn rl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(args)
        .output()
        .expect("run rl")
}

#[test]
fn the_fake_drives_serve_our_master_and_record_the_bus() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fake_robot_canopen");
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("bus.log");
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/rlmdl/planar3.xml");
    let log_arg = log.to_str().expect("a UTF-8 path");
    let (child, first, bus) =
        fake_drives(&["--model", model, "--duration", "4", "--candump", log_arg]);
    assert!(first.contains("nodes [1, 2, 3]"), "{first}");
    let bus = bus.as_str();
    let mut config = Cia402Config::new(CanAddress::parse(bus).unwrap(), &[1, 2, 3])
        .with_period(Duration::from_millis(10));
    config.sdo_timeout = Duration::from_millis(200);
    let mut dev = Cia402::new(config).unwrap();
    dev.open().unwrap();
    dev.start().unwrap();
    let mut q = [0.0; 3];
    dev.joint_position(&mut q).unwrap();
    for _ in 0..20 {
        q[0] += 0.001;
        dev.set_joint_position(&q).unwrap();
        dev.step().unwrap();
        std::thread::sleep(Duration::from_millis(10));
    }
    dev.stop().unwrap();
    dev.close().unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(text.lines().count() > 100, "{} lines", text.lines().count());
    for line in text.lines() {
        rl::drivers::proto::can::candump::parse_line(line)
            .unwrap_or_else(|e| panic!("{line}: {e}"));
    }
    assert!(text.contains(" can0 080#"), "SYNC recorded");
}

#[test]
fn bad_arguments_exit_with_2() {
    for args in [
        &[
            "fake-robot",
            "canopen",
            "--bus",
            "can://x",
            "--duration",
            "1",
        ][..],
        &["fake-robot", "canopen", "--nodes", "0-3", "--duration", "1"],
        &["fake-robot", "canopen", "--nodes", "1-9", "--duration", "1"],
        &[
            "fake-robot",
            "canopen",
            "--nodes",
            "1,2",
            "--model",
            concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/rlmdl/planar3.xml"),
            "--duration",
            "1",
        ],
    ] {
        let out = rl(args);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// Starts `rl fake-robot canopen` on a free UDP port with `extra` flags; returns it, its first
/// line and its bus.
fn fake_drives(extra: &[&str]) -> (std::process::Child, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args([
            "fake-robot",
            "canopen",
            "--bus",
            "cannelloni+udp://127.0.0.1:0",
        ])
        .args(extra)
        .stdout(Stdio::piped())
        .spawn()
        .expect("run rl");
    let mut first = String::new();
    BufReader::new(child.stdout.as_mut().unwrap())
        .read_line(&mut first)
        .unwrap();
    let bus = first
        .split(" on ")
        .nth(1)
        .and_then(|s| s.split(';').next())
        .unwrap()
        .to_owned();
    (child, first, bus)
}

/// `rl run` against six drives on `bus` for a second, with `extra` flags.
fn run_on(bus: &str, extra: &[&str]) -> std::process::Output {
    let out = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args([
            "run",
            "--device",
            &format!("{bus}?nodes=1-6"),
            "--duration",
            "1s",
        ])
        .args(extra)
        .output()
        .expect("rl run");
    // The fake takes the next master after a quarter second of silence.
    std::thread::sleep(Duration::from_millis(300));
    out
}

#[test]
fn rl_run_reads_the_units_the_fake_drives_are_given_or_is_refused_without_them() {
    // A 12-bit encoder behind 121:1: with units assumed (2^20, 100:1) every joint would move
    // 1/211 of its command and the run would fail on its tracking error.
    let (mut fake, _, bus) = fake_drives(&[
        "--counts-per-rev",
        "4096",
        "--gear",
        "121",
        "--duration",
        "60",
    ]);
    pairs::run_until_on_time("units read", 1000.0, || run_on(&bus, &[]));
    let _ = fake.kill();
    let _ = fake.wait();

    // Drives without 0x608F/0x6091/0x6092: refused before anything is enabled …
    let (mut fake, _, bus) = fake_drives(&[
        "--counts-per-rev",
        "4096",
        "--gear",
        "121",
        "--no-unit-objects",
        "--duration",
        "60",
    ]);
    let out = run_on(&bus, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("node 1: cannot read 0x608f:1 (encoder increments): aborted 0x06020000")
            && err.contains("give the axis units instead")
            && !err.contains("no drive answers"),
        "{err}"
    );
    // … and run with the units given.
    pairs::run_until_on_time("units given", 1000.0, || {
        run_on(&bus, &["--units", "cpr:4096,gear:121"])
    });
    let _ = fake.kill();
    let _ = fake.wait();
}
