//! The rapidly-exploring random tree (LaValle 1998; RL's `Rrt`) and the two growth steps the
//! whole family shares:
//!
//! - *extend*: from the nearest vertex, one step of at most `delta` towards the target;
//! - *connect*: steps of at most `delta` towards the target until it is reached or a step is
//!   invalid, every step a vertex (as OMPL and VAMP add them: [`connect`]), or only the last
//!   valid one, joined to the nearest vertex by one edge (RL's `RrtCon::connect`:
//!   [`connect_once`]).
//!
//! [`Rrt`] grows one tree from the start towards uniform samples and stops when a new vertex is
//! within `epsilon` of the goal.

use super::tree::{NONE, Tree};
use super::{Context, Planner, Stats};
use crate::error::PlanError;
use crate::nn::NnKind;
use crate::path::Path;
use crate::space::JointSpace;

/// Settings of the RRT family.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RrtSettings {
    /// The longest edge one step adds (RL's `delta`; VAMP's `range`), in the space's metric.
    pub delta: f64,
    /// Configurations closer than this count as equal (RL's `epsilon`).
    pub epsilon: f64,
    /// The nearest-neighbour structure of each tree.
    pub nn: NnKind,
    /// Two-tree planners: grow the smaller tree next (VAMP's `balance`) instead of alternating
    /// (RL).
    pub balance: bool,
    /// Dynamic-domain sampling for extensions towards samples (Yershova et al., ICRA 2005;
    /// VAMP's default): `None` is RL's plain RRT. Only [`RrtExtCon`](super::RrtExtCon) (VAMP's
    /// RRTC) uses it; the other planners extend plainly.
    pub dynamic_domain: Option<DynamicDomain>,
}

/// Dynamic-domain RRT: a vertex whose extension failed gets a radius; samples farther from
/// their nearest vertex than its radius are skipped. The radius grows by `1 + alpha` when an
/// extension from the vertex succeeds and shrinks by `1 − alpha` (not below `min_radius`) when
/// one fails.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicDomain {
    /// The radius a vertex gets at its first failure.
    pub radius: f64,
    /// The relative change per success or failure.
    pub alpha: f64,
    /// The smallest radius.
    pub min_radius: f64,
}

impl DynamicDomain {
    /// VAMP's defaults: radius 4, alpha 1e-4, smallest radius 1.
    pub const VAMP: Self = Self {
        radius: 4.0,
        alpha: 1e-4,
        min_radius: 1.0,
    };
}

impl Default for RrtSettings {
    fn default() -> Self {
        Self {
            delta: 1.0,
            epsilon: 1e-3,
            nn: NnKind::Linear,
            balance: false,
            dynamic_domain: None,
        }
    }
}

impl RrtSettings {
    /// Checks the numbers.
    pub fn validate(&self) -> Result<(), PlanError> {
        if !(self.delta.is_finite() && self.delta > 0.0) {
            return Err(PlanError::setting(
                "delta",
                format!("{} is not positive", self.delta),
            ));
        }
        if !(self.epsilon.is_finite() && self.epsilon >= 0.0) {
            return Err(PlanError::setting(
                "epsilon",
                format!("{} is not ≥ 0", self.epsilon),
            ));
        }
        Ok(())
    }
}

/// The outcome of one growth step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Step {
    /// The target itself is now a vertex (or already was).
    Reached(u32),
    /// Progress: the last new vertex.
    Advanced(u32),
    /// No step was valid.
    Trapped,
}

impl Step {
    pub(crate) fn vertex(self) -> Option<u32> {
        match self {
            Step::Reached(v) | Step::Advanced(v) => Some(v),
            Step::Trapped => None,
        }
    }
}

/// One step of at most `delta` from the vertex nearest to `target` towards it.
pub(crate) fn extend(
    ctx: &mut Context,
    tree: &mut Tree,
    target: &[f64],
    delta: f64,
    buf: &mut Vec<f64>,
) -> Step {
    let Some((n, d)) = tree.nearest(ctx.space, target) else {
        return Step::Trapped;
    };
    extend_from(ctx, tree, (n, d), target, delta, buf)
}

/// [`extend`] from vertex `n` at distance `d` from `target` (its nearest).
fn extend_from(
    ctx: &mut Context,
    tree: &mut Tree,
    (n, d): (u32, f64),
    target: &[f64],
    delta: f64,
    buf: &mut Vec<f64>,
) -> Step {
    if d == 0.0 {
        return Step::Reached(n);
    }
    buf.resize(ctx.space.nq(), 0.0);
    let reached = d <= delta;
    if reached {
        buf.copy_from_slice(target);
    } else {
        ctx.space.interpolate(tree.q(n), target, delta / d, buf);
    }
    if !ctx.motion_valid(tree.q(n), buf, true) {
        return Step::Trapped;
    }
    let v = tree.add(ctx.space, buf, n);
    if reached {
        Step::Reached(v)
    } else {
        Step::Advanced(v)
    }
}

/// [`extend`] with the settings' dynamic domain (when it has one): the growth step of the
/// two-tree planners towards samples.
pub(crate) fn extend_with(
    ctx: &mut Context,
    tree: &mut Tree,
    target: &[f64],
    s: &RrtSettings,
    buf: &mut Vec<f64>,
) -> Step {
    let Some(dd) = s.dynamic_domain else {
        return extend(ctx, tree, target, s.delta, buf);
    };
    let Some((n, d)) = tree.nearest(ctx.space, target) else {
        return Step::Trapped;
    };
    let r = tree.radius(n);
    if r < d {
        return Step::Trapped;
    }
    let step = extend_from(ctx, tree, (n, d), target, s.delta, buf);
    let r = match step {
        Step::Trapped if r.is_infinite() => dd.radius,
        Step::Trapped => (r * (1.0 - dd.alpha)).max(dd.min_radius),
        _ if r.is_finite() => r * (1.0 + dd.alpha),
        _ => r,
    };
    tree.set_radius(n, r);
    step
}

