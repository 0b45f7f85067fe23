//! Planners (RL's `Planner` family), one file each: [`Prm`], [`Rrt`], [`RrtGoalBias`],
//! [`RrtDual`], [`RrtConCon`], [`RrtExtCon`], [`RrtExtExt`]; the roadmap query
//! ([`graph::shortest_path`], A*).
//!
//! A planner works in a [`Context`]: the space, the validity check, the edge verifier, the
//! sampler, a seeded random generator and a time [`Budget`]. The same seed, problem and checker
//! give the same path (nothing reads the clock except the budget, which only stops the search).
//!
//! Edges: RL's RRTs check only the new vertices and rely on a small step `delta`; here every
//! new edge also goes through the verifier, so a step `delta` larger than the verifier's
//! resolution (VAMP's setting: steps of 1 rad checked every 1/32 rad) is safe too. With `delta`
//! at or below the resolution the verifier checks exactly the new vertex, as RL does.

mod bidirectional;
pub mod graph;
mod prm;
mod rrt;
mod rrt_con_con;
mod rrt_dual;
mod rrt_ext_con;
mod rrt_ext_ext;
mod rrt_goal_bias;
mod tree;

pub use prm::{Prm, PrmSettings};
pub use rrt::{DynamicDomain, Rrt, RrtSettings};
pub use rrt_con_con::RrtConCon;
pub use rrt_dual::RrtDual;
pub use rrt_ext_con::RrtExtCon;
pub use rrt_ext_ext::RrtExtExt;
pub use rrt_goal_bias::RrtGoalBias;

use crate::budget::Budget;
use crate::error::PlanError;
use crate::path::Path;
use crate::rng::Rng;
use crate::sampler::Sampler;
use crate::space::JointSpace;
use crate::validity::Validity;
use crate::verifier::{Scratch, Verifier};

/// What a planner works with.
pub struct Context<'a> {
    /// The configuration space.
    pub space: &'a JointSpace,
    /// The validity check.
    pub validity: &'a mut dyn Validity,
    /// The edge verifier.
    pub verifier: Verifier,
    /// The sampler.
    pub sampler: Box<dyn Sampler>,
    /// The random generator (seeded).
    pub rng: Rng,
    /// When to stop.
    pub budget: Budget,
    scratch: Scratch,
}

impl<'a> Context<'a> {
    /// A context; `seed` seeds the random generator.
    pub fn new(
        space: &'a JointSpace,
        validity: &'a mut dyn Validity,
        verifier: Verifier,
        sampler: Box<dyn Sampler>,
        seed: u64,
        budget: Budget,
    ) -> Self {
        Self {
            space,
            validity,
            verifier,
            sampler,
            rng: Rng::seed_from(seed),
            budget,
            scratch: Scratch::default(),
        }
    }

    /// Whether `q` is valid.
    #[inline]
    pub fn is_valid(&mut self, q: &[f64]) -> bool {
        self.validity.is_valid(q)
    }

    /// Whether the motion `a → b` is valid (checking `b` too when `include_end`).
    #[inline]
    pub fn motion_valid(&mut self, a: &[f64], b: &[f64], include_end: bool) -> bool {
        self.verifier.is_valid(
            self.space,
            self.validity,
            (a, b),
            include_end,
            &mut self.scratch,
        )
    }

    /// A sample from the sampler (not checked).
    #[inline]
    pub fn sample(&mut self, out: &mut [f64]) {
        self.sampler.generate(self.space, &mut self.rng, out);
    }

    /// A valid sample; `false` when the budget ran out.
    pub fn sample_valid(&mut self, out: &mut [f64]) -> bool {
        self.sampler
            .generate_valid(self.space, self.validity, &mut self.rng, &self.budget, out)
    }
}

/// What a planner did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Iterations of its main loop.
    pub iterations: u64,
    /// Vertices of its trees or roadmap.
    pub vertices: usize,
    /// Edges.
    pub edges: usize,
}

