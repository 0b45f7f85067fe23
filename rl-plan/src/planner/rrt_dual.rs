//! Bidirectional RRT (RL's `RrtDual`): each iteration extends the start tree and then the goal
//! tree one step towards the same sample; the search ends when the two new vertices are within
//! `epsilon` of each other (and the short edge between them is valid).

use super::rrt::{RrtSettings, extend};
use super::tree::Pair;
use super::{Context, Planner, Stats};
use crate::error::PlanError;
use crate::path::Path;
use crate::space::JointSpace;

/// RL's `RrtDual`.
pub struct RrtDual {
    settings: RrtSettings,
    pair: Pair,
    stats: Stats,
}

impl RrtDual {
    /// A planner for `space`.
    pub fn new(space: &JointSpace, settings: RrtSettings) -> Result<Self, PlanError> {
        settings.validate()?;
        Ok(Self {
            settings,
            pair: Pair::new(space, settings.nn)?,
            stats: Stats::default(),
        })
    }
}

impl Planner for RrtDual {
    fn name(&self) -> &'static str {
        "RRT Dual"
    }

    fn solve(&mut self, ctx: &mut Context, start: &[f64], goal: &[f64]) -> Option<Path> {
        self.pair.reset(ctx.space, start, goal);
        let mut chosen = vec![0.0; ctx.space.nq()];
        let mut buf = Vec::new();
        let delta = self.settings.delta;
        let mut i = 0u64;
        let result = loop {
            if !ctx.budget.allows(i) {
                break None;
            }
            i += 1;
            ctx.sample(&mut chosen);
            let (t0, t1) = self.pair.split();
            let Some(v0) = extend(ctx, t0, &chosen, delta, &mut buf).vertex() else {
                continue;
            };
            let Some(v1) = extend(ctx, t1, &chosen, delta, &mut buf).vertex() else {
                continue;
            };
            let (q0, q1) = (t0.q(v0).to_vec(), t1.q(v1).to_vec());
            if ctx.space.distance(&q0, &q1) <= self.settings.epsilon
                && (q0 == q1 || ctx.motion_valid(&q0, &q1, false))
            {
                break Some(self.pair.path(v0, v1));
            }
        };
        self.stats = Stats {
            iterations: i,
            vertices: self.pair.vertices(),
            edges: self.pair.vertices().saturating_sub(2),
        };
        result
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}
