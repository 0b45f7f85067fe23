//! RRT with goal bias (RL's `RrtGoalBias`): the target of an iteration is the goal itself with
//! probability `p` (RL's default 0.05), a sample otherwise.

use super::rrt::{RrtSettings, solve_single};
use super::tree::Tree;
use super::{Context, Planner, Stats};
use crate::error::PlanError;
use crate::path::Path;
use crate::space::JointSpace;

/// RL's `RrtGoalBias`.
pub struct RrtGoalBias {
    settings: RrtSettings,
    probability: f64,
    tree: Tree,
    stats: Stats,
}

impl RrtGoalBias {
    /// A planner for `space` that aims at the goal with probability `probability`.
    pub fn new(
        space: &JointSpace,
        settings: RrtSettings,
        probability: f64,
    ) -> Result<Self, PlanError> {
        settings.validate()?;
        if !(0.0..=1.0).contains(&probability) {
            return Err(PlanError::setting(
                "probability",
                format!("{probability} is not in [0, 1]"),
            ));
        }
        Ok(Self {
            settings,
            probability,
            tree: Tree::new(space, settings.nn)?,
            stats: Stats::default(),
        })
    }
}

impl Planner for RrtGoalBias {
    fn name(&self) -> &'static str {
        "RRT Goal Bias"
    }

    fn solve(&mut self, ctx: &mut Context, start: &[f64], goal: &[f64]) -> Option<Path> {
        let p = self.probability;
        solve_single(
            ctx,
            &mut self.tree,
            &self.settings,
            &mut self.stats,
            start,
            goal,
            |ctx, out| {
                if ctx.rng.uniform() < p {
                    out.copy_from_slice(goal);
                } else {
                    ctx.sample(out);
                }
            },
        )
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}
