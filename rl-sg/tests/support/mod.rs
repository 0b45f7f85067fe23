//! Shared helpers for rl-sg's integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use rl_core::algo::ik::SplitMix64;
use rl_core::spatial::PlueckerTransform;

/// Random test states from rl-core's SplitMix64.
pub struct Rng(SplitMix64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(SplitMix64::new(seed))
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0.next_f64()
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    pub fn vec3(&mut self, r: f64) -> DVec3 {
        DVec3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
    }
    /// A uniformly random rotation (Shoemake).
    pub fn quat(&mut self) -> DQuat {
        let (u1, u2, u3) = (self.uniform(), self.uniform(), self.uniform());
        let tau = std::f64::consts::TAU;
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        DQuat::from_xyzw(
            a * (tau * u2).sin(),
            a * (tau * u2).cos(),
            b * (tau * u3).sin(),
            b * (tau * u3).cos(),
        )
    }
    pub fn pose(&mut self, r: f64) -> PlueckerTransform {
        PlueckerTransform::from_quat_translation(self.quat(), self.vec3(r))
    }
}

/// The repository root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// RL's example scenes.
pub fn rlsg_data() -> PathBuf {
    repo().join("tests/data/rlsg")
}

/// Files below `dir` whose name ends with `suffix`, sorted.
pub fn files_ending(dir: &Path, suffix: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.to_string_lossy().ends_with(suffix) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// example-robot-data with its meshes: `$RL_ROBOT_DATA` if it has them, else
/// `scripts/robot-data` with `RL_ROBOT_DATA_MESHES=1` (downloads once).
pub fn robot_data_with_meshes() -> Result<PathBuf, String> {
    let probe = "robots/ur_description/meshes/ur5/collision/base.stl";
    if let Some(d) = std::env::var_os("RL_ROBOT_DATA") {
        let d = PathBuf::from(d);
        if d.join(probe).exists() {
            return Ok(d);
        }
    }
    let script = repo().join("scripts/robot-data");
    let out = std::process::Command::new(&script)
        .env_remove("RL_ROBOT_DATA")
        .env("RL_ROBOT_DATA_MESHES", "1")
        .output()
        .map_err(|e| format!("cannot run {}: {e}", script.display()))?;
    if !out.status.success() {
        return Err(format!(
            "{} failed: {}",
            script.display(),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let d = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    if d.join(probe).exists() {
        Ok(d)
    } else {
        Err(format!("{} has no meshes", d.display()))
    }
}