/// [`connect`] with the settings' step.
pub(crate) fn connect_with(
    ctx: &mut Context,
    tree: &mut Tree,
    target: &[f64],
    s: &RrtSettings,
    buf: &mut Vec<f64>,
) -> Step {
    connect(ctx, tree, target, s.delta, buf)
}

/// RL's connect (`RrtCon::connect`): steps of at most `delta` from the vertex nearest to
/// `target` until it is reached or a step is invalid, then *one* vertex at the last valid step,
/// its edge from the nearest vertex. Every step's motion is verified (the steps lie on that
/// edge, so the edge is verified at the resolution). A tree grows by one vertex per connect, as
/// RL's does, not by one per step.
pub(crate) fn connect_once(
    ctx: &mut Context,
    tree: &mut Tree,
    target: &[f64],
    delta: f64,
    buf: &mut Vec<f64>,
) -> Step {
    connect_steps(ctx, tree, target, delta, buf, false)
}

/// Steps of at most `delta` from the vertex nearest to `target` until it is reached or a step
/// is invalid, each step a vertex.
pub(crate) fn connect(
    ctx: &mut Context,
    tree: &mut Tree,
    target: &[f64],
    delta: f64,
    buf: &mut Vec<f64>,
) -> Step {
    connect_steps(ctx, tree, target, delta, buf, true)
}

/// The steps of a connect; a vertex for each valid step (`per_step`) or for the last one.
fn connect_steps(
    ctx: &mut Context,
    tree: &mut Tree,
    target: &[f64],
    delta: f64,
    buf: &mut Vec<f64>,
    per_step: bool,
) -> Step {
    let Some((n, d)) = tree.nearest(ctx.space, target) else {
        return Step::Trapped;
    };
    if d == 0.0 {
        return Step::Reached(n);
    }
    let steps = ((d / delta).ceil() as usize).max(1);
    let nq = ctx.space.nq();
    // `buf`: the step being tried, the last valid step, the origin.
    buf.resize(3 * nq, 0.0);
    let (step, rest) = buf.split_at_mut(nq);
    let (last, origin) = rest.split_at_mut(nq);
    origin.copy_from_slice(tree.q(n));
    last.copy_from_slice(origin);
    let (mut from, mut valid) = (n, 0);
    for k in 1..=steps {
        if k == steps {
            step.copy_from_slice(target);
        } else {
            ctx.space
                .interpolate(origin, target, k as f64 / steps as f64, step);
        }
        if !ctx.motion_valid(last, step, true) {
            break;
        }
        if per_step {
            from = tree.add(ctx.space, step, from);
        }
        last.copy_from_slice(step);
        valid = k;
    }
    if valid == 0 {
        return Step::Trapped;
    }
    if !per_step {
        from = tree.add(ctx.space, last, n);
    }
    if valid == steps {
        Step::Reached(from)
    } else {
        Step::Advanced(from)
    }
}

/// The path from the start tree's root to vertex `v` (within `epsilon` of the goal), then the
/// goal itself when `v` is not exactly it and the last short edge is valid.
pub(crate) fn finish_at_goal(ctx: &mut Context, tree: &Tree, v: u32, goal: &[f64]) -> Option<Path> {
    let mut p = tree.path_from_root(v);
    if tree.q(v) != goal {
        if !ctx.motion_valid(tree.q(v), goal, false) {
            return None;
        }
        p.push(goal);
    }
    Some(p)
}

/// RL's `Rrt`: one tree from the start.
pub struct Rrt {
    settings: RrtSettings,
    tree: Tree,
    stats: Stats,
}

impl Rrt {
    /// A planner for `space`.
    pub fn new(space: &JointSpace, settings: RrtSettings) -> Result<Self, PlanError> {
        settings.validate()?;
        Ok(Self {
            settings,
            tree: Tree::new(space, settings.nn)?,
            stats: Stats::default(),
        })
    }
}

/// The single-tree loop shared by [`Rrt`] and [`super::RrtGoalBias`]: `choose` picks the
/// target of each iteration.
pub(crate) fn solve_single(
    ctx: &mut Context,
    tree: &mut Tree,
    settings: &RrtSettings,
    stats: &mut Stats,
    start: &[f64],
    goal: &[f64],
    mut choose: impl FnMut(&mut Context, &mut [f64]),
) -> Option<Path> {
    tree.clear();
    *stats = Stats::default();
    tree.add(ctx.space, start, NONE);
    let mut chosen = vec![0.0; ctx.space.nq()];
    let mut buf = Vec::new();
    let mut i = 0u64;
    let result = loop {
        if !ctx.budget.allows(i) {
            break None;
        }
        i += 1;
        choose(ctx, &mut chosen);
        if let Some(v) = extend(ctx, tree, &chosen, settings.delta, &mut buf).vertex()
            && ctx.space.distance(tree.q(v), goal) <= settings.epsilon
            && let Some(p) = finish_at_goal(ctx, tree, v, goal)
        {
            break Some(p);
        }
    };
    stats.iterations = i;
    stats.vertices = tree.len();
    stats.edges = tree.len().saturating_sub(1);
    result
}

impl Planner for Rrt {
    fn name(&self) -> &'static str {
        "RRT"
    }

    fn solve(&mut self, ctx: &mut Context, start: &[f64], goal: &[f64]) -> Option<Path> {
        solve_single(
            ctx,
            &mut self.tree,
            &self.settings,
            &mut self.stats,
            start,
            goal,
            |ctx, out| ctx.sample(out),
        )
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}
