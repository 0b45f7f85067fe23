//! Executing the benchmark's paths: each optimised path blended (checked with the exact
//! geometry), retimed with bounded jerk along the blended configurations, and both measured
//! against TOPP-RA's velocity-and-acceleration optimum on the same geometry
//! ([`crate::execute`]). The table gives the ratios per path.

use rl_core::traj::Trajectory;

use crate::error::PlanError;
use crate::execute::{
    BlendOptions, Execution, ExecutionLimits, jerk_limited, rests_of, time_optimal,
};
use crate::path::Path;
use crate::problem::Robot;
use crate::validity::Validity;

use super::Run;
use super::stats::Summary;

/// Trajectory axes (the MotionBenchMaker arms have 6 and 7 joints).
const D: usize = 8;
/// Blended segments: paths of up to 25 waypoints.
const MAX: usize = 128;
/// TOPP-RA stages: for the optimum on the blended path, and per run of the retiming.
const TOPP_STAGES: usize = 4000;
const RETIME_STAGES: usize = 1000;

/// Durations of one path's executions, s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// Stopping at every waypoint (rl-core's jerk-limited moves).
    pub stop: f64,
    /// Blended through the waypoints (`Execution::blended`).
    pub blended: f64,
    /// Retimed with bounded jerk along the blended configurations (`jerk_limited`).
    pub retimed: f64,
    /// TOPP-RA on the blended configurations: velocity and acceleration, jerk free.
    pub optimum: f64,
}

impl Timing {
    /// The faster of the blended and the retimed trajectory (both certified).
    pub fn best(&self) -> f64 {
        self.blended.min(self.retimed)
    }
}

/// Times `path` for `robot` within `limits`, blends checked with `validity` at the planner's
/// resolution `delta`.
pub fn time_path(
    robot: &Robot,
    validity: &mut dyn Validity,
    path: &Path,
    limits: &ExecutionLimits,
    delta: f64,
) -> Result<Timing, PlanError> {
    let n = limits.velocity.len();
    let ex = Execution::new(&robot.space, path, limits.clone())?;
    let b = ex.blended::<D, MAX>(&robot.space, validity, &BlendOptions::for_resolution(delta))?;
    let tr = &*b.trajectory;
    let optimum = time_optimal(tr, limits, TOPP_STAGES)?.duration();
    let rests = rests_of::<D, _, MAX>(tr, n);
    let retimed = jerk_limited(tr, &rests, limits, RETIME_STAGES, 1e-3)?.duration();
    Ok(Timing {
        stop: b.report.stop_duration_s,
        blended: tr.duration(),
        retimed,
        optimum,
    })
}

/// The ratios over the runs that were timed, one line each: what / TOPP-RA's optimum.
pub fn retime_table(runs: &[Run]) -> String {
    let timed: Vec<Timing> = runs.iter().filter_map(|r| r.timing).collect();
    let failed = runs.iter().filter(|r| r.timing_error.is_some()).count();
    let row = |name: &str, f: &dyn Fn(&Timing) -> f64| {
        let s = Summary::of(&timed.iter().map(f).collect::<Vec<_>>());
        format!(
            "{name:<34} {:>6.3} {:>6.3} {:>6.3} {:>6.3} {:>6.3} {:>6.3}\n",
            s.min, s.q25, s.median, s.mean, s.p95, s.max
        )
    };
    let mut out = format!(
        "execution of {} paths ({} could not be timed), durations over TOPP-RA's (velocity and acceleration) on the same blended path:\n{:<34} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6}\n",
        timed.len(),
        failed,
        "",
        "min",
        "q25",
        "median",
        "mean",
        "p95",
        "max"
    );
    out.push_str(&row("stop at every waypoint", &|t| t.stop / t.optimum));
    out.push_str(&row("blended", &|t| t.blended / t.optimum));
    out.push_str(&row("retimed, jerk bounded", &|t| t.retimed / t.optimum));
    out.push_str(&row("faster of blended and retimed", &|t| {
        t.best() / t.optimum
    }));
    out.push_str(&row("retimed / blended", &|t| t.retimed / t.blended));
    let mut why: Vec<(String, usize)> = Vec::new();
    for e in runs.iter().filter_map(|r| r.timing_error.as_ref()) {
        match why.iter_mut().find(|(w, _)| w == e) {
            Some((_, n)) => *n += 1,
            None => why.push((e.clone(), 1)),
        }
    }
    for (w, n) in why {
        out.push_str(&format!("not timed ({n}): {w}\n"));
    }
    out
}
