//! `rl run --zenoh` against peers not written here: a Python subscriber (PyPI eclipse-zenoh
//! 1.10.2 and rosbags, in the venv scripts/test makes) records the joint states of a running
//! `rl run` — count, order and values equal to its telemetry CSV — and sees the controller's
//! liveliness token come and go; a Python publisher stops a run and has its targets refused
//! (counted, with the reason) while the run follows its planned motion. Needs `--features
//! zenoh`; SKIPPED without the venv.
#![cfg(feature = "zenoh")]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

mod cli;
mod late;
#[path = "../rl-cell/tests/support/mod.rs"]
mod support;
use cli::exit_by;
use support::{free_port, python};

use rl_cell::ros2::msg::{JOINT_TRAJECTORY, STRING};
use rl_cell::ros2::names::topic_key;

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rl-cell-run-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// One controller run at a time (each is a SCHED_FIFO loop and an in-process fake).
fn one_run_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static RUNS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    RUNS.lock().unwrap_or_else(|p| p.into_inner())
}

/// Starts `peer.py subscribe` listening on `port` for `key`, and waits for it to be ready.
fn subscriber(python: &Path, port: u16, key: &str, out: &Path) -> Child {
    let mut child = Command::new(python)
        .arg(support::peer_script("peer.py"))
        .args([
            "subscribe",
            "--listen",
            &format!("tcp/127.0.0.1:{port}"),
            "--key",
            key,
        ])
        .arg("--out")
        .arg(out)
        .args(["--duration", "60", "--idle", "2"])
        .stdout(Stdio::piped())
        .spawn()
        .expect("python runs");
    let mut line = String::new();
    BufReader::new(child.stdout.as_mut().expect("stdout"))
        .read_line(&mut line)
        .expect("ready");
    assert_eq!(line.trim(), "ready");
    child
}

