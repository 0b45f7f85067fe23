//! Shared by rl-cell's tests and the `rl` package's cell tests (`#[path]`): the Python peers
//! (PyPI eclipse-zenoh and rosbags in a venv that scripts/test makes), free ports.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// rl-cell's directory, from rl-cell's tests or the workspace root's.
fn cell_dir() -> PathBuf {
    let m = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    if m.ends_with("rl-cell") {
        m
    } else {
        m.join("rl-cell")
    }
}

/// The venv's Python with `zenoh` and `rosbags`: `$RL_CELL_PYTHON`, or the venv scripts/test
/// makes (`target/cell-venv`). `None` (the caller prints SKIPPED) when neither imports both.
pub fn python() -> Option<PathBuf> {
    let candidate = match std::env::var_os("RL_CELL_PYTHON") {
        Some(p) => PathBuf::from(p),
        None => cell_dir().join("../target/cell-venv/bin/python"),
    };
    let ok = Command::new(&candidate)
        .args(["-c", "import zenoh, rosbags"])
        .output()
        .is_ok_and(|o| o.status.success());
    ok.then_some(candidate)
}

/// A peer script's path.
pub fn peer_script(name: &str) -> PathBuf {
    cell_dir().join("tests/peers").join(name)
}

/// A TCP port free on loopback now.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

/// `peer.py publish --connect ENDPOINT --plan PLAN`, run to its end (stderr shown).
pub fn publish(python: &Path, endpoint: &str, plan: &Path) -> Output {
    Command::new(python)
        .arg(peer_script("peer.py"))
        .args(["publish", "--connect", endpoint, "--plan"])
        .arg(plan)
        .stderr(Stdio::inherit())
        .output()
        .expect("python runs")
}

/// What `peer.py subscribe` wrote to `path`: one JSON value per sample or liveliness token. A
/// sample the peer could not decode (it records the decoder's error and the bytes) fails here,
/// naming its key, the error and the bytes.
pub fn recorded(path: &Path) -> Vec<serde_json::Value> {
    let records: Vec<serde_json::Value> = std::fs::read_to_string(path)
        .expect("recorded")
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect();
    for r in &records {
        assert!(
            r.get("error").is_none(),
            "the peer could not decode a sample on {}: {} (bytes {})",
            r["key"],
            r["error"],
            r["payload_hex"]
        );
    }
    records
}
