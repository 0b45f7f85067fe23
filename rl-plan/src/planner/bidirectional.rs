//! The search RL's RRT-Connect variants share ([`super::RrtConCon`], [`super::RrtExtCon`],
//! [`super::RrtExtExt`]): two trees, one from the start and one from the goal; each iteration
//! the growing tree grows towards a sample, the other tree grows towards the new vertex, and
//! the search ends when it reaches it. The trees swap roles every iteration (or, with
//! `balance`, the smaller one grows). The variants differ only in how each tree grows
//! ([`Growth`]); each keeps its own file as its public face, made by [`two_tree_planner!`].

use super::rrt::{RrtSettings, Step, connect_once, connect_with, extend, extend_with};
use super::tree::{Pair, Tree};
use super::{Context, Stats};
use crate::error::PlanError;
use crate::path::Path;
use crate::space::JointSpace;

/// How a tree grows towards a target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Growth {
    /// One step of at most `delta` (plain: no dynamic domain).
    Extend,
    /// One step of at most `delta`, within the settings' dynamic domain when they have one.
    ExtendInDomain,
    /// Steps of at most `delta` until the target is reached or a step is invalid, each a
    /// vertex (OMPL, VAMP).
    Connect,
    /// The same steps, one vertex at the last valid one (RL's `RrtCon::connect`).
    ConnectOnce,
}

/// A growth step: the tree grows towards the target with the settings' step (and domain).
type GrowthStep = fn(&mut Context, &mut Tree, &[f64], &RrtSettings, &mut Vec<f64>) -> Step;

impl Growth {
    /// The step function.
    fn step(self) -> GrowthStep {
        match self {
            Growth::Extend => |ctx, tree, target, s, buf| extend(ctx, tree, target, s.delta, buf),
            Growth::ExtendInDomain => extend_with,
            Growth::Connect => connect_with,
            Growth::ConnectOnce => {
                |ctx, tree, target, s, buf| connect_once(ctx, tree, target, s.delta, buf)
            }
        }
    }
}

/// A two-tree planner: its settings, its trees, what it did last, and how its trees grow.
pub(crate) struct TwoTrees {
    settings: RrtSettings,
    pair: Pair,
    stats: Stats,
    /// How the growing tree grows towards a sample.
    towards_sample: Growth,
    /// How the other tree grows towards the growing tree's new vertex.
    towards_tree: Growth,
}

impl TwoTrees {
    /// A planner for `space`.
    pub(crate) fn new(
        space: &JointSpace,
        settings: RrtSettings,
        towards_sample: Growth,
        towards_tree: Growth,
    ) -> Result<Self, PlanError> {
        settings.validate()?;
        Ok(Self {
            settings,
            pair: Pair::new(space, settings.nn)?,
            stats: Stats::default(),
            towards_sample,
            towards_tree,
        })
    }

    /// What the last [`TwoTrees::solve`] did.
    pub(crate) fn stats(&self) -> Stats {
        self.stats
    }

    /// Searches a path from `start` to `goal` until the trees meet or the budget runs out.
    pub(crate) fn solve(&mut self, ctx: &mut Context, start: &[f64], goal: &[f64]) -> Option<Path> {
        let s = &self.settings;
        let (towards_sample, towards_tree) = (self.towards_sample.step(), self.towards_tree.step());
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
            let Some(va) = towards_sample(ctx, a, &chosen, s, &mut buf).vertex() else {
                continue;
            };
            new.clear();
            new.extend_from_slice(a.q(va));
            if let Step::Reached(vb) = towards_tree(ctx, b, &new, s, &mut buf) {
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
}

/// Defines a two-tree planner's public face: the struct (with the doc comments given), its
/// `new` and its [`super::Planner`] implementation with RL's name, on [`TwoTrees`] with the
/// given growth towards samples and towards the other tree.
macro_rules! two_tree_planner {
    (
        $(#[$doc:meta])*
        $planner:ident, $name:literal,
        towards_sample: $towards_sample:ident, towards_tree: $towards_tree:ident $(,)?
    ) => {
        $(#[$doc])*
        pub struct $planner($crate::planner::bidirectional::TwoTrees);

        impl $planner {
            /// A planner for `space`.
            pub fn new(
                space: &$crate::space::JointSpace,
                settings: $crate::planner::RrtSettings,
            ) -> Result<Self, $crate::error::PlanError> {
                use $crate::planner::bidirectional::{Growth, TwoTrees};
                TwoTrees::new(
                    space,
                    settings,
                    Growth::$towards_sample,
                    Growth::$towards_tree,
                )
                .map(Self)
            }
        }

        impl $crate::planner::Planner for $planner {
            fn name(&self) -> &'static str {
                $name
            }

            fn solve(
                &mut self,
                ctx: &mut $crate::planner::Context,
                start: &[f64],
                goal: &[f64],
            ) -> Option<$crate::path::Path> {
                self.0.solve(ctx, start, goal)
            }

            fn stats(&self) -> $crate::planner::Stats {
                self.0.stats()
            }
        }
    };
}

pub(crate) use two_tree_planner;
