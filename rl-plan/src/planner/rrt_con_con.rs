//! RRT-Connect with *connect* on both sides (RL's `RrtConCon`; Kuffner and LaValle, ICRA 2000,
//! the connect-connect variant): the growing tree connects towards a sample, the other tree
//! connects towards the growing tree's newest vertex; the trees swap roles every iteration.

use super::rrt::{RrtSettings, Step, connect, connect_with};
use super::tree::Pair;
use super::{Context, Planner, Stats};
use crate::error::PlanError;
use crate::path::Path;
use crate::space::JointSpace;

/// RL's `RrtConCon`.
pub struct RrtConCon {
    settings: RrtSettings,
    pair: Pair,
    stats: Stats,
}

impl RrtConCon {
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

impl Planner for RrtConCon {
    fn name(&self) -> &'static str {
        "RRT Connect Connect"
    }

    fn solve(&mut self, ctx: &mut Context, start: &[f64], goal: &[f64]) -> Option<Path> {
        let s = self.settings;
        bidirectional(
            ctx,
            &mut self.pair,
            &mut self.stats,
            &s,
            start,
            goal,
            connect_with,
        )
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}

/// The loop shared by the connect-type two-tree planners: `grow` (extend or connect) the
/// growing tree towards a sample, then connect the other tree to the new vertex.
pub(crate) fn bidirectional(
    ctx: &mut Context,
    pair: &mut Pair,
    stats: &mut Stats,
    s: &RrtSettings,
    start: &[f64],
    goal: &[f64],
    grow: fn(&mut Context, &mut super::tree::Tree, &[f64], &RrtSettings, &mut Vec<f64>) -> Step,
) -> Option<Path> {
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
        let Some(va) = grow(ctx, a, &chosen, s, &mut buf).vertex() else {
            continue;
        };
        new.clear();
        new.extend_from_slice(a.q(va));
        if let Step::Reached(vb) = connect(ctx, b, &new, s.delta, &mut buf) {
            break Some(pair.path(va, vb));
        }
    };
    stats.iterations = i;
    stats.vertices = pair.vertices();
    stats.edges = stats.vertices.saturating_sub(2);
    result
}
