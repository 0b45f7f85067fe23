//! One JSON schema for loop statistics (issue 12): the `loop` object of `rl jitter --json` and of
//! `rl run --json` has exactly the keys of rl-rt's `LoopStats::to_json`, nested objects
//! included, and its numbers agree with the command's own summary keys.

mod late;
use std::collections::BTreeSet;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

/// Every key path of `v` (`wakeup.p99_us`, `overrun_log[].cycle`, …).
fn key_paths(v: &Value, prefix: &str, out: &mut BTreeSet<String>) {
    match v {
        Value::Object(map) => {
            for (k, x) in map {
                let path = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                out.insert(path.clone());
                key_paths(x, &path, out);
            }
        }
        Value::Array(items) => {
            for x in items {
                key_paths(x, &format!("{prefix}[]"), out);
            }
        }
        _ => {}
    }
}

fn keys(v: &Value) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    key_paths(v, "", &mut out);
    out
}

/// rl-rt's schema, from a record with one overrun logged (so `overrun_log`'s entries show).
fn rl_rt_schema() -> BTreeSet<String> {
    let mut stats = rl::rt::LoopStats::new(1_000_000, 100);
    stats.record_cycle(5_000, 1_000);
    stats.record_overrun(1, 2_000_000);
    let v: Value = serde_json::from_str(&stats.to_json()).expect("rl-rt writes JSON");
    keys(&v)
}

/// Runs `rl args`, at most `limit`, and parses its standard output.
fn rl_json(args: &[&str], limit: Duration) -> Value {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn rl");
    let start = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("rl {args:?} took longer than {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out: Output = child.wait_with_output().expect("output");
    let v: Value = serde_json::from_slice(&out.stdout).expect("JSON on standard output");
    // A run the machine made late (lost replies while the loop or the fake measured itself
    // late) still writes the whole report, which is all this test reads.
    let late = late::json_late(&v);
    if let Some(why) = &late {
        println!("rl {args:?}: the machine was late, the report is still checked: {why}");
    }
    assert!(
        out.status.success() || late.is_some(),
        "rl {args:?}: {}\n{}",
        String::from_utf8_lossy(&out.stderr),
        String::from_utf8_lossy(&out.stdout)
    );
    v
}

/// The keys of `loop`, without the entries of `overrun_log` (present only after an overrun).
fn loop_keys(v: &Value) -> BTreeSet<String> {
    let l = &v["loop"];
    assert!(l.is_object(), "no loop object in {v}");
    keys(l)
        .into_iter()
        .filter(|k| !k.starts_with("overrun_log[]"))
        .collect()
}

#[test]
fn jitter_and_run_share_rl_rts_loop_statistics_schema() {
    let schema = rl_rt_schema();
    assert!(schema.contains("overrun_log[].late_by_us"), "{schema:?}");
    let without_log: BTreeSet<String> = schema
        .iter()
        .filter(|k| !k.starts_with("overrun_log[]"))
        .cloned()
        .collect();

    let jitter = rl_json(
        &[
            "jitter",
            "--policy",
            "other",
            "--no-mlock",
            "--no-cpu-latency-hint",
            "--cycles",
            "200",
            "--interval-us",
            "500",
            "--json",
        ],
        Duration::from_secs(30),
    );
    assert_eq!(loop_keys(&jitter), without_log, "rl jitter --json's loop");
    // The short keys are the same measurement.
    assert_eq!(jitter["loop"]["cycles"], jitter["cycles"]);
    assert_eq!(jitter["loop"]["cycles"], 200);
    assert_eq!(jitter["loop"]["period_ns"], 500_000);
    assert_eq!(jitter["loop"]["wakeup"]["max_us"], jitter["max_us"]);
    assert_eq!(jitter["loop"]["wakeup"]["p99_us"], jitter["p99_us"]);
    assert_eq!(jitter["loop"]["overruns"], jitter["overruns"]);

    let run = rl_json(
        &["run", "--duration", "500ms", "--no-mlock", "--json"],
        Duration::from_secs(60),
    );
    assert_eq!(loop_keys(&run), without_log, "rl run --json's loop");
    assert_eq!(run["loop"]["cycles"], run["cycles"]);
    assert_eq!(run["loop"]["period_ns"], 7_110_000);
}
