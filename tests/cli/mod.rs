//! Shared by the tests that run the `rl` tool: run it (within a time limit), or run it and
//! parse its JSON.
#![allow(dead_code)]

use std::ffi::OsStr;
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serde_json::Value;

/// Runs `rl` with `args` and returns what it did.
pub fn rl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(args)
        .output()
        .expect("run rl")
}

/// Runs `rl` with `args`, which must succeed, and parses its JSON output.
pub fn rl_json(args: &[&str]) -> Value {
    let out = rl(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Runs `cmd` to completion with its output captured, at most `limit`: beyond it, kills the
/// child and fails the test with its stderr.
pub fn run_bounded(mut cmd: Command, limit: Duration) -> Output {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn rl");
    let finished = exit_by(&mut child, Instant::now() + limit).is_some();
    let out = child.wait_with_output().expect("output");
    assert!(
        finished,
        "rl did not finish within {limit:?}; stderr:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Waits for `child` to exit until `deadline`; beyond it kills the child and returns `None`.
pub fn exit_by(child: &mut Child, deadline: Instant) -> Option<ExitStatus> {
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            return Some(status);
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            return None;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// `rl ARGS`, killed and failed beyond `limit`.
pub fn rl_within<S: AsRef<OsStr>>(args: &[S], limit: Duration) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_rl"));
    cmd.args(args);
    run_bounded(cmd, limit)
}

/// Reads `child`'s stderr (piped) line by line on a thread: the receiver hears once when a
/// line first contains `needle`; the thread returns all it read.
pub fn watch_stderr(child: &mut Child, needle: &'static str) -> (Receiver<()>, JoinHandle<String>) {
    let stderr = child.stderr.take().expect("stderr");
    let (tx, rx) = channel();
    let reader = std::thread::spawn(move || {
        let mut all = String::new();
        let mut told = false;
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if !told && line.contains(needle) {
                let _ = tx.send(());
                told = true;
            }
            all.push_str(&line);
            all.push('\n');
        }
        all
    });
    (rx, reader)
}

/// The commanded positions (`cmd_*` columns) of a telemetry CSV's last row (seven decimals).
pub fn last_commanded(csv: &std::path::Path) -> Vec<f64> {
    let text = std::fs::read_to_string(csv).expect("telemetry");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let last: Vec<&str> = lines.last().expect("rows").split(',').collect();
    header
        .iter()
        .zip(&last)
        .filter(|(h, _)| h.starts_with("cmd_"))
        .map(|(_, v)| v.parse().expect("number"))
        .collect()
}

/// The Python of target/ruckig-venv (scripts/test makes it) if it imports `ruckig`.
pub fn ruckig_python() -> Option<std::path::PathBuf> {
    let python =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/ruckig-venv/bin/python");
    let ok = python.exists()
        && Command::new(&python)
            .args(["-c", "import ruckig"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
    ok.then_some(python)
}
