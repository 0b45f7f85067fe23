//! RRT-Connect as Kuffner and LaValle published it (ICRA 2000), RL's `RrtExtCon`, OMPL's
//! `RRTConnect` and VAMP's `RRTC`: the growing tree *extends* one step towards a sample, the
//! other tree *connects* towards the new vertex; the trees swap roles (or, with `balance`, the
//! smaller one grows).

use super::rrt::{RrtSettings, extend_with};
use super::rrt_con_con::bidirectional;
use super::tree::Pair;
use super::{Context, Planner, Stats};
use crate::error::PlanError;
use crate::path::Path;
use crate::space::JointSpace;

/// RL's `RrtExtCon`.
pub struct RrtExtCon {
    settings: RrtSettings,
    pair: Pair,
    stats: Stats,
}

impl RrtExtCon {
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

impl Planner for RrtExtCon {
    fn name(&self) -> &'static str {
        "RRT Extend Connect"
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
            extend_with,
        )
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}
