//! `rl run --device ur://HOST:PORT` against the fake UR controller in this process: the
//! controller runtime opens the arm over RTDE and plans from the joints `open` read (the arm
//! stands away from the model's home), the follower program runs on the fake, the embedded
//! RV-6SL tour (six joints) is tracked at the controller's 500 Hz, and the run stops the
//! program and pauses RTDE. The fake binds a loopback address of this test's own, where the
//! driver's default dashboard (29999) and script (30002) ports are free.

use std::net::{IpAddr, Ipv4Addr};
use std::process::Command;

use rl_drivers::fake::ur_controller::{FakeUr, FakeUrConfig, runtime_state};

mod late;

const HOST: Ipv4Addr = Ipv4Addr::new(127, 0, 0, 95);

#[test]
fn rl_run_drives_the_fake_ur() {
    // A run the machine made late (a CI run: the loop waited 11 ms for its CPU and missed 6
    // deadlines in a row) runs again, at most three times, then SKIPPED with the reasons.
    late::while_late("rl_run_drives_the_fake_ur", one_run, |why| why.clone());
}

/// One run against a fresh fake; `Some(why)` when the machine was late (see
/// [`late::json_late`]), `None` when it passed (or was SKIPPED).
fn one_run() -> Option<String> {
    let home = rl::controller::rv6sl()
        .expect("embedded model")
        .home_or_neutral();
    // The arm stands away from the model's home: the run plans from where `open` finds it.
    let mut initial_q = [0.0; 6];
    for (k, q) in initial_q.iter_mut().enumerate() {
        *q = home[k] + [0.3, -0.2, 0.4, 0.1, -0.3, 0.2][k];
    }
    let fake = match FakeUr::spawn(FakeUrConfig {
        bind: IpAddr::V4(HOST),
        rtde_port: 0,
        dashboard_port: Some(29_999),
        script_ports: vec![30_002],
        realtime_port: None,
        realtime_read_only_port: None,
        initial_q,
        on_thread_start: Some(rl::devices::fake_thread_realtime),
        ..FakeUrConfig::loopback()
    }) {
        Ok(f) => f,
        Err(e) => {
            println!(
                "SKIPPED: rl_run_drives_the_fake_ur: ports 29999/30002 on {HOST} are taken ({e})"
            );
            return None;
        }
    };
    let out = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(["run", "--device"])
        .arg(format!("ur://{}", fake.rtde_addr()))
        .args(["--duration", "2s", "--speed", "0.25", "--json"])
        .output()
        .expect("rl runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let report: serde_json::Value = serde_json::from_str(stdout.trim())
        .unwrap_or_else(|e| panic!("no JSON report ({e}): {stdout} {stderr}"));
    println!("{report:#}");
    if let Some(why) = late::json_late(&report) {
        return Some(why);
    }
    // The fake's own clock: a run that failed on timing (its likely cause) while the fake's
    // thread woke a cycle late or more (its slips: it was not running when the arm's state was
    // due, as a real controller always is) is the machine's doing too.
    let s = fake.status();
    if !out.status.success() && !report["likely_cause"].is_null() && s.slips > 0 {
        return Some(format!(
            "{}; the fake slipped {} times, up to {} µs late",
            report["likely_cause"], s.slips, s.max_lateness_us
        ));
    }
    assert!(out.status.success(), "{stderr}");
    assert_eq!(report["failed"], false, "{report}");
    assert_eq!(report["device_stopped"], true, "{report}");
    assert!(report["device_fault"].is_null(), "{report}");
    // 2 s at the controller's 2 ms.
    let cycles = report["cycles"].as_u64().unwrap();
    assert!(cycles >= 900, "{cycles} cycles");
    let s = fake.status();
    assert_eq!(s.programs_started, 1);
    assert!(s.servoj_calls >= 900, "{s:?}");
    assert_eq!(s.runtime_state, runtime_state::STOPPED);
    assert_eq!(s.output_int[24], 0, "the program ran to its end");
    assert_eq!(s.protocol_errors, 0);
    assert_eq!(s.protective_stops, 0);
    None
}
