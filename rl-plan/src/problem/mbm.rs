//! MotionBenchMaker problem sets: a directory tree with `sceneNNNN.yaml` (a MoveIt planning
//! scene) beside `requestNNNN.yaml` (a motion plan request) for every problem, usually one
//! sub-directory per scenario (`table_pick_panda/`, `bookshelf_small_panda/`, …).

use std::path::{Path, PathBuf};

use super::Robot;
use super::moveit::MotionRequest;
use crate::error::PlanError;

/// One problem of a set.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct MbmProblem {
    /// `scenario/NNNN` (the directory relative to the set's root, and the number).
    pub name: String,
    /// The scenario: the directory relative to the set's root (`.` at the root).
    pub scenario: String,
    /// The number in the file names.
    pub index: String,
    /// The planning scene.
    pub scene: PathBuf,
    /// The motion plan request.
    pub request: PathBuf,
}

/// Every problem under `dir` (recursively), sorted by scenario and number. A request without
/// its scene is an error that names it.
pub fn find_problems(dir: &Path) -> Result<Vec<MbmProblem>, PlanError> {
    let mut out = Vec::new();
    walk(dir, dir, &mut out)?;
    out.sort();
    Ok(out)
}

fn walk(root: &Path, dir: &Path, out: &mut Vec<MbmProblem>) -> Result<(), PlanError> {
    let entries =
        std::fs::read_dir(dir).map_err(|e| PlanError::Load(format!("{}: {e}", dir.display())))?;
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            walk(root, &p, out)?;
            continue;
        }
        let Some(name) = p.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        let Some(index) = name
            .strip_prefix("request")
            .and_then(|n| n.strip_suffix(".yaml"))
        else {
            continue;
        };
        let scene = p.with_file_name(format!("scene{index}.yaml"));
        if !scene.exists() {
            return Err(PlanError::file(
                &p,
                "problem",
                format!("no {} beside the request", scene.display()),
            ));
        }
        let scenario = dir
            .strip_prefix(root)
            .ok()
            .map(|s| s.to_string_lossy().into_owned())
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| ".".into());
        out.push(MbmProblem {
            name: format!("{scenario}/{index}"),
            scenario,
            index: index.to_string(),
            scene,
            request: p,
        });
    }
    Ok(())
}

impl MbmProblem {
    /// The environment, start and goal of this problem for `robot`.
    pub fn load(&self, robot: &Robot) -> Result<(rl_sg::Model, Vec<f64>, Vec<f64>), PlanError> {
        let env = rl_sg::load::moveit::load_environment(&self.scene)?;
        let req = MotionRequest::load(&self.request)?;
        let (start, goal) = req.configurations(&robot.space)?;
        Ok((env, start, goal))
    }
}
