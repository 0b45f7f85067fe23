//! A path to play back: the CSV files `rl plan` writes. `--out` writes a header of joint names
//! and one waypoint per row; `--trajectory` writes `t`, the joint names, then their `/v` and `/a`
//! columns, one sample per row. Waypoints without times are placed one second apart.
//!
//! Columns are matched to the model's joints by name; if the names differ but the count fits,
//! they are taken in order.

use std::path::Path;

use crate::error::ViewError;
use crate::load::JointInfo;

/// Times and configurations of a path, for model 0.
#[derive(Clone, Debug, PartialEq)]
pub struct PathData {
    /// Time of each sample, s (non-decreasing).
    pub t: Vec<f64>,
    /// Configuration of each sample (the model's `q` order).
    pub q: Vec<Vec<f64>>,
}

impl PathData {
    /// Reads the CSV at `path` for a model with `joints`.
    pub fn load(path: &Path, joints: &[JointInfo]) -> Result<PathData, ViewError> {
        let max = rl_core::loader::InputLimits::DEFAULT.max_bytes;
        let text = rl_core::loader::read_text(path, max).map_err(|e| ViewError::Io {
            path: path.to_path_buf(),
            reason: e.kind.to_string(),
        })?;
        Self::parse(&text, joints).map_err(|(line, reason)| ViewError::Path {
            path: path.to_path_buf(),
            line,
            reason,
        })
    }

    /// Parses CSV text; errors carry the line (1-based, 0 for the whole file).
    pub fn parse(text: &str, joints: &[JointInfo]) -> Result<PathData, (usize, String)> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let (_, header) = lines.next().ok_or((0, "empty file".to_string()))?;
        let names: Vec<&str> = header.split(',').map(str::trim).collect();
        let time_col = names.iter().position(|n| *n == "t");
        // Position columns: not `t`, not a `/v` or `/a` derivative.
        let pos_cols: Vec<usize> = (0..names.len())
            .filter(|&i| Some(i) != time_col && !names[i].contains('/'))
            .collect();
        let by_name: Option<Vec<usize>> = joints
            .iter()
            .map(|j| pos_cols.iter().copied().find(|&c| names[c] == j.name))
            .collect();
        let cols = match by_name {
            Some(c) => c,
            None if pos_cols.len() == joints.len() => pos_cols,
            None => {
                return Err((
                    1,
                    format!(
                        "{} position columns, the model has {} joints ({})",
                        pos_cols.len(),
                        joints.len(),
                        joints
                            .iter()
                            .map(|j| j.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ));
            }
        };
        let mut t = Vec::new();
        let mut q = Vec::new();
        for (k, (i, line)) in lines.enumerate() {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            if cells.len() != names.len() {
                return Err((
                    i + 1,
                    format!("{} fields, the header has {}", cells.len(), names.len()),
                ));
            }
            let num = |c: usize| -> Result<f64, (usize, String)> {
                cells[c]
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or((
                        i + 1,
                        format!("field {} ({:?}) is not a finite number", c + 1, cells[c]),
                    ))
            };
            let time = match time_col {
                Some(c) => num(c)?,
                None => k as f64,
            };
            if t.last().is_some_and(|&last| time < last) {
                return Err((i + 1, format!("time {time} goes backwards")));
            }
            t.push(time);
            q.push(
                cols.iter()
                    .map(|&c| num(c))
                    .collect::<Result<Vec<_>, _>>()?,
            );
        }
        if t.is_empty() {
            return Err((0, "no samples".into()));
        }
        Ok(PathData { t, q })
    }
}
