//! Corner cutting with subdivision (RL's `AdvancedOptimizer`): a waypoint `j` between `i` and
//! `k` goes when the edge `i → k` is valid and `j` lies more than `ratio · d(i, k)` from the
//! point of the chord at the same fraction (`d(i, j) / (d(i, j) + d(j, k))`); when no more can
//! go, every segment longer than `length` is cut in half and the pass repeats.

use super::Optimizer;
use crate::path::Path;
use crate::planner::Context;

/// RL's `AdvancedOptimizer`.
#[derive(Clone, Copy, Debug)]
pub struct AdvancedOptimizer {
    /// Longest segment after subdivision (RL: 1).
    pub length: f64,
    /// Smallest relative corner that is cut (RL: 0.1).
    pub ratio: f64,
}

impl Default for AdvancedOptimizer {
    fn default() -> Self {
        Self {
            length: 1.0,
            ratio: 0.1,
        }
    }
}

impl AdvancedOptimizer {
    /// Cuts every segment longer than `length` in half; `true` if any was.
    fn subdivide(&self, ctx: &Context, path: &mut Path) -> bool {
        let mut any = false;
        let mut i = 0;
        let mut mid = vec![0.0; path.nq()];
        while i + 1 < path.len() {
            let (a, b) = (path.point(i), path.point(i + 1));
            if ctx.space.distance(a, b) > self.length {
                ctx.space.interpolate(a, b, 0.5, &mut mid);
                path.insert(i + 1, &mid);
                any = true;
            } else {
                i += 1;
            }
        }
        any
    }
}

impl Optimizer for AdvancedOptimizer {
    fn name(&self) -> &'static str {
        "advanced"
    }

    fn process(&mut self, ctx: &mut Context, path: &mut Path) -> bool {
        let mut any = false;
        let mut inter = vec![0.0; path.nq()];
        let mut changed = true;
        while changed && path.len() > 2 && !ctx.budget.expired() {
            while changed && path.len() > 2 && !ctx.budget.expired() {
                changed = false;
                let mut i = 0;
                while i + 2 < path.len() {
                    let (a, b, c) = (
                        path.point(i).to_vec(),
                        path.point(i + 1).to_vec(),
                        path.point(i + 2).to_vec(),
                    );
                    let ik = ctx.space.distance(&a, &c);
                    if ik > 0.0 && ctx.motion_valid(&a, &c, false) {
                        let (ij, jk) = (ctx.space.distance(&a, &b), ctx.space.distance(&b, &c));
                        ctx.space.interpolate(&a, &c, ij / (ij + jk), &mut inter);
                        if ctx.space.distance(&b, &inter) / ik > self.ratio {
                            path.remove_range(i + 1..i + 2);
                            changed = true;
                            any = true;
                            continue;
                        }
                    }
                    i += 1;
                }
            }
            if self.subdivide(ctx, path) {
                changed = true;
                any = true;
            }
        }
        any
    }
}