/// The JSON report `rl run --json` wrote to its standard output; without one, its stderr.
fn json_report(out: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "no JSON report ({e}): {}",
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

fn records(path: &Path) -> Vec<serde_json::Value> {
    support::recorded(path)
}

#[test]
fn a_python_subscriber_records_what_the_telemetry_csv_holds() {
    let Some(python) = python() else {
        println!(
            "SKIPPED: no Python with eclipse-zenoh and rosbags (scripts/test makes target/cell-venv)"
        );
        return;
    };
    let _one = one_run_at_a_time();
    let dir = temp("csv");
    let port = free_port();
    let seen = dir.join("seen.jsonl");
    let csv = dir.join("telemetry.csv");
    // A run the machine made late (lost replies while the loop or the fake measured itself
    // late) goes again, at most three times (then SKIPPED).
    let Some((out, report)) = late::while_late(
        "the subscriber's run",
        || {
            let mut sub = subscriber(
                &python,
                port,
                "0/*/sensor_msgs::msg::dds_::JointState_/*",
                &seen,
            );
            let out = Command::new(env!("CARGO_BIN_EXE_rl"))
                .args(["run", "--duration", "2s", "--json", "--zenoh"])
                .arg(format!("tcp/127.0.0.1:{port}"))
                .args(["--zenoh-wait", "10s", "--telemetry"])
                .arg(&csv)
                .output()
                .expect("rl runs");
            let report = json_report(&out);
            assert!(
                exit_by(&mut sub, Instant::now() + Duration::from_secs(20))
                    .is_some_and(|s| s.success())
            );
            (out, report)
        },
        |(_, report)| late::json_late(report),
    ) else {
        return;
    };
    assert!(
        out.status.success(),
        "rl run failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let z = &report["zenoh"];
    assert!(z["subscriber_after_s"].is_number(), "{z}");
    assert_eq!(z["outbound"]["dropped"], 0);
    assert_eq!(z["outbound"]["failed"], 0);
    let text = std::fs::read_to_string(&csv).expect("csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() > 200, "{} rows", rows.len());
    assert_eq!(z["outbound"]["joint_states"], 2 * rows.len() as u64);

    let all = records(&seen);
    for (topic, prefix) in [("joint_states", "meas_"), ("joint_commands", "cmd_")] {
        let got: Vec<&serde_json::Value> = all
            .iter()
            .filter(|r| {
                r["key"]
                    .as_str()
                    .is_some_and(|k| k.starts_with(&format!("0/{topic}/")))
            })
            .collect();
        assert_eq!(
            got.len(),
            rows.len(),
            "{topic}: one message per telemetry row"
        );
        let cols: Vec<usize> = header
            .iter()
            .enumerate()
            .filter(|(_, h)| h.starts_with(prefix))
            .map(|(k, _)| k)
            .collect();
        let ff: Vec<usize> = header
            .iter()
            .enumerate()
            .filter(|(_, h)| h.starts_with("ff_"))
            .map(|(k, _)| k)
            .collect();
        for (k, (r, row)) in got.iter().zip(&rows).enumerate() {
            assert_eq!(r["seq"].as_i64(), Some(k as i64 + 1), "{topic}: in order");
            let names: Vec<String> = cols
                .iter()
                .map(|&c| header[c][prefix.len()..].to_owned())
                .collect();
            assert_eq!(r["name"], serde_json::json!(names));
            // The CSV holds 7 decimals (4 for the feed-forward): the message's values, written
            // the same way, are the CSV's.
            for (j, &c) in cols.iter().enumerate() {
                let v = f64::from_bits(r["position_bits"][j].as_u64().expect("position"));
                assert_eq!(
                    format!("{v:.7}"),
                    row[c],
                    "{topic} row {k} column {}",
                    header[c]
                );
            }
            if topic == "joint_commands" {
                for (j, &c) in ff.iter().enumerate() {
                    let v = f64::from_bits(r["effort_bits"][j].as_u64().expect("effort"));
                    assert_eq!(format!("{v:.4}"), row[c], "row {k} column {}", header[c]);
                }
            } else {
                assert_eq!(r["effort"], serde_json::json!([]), "no measured effort");
            }
        }
    }
    // The controller's node appeared and left.
    let zid = z["zid"].as_str().expect("zid");
    let node: Vec<&str> = all
        .iter()
        .filter_map(|r| {
            let t = r.get("token")?.as_str()?;
            (t.contains(&format!("/{zid}/")) && t.contains("/NN/")).then(|| r["kind"].as_str())?
        })
        .collect();
    assert_eq!(node.len(), 2, "{node:?}");
    assert!(
        node[0].contains("PUT") && node[1].contains("DELETE"),
        "{node:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_python_publisher_stops_the_run_and_its_targets_are_refused_and_counted() {
    let Some(python) = python() else {
        println!(
            "SKIPPED: no Python with eclipse-zenoh and rosbags (scripts/test makes target/cell-venv)"
        );
        return;
    };
    let _one = one_run_at_a_time();
    let dir = temp("stop");
    let port = free_port();
    let target = serde_json::json!({"key": topic_key(0, "/arm1/joint_trajectory", &JOINT_TRAJECTORY),
        "type": "trajectory_msgs/msg/JointTrajectory", "sequence": 1,
        "msg": {"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
            "joint_names": (0..6).map(|k| format!("joint{k}")).collect::<Vec<_>>(),
            "points": [{"positions": vec![0.0f64; 6], "velocities": [], "accelerations": [], "effort": [],
                "time_from_start": {"sec": 0, "nanosec": 0}}]}});
    let stop = serde_json::json!({"key": topic_key(0, "/arm1/stop", &STRING),
        "type": "std_msgs/msg/String", "sequence": 1, "msg": {"data": "rest"}, "after_s": 1.0});
    let plan = serde_json::json!({"settle_s": 2.0, "samples": [target, stop]});
    let plan_path = dir.join("plan.json");
    std::fs::write(&plan_path, plan.to_string()).expect("plan");
    // A run the machine made late goes again, at most three times (then SKIPPED).
    let Some((out, report, started)) = late::while_late(
        "the stopped run",
        || {
            let mut run = Command::new(env!("CARGO_BIN_EXE_rl"))
                .args([
                    "run",
                    "--duration",
                    "60s",
                    "--json",
                    "--zenoh-namespace",
                    "/arm1",
                    "--zenoh-listen",
                ])
                .arg(format!("tcp/127.0.0.1:{port}"))
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .expect("rl runs");
            let started = Instant::now();
            let published = support::publish(&python, &format!("tcp/127.0.0.1:{port}"), &plan_path);
            assert!(published.status.success());
            let ended = exit_by(&mut run, Instant::now() + Duration::from_secs(30));
            let out = run.wait_with_output().expect("output");
            assert!(
                ended.is_some(),
                "the stop request did not end the run: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            let report = json_report(&out);
            (out, report, started)
        },
        |(_, report, _)| late::json_late(report),
    ) else {
        return;
    };
    assert!(started.elapsed() < Duration::from_secs(30));
    assert_eq!(
        report["end"], "stopped on request, brought to rest",
        "{report}"
    );
    assert_eq!(
        out.status.code(),
        Some(130),
        "stopped on request: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let targets = &report["zenoh"]["inbound"]["targets"];
    assert_eq!(targets["received"], 1);
    assert_eq!(targets["refused_by_reason"]["sink"], 1);
    assert!(
        targets["first_refusal"]
            .as_str()
            .is_some_and(|r| r.contains("no streamed targets")),
        "{targets}"
    );
    assert_eq!(report["zenoh"]["inbound"]["stops"]["accepted"], 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_python_publisher_streams_targets_that_the_arm_follows() {
    let Some(python) = python() else {
        println!(
            "SKIPPED: no Python with eclipse-zenoh and rosbags (scripts/test makes target/cell-venv)"
        );
        return;
    };
    let _one = one_run_at_a_time();
    let dir = temp("follow");
    let csv = dir.join("t.csv");
    let port = free_port();
    let goals = [
        [0.1, 0.0, 0.1, 0.0, 0.0, 0.0],
        [0.2, -0.1, 0.3, 0.0, 0.2, 0.0],
        [-0.1, 0.05, 0.2, 0.1, -0.1, 0.05],
    ];
    let target = |n: usize, q: &[f64; 6], after_s: f64| {
        serde_json::json!({"key": topic_key(0, "/arm1/joint_trajectory", &JOINT_TRAJECTORY),
            "type": "trajectory_msgs/msg/JointTrajectory", "sequence": n + 1, "after_s": after_s,
            "msg": {"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
                "joint_names": (0..6).map(|k| format!("joint{k}")).collect::<Vec<_>>(),
                "points": [{"positions": q, "velocities": [], "accelerations": [], "effort": [],
                    "time_from_start": {"sec": 0, "nanosec": 0}}]}})
    };
    let mut samples: Vec<_> = goals
        .iter()
        .enumerate()
        .map(|(n, q)| target(n, q, if n == 0 { 0.5 } else { 1.5 }))
        .collect();
    samples.push(
        serde_json::json!({"key": topic_key(0, "/arm1/stop", &STRING),
        "type": "std_msgs/msg/String", "sequence": 1, "msg": {"data": "rest"}, "after_s": 2.0}),
    );
    let plan = serde_json::json!({"settle_s": 2.0, "samples": samples});
    let plan_path = dir.join("plan.json");
    std::fs::write(&plan_path, plan.to_string()).expect("plan");
    // A run the machine made late goes again, at most three times (then SKIPPED).
    let Some((_, report)) = late::while_late(
        "the following run",
        || {
            let mut run = Command::new(env!("CARGO_BIN_EXE_rl"))
                .args([
                    "run",
                    "--follow",
                    "zenoh",
                    "--input-timeout",
                    "10s",
                    "--json",
                    "--zenoh-namespace",
                    "/arm1",
                    "--zenoh-listen",
                ])
                .arg(format!("tcp/127.0.0.1:{port}"))
                .arg("--telemetry")
                .arg(&csv)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .expect("rl runs");
            let published = support::publish(&python, &format!("tcp/127.0.0.1:{port}"), &plan_path);
            assert!(published.status.success());
            let ended = exit_by(&mut run, Instant::now() + Duration::from_secs(30));
            let out = run.wait_with_output().expect("output");
            assert!(
                ended.is_some(),
                "the stop request did not end the run: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            let report = json_report(&out);
            (out, report)
        },
        |(_, report)| late::json_late(report),
    ) else {
        return;
    };
    let targets = &report["zenoh"]["inbound"]["targets"];
    assert_eq!(targets["received"], 3, "{targets}");
    assert_eq!(targets["refused"], 0, "{targets}");
    assert_eq!(report["inputs"]["targets"], 3, "{report}");
    assert_eq!(report["law"]["targets"], 3, "{report}");
    assert_eq!(
        report["end"], "stopped on request, brought to rest",
        "{report}"
    );
    // The last target stayed 2 s: the arm was commanded exactly there (seven decimals).
    let last = cli::last_commanded(&csv);
    for (k, (a, b)) in last.iter().zip(&goals[2]).enumerate() {
        assert!(
            (a - b).abs() <= 0.5e-7,
            "joint {k} commanded at {a}, the target {b}"
        );
    }
    println!(
        "targets taken at most {:.3} ms after the bridge sent them (period {:.2} ms)",
        report["law"]["apply_delay_max_s"]
            .as_f64()
            .unwrap_or(f64::NAN)
            * 1e3,
        report["period_s"].as_f64().unwrap_or(f64::NAN) * 1e3
    );
    let _ = std::fs::remove_dir_all(&dir);
}
