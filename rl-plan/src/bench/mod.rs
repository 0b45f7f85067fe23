//! Benchmark records and their outputs: summary statistics as VAMP's evaluation prints them,
//! OMPL's benchmark log format (which `ompl_benchmark_statistics.py` turns into a Planner Arena
//! database), and the CSV columns RL's rlPlanDemo appends to its `benchmark.csv`.

mod ompl_log;
mod retime;
mod runner;
mod stats;

pub use ompl_log::write_ompl_log;
pub use retime::{Timing, retime_table, time_path};
pub use runner::{BenchOptions, CheckerKind, run_mbm};
pub use stats::Summary;

use std::io::Write;
use std::time::Duration;

use crate::solve::PlanResult;

/// One planning run of a benchmark.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The problem's name (`scenario/NNNN`).
    pub problem: String,
    /// The run's number (0-based) for this problem.
    pub run: usize,
    /// The seed it used.
    pub seed: u64,
    /// The robot's name.
    pub robot: String,
    /// The nearest-neighbour structure's name.
    pub nn: String,
    /// Whether start and goal were valid (an invalid problem has no result).
    pub valid: bool,
    /// What the planner did (for valid problems).
    pub result: Option<PlanResult>,
    /// The independent check of the optimised path, if one ran: `Some(true)` when the exact
    /// geometry found no collision at the fine resolution.
    pub fine_valid: Option<bool>,
    /// Time limit per run.
    pub time_limit: Duration,
    /// The optimised path's executions, if they were timed ([`BenchOptions::retime`]).
    pub timing: Option<Timing>,
    /// Why the path could not be timed.
    pub timing_error: Option<String>,
}

impl Run {
    /// Whether it found a path.
    pub fn solved(&self) -> bool {
        self.result.as_ref().is_some_and(|r| r.solved)
    }
}

/// The header of RL's `benchmark.csv` (rlPlanDemo), then the columns rl-rs adds.
pub const RL_CSV_HEADER: &str = "Date,Time,Solved,Engine,Planner,Robot,Nearest Neighbors,Vertices,Edges,Total CD,Free CD,Exploration Duration (s),Duration (s), Path Length,Problem,Run,Seed,Iterations,Optimization Duration (s),Optimized Path Length,Fine Check";

/// Writes `runs` as RL's CSV (header first), `engine` naming the collision checker.
pub fn write_rl_csv(out: &mut dyn Write, runs: &[Run], engine: &str) -> std::io::Result<()> {
    writeln!(out, "{RL_CSV_HEADER}")?;
    let (date, time) = civil_now();
    for r in runs {
        let Some(res) = &r.result else { continue };
        let len = |x: f64| {
            if x.is_finite() {
                format!("{x}")
            } else {
                String::new()
            }
        };
        writeln!(
            out,
            "{date},{time},{},{engine},{},{},{},{},{},{},{},0,{},{},{},{},{},{},{},{},{}",
            res.solved,
            res.planner,
            r.robot,
            r.nn,
            res.vertices,
            res.edges,
            res.planning_checks,
            res.planning_free_checks,
            res.planning_time.as_secs_f64(),
            len(res.length_before),
            r.problem,
            r.run,
            r.seed,
            res.iterations,
            res.optimization_time.as_secs_f64(),
            len(res.length_after),
            match r.fine_valid {
                Some(true) => "valid",
                Some(false) => "collision",
                None => "",
            }
        )?;
    }
    Ok(())
}

/// The table VAMP's `evaluate_mbm.py` prints, for the solved runs of `runs`: planning,
/// simplification and total time (µs), iterations and time per iteration (µs), as mean,
/// standard deviation, min, quartiles, 95th percentile and max; then solved / valid / total,
/// and configurations checked per second of planning.
pub fn vamp_table(runs: &[Run]) -> String {
    let solved: Vec<&PlanResult> = runs
        .iter()
        .filter_map(|r| r.result.as_ref())
        .filter(|r| r.solved)
        .collect();
    let us = |d: Duration| d.as_secs_f64() * 1e6;
    let columns: [(&str, Vec<f64>); 5] = [
        (
            "planning µs",
            solved.iter().map(|r| us(r.planning_time)).collect(),
        ),
        (
            "simplify µs",
            solved.iter().map(|r| us(r.optimization_time)).collect(),
        ),
        (
            "total µs",
            solved
                .iter()
                .map(|r| us(r.planning_time + r.optimization_time))
                .collect(),
        ),
        (
            "iterations",
            solved.iter().map(|r| r.iterations as f64).collect(),
        ),
        (
            "µs/iteration",
            solved
                .iter()
                .filter(|r| r.iterations > 0)
                .map(|r| us(r.planning_time) / r.iterations as f64)
                .collect(),
        ),
    ];
    let summaries: Vec<Summary> = columns.iter().map(|c| Summary::of(&c.1)).collect();
    let mut s = String::new();
    s.push_str("|      |");
    for (name, _) in &columns {
        s.push_str(&format!(" {name:>13} |"));
    }
    s.push_str("\n|------|");
    for _ in &columns {
        s.push_str("--------------:|");
    }
    s.push('\n');
    type Row = (&'static str, fn(&Summary) -> f64);
    let rows: [Row; 8] = [
        ("mean", |x| x.mean),
        ("std", |x| x.std),
        ("min", |x| x.min),
        ("25%", |x| x.q25),
        ("50%", |x| x.median),
        ("75%", |x| x.q75),
        ("95%", |x| x.p95),
        ("max", |x| x.max),
    ];
    for (name, f) in rows {
        s.push_str(&format!("| {name:<4} |"));
        for sm in &summaries {
            s.push_str(&format!(" {:>13.2} |", f(sm)));
        }
        s.push('\n');
    }
    let total = runs.len();
    let valid = runs.iter().filter(|r| r.valid).count();
    let n_solved = runs.iter().filter(|r| r.solved()).count();
    s.push_str(&format!(
        "Solved / Valid / Total # Problems: {n_solved} / {valid} / {total}\n"
    ));
    let checks: u64 = solved.iter().map(|r| r.planning_checks).sum();
    let secs: f64 = solved.iter().map(|r| r.planning_time.as_secs_f64()).sum();
    if secs > 0.0 {
        s.push_str(&format!(
            "Collision checks per second (planning, solved runs): {:.3e} ({} checks in {:.3} ms)\n",
            checks as f64 / secs,
            checks,
            secs * 1e3
        ));
    }
    let fine: Vec<bool> = runs.iter().filter_map(|r| r.fine_valid).collect();
    if !fine.is_empty() {
        s.push_str(&format!(
            "Exact-geometry fine check of the returned paths: {} of {} free of collision\n",
            fine.iter().filter(|v| **v).count(),
            fine.len()
        ));
    }
    s
}

/// Today's UTC date and time of day (`YYYY-MM-DD`, `HH:MM:SS`), from the system clock.
pub fn civil_now() -> (String, String) {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Howard Hinnant's civil_from_days.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    (
        format!("{y:04}-{m:02}-{d:02}"),
        format!("{:02}:{:02}:{:02}", rem / 3600, rem % 3600 / 60, rem % 60),
    )
}
