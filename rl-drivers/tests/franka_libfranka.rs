//! The fake Franka against libfranka itself: libfranka 0.21.2 as franky-control 2.0.0 ships it,
//! in a venv that `scripts/test` installs (`target/franky-control-venv`), runs
//! `tests/franka_peers/libfranka_session.py` against the fake: connect and read the state, a
//! joint motion, a torque-controlled motion of two seconds, a reflex (a torque step) and its
//! recovery. The fake serves the FR3's URDF from franky-sim's venv when it is there (else an
//! FR3-shaped arm of this crate's making) and integrates its dynamics. Without the venv the test
//! prints `SKIPPED: <reason>`.

use std::net::{IpAddr, Ipv4Addr};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

mod support;

use rl_drivers::fake::franka_controller::{FakeFranka, FakeFrankaConfig, fr3_shaped_urdf};
use support::stall::unless_stalled;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace")
        .to_path_buf()
}

/// The venv's python, or why there is none.
fn franky_control() -> Result<PathBuf, String> {
    let python = std::env::var_os("RL_FRANKY_CONTROL_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join("target/franky-control-venv/bin/python"));
    let ok = Command::new(&python)
        .args(["-c", "import franky"])
        .output()
        .is_ok_and(|o| o.status.success());
    if ok {
        Ok(python)
    } else {
        Err(format!(
            "no franky-control at {} (scripts/test installs it)",
            python.display()
        ))
    }
}

/// The FR3's URDF as franky-sim ships it, if its venv is there.
pub fn fr3_urdf() -> Option<String> {
    let site = workspace().join("target/franky-sim-venv/lib");
    let dir = std::fs::read_dir(&site).ok()?.flatten().next()?.path();
    std::fs::read_to_string(dir.join("site-packages/franky_sim/assets/fr3_clean.urdf")).ok()
}

fn real_time() {
    let _ = rl_rt::RtThreadBuilder::new("fake-franka")
        .policy(rl_rt::Policy::Fifo)
        .priority(85)
        .best_effort(true)
        .apply_to_current();
}

/// A fake on port 1337 (libfranka's fixed port) of a loopback address of its own.
fn spawn_on_own_address(urdf: String) -> FakeFranka {
    let pid = std::process::id();
    for k in 0..64u32 {
        let n = pid.wrapping_mul(64).wrapping_add(k);
        let ip = IpAddr::V4(Ipv4Addr::new(
            127,
            (n >> 16) as u8 | 0x40,
            (n >> 8) as u8,
            (n as u8).max(2),
        ));
        let config = FakeFrankaConfig {
            bind: ip,
            on_thread_start: Some(real_time),
            ..FakeFrankaConfig::loopback().with_urdf(urdf.clone())
        };
        if let Ok(f) = FakeFranka::spawn(config) {
            return f;
        }
    }
    panic!("no free loopback address for port 1337");
}

#[test]
fn libfranka_connects_moves_controls_torques_and_recovers_against_the_fake() {
    let python = match franky_control() {
        Ok(p) => p,
        Err(reason) => {
            println!("SKIPPED: {reason}");
            return;
        }
    };
    let (urdf, which) = match fr3_urdf() {
        Some(u) => (u, "the FR3's URDF (franky-sim)"),
        None => (fr3_shaped_urdf(), "an FR3-shaped arm (no franky-sim venv)"),
    };
    // A session whose fake robot slipped its own 1 kHz tick (the machine held its SCHED_FIFO
    // thread: under qemu-arm in a clean-clone CI, 9 slips of up to 5.2 ms, 45 states lost)
    // loses commands, and libfranka's motions then end in discontinuity reflexes, as they
    // would on the real robot: such a failed session goes again, at most three times, then
    // SKIPPED with the numbers (tests/support/stall.rs). The same when the client lost them:
    // libfranka's loop in another process, which the canary sees stalled (a thread on each CPU
    // that woke 0.9 ms late or more). A session that fails with the fake and the machine on
    // time fails the test.
    unless_stalled("libfranka against the fake", || {
        session(&python, urdf.clone(), which)
    });
}

/// One libfranka session against a new fake; `Err` when it failed while the fake slipped or
/// the machine stalled a thread.
fn session(python: &Path, urdf: String, which: &str) -> Result<(), String> {
    let fake = spawn_on_own_address(urdf);
    let canary = support::stall::Canary::start();
    let host = fake.addr().ip().to_string();
    let script = workspace().join("tests/franka_peers/libfranka_session.py");
    let start = Instant::now();
    let out = Command::new(python)
        .arg(&script)
        .arg(&host)
        .output()
        .expect("python runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!(
        "libfranka against the fake ({which}) in {:?}:\n{stdout}",
        start.elapsed()
    );
    std::thread::sleep(Duration::from_millis(20));
    let s = fake.status();
    println!(
        "fake: states {} commands {} lost {} (max {} in a row) late {} motions {} finished {} \
         reflexes {} recoveries {} refused {} slips {} max lateness {} µs raised {:?}",
        s.states,
        s.commands,
        s.lost,
        s.max_lost_in_a_row,
        s.late,
        s.motions,
        s.finished,
        s.reflexes,
        s.recoveries,
        s.refused_requests,
        s.slips,
        s.max_lateness_us,
        s.raised
    );
    let report: Option<serde_json::Value> = serde_json::from_str(stdout.trim()).ok();
    let steps_ok = report.as_ref().is_some_and(|r| {
        [
            "connect",
            "joint_motion",
            "torque_motion",
            "error_and_recovery",
        ]
        .iter()
        .all(|step| r["steps"][step]["ok"] == true)
    });
    let ok = out.status.success() && steps_ok && s.reflexes == 1;
    let stalled = canary.worst();
    if !ok && s.slips > 0 {
        return Err(format!(
            "failed with the fake's tick slipped {} times (at most {} µs late), {} states lost",
            s.slips, s.max_lateness_us, s.lost
        ));
    }
    if !ok && s.lost > 0 && stalled >= support::stall::STALL {
        return Err(format!(
            "failed with {} commands lost ({} in a row) while the machine stalled a thread \
             {stalled:?}",
            s.lost, s.max_lost_in_a_row
        ));
    }
    assert!(
        out.status.success(),
        "libfranka's session failed:\n{stdout}\n{stderr}"
    );
    let report = report.expect("one JSON line");
    for step in [
        "connect",
        "joint_motion",
        "torque_motion",
        "error_and_recovery",
    ] {
        assert_eq!(report["steps"][step]["ok"], true, "{step}: {stdout}");
    }
    // The fake saw it all: one reflex (the torque step) and its recovery.
    assert_eq!(s.reflexes, 1, "{s:?}");
    assert!(s.recoveries >= 1, "{s:?}");
    assert!(s.motions >= 4, "{s:?}");
    Ok(())
}
