//! OMPL's benchmark log format (the grammar in OMPL's "How to Benchmark Planners", section
//! "The benchmark logfile format"): one experiment per file — a preamble (version, experiment
//! name, host, date, setup and CPU blocks, seed, time and memory limits, run count, total
//! time, the `status` enum), then per planner its common properties, the names and types of
//! the per-run properties, and one line of `;`-terminated values per run, closed by `.`.
//! `ompl_benchmark_statistics.py` reads such files into the database Planner Arena shows.

use std::io::Write;

use super::Run;

/// OMPL's `PlannerStatus` values, in order.
const STATUS: &str = "status|Unknown status|Invalid start|Invalid goal|Unrecognized goal type|Timeout|Approximate solution|Exact solution|Crash|Abort|Infeasible";

/// The per-run properties written, with their OMPL types.
const PROPERTIES: [&str; 14] = [
    "time REAL",
    "solved BOOLEAN",
    "status ENUM",
    "approximate solution BOOLEAN",
    "solution length REAL",
    "solution segments INTEGER",
    "simplification time REAL",
    "simplified solution length REAL",
    "simplified solution segments INTEGER",
    "simplified correct solution strict BOOLEAN",
    "graph states INTEGER",
    "graph motions INTEGER",
    "iterations INTEGER",
    "collision checks INTEGER",
];

fn host() -> String {
    std::fs::read_to_string("/etc/hostname")
        .ok()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "localhost".into())
}

fn cpu() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

/// Writes one experiment (`name`) of `runs` of the planner `planner` (all runs of one problem),
/// with `setup` describing the configuration.
pub fn write_ompl_log(
    out: &mut dyn Write,
    name: &str,
    planner: &str,
    setup: &str,
    runs: &[Run],
) -> std::io::Result<()> {
    let (date, time) = super::civil_now();
    let seed = runs.first().map_or(0, |r| r.seed);
    let limit = runs.first().map_or(0.0, |r| r.time_limit.as_secs_f64());
    let total: f64 = runs
        .iter()
        .filter_map(|r| r.result.as_ref())
        .map(|r| (r.planning_time + r.optimization_time).as_secs_f64())
        .sum();
    writeln!(out, "rl-rs version {}", env!("CARGO_PKG_VERSION"))?;
    writeln!(out, "Experiment {}", name.replace(char::is_whitespace, "_"))?;
    writeln!(out, "Running on {}", host())?;
    writeln!(out, "Starting at {date} {time}")?;
    writeln!(out, "<<<|\n{setup}\n|>>>")?;
    writeln!(out, "<<<|\n{}\n|>>>", cpu())?;
    writeln!(out, "{seed} is the random seed")?;
    writeln!(out, "{limit} seconds per run")?;
    writeln!(out, "0 MB per run")?;
    writeln!(out, "{} runs per planner", runs.len())?;
    writeln!(out, "{total} seconds spent to collect the data")?;
    writeln!(out, "1 enum type")?;
    writeln!(out, "{STATUS}")?;
    writeln!(out, "1 planners")?;
    writeln!(out, "{}", planner.replace(char::is_whitespace, "_"))?;
    writeln!(out, "0 common properties")?;
    writeln!(out, "{} properties for each run", PROPERTIES.len())?;
    for p in PROPERTIES {
        writeln!(out, "{p}")?;
    }
    writeln!(out, "{} runs", runs.len())?;
    for r in runs {
        let b = |x: bool| if x { "1" } else { "0" };
        let f = |x: f64| {
            if x.is_finite() {
                format!("{x}")
            } else {
                String::new()
            }
        };
        match &r.result {
            None => {
                // Invalid start or goal: status only.
                writeln!(out, "0; 0; 1; 0; ; ; ; ; ; ; ; ; ; ; ")?;
            }
            Some(res) => {
                let segments = |p: &Option<crate::path::Path>| {
                    p.as_ref()
                        .map_or(String::new(), |p| p.len().saturating_sub(1).to_string())
                };
                let status = if res.solved { 6 } else { 4 };
                writeln!(
                    out,
                    "{}; {}; {status}; 0; {}; {}; {}; {}; {}; {}; {}; {}; {}; {}; ",
                    res.planning_time.as_secs_f64(),
                    b(res.solved),
                    f(res.length_before),
                    segments(&res.path),
                    res.optimization_time.as_secs_f64(),
                    f(res.length_after),
                    segments(&res.optimized),
                    r.fine_valid.map_or("", b),
                    res.vertices,
                    res.edges,
                    res.iterations,
                    res.planning_checks,
                )?;
            }
        }
    }
    writeln!(out, ".")?;
    Ok(())
}
