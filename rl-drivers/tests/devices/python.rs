//! The Python peers of the device tests (PyPI `pymodbus`, `pyserial`, `ur-rtde`, `netft`,
//! `pynetft`), in the venv `scripts/test` installs at `target/devices-venv`
//! (`RL_DEVICES_PYTHON` names another interpreter).
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;

/// The workspace's root.
pub fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace")
        .to_path_buf()
}

/// A peer script of `rl-drivers/tests/peers/`.
pub fn script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/peers")
        .join(name)
}

/// The venv's python if it imports `modules`, or why not.
pub fn python_with(modules: &[&str]) -> Result<PathBuf, String> {
    let python = std::env::var_os("RL_DEVICES_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join("target/devices-venv/bin/python"));
    let import = format!("import {}", modules.join(", "));
    let out = Command::new(&python).args(["-c", &import]).output();
    match out {
        Ok(o) if o.status.success() => Ok(python),
        Ok(o) => Err(format!(
            "{} cannot `{import}` ({}; scripts/test installs the venv)",
            python.display(),
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .last()
                .unwrap_or("")
        )),
        Err(e) => Err(format!(
            "no python at {} ({e}; scripts/test installs the venv)",
            python.display()
        )),
    }
}
