//! Our fake UR controller read by a client not written here: PyPI `ur-rtde` 1.6.5 (SDU's
//! ur_rtde, C++). Its receive interface sets up the 58 variables it asks for by default at
//! 500 Hz and reads them for two seconds: every package 2 ms after the one before, none
//! refused, 0 protocol errors on either side; the controller time of the newest package ur_rtde
//! holds keeps pace with the wall clock (a slower reader would fall behind). Its IO interface
//! writes digital outputs, the speed slider and an analog output through its 16 input recipes,
//! and the receive interface reads them back. Its dashboard client talks to the fake's dashboard. Without the venv of
//! `scripts/test` it prints `SKIPPED`.

#[path = "devices/python.rs"]
mod python;

#[path = "devices/realtime.rs"]
mod realtime;

use realtime::realtime;
use std::net::{IpAddr, Ipv4Addr};
use std::process::Command;

use rl_drivers::fake::ur_controller::{FakeUr, FakeUrConfig};

/// A loopback address of this test's own: ur_rtde knows only port 30004.
const HOST: Ipv4Addr = Ipv4Addr::new(127, 0, 0, 94);

#[test]
fn ur_rtde_reads_our_fake_at_500_hz_with_no_protocol_errors() {
    let python = match python::python_with(&["rtde_receive", "rtde_io", "dashboard_client"]) {
        Ok(p) => p,
        Err(why) => {
            println!("SKIPPED: ur_rtde_reads_our_fake_at_500_hz_with_no_protocol_errors: {why}");
            return;
        }
    };
    let fake = match FakeUr::spawn(FakeUrConfig {
        bind: IpAddr::V4(HOST),
        dashboard_port: Some(0),
        script_ports: vec![0, 0],
        on_thread_start: Some(realtime),
        ..FakeUrConfig::loopback()
    }) {
        Ok(f) => f,
        Err(e) => {
            println!(
                "SKIPPED: ur_rtde_reads_our_fake_at_500_hz_with_no_protocol_errors: {HOST}:30004 is taken ({e})"
            );
            return;
        }
    };
    let out = Command::new(&python)
        .arg(python::script("ur_rtde_check.py"))
        .arg(HOST.to_string())
        .arg(fake.dashboard_addr().unwrap().port().to_string())
        .arg("2.0")
        .output()
        .expect("python");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let s = fake.status();
    println!("fake: {s:?}");

    assert_eq!(v["connected"], true);
    // 500 Hz: consecutive timestamps 2 ms apart, or whole multiples where Python's polling
    // missed some (ur_rtde's own thread receives them all; the fake counts what it sent).
    let stamps: Vec<f64> = serde_json::from_value(v["stamps"].clone()).unwrap();
    let walls: Vec<f64> = serde_json::from_value(v["walls"].clone()).unwrap();
    // Python polls ur_rtde's latest package (its own thread receives every one); on a loaded
    // machine the polling sees a part of them, never fewer than a hundred in 2 s.
    assert!(
        stamps.len() >= 100,
        "{} distinct timestamps in 2 s",
        stamps.len()
    );
    for w in stamps.windows(2) {
        let k = (w[1] - w[0]) / 0.002;
        assert!(
            (k - k.round()).abs() < 1e-6 && k.round() >= 1.0,
            "a step of {} s",
            w[1] - w[0]
        );
    }
    // ur_rtde keeps up with 500 Hz: the controller time of the newest package it holds
    // stays with the wall clock. Its lag (wall clock − controller time, both from the first
    // sample) can only grow by Python's late polls and by the fake's own slips (a tick that
    // wakes more than a cycle late does not catch up, so `timestamp` falls behind the wall
    // clock by what the slip cost: `slipped_us`, counted by the fake), so its minimum over the
    // last fifth of the samples is that of the first fifth plus those slips: a reader slower
    // than the stream would fall behind and the minimum grow with it (by 0.5 s over 2 s at
    // half the rate). A CI run saw the fake slip twice (12.8 ms at worst) and Python every
    // one of 989 packages, with the lag grown by the 21.9 ms the slips cost.
    let lag: Vec<f64> = walls
        .iter()
        .zip(&stamps)
        .map(|(w, t)| (w - walls[0]) - (t - stamps[0]))
        .collect();
    let fifth = lag.len() / 5;
    let min = |l: &[f64]| l.iter().copied().fold(f64::INFINITY, f64::min);
    let (early, late) = (min(&lag[..fifth]), min(&lag[lag.len() - fifth..]));
    let span = (stamps[stamps.len() - 1] - stamps[0]) / 0.002;
    let slipped = s.slipped_us as f64 * 1e-6;
    println!(
        "ur_rtde: Python saw {} timestamps over {span:.0} periods of 2 ms; lag {:.1} ms at \
         the start, {:.1} ms at the end (minima); the fake slipped {} times, {} µs at worst, \
         {:.1} ms in all",
        stamps.len(),
        early * 1e3,
        late * 1e3,
        s.slips,
        s.max_lateness_us,
        slipped * 1e3
    );
    assert!(
        late - early < 0.02 + slipped,
        "ur_rtde fell behind the stream: lag {:.1} ms at the start, {:.1} ms at the end, \
         of which the fake's slips explain {:.1} ms",
        early * 1e3,
        late * 1e3,
        slipped * 1e3
    );
    assert!(span > 500.0, "the stream covered only {span} periods");
    // Where the fake kept its clock (no slips: it runs SCHED_FIFO as root, as in CI), the
    // 2 s Python read span 500 packages a wall-clock second.
    if s.slips == 0 {
        assert!(span >= 950.0, "{span} periods in 2 s without a slip");
    }
    // No protocol errors, no refused recipes: ur_rtde's 58 output variables and 16 input
    // recipes were all known.
    assert_eq!(s.protocol_errors, 0, "{:?}", s.last_protocol_error);
    assert_eq!(s.refused_recipes, 0);
    assert!(s.outputs_sent > 900, "{s:?}");
    // What it read is the fake's state.
    assert_eq!(v["robot_mode"], 7);
    assert_eq!(v["safety_mode"], 1);
    assert_eq!(v["runtime_state"], 1);
    assert_eq!(
        v["joint_mode"],
        serde_json::json!([253, 253, 253, 253, 253, 253])
    );
    assert_eq!(v["main_voltage"], 48.0);
    let q: Vec<f64> = serde_json::from_value(v["actual_q"].clone()).unwrap();
    for (a, b) in q.iter().zip(s.q) {
        assert!((a - b).abs() < 1e-12);
    }
    // The IO interface's writes, read back: standard output 3, configurable output 1 (bit 9),
    // the slider at 0.5, 0.3 of the analog output's 10 V.
    assert_eq!(v["io"], serde_json::json!([true, true, true, true]));
    assert_eq!(v["digital_out"], (1 << 3) | (1 << 9));
    assert_eq!(v["digital_out_after"], 1 << 9);
    assert_eq!(v["speed_scaling"], 0.5);
    assert_eq!(v["target_speed_fraction"], 0.5);
    assert!(
        (v["analog_out0"].as_f64().unwrap() - 3.0).abs() < 1e-9,
        "{}",
        v["analog_out0"]
    );
    assert_eq!(s.digital_outputs, 1 << 9);
    assert_eq!(s.speed_slider, 0.5);
    // The dashboard.
    let d = &v["dashboard"];
    assert_eq!(d["connected"], true);
    assert!(d["robotmode"].as_str().unwrap().contains("RUNNING"), "{d}");
    assert_eq!(d["remote"], true);
    assert_eq!(d["running"], false);
    assert!(s.dashboard_unknown == 0, "{s:?}");
}
