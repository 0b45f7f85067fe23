//! `rl run --follow SOURCE` as a user runs it: targets as text lines on standard input or in
//! UDP datagrams, against the embedded fake H7. The arm ends commanded exactly at the last
//! target (telemetry CSV), every line is counted (malformed, refused, foreign), the end of input
//! ends the run with exit 0, and flags that do not fit are refused before anything moves.

use std::io::Write;
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod cli;
use cli::{exit_by, last_commanded, rl};
mod late;

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rl-follow-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// One controller run at a time (each is a SCHED_FIFO loop and an in-process fake). A run the
/// machine made late (lost replies while the loop or the fake measured itself late) runs again
/// by the shared rule ([`late::while_late`], [`late::json_late`]).
fn one_run_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static RUNS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    RUNS.lock().unwrap_or_else(|p| p.into_inner())
}

fn assert_at(q: &[f64], goal: &[f64]) {
    assert_eq!(q.len(), goal.len(), "{q:?}");
    for (k, (a, b)) in q.iter().zip(goal).enumerate() {
        // The CSV writes seven decimals.
        assert!(
            (a - b).abs() <= 0.5e-7,
            "joint {k} commanded at {a}, the target {b}"
        );
    }
}

/// Runs `rl run --follow -` fed `lines` (with pauses: `None`), returns the exit code and the
/// JSON report.
fn follow_stdin(
    feed: &[Option<&str>],
    extra: &[&str],
    csv: &Path,
) -> (Option<i32>, serde_json::Value) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(["run", "--follow", "-", "--json", "--telemetry"])
        .arg(csv)
        .args(extra)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("rl runs");
    let mut stdin = child.stdin.take().expect("stdin");
    for item in feed {
        match item {
            Some(line) => writeln!(stdin, "{line}").expect("line written"),
            None => std::thread::sleep(Duration::from_millis(1200)),
        }
    }
    drop(stdin);
    let ended = exit_by(&mut child, Instant::now() + Duration::from_secs(30));
    let out = child.wait_with_output().expect("output");
    assert!(
        ended.is_some(),
        "the end of input did not end the run: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "JSON report ({e}): {}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    (out.status.code(), report)
}

