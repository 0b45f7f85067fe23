//! The Modbus frames of our gripper fake and our gripper driver checked by PyPI pymodbus
//! 3.16.1: pymodbus's client drives the fake (over RTU on its pseudo-terminal, and over TCP)
//! through an activation, a grasp and the requests the gripper refuses; pymodbus's server
//! answers our driver (over RTU on a pseudo-terminal, and over TCP) and logs what it decoded.
//! Without the venv of `scripts/test` each test prints `SKIPPED`.

#[path = "devices/python.rs"]
mod python;

#[path = "devices/realtime.rs"]
mod realtime;

use realtime::realtime;
use std::io::{BufRead, BufReader};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::time::{Duration, Instant};

use rl_drivers::fake::robotiq_gripper::{FakeGripper, FakeGripperConfig, Pty};
use rl_drivers::proto::robotiq::Model;
use rl_drivers::robotiq::{Exchange, GripperConfig, RobotiqGripper, SerialPort};
use rl_drivers::{CyclicDevice, Device, State};
use serde_json::Value;

fn pymodbus(test: &str) -> Option<std::path::PathBuf> {
    match python::python_with(&["pymodbus", "serial"]) {
        Ok(p) => Some(p),
        Err(why) => {
            println!("SKIPPED: {test}: {why}");
            None
        }
    }
}

fn regs(v: &Value) -> Vec<u16> {
    serde_json::from_value(v.clone()).unwrap_or_else(|e| panic!("{v}: {e}"))
}

#[test]
fn pymodbus_drives_the_fake_gripper_over_rtu_and_tcp() {
    let Some(py) = pymodbus("pymodbus_drives_the_fake_gripper_over_rtu_and_tcp") else {
        return;
    };
    let fake = FakeGripper::spawn(FakeGripperConfig {
        on_thread_start: Some(realtime),
        activation_time: Duration::from_millis(300),
        tcp: Some("127.0.0.1:0".parse().unwrap()),
        ..FakeGripperConfig::serial()
    })
    .unwrap();
    let path = fake.serial_path().unwrap().to_string_lossy().into_owned();
    let port = fake.tcp_addr().unwrap().port().to_string();
    for args in [
        vec!["rtu", path.as_str()],
        vec!["tcp", "127.0.0.1", port.as_str()],
    ] {
        // A fresh gripper state for each client: reset, and a 40 mm object in the hand.
        fake.set_object(Some(0.040));
        let out = Command::new(&py)
            .arg(python::script("pymodbus_client.py"))
            .args(&args)
            .output()
            .expect("python");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: Value = serde_json::from_slice(&out.stdout).expect("json");
        println!("{} {v}", args[0]);
        assert_eq!(v["errors"], Value::Array(vec![]), "{v}");
        // Activation: 0x11 (gACT, gSTA 1), then 0x31 (gSTA 3) after the activation time.
        assert_eq!(regs(&v["activating"])[0], 0x1100);
        assert_eq!(regs(&v["activated"])[0], 0x3100);
        let t = v["activation_s"].as_f64().unwrap();
        assert!((0.25..2.0).contains(&t), "activation took {t} s");
        // The read/write answered the status after the write: going, moving, request echoed.
        assert_eq!(regs(&v["readwrite"])[..2], [0x3900, 0x00FF]);
        // The grasp ends on the object: gOBJ 2 (0xB9), at the object's width.
        let g = regs(&v["grasped"]);
        assert_eq!(g[0], 0xB900, "{g:04X?}");
        let opening = 0.085 * (1.0 - (f64::from(g[2] >> 8) - 3.0) / 227.0);
        assert!((opening - 0.040).abs() < 0.0004, "{opening}");
        // The single write changed the position request only.
        assert_eq!(regs(&v["holding"]), [0x0900, 0x0000, 0xFFFF]);
        // Refusals: outside the maps (2), an unsupported function (1), past the map (2).
        assert_eq!(v["outside_map"], serde_json::json!([true, 2]));
        assert_eq!(v["coils"], serde_json::json!([true, 1]));
        assert_eq!(v["past_the_map"], serde_json::json!([true, 2]));
        // RTU is paced like the line: 8 + 11 bytes at 115200 baud (1.65 ms) plus 1 ms.
        let ms = v["read_ms"].as_f64().unwrap();
        if args[0] == "rtu" {
            assert!(ms >= 2.6, "a read took {ms} ms");
        }
        // Reset for the next client.
        fake.set_object(None);
    }
    let s = fake.status();
    assert_eq!(
        (s.crc_errors, s.garbage_bytes, s.other_units),
        (0, 0, 0),
        "{s:?}"
    );
    assert_eq!(s.exceptions, 6, "{s:?}");
}

