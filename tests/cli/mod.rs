//! Shared by the tests that run the `rl` tool: run it, or run it and parse its JSON.
#![allow(dead_code)]

use std::process::{Command, Output};

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