#[test]
fn targets_on_standard_input_are_followed_counted_and_the_end_of_input_ends_the_run() {
    let _one = one_run_at_a_time();
    let dir = temp("stdin");
    let csv = dir.join("t.csv");
    let goal = [0.2, -0.1, 0.3, 0.0, 0.2, 0.0];
    let feed = [
        Some("# a comment, then a blank line"),
        Some(""),
        Some("position 0.1 0.1 0.1 0 0 0"),
        Some("p 0.1, 0.1, 0.1, 0, 0, 0 v 0.05 0 0 0 0 0"),
        Some("position 1 2 x 0 0 0"),
        Some("position 9 0 0 0 0 0"),
        Some("velocity 0.1 0 0"),
        None,
        Some("position 0.2 -0.1 0.3 0 0.2 0"),
        None,
        None,
    ];
    let Some((code, report)) = late::while_late(
        "follow on standard input",
        || follow_stdin(&feed, &["--input-timeout", "10s"], &csv),
        |(_, report)| late::json_late(report),
    ) else {
        return;
    };
    let follow = &report["follow"];
    assert_eq!(code, Some(0), "{report}");
    assert_eq!(
        report["end"], "stopped on request, brought to rest",
        "{report}"
    );
    assert_eq!(report["trajectory_source"], "follow");
    assert_eq!(follow["lines"], 8, "{follow}");
    assert_eq!(follow["targets_sent"], 3, "{follow}");
    assert_eq!(follow["malformed"], 2, "{follow}");
    assert_eq!(follow["refused"], 1, "{follow}");
    assert_eq!(follow["ended_by_eof"], true, "{follow}");
    assert!(
        follow["first_malformed"]
            .as_str()
            .is_some_and(|m| m.starts_with("line 5:") && m.contains("'x'")),
        "{follow}"
    );
    assert!(
        follow["first_refused"]
            .as_str()
            .is_some_and(|m| m.starts_with("line 6:") && m.contains("outside its limits")),
        "{follow}"
    );
    // The first two came in one cycle: the law takes the newest of a cycle's targets.
    assert_eq!(report["inputs"]["targets"], 3, "{report}");
    assert!(report["law"]["targets"].as_u64() >= Some(2), "{report}");
    assert_eq!(report["law"]["unreachable"], 0, "{report}");
    // The refusal is the run's input channel's: counted there too.
    assert_eq!(report["inputs"]["refused_invalid"], 1, "{report}");
    // The last target stayed 2.4 s: the arm was commanded exactly there, at rest.
    assert_at(&last_commanded(&csv), &goal);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn targets_in_udp_datagrams_are_followed_and_a_second_sender_is_refused() {
    let _one = one_run_at_a_time();
    let dir = temp("udp");
    let csv = dir.join("t.csv");
    // A free port on loopback for the run to bind.
    let port = UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("free port")
        .port();
    let goal = [-0.2, 0.1, 0.2, 0.1, -0.1, 0.05];
    let Some((out, report, ours)) = late::while_late(
        "follow over UDP",
        || {
            let mut child = Command::new(env!("CARGO_BIN_EXE_rl"))
                .args([
                    "run",
                    "--follow",
                    &format!("udp:{port}"),
                    "--json",
                    "--input-timeout",
                    "3s",
                ])
                .arg("--telemetry")
                .arg(&csv)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .expect("rl runs");
            let to = format!("127.0.0.1:{port}");
            let ours = UdpSocket::bind("127.0.0.1:0").expect("socket");
            let theirs = UdpSocket::bind("127.0.0.1:0").expect("socket");
            // The socket is bound once the run has started: send until the run takes the first.
            let started = Instant::now();
            while started.elapsed() < Duration::from_secs(5) {
                ours.send_to(b"position 0.1 0 0 0 0 0\n", &to)
                    .expect("sent");
                std::thread::sleep(Duration::from_millis(100));
            }
            ours.send_to(
                b"p 0 0 0.1 0 0 0\nposition -0.2 0.1 0.2 0.1 -0.1 0.05\n",
                &to,
            )
            .expect("sent");
            theirs
                .send_to(b"position 1 1 1 1 1 1\n", &to)
                .expect("sent");
            std::thread::sleep(Duration::from_millis(1500));
            ours.send_to(b"stop\n", &to).expect("sent");
            let ended = exit_by(&mut child, Instant::now() + Duration::from_secs(30));
            let out = child.wait_with_output().expect("output");
            assert!(ended.is_some(), "{}", String::from_utf8_lossy(&out.stderr));
            let report: serde_json::Value =
                serde_json::from_slice(&out.stdout).expect("JSON report");
            (out, report, ours)
        },
        |(_, report, _)| late::json_late(report),
    ) else {
        return;
    };
    assert_eq!(out.status.code(), Some(0), "{report}");
    let follow = &report["follow"];
    assert_eq!(follow["foreign"], 1, "{follow}");
    assert_eq!(follow["stops"], 1, "{follow}");
    assert_eq!(follow["malformed"], 0, "{follow}");
    assert_eq!(
        follow["peer"].as_str(),
        Some(ours.local_addr().expect("addr").to_string().as_str()),
        "{follow}"
    );
    let sent = follow["targets_sent"].as_u64().expect("count");
    assert!(sent >= 3, "{follow}");
    assert_eq!(report["inputs"]["targets"].as_u64(), Some(sent), "{report}");
    assert_at(&last_commanded(&csv), &goal);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn targets_that_stop_coming_bring_the_arm_to_rest_and_fail_the_run() {
    let _one = one_run_at_a_time();
    let dir = temp("stale");
    let csv = dir.join("t.csv");
    let port = UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("free port")
        .port();
    let Some((out, report)) = late::while_late(
        "follow with inputs that stop",
        || {
            let out = cli::run_bounded(
                {
                    let mut c = Command::new(env!("CARGO_BIN_EXE_rl"));
                    c.args([
                        "run",
                        "--follow",
                        &format!("udp:{port}"),
                        "--json",
                        "--input-timeout",
                        "500ms",
                    ])
                    .arg("--telemetry")
                    .arg(&csv);
                    c
                },
                Duration::from_secs(30),
            );
            let report: serde_json::Value =
                serde_json::from_slice(&out.stdout).expect("JSON report");
            (out, report)
        },
        |(_, report)| late::json_late(report),
    ) else {
        return;
    };
    assert_eq!(
        report["end"], "inputs stopped coming, brought to rest",
        "{report}"
    );
    assert_ne!(out.status.code(), Some(0), "{report}");
    assert_eq!(report["inputs"]["stale"], true, "{report}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn follow_flags_that_do_not_fit_are_refused_before_anything_moves() {
    for (args, says) in [
        (&["run", "--follow", "tcp:1234"][..], "udp:PORT"),
        (
            &["run", "--follow", "-", "--waypoints", "w.csv"][..],
            "--waypoints does not apply with --follow",
        ),
        (&["run", "--follow", "zenoh"][..], "--zenoh"),
        (
            &["run", "--follow", "-", "--input-timeout", "0s"][..],
            "--input-timeout",
        ),
        (&["run", "--input-timeout", "1s"][..], "--follow"),
    ] {
        let out = rl(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
}
