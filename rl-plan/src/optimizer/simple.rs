//! Shortcutting (RL's `SimpleOptimizer`): walk the triples `i, j, k` of consecutive waypoints
//! and drop `j` whenever the edge `i → k` is valid; repeat until a pass changes nothing.

use super::Optimizer;
use crate::path::Path;
use crate::planner::Context;

/// RL's `SimpleOptimizer`.
#[derive(Clone, Copy, Debug, Default)]
pub struct SimpleOptimizer;

impl Optimizer for SimpleOptimizer {
    fn name(&self) -> &'static str {
        "simple"
    }

    fn process(&mut self, ctx: &mut Context, path: &mut Path) -> bool {
        let mut any = false;
        let mut changed = true;
        while changed && path.len() > 2 && !ctx.budget.expired() {
            changed = false;
            let mut i = 0;
            while i + 2 < path.len() {
                let (a, c) = (path.point(i).to_vec(), path.point(i + 2).to_vec());
                if ctx.motion_valid(&a, &c, false) {
                    path.remove_range(i + 1..i + 2);
                    changed = true;
                    any = true;
                } else {
                    i += 1;
                }
            }
        }
        any
    }
}
