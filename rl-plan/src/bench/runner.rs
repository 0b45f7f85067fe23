//! Running a MotionBenchMaker set: every problem, a number of seeded runs each, with the fast
//! or the exact checker, and optionally the independent fine check of every returned path.

use std::time::Instant;

use super::Run;
use crate::error::PlanError;
use crate::problem::Robot;
use crate::problem::mbm::MbmProblem;
use crate::solve::{PlanOptions, PlanResult, path_valid, plan};
use crate::validity::Validity;
use crate::verifier::Verifier;

/// Which checker plans.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CheckerKind {
    /// The SIMD sphere checker.
    Spheres,
    /// rl-sg's exact geometry.
    Exact,
    /// Covering spheres, the file's spheres, then the exact geometry
    /// ([`crate::fast::HybridChecker`]).
    Hybrid,
}

/// How to run a set.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchOptions {
    /// Planning options (the seed of run `k` is `seed + k`).
    pub plan: PlanOptions,
    /// Runs per problem.
    pub runs: usize,
    /// The checker.
    pub checker: CheckerKind,
    /// Check every optimised path with the exact geometry at the planner's resolution divided
    /// by this factor (10 in the tests); `None`: no check.
    pub fine_check: Option<f64>,
    /// Time the execution of every optimised path within these limits (blended, retimed,
    /// TOPP-RA: [`super::time_path`]); `None`: not timed.
    pub retime: Option<crate::execute::ExecutionLimits>,
}

/// Runs `problems` for `robot`; `progress` sees every run as it finishes. A problem whose
/// start or goal the exact geometry finds in collision (or out of bounds) is *invalid* and not
/// planned, as in VAMP's evaluation; a valid problem the fast checker cannot start from counts
/// as unsolved.
pub fn run_mbm(
    robot: &Robot,
    problems: &[MbmProblem],
    options: &BenchOptions,
    progress: &mut dyn FnMut(&Run),
) -> Result<Vec<Run>, PlanError> {
    let mut out = Vec::new();
    let robot_name = robot.kinematics.model.name().to_string();
    let nn = match &options.plan.planner {
        crate::planner::PlannerKind::Prm(s) => s.nn,
        k => k
            .clone()
            .rrt_settings_mut()
            .map(|s| s.nn)
            .unwrap_or_default(),
    };
    for p in problems {
        let (env, start, goal) = p.load(robot)?;
        let mut exact = robot.exact_checker(env.clone())?;
        let valid = robot.space.contains(&start)
            && robot.space.contains(&goal)
            && exact.is_valid(&start)
            && exact.is_valid(&goal);
        let mut fast: Option<Box<dyn Validity>> = match options.checker {
            CheckerKind::Spheres if valid => Some(Box::new(robot.sphere_checker(&env)?)),
            CheckerKind::Hybrid if valid => Some(Box::new(robot.hybrid_checker(&env)?)),
            _ => None,
        };
        for k in 0..options.runs.max(1) {
            let seed = options.plan.seed.wrapping_add(k as u64);
            let mut run = Run {
                problem: p.name.clone(),
                run: k,
                seed,
                robot: robot_name.clone(),
                nn: format!("{nn:?}"),
                valid,
                result: None,
                fine_valid: None,
                time_limit: options.plan.time,
                timing: None,
                timing_error: None,
            };
            if valid {
                let mut opts = options.plan.clone();
                opts.seed = seed;
                let checker: &mut dyn Validity = match fast.as_mut() {
                    Some(f) => f.as_mut(),
                    None => &mut exact,
                };
                let t0 = Instant::now();
                let result = match plan(&robot.space, checker, &start, &goal, &opts) {
                    Ok(r) => r,
                    Err(PlanError::InvalidEndpoint { .. }) => PlanResult::unsolved(t0.elapsed()),
                    Err(e) => return Err(e),
                };
                if let (Some(factor), Some(path)) = (options.fine_check, &result.optimized) {
                    let fine = Verifier::sequential(opts.verifier.delta / factor);
                    run.fine_valid = Some(path_valid(&robot.space, &mut exact, path, &fine));
                }
                if let (Some(limits), Some(path)) = (&options.retime, &result.optimized) {
                    match super::time_path(robot, &mut exact, path, limits, opts.verifier.delta) {
                        Ok(t) => run.timing = Some(t),
                        Err(e) => run.timing_error = Some(e.to_string()),
                    }
                }
                run.result = Some(result);
            }
            progress(&run);
            out.push(run);
        }
    }
    Ok(out)
}