/// Starts the pymodbus server script and waits for its "ready".
fn server(py: &std::path::Path, args: &[&str]) -> (Child, BufReader<ChildStdout>) {
    let mut child = Command::new(py)
        .arg(python::script("pymodbus_server.py"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("python");
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    assert_eq!(line.trim(), "ready", "the pymodbus server did not start");
    (child, out)
}

/// Ends the server (closes its input) and returns its log.
fn finish(mut child: Child, mut out: BufReader<ChildStdout>) -> Value {
    drop(child.stdin.take());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    assert!(child.wait().unwrap().success());
    serde_json::from_str(&line).expect("json")
}

fn run_driver(g: &mut RobotiqGripper) {
    g.open().unwrap();
    g.start().unwrap();
    g.set_force_count(100).unwrap();
    g.set_position_count(200).unwrap();
    let end = Instant::now() + Duration::from_secs(3);
    while !g.motion_done() {
        assert!(Instant::now() < end, "{:?}", g.status());
        g.step().unwrap();
        std::thread::sleep(g.update_period());
    }
    assert_eq!(g.status().position, 200);
    g.stop().unwrap();
    g.close().unwrap();
    assert_eq!(g.state(), State::Closed);
    let m = g.counters();
    assert!(m.reads >= 3 && m.writes >= 3, "{m:?}");
}

#[test]
fn our_driver_talks_to_pymodbus_servers_over_rtu_and_tcp() {
    let Some(py) = pymodbus("our_driver_talks_to_pymodbus_servers_over_rtu_and_tcp") else {
        return;
    };
    let config = GripperConfig {
        response_timeout: Duration::from_millis(500),
        ..GripperConfig::new(Model::TwoF85)
    };
    // RTU: pymodbus opens the pseudo-terminal's slave; our driver has the master side.
    let pty = Pty::open().unwrap();
    let path = pty.path().to_string_lossy().into_owned();
    let (child, out) = server(&py, &["rtu", &path]);
    let line = SerialPort::from_fd(pty.master).unwrap();
    let mut g = RobotiqGripper::rtu_on(config, line, 115_200, "pty").unwrap();
    run_driver(&mut g);
    let log = finish(child, out);
    println!("rtu {log}");
    check_log(&log, Exchange::ReadWrite);
    drop(pty.slave);

    // TCP, with separate writes and reads.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let (child, out) = server(&py, &["tcp", &port.to_string()]);
    let config = GripperConfig {
        exchange: Exchange::Separate,
        ..config
    };
    let mut g = RobotiqGripper::tcp(config, format!("127.0.0.1:{port}").parse().unwrap()).unwrap();
    run_driver(&mut g);
    let log = finish(child, out);
    println!("tcp {log}");
    check_log(&log, Exchange::Separate);
}

/// What pymodbus decoded is what the driver meant: the opening read, the reset and the
/// activation, and the commands of the steps; the last output is the stop's halt.
fn check_log(log: &Value, exchange: Exchange) {
    let requests: Vec<(u8, u16, u16, Option<Vec<u16>>)> =
        serde_json::from_value(log["requests"].clone()).unwrap();
    // open: read the status.
    assert_eq!(requests[0], (4, 0x07D0, 3, None));
    // start: read, reset (speed 255, force 128), activate, …
    assert_eq!(requests[1], (4, 0x07D0, 3, None));
    assert_eq!(
        requests[2],
        (16, 0x03E8, 3, Some(vec![0x0000, 0x0000, 0xFF80]))
    );
    assert_eq!(
        requests[3],
        (16, 0x03E8, 3, Some(vec![0x0100, 0x0000, 0xFF80]))
    );
    // The steps' command: activated, go to 200 at speed 255 and force 100.
    let step = vec![0x0900, 200, 0xFF64];
    let written: Vec<&Vec<u16>> = requests.iter().filter_map(|r| r.3.as_ref()).collect();
    assert!(written.contains(&&step), "{requests:?}");
    match exchange {
        Exchange::ReadWrite => assert!(requests.iter().any(|r| r.0 == 23), "{requests:?}"),
        Exchange::Separate => assert!(requests.iter().all(|r| r.0 == 4 || r.0 == 16)),
    }
    // stop: halt (rGTO 0), activation kept.
    assert_eq!(regs(&log["output"])[..3], [0x0100, 200, 0xFF64]);
}
