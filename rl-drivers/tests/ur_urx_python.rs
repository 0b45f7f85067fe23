//! Our fake UR controller's real-time interface read by a client not written here: PyPI `urx`
//! 0.11.0's real-time monitor (`urx.urrtmon.URRTMonitor`, Python, port 30003 fixed), beside our
//! own [`UrRealtime`] on the same stream. While both read, a script sent to 30003 moves the
//! arm; urx parses every message on its own thread: the controller times it got are 2 ms
//! apart, none missing, and at the end the joints,
//! target joints, tool vector and TCP force it decoded are the fake's, and the tool vector is
//! what our decoder read. Without the venv of `scripts/test` it prints `SKIPPED`.

#[path = "devices/python.rs"]
mod python;

#[path = "devices/realtime.rs"]
mod realtime;

use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, TcpStream};
use std::process::Command;
use std::time::{Duration, Instant};

use rl_drivers::fake::ur_controller::{FakeUr, FakeUrConfig};
use rl_drivers::ur::{UrRealtime, UrRealtimeConfig};
use rl_drivers::{CyclicDevice, Device};

/// A loopback address of this test's own: urx knows only port 30003.
const HOST: Ipv4Addr = Ipv4Addr::new(127, 0, 0, 96);
const NAME: &str = "urx_reads_our_fake_real_time_interface";

#[test]
fn urx_reads_our_fake_real_time_interface() {
    let python = match python::python_with(&["urx.urrtmon"]) {
        Ok(p) => p,
        Err(why) => {
            println!("SKIPPED: {NAME}: {why}");
            return;
        }
    };
    let fake = match FakeUr::spawn(FakeUrConfig {
        bind: IpAddr::V4(HOST),
        rtde_port: 0,
        dashboard_port: None,
        script_ports: vec![],
        realtime_port: Some(30_003),
        realtime_read_only_port: None,
        on_thread_start: Some(realtime::realtime),
        ..FakeUrConfig::loopback()
    }) {
        Ok(f) => f,
        Err(e) => {
            println!("SKIPPED: {NAME}: {HOST}:30003 is taken ({e})");
            return;
        }
    };
    let wrench = [12.5, -3.25, 40.0, 0.5, -0.125, 1.75];
    fake.set_tcp_force(wrench);
    let q0 = fake.status().q;
    let target: Vec<f64> = q0
        .iter()
        .enumerate()
        .map(|(k, q)| q + 0.02 * (k as f64 + 1.0))
        .collect();

    let child = Command::new(&python)
        .arg(python::script("urx_check.py"))
        .arg(HOST.to_string())
        .arg("1.5")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("python");
    // Our reader on the same stream, stepping while urx reads, and the script that moves the
    // arm while both read.
    let mut ours = UrRealtime::new(UrRealtimeConfig::new(IpAddr::V4(HOST))).unwrap();
    ours.open().unwrap();
    ours.start().unwrap();
    let script = format!(
        "def urx_peer():\n  movej([{}], a=1.4, v=0.5)\nend\n",
        target
            .iter()
            .map(|q| format!("{q:.9}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let mut child = child;
    let t0 = Instant::now();
    let mut sent = false;
    while child.try_wait().expect("python").is_none() {
        assert!(t0.elapsed() < Duration::from_secs(30), "urx_check.py hangs");
        let _ = ours.step();
        if !sent && t0.elapsed() > Duration::from_millis(300) {
            TcpStream::connect((HOST, 30_003))
                .and_then(|mut s| s.write_all(script.as_bytes()))
                .expect("script to 30003");
            sent = true;
        }
    }
    let out = child.wait_with_output().expect("python");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let s = fake.status();
    let end = Instant::now() + Duration::from_millis(100);
    while Instant::now() < end {
        let _ = ours.step();
    }
    let mine = *ours.realtime_state();
    println!(
        "urx: {} messages; fake: {} slips ({} µs at worst), {} real-time messages sent, {} skipped",
        v["messages"], s.slips, s.max_lateness_us, s.realtime_sent, s.realtime_skipped
    );

    // urx parsed every message on its thread: controller times 2 ms apart; where the fake
    // slipped, its clock jumped (it does not catch up), by whole periods.
    let stamps: Vec<f64> = serde_json::from_value(v["ctrl_stamps"].clone()).unwrap();
    assert!(stamps.len() >= 300, "{} messages in 1.5 s", stamps.len());
    // The fake's clock counts its cycles (a slipped cycle delays it, never skips it), and
    // it skips a message for a client only when that client's queue is full: urx got every
    // one, 2 ms apart.
    for w in stamps.windows(2) {
        assert!(
            ((w[1] - w[0]) / 0.002 - 1.0).abs() < 1e-6,
            "a step of {} s in urx's messages",
            w[1] - w[0]
        );
    }
    assert_eq!(s.programs_started, 1, "{:?}", s.last_program_error);

    // What urx decoded at the end is the fake's state: the arm at rest at the target. The
    // fake's status and our reader's state are read a little later than urx's last message,
    // while the arm's last motion step settles in the last bits: equal to 1e-12.
    let f = |key: &str| -> Vec<f64> { serde_json::from_value(v[key].clone()).unwrap() };
    let close = |what: &str, a: &[f64], b: &[f64]| {
        assert_eq!(a.len(), b.len(), "{what}");
        for (k, (x, y)) in a.iter().zip(b).enumerate() {
            assert!((x - y).abs() < 1e-12, "{what}[{k}]: urx {x}, ours {y}");
        }
    };
    for (k, (a, t)) in f("q_actual").iter().zip(&target).enumerate() {
        assert!((a - t).abs() < 1e-9, "joint {k}: urx {a}, target {t}");
    }
    close("q actual", &f("q_actual"), &s.q);
    close("q target", &f("q_target"), &s.target_q);
    assert_eq!(f("tcp_force"), wrench.to_vec());
    // urx's "tcp" is the tool vector target (columns 74–79), as our decoder reads it.
    close("tool vector target", &f("tcp"), &mine.tool_vector_target);
    close("q actual (our reader)", &f("q_actual"), &mine.q_actual);
}
