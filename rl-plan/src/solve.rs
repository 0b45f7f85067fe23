//! One planning call from end to end: check the end points, try the straight motion, run the
//! planner within its budget, optimise the path within what is left of the budget, and report
//! times, counts and lengths.

use std::time::{Duration, Instant};

use crate::budget::{Budget, Cancel};
use crate::error::PlanError;
use crate::optimizer::OptimizerKind;
use crate::path::Path;
use crate::planner::{Context, PlannerKind};
use crate::sampler::SamplerKind;
use crate::space::JointSpace;
use crate::validity::Validity;
use crate::verifier::Verifier;

/// How to plan.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanOptions {
    /// The planner and its settings.
    pub planner: PlannerKind,
    /// The sampler.
    pub sampler: SamplerKind,
    /// The edge verifier.
    pub verifier: Verifier,
    /// The optimiser run on the planner's path.
    pub optimizer: OptimizerKind,
    /// The optimiser's verifier (`None`: the planner's).
    pub optimizer_verifier: Option<Verifier>,
    /// The random seed: the same seed gives the same path.
    pub seed: u64,
    /// Time for planning.
    pub time: Duration,
    /// Time for optimising (after planning).
    pub optimize_time: Duration,
    /// Try the straight motion from start to goal before planning (as VAMP does).
    pub try_direct: bool,
}

impl Default for PlanOptions {
    fn default() -> Self {
        Self {
            planner: PlannerKind::parse("rrt-connect").expect("known planner"),
            sampler: SamplerKind::Uniform,
            verifier: Verifier::recursive(1.0 / 32.0),
            optimizer: OptimizerKind::Simple,
            optimizer_verifier: None,
            seed: 0,
            time: Duration::from_secs(1),
            optimize_time: Duration::from_secs(1),
            try_direct: true,
        }
    }
}

/// What a planning call found and what it cost.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanResult {
    /// The planner's name.
    pub planner: &'static str,
    /// Whether a path was found.
    pub solved: bool,
    /// The planner's path (start to goal).
    pub path: Option<Path>,
    /// The optimised path (the planner's when no optimiser ran).
    pub optimized: Option<Path>,
    /// Time spent planning (including the straight-motion try).
    pub planning_time: Duration,
    /// Time spent optimising.
    pub optimization_time: Duration,
    /// Planner iterations (0 when the straight motion was valid).
    pub iterations: u64,
    /// Vertices of the planner's trees or roadmap.
    pub vertices: usize,
    /// Edges.
    pub edges: usize,
    /// Configurations checked while planning.
    pub planning_checks: u64,
    /// Of those, the ones found collision-free (RL's "Free CD").
    pub planning_free_checks: u64,
    /// Configurations checked while optimising.
    pub optimization_checks: u64,
    /// Length of the planner's path (NaN when not solved).
    pub length_before: f64,
    /// Length of the optimised path (NaN when not solved).
    pub length_after: f64,
}

impl PlanResult {
    /// The result of a call that found nothing (an end point the checker refuses, say).
    pub fn unsolved(planning_time: Duration) -> Self {
        Self {
            planner: "",
            solved: false,
            path: None,
            optimized: None,
            planning_time,
            optimization_time: Duration::ZERO,
            iterations: 0,
            vertices: 0,
            edges: 0,
            planning_checks: 0,
            planning_free_checks: 0,
            optimization_checks: 0,
            length_before: f64::NAN,
            length_after: f64::NAN,
        }
    }
}

/// Whether every waypoint of `path` and every motion between consecutive waypoints (at the
/// resolution of `verifier`) passes `validity`: the independent check of a returned path.
pub fn path_valid(
    space: &JointSpace,
    validity: &mut dyn Validity,
    path: &Path,
    verifier: &Verifier,
) -> bool {
    let mut scratch = crate::verifier::Scratch::default();
    (0..path.len()).all(|i| validity.is_valid(path.point(i)))
        && (1..path.len()).all(|i| {
            verifier.is_valid(
                space,
                validity,
                (path.point(i - 1), path.point(i)),
                false,
                &mut scratch,
            )
        })
}

