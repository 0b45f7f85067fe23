//! Greedy shortcutting (VAMP's `shortcut_path`, Thomason, Kingston & Kavraki 2024): first the
//! straight motion from start to goal; then, for every waypoint `i` from the start, the
//! farthest waypoint `j > i + 1` it sees directly — the edge `i → j` valid — replaces everything
//! between them. Passes repeat until one changes nothing or `passes` ran (VAMP: 5).
//!
//! Against RL's [`super::SimpleOptimizer`] (drop one waypoint whose neighbours see each other,
//! repeat): the same kind of result, fewer checks when long shortcuts exist, since the first
//! edge tried from `i` is the longest.

use super::Optimizer;
use crate::path::Path;
use crate::planner::Context;

/// VAMP's shortcutting (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct ShortcutOptimizer {
    /// The most passes.
    pub passes: usize,
}

impl Default for ShortcutOptimizer {
    fn default() -> Self {
        Self { passes: 5 }
    }
}

impl Optimizer for ShortcutOptimizer {
    fn name(&self) -> &'static str {
        "shortcut"
    }

    fn process(&mut self, ctx: &mut Context, path: &mut Path) -> bool {
        if path.len() < 3 || ctx.budget.expired() {
            return false;
        }
        let last = path.len() - 1;
        if ctx.motion_valid(path.point(0), path.point(last), false) {
            path.remove_range(1..last);
            return true;
        }
        let mut any = false;
        for _ in 0..self.passes {
            let mut changed = false;
            let mut i = 0;
            while i + 2 < path.len() {
                let mut j = path.len() - 1;
                while j > i + 1 {
                    if ctx.budget.expired() {
                        return any;
                    }
                    if ctx.motion_valid(path.point(i), path.point(j), false) {
                        path.remove_range(i + 1..j);
                        changed = true;
                        break;
                    }
                    j -= 1;
                }
                i += 1;
            }
            any |= changed;
            if !changed {
                break;
            }
        }
        any
    }
}