/// A planner.
pub trait Planner {
    /// Its name (RL's: `RRT Connect Connect`, `PRM`, …).
    fn name(&self) -> &'static str;

    /// Searches a path from `start` to `goal` (both valid) until found or the budget runs
    /// out; `None` when not found.
    fn solve(&mut self, ctx: &mut Context, start: &[f64], goal: &[f64]) -> Option<Path>;

    /// What the last [`Planner::solve`] did.
    fn stats(&self) -> Stats;
}

/// A planner by name, with its settings: what the command line and RL's scenario files choose.
#[derive(Clone, Debug, PartialEq)]
pub enum PlannerKind {
    /// [`Prm`].
    Prm(PrmSettings),
    /// [`Rrt`].
    Rrt(RrtSettings),
    /// [`RrtGoalBias`] with the goal probability.
    RrtGoalBias(RrtSettings, f64),
    /// [`RrtDual`].
    RrtDual(RrtSettings),
    /// [`RrtConCon`].
    RrtConCon(RrtSettings),
    /// [`RrtExtCon`] (Kuffner and LaValle's RRT-Connect, OMPL's and VAMP's).
    RrtExtCon(RrtSettings),
    /// [`RrtExtExt`].
    RrtExtExt(RrtSettings),
}

impl PlannerKind {
    /// The planner for a name: RL's element names (`prm`, `rrt`, `rrtGoalBias`, `rrtDual`,
    /// `rrtConCon`, `rrtExtCon`, `rrtExtExt`) or the command line's (`rrt-connect` =
    /// `rrtExtCon`, `rrt-con-con`, `rrt-ext-ext`, `rrt-dual`, `rrt-goal-bias`), with default
    /// settings.
    pub fn parse(name: &str) -> Result<Self, PlanError> {
        let r = RrtSettings::default();
        Ok(match name {
            "prm" => Self::Prm(PrmSettings::default()),
            "rrt" => Self::Rrt(r),
            "rrtGoalBias" | "rrt-goal-bias" => Self::RrtGoalBias(r, 0.05),
            "rrtDual" | "rrt-dual" => Self::RrtDual(r),
            "rrtConCon" | "rrt-con-con" => Self::RrtConCon(r),
            "rrtExtCon" | "rrt-ext-con" | "rrt-connect" => Self::RrtExtCon(r),
            "rrtExtExt" | "rrt-ext-ext" => Self::RrtExtExt(r),
            other => {
                return Err(PlanError::setting(
                    "planner",
                    format!(
                        "unknown planner \"{other}\" (known: prm, rrt, rrt-goal-bias, rrt-dual, \
                         rrt-connect, rrt-con-con, rrt-ext-ext)"
                    ),
                ));
            }
        })
    }

    /// The RRT settings (every planner but PRM has them).
    pub fn rrt_settings_mut(&mut self) -> Option<&mut RrtSettings> {
        match self {
            Self::Prm(_) => None,
            Self::Rrt(s)
            | Self::RrtGoalBias(s, _)
            | Self::RrtDual(s)
            | Self::RrtConCon(s)
            | Self::RrtExtCon(s)
            | Self::RrtExtExt(s) => Some(s),
        }
    }

    /// Builds the planner for `space`.
    pub fn build(&self, space: &JointSpace) -> Result<Box<dyn Planner>, PlanError> {
        Ok(match self {
            Self::Prm(s) => Box::new(Prm::new(space, s.clone())?),
            Self::Rrt(s) => Box::new(Rrt::new(space, *s)?),
            Self::RrtGoalBias(s, p) => Box::new(RrtGoalBias::new(space, *s, *p)?),
            Self::RrtDual(s) => Box::new(RrtDual::new(space, *s)?),
            Self::RrtConCon(s) => Box::new(RrtConCon::new(space, *s)?),
            Self::RrtExtCon(s) => Box::new(RrtExtCon::new(space, *s)?),
            Self::RrtExtExt(s) => Box::new(RrtExtExt::new(space, *s)?),
        })
    }
}
