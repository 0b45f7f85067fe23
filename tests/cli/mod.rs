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
