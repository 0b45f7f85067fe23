//! Bidirectional RRT with *extend* on both sides (RL's `RrtExtExt`): the growing tree extends
//! towards a sample, the other tree extends one step towards the new vertex; the search ends
//! when that step reaches it. The trees swap roles every iteration.

use super::rrt::{RrtSettings, Step, extend};
use super::tree::Pair;
use super::{Context, Planner, Stats};
use crate::error::PlanError;
use crate::path::Path;
use crate::space::JointSpace;

/// RL's `RrtExtExt`.
pub struct RrtExtExt {
    settings: RrtSettings,
    pair: Pair,
    stats: Stats,
}

impl RrtExtExt {
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

impl Planner for RrtExtExt {
    fn name(&self) -> &'static str {
        "RRT Extend Extend"
    }

    fn solve(&mut self, ctx: &mut Context, start: &[f64], goal: &[f64]) -> Option<Path> {
        let s = self.settings;
        let pair = &mut self.pair;
        pair.reset(ctx.space, start, goal);
        let mut chosen = vec![0.0; ctx.space.nq()];
        let mut buf = Vec::new();
        let mut new = Vec::new();
        let mut i = 0u64;
        let result = loop {
            if !ctx.budget.allows(i) {
                break None;
            }
            pair.next(s.balance, i == 0);
            i += 1;
            ctx.sample(&mut chosen);
            let (a, b) = pair.split();
            let Some(va) = extend(ctx, a, &chosen, s.delta, &mut buf).vertex() else {
                continue;
            };
            new.clear();
            new.extend_from_slice(a.q(va));
            if let Step::Reached(vb) = extend(ctx, b, &new, s.delta, &mut buf) {
                break Some(pair.path(va, vb));
            }
        };
        self.stats = Stats {
            iterations: i,
            vertices: pair.vertices(),
            edges: pair.vertices().saturating_sub(2),
        };
        result
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}