/// Checks that `q` is a valid configuration of `space` (bounds and `validity`).
pub fn check_endpoint(
    space: &JointSpace,
    validity: &mut dyn Validity,
    which: &'static str,
    q: &[f64],
) -> Result<(), PlanError> {
    space.check(which, q).map_err(|e| match e {
        PlanError::OutsideBounds { .. } => PlanError::InvalidEndpoint {
            which,
            reason: e.to_string(),
        },
        e => e,
    })?;
    if !validity.is_valid(q) {
        return Err(PlanError::InvalidEndpoint {
            which,
            reason: "in collision".into(),
        });
    }
    Ok(())
}

/// Plans from `start` to `goal`: see the module docs. An invalid end point is an error; a
/// search that runs out of time is a result with `solved == false`.
pub fn plan(
    space: &JointSpace,
    validity: &mut dyn Validity,
    start: &[f64],
    goal: &[f64],
    options: &PlanOptions,
) -> Result<PlanResult, PlanError> {
    plan_cancellable(space, validity, start, goal, options, None)
}

/// [`plan`], ended early with [`PlanError::Cancelled`] when `cancel` is requested (checked as
/// often as the time budget, so within one planner or optimiser iteration).
pub fn plan_cancellable(
    space: &JointSpace,
    validity: &mut dyn Validity,
    start: &[f64],
    goal: &[f64],
    options: &PlanOptions,
    cancel: Option<&Cancel>,
) -> Result<PlanResult, PlanError> {
    let cancelled = || cancel.is_some_and(Cancel::is_requested);
    if cancelled() {
        return Err(PlanError::Cancelled);
    }
    check_endpoint(space, validity, "start", start)?;
    check_endpoint(space, validity, "goal", goal)?;
    let mut planner = options.planner.build(space)?;
    let sampler = options.sampler.build(space, options.seed);
    let (checks0, free0) = (validity.checks(), validity.free_checks());
    let t0 = Instant::now();
    let mut ctx = Context::new(
        space,
        validity,
        options.verifier,
        sampler,
        options.seed,
        Budget::new(options.time).with_cancel(cancel.cloned()),
    );
    let direct = options.try_direct && ctx.motion_valid(start, goal, false);
    let (path, stats) = if direct {
        let mut p = Path::new(space.nq());
        p.push(start);
        p.push(goal);
        (Some(p), Default::default())
    } else {
        let p = planner.solve(&mut ctx, start, goal);
        (p, planner.stats())
    };
    let planning_time = t0.elapsed();
    let planning_checks = ctx.validity.checks() - checks0;
    let planning_free_checks = ctx.validity.free_checks() - free0;
    let mut result = PlanResult {
        planner: planner.name(),
        solved: path.is_some(),
        optimized: None,
        planning_time,
        optimization_time: Duration::ZERO,
        iterations: stats.iterations,
        vertices: stats.vertices,
        edges: stats.edges,
        planning_checks,
        planning_free_checks,
        optimization_checks: 0,
        length_before: f64::NAN,
        length_after: f64::NAN,
        path: None,
    };
    if let Some(p) = path {
        result.length_before = p.length(space);
        let mut optimized = p.clone();
        if let Some(mut opt) = options.optimizer.build() {
            let c1 = ctx.validity.checks();
            let t1 = Instant::now();
            ctx.budget = Budget::new(options.optimize_time).with_cancel(cancel.cloned());
            if let Some(v) = options.optimizer_verifier {
                ctx.verifier = v;
            }
            opt.process(&mut ctx, &mut optimized);
            result.optimization_time = t1.elapsed();
            result.optimization_checks = ctx.validity.checks() - c1;
        }
        result.length_after = optimized.length(space);
        result.path = Some(p);
        result.optimized = Some(optimized);
    }
    if cancelled() {
        return Err(PlanError::Cancelled);
    }
    Ok(result)
}
