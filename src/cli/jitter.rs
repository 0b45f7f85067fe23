//! `rl jitter` (a cyclictest-equivalent measurement with rl-rt's own loop and an empty step)
//! and `rl preflight` (what stands between this machine and hard real time).

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use clap::{Args, ValueEnum};
use rl_rt::preflight::{self, Status};
use rl_rt::{
    CyclicLoop, LoopEnd, LoopError, LoopReport, OverrunPolicy, Policy, RtThreadBuilder, Scheduling,
    StopFlag,
};

use super::output::{Replacement, errln, out, outln};
use super::progress::{LIVE_INTERVAL, ProgressLine, fraction};
use super::{CliError, CliResult, parse_duration, refuse_given};

/// Largest `--histogram-range-us`: one second in 1 µs bins (8 MB of counters).
pub const MAX_HISTOGRAM_RANGE_US: usize = 1_000_000;

/// Scheduling policy of the measuring thread.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PolicyArg {
    /// SCHED_FIFO.
    Fifo,
    /// SCHED_RR.
    Rr,
    /// SCHED_OTHER (priority 0).
    Other,
}

/// What the loop does when a cycle overruns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OverrunArg {
    /// Skip the deadlines already past (as cyclictest does).
    Skip,
    /// Run every missed cycle late, back to back.
    CatchUp,
    /// End with an error.
    Stop,
}

/// Arguments of `rl jitter`.
#[derive(Args, Debug)]
pub struct JitterArgs {
    /// Loop period in microseconds (cyclictest -i).
    #[arg(long, default_value_t = 1000)]
    pub interval_us: u64,
    /// How long to measure: a number with unit us, ms, s, m or h (e.g. 500ms, 30s, 2m).
    #[arg(long, default_value = "30s", value_parser = parse_duration)]
    pub duration: Duration,
    /// Run exactly this many cycles instead of --duration (cyclictest -l).
    #[arg(long)]
    pub cycles: Option<u64>,
    /// Real-time priority (cyclictest -p); default 90 for fifo/rr, 0 for other.
    #[arg(long)]
    pub priority: Option<i32>,
    /// Pin the measuring thread to this CPU (cyclictest -a).
    #[arg(long)]
    pub cpu: Option<usize>,
    /// Scheduling policy (cyclictest --policy).
    #[arg(long, value_enum, default_value_t = PolicyArg::Fifo)]
    pub policy: PolicyArg,
    /// Write the wake-up latency histogram to FILE in cyclictest's -h format.
    #[arg(long, value_name = "FILE")]
    pub histogram: Option<PathBuf>,
    /// Histogram range in µs (1 µs bins; cyclictest -h N), 1 to 1 000 000; later wake-ups are
    /// counted as overflows.
    #[arg(long, default_value_t = 10_000)]
    pub histogram_range_us: usize,
    /// Overrun policy of the loop.
    #[arg(long, value_enum, default_value_t = OverrunArg::Skip)]
    pub overrun: OverrunArg,
    /// Do not lock memory (mlockall; cyclictest -m is the default here).
    #[arg(long)]
    pub no_mlock: bool,
    /// Do not hold /dev/cpu_dma_latency at 0 µs while measuring (cyclictest --laptop).
    #[arg(long)]
    pub no_cpu_latency_hint: bool,
    /// Print one JSON object instead of the text report.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `rl preflight`.
#[derive(Args, Debug)]
pub struct PreflightArgs {
    /// Print the findings as JSON (`{"schema": "rl.preflight/1", "findings": [...]}`).
    #[arg(long)]
    pub json: bool,
    /// Exit with code 1 if any finding is a warning or a failure (for scripts and CI).
    #[arg(long)]
    pub strict: bool,
}

/// Runs `rl jitter`.
pub fn run_jitter(args: JitterArgs) -> CliResult {
    if args.interval_us == 0 {
        return Err(CliError::usage("--interval-us must be at least 1"));
    }
    if !(1..=MAX_HISTOGRAM_RANGE_US).contains(&args.histogram_range_us) {
        return Err(CliError::usage(format!(
            "--histogram-range-us {}: give 1 to {MAX_HISTOGRAM_RANGE_US} µs",
            args.histogram_range_us
        )));
    }
    if args.cycles.is_some() {
        refuse_given(&["duration"], "with --cycles: the run is counted in cycles")?;
    }
    let period = Duration::from_micros(args.interval_us);
    let cycles = match args.cycles {
        Some(n) => n,
        None => (args.duration.as_nanos() / period.as_nanos()) as u64,
    };
    if cycles == 0 {
        return Err(CliError::usage(
            "nothing to measure: --duration is shorter than one interval",
        ));
    }
    let policy = match args.policy {
        PolicyArg::Fifo => Policy::Fifo,
        PolicyArg::Rr => Policy::RoundRobin,
        PolicyArg::Other => Policy::Other,
    };
    let priority = args
        .priority
        .unwrap_or(if policy.is_realtime() { 90 } else { 0 });
    let overrun = match args.overrun {
        OverrunArg::Skip => OverrunPolicy::Skip,
        OverrunArg::CatchUp => OverrunPolicy::CatchUp,
        OverrunArg::Stop => OverrunPolicy::Stop,
    };

    let mut builder = RtThreadBuilder::new("rl-jitter")
        .policy(policy)
        .priority(priority);
    if let Some(cpu) = args.cpu {
        builder = builder.cpus([cpu]);
    }
    // Bad priority or CPU is a usage error, found before anything is locked or blocked.
    builder
        .validate()
        .map_err(|e| CliError::usage(e.to_string()))?;
    // So is a histogram file that cannot be created: found before the measurement, not after.
    // Written beside its destination and moved over it once complete (a failed measurement
    // leaves an existing file as it was).
    let histogram = match &args.histogram {
        Some(path) => Some(Replacement::create(path).map_err(|e| {
            CliError::usage(format!(
                "--histogram: cannot create {}: {e}",
                path.display()
            ))
        })?),
        None => None,
    };

    let stop = StopFlag::new();
    stop.raise_on_termination_signals()
        .map_err(|e| CliError::failed(format!("cannot watch SIGINT/SIGTERM: {e}")))?;
    if !args.no_mlock {
        rl_rt::memory::lock_memory()
            .map_err(|e| CliError::failed(format!("{e}; or measure without it: --no-mlock")))?;
    }

    // Like cyclictest: keep CPUs out of deep idle states for the run (released on drop).
    let latency_hint = if args.no_cpu_latency_hint {
        None
    } else {
        match rl_rt::cpu_latency::CpuLatencyHint::hold(0) {
            Ok(hint) => Some(hint),
            Err(e) => {
                errln!(
                    "rl jitter: note: cannot hold {} at 0 µs ({e}); deep idle states may add latency",
                    rl_rt::cpu_latency::CPU_DMA_LATENCY
                );
                None
            }
        }
    };

    let looped = CyclicLoop::new(period)
        .map_err(|e| CliError::usage(e.to_string()))?
        .overrun_policy(overrun)
        .max_cycles(cycles)
        .stop_flag(&stop)
        .histogram_range(Duration::from_micros(args.histogram_range_us as u64));
    // The step only counts its cycles (one relaxed store): this thread reads the count for the
    // progress line, on a terminal only.
    let cycles_run = Arc::new(AtomicU64::new(0));
    let counter = Arc::clone(&cycles_run);
    let thread = builder
        .spawn(move || {
            looped.run(|cycle| {
                counter.store(cycle.index + 1, Ordering::Relaxed);
                ControlFlow::Continue(())
            })
        })
        .map_err(|e| match e {
            rl_rt::ThreadError::InvalidPriority { .. }
            | rl_rt::ThreadError::InvalidCpu { .. }
            | rl_rt::ThreadError::Affinity { .. } => CliError::usage(e.to_string()),
            e @ rl_rt::ThreadError::PermissionDenied { .. } => CliError::failed(format!(
                "{e}; or measure without real-time scheduling: --policy other"
            )),
            e => CliError::failed(e.to_string()),
        })?;
    let granted = thread.granted().clone();
    let cpu_dma_latency_us = latency_hint.as_ref().map(|h| h.max_latency_us());
    let mut line = ProgressLine::stderr("rl jitter: ");
    if line.is_active() {
        while !thread.is_finished() {
            std::thread::sleep(LIVE_INTERVAL);
            let done = cycles_run.load(Ordering::Relaxed);
            line.update(|| {
                format!(
                    "{} cycles, {:.1} s",
                    fraction(done as usize, cycles as usize),
                    done as f64 * period.as_secs_f64()
                )
            });
        }
        line.clear();
    }
    drop(line);
    let report = match thread.join() {
        Ok(Ok(report)) => report,
        Ok(Err(e @ LoopError::Overrun { .. })) => return Err(CliError::failed(e.to_string())),
        Ok(Err(e)) => return Err(CliError::failed(e.to_string())),
        Err(_) => return Err(CliError::failed("the measuring thread panicked")),
    };
    drop(latency_hint);

    if let (Some(path), Some(mut w)) = (&args.histogram, histogram) {
        report
            .stats
            .wakeup
            .write_cyclictest(&mut w)
            .and_then(|()| w.commit())
            .map_err(|e| CliError::failed(format!("cannot write {}: {e}", path.display())))?;
    }

    let stats = &report.stats;
    let interrupted = report.end == LoopEnd::StopRequested;
    if args.json {
        let value = jitter_json(&report, &granted, &args, cpu_dma_latency_us);
        outln!("{value}")?;
    } else {
        outln!(
            "rl jitter: {} cycles of {} µs, {}, mlockall {}, cpu_dma_latency {}, overrun policy {}{}",
            stats.cycles(),
            args.interval_us,
            granted,
            if args.no_mlock { "no" } else { "yes" },
            cpu_dma_latency_us.map_or("not held".to_owned(), |us| format!("{us} µs")),
            overrun,
            if interrupted { " (interrupted)" } else { "" }
        )?;
        outln!("{stats}")?;
        if let Some(c) = report.counters {
            outln!("loop thread: {c}")?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// The `rl jitter --json` object: `loop`, the loop statistics in rl-rt's one schema
/// ([`rl_rt::LoopStats::to_json`], the same object as `rl run --json`'s `loop`); the documented
/// short keys `cycles`, `overruns`, `min_us`, `mean_us`, `p50_us`, `p99_us`, `p999_us`,
/// `p9999_us`, `max_us` (wake-up latency); then the settings and the loop thread's health
/// counters.
fn jitter_json(
    report: &LoopReport,
    granted: &Scheduling,
    args: &JitterArgs,
    cpu_dma_latency_us: Option<u32>,
) -> serde_json::Value {
    let stats = &report.stats;
    let w = stats.wakeup.summary();
    let step = stats.step.summary();
    let us = |ns: u64| ns as f64 / 1_000.0;
    // rl-rt writes the schema; it is valid JSON by construction (tested there and below).
    let loop_stats: serde_json::Value =
        serde_json::from_str(&stats.to_json()).unwrap_or(serde_json::Value::Null);
    let value = serde_json::json!({
        "loop": loop_stats,
        "cycles": stats.cycles(),
        "overruns": stats.overruns,
        "min_us": us(w.min_ns),
        "mean_us": us(w.mean_ns),
        "p50_us": us(w.p50_ns),
        "p99_us": us(w.p99_ns),
        "p999_us": us(w.p999_ns),
        "p9999_us": us(w.p9999_ns),
        "max_us": us(w.max_ns),
        "missed_deadlines": stats.missed_deadlines,
        "overrun_cycles": stats.overrun_log().iter().map(|o| o.cycle).collect::<Vec<_>>(),
        "histogram_overflows": w.overflow,
        "histogram_range_us": stats.wakeup.range_us(),
        "interval_us": args.interval_us,
        "overrun_policy": report.policy.to_string(),
        "policy": granted.policy.map(|p| p.to_string()),
        "priority": granted.priority,
        "cpus": granted.cpus,
        "mlockall": !args.no_mlock,
        "cpu_dma_latency_us": cpu_dma_latency_us,
        "interrupted": report.end == LoopEnd::StopRequested,
        "minor_faults": report.counters.map(|c| c.minor_faults),
        "major_faults": report.counters.map(|c| c.major_faults),
        "involuntary_switches": report.counters.map(|c| c.involuntary_switches),
        "step": { "mean_us": us(step.mean_ns), "max_us": us(step.max_ns) },
    });
    rl::json::versioned("jitter", 1, value)
}

/// Runs `rl preflight`.
pub fn run_preflight(args: PreflightArgs) -> CliResult {
    let report = preflight::check();
    if args.json {
        // rl-rt writes the findings as an array; the tool's output is an object with the
        // version key and the array as `findings`.
        let findings: serde_json::Value =
            serde_json::from_str(&report.to_json()).unwrap_or(serde_json::Value::Null);
        let value =
            rl::json::versioned("preflight", 1, serde_json::json!({ "findings": findings }));
        outln!("{value}")?;
    } else {
        out!("{report}")?;
        let worst = report.worst();
        outln!(
            "\nverdict: {}",
            match worst {
                Status::Ok | Status::Info => "ready for hard real time",
                Status::Warn => "runs, but latency is not bounded as on a tuned PREEMPT_RT machine",
                Status::Fail => "real-time scheduling is not possible as configured",
            }
        )?;
    }
    if args.strict && report.worst() >= Status::Warn {
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_parse_with_units() {
        assert_eq!(parse_duration("30s"), Ok(Duration::from_secs(30)));
        assert_eq!(parse_duration("500ms"), Ok(Duration::from_millis(500)));
        assert_eq!(parse_duration("2m"), Ok(Duration::from_secs(120)));
        assert_eq!(parse_duration("250us"), Ok(Duration::from_micros(250)));
        assert_eq!(parse_duration("1.5"), Ok(Duration::from_millis(1500)));
        assert!(parse_duration("10 parsecs").is_err());
        assert!(parse_duration("fast").is_err());
    }

    #[derive(clap::Parser)]
    struct Wrapper {
        #[command(flatten)]
        args: JitterArgs,
    }

    fn args(line: &[&str]) -> JitterArgs {
        use clap::Parser;
        Wrapper::parse_from(std::iter::once("jitter").chain(line.iter().copied())).args
    }

    #[test]
    fn json_carries_the_documented_keys_consistently() {
        let a = args(&[
            "--policy",
            "other",
            "--cycles",
            "50",
            "--interval-us",
            "200",
            "--json",
        ]);
        let looped = CyclicLoop::new(Duration::from_micros(200))
            .expect("valid")
            .max_cycles(50);
        let report = looped
            .run(|_| ControlFlow::Continue(()))
            .expect("loop runs");
        let granted = rl_rt::thread::current_scheduling().expect("read back");
        let v = jitter_json(&report, &granted, &a, Some(0));
        assert_eq!(v["cycles"], 50);
        let key = |k: &str| {
            v[k].as_f64()
                .unwrap_or_else(|| panic!("{k} missing in {v}"))
        };
        let ordered = [
            "min_us", "p50_us", "p99_us", "p999_us", "p9999_us", "max_us",
        ]
        .map(key);
        assert!(ordered.windows(2).all(|w| w[0] <= w[1]), "{ordered:?}");
        assert!(key("min_us") <= key("mean_us") && key("mean_us") <= key("max_us"));
        assert!(v["overruns"].is_u64());
        assert_eq!(v["interval_us"], 200);
        assert_eq!(v["overrun_policy"], "skip");
    }

    #[test]
    fn run_writes_a_cyclictest_histogram() {
        let path = std::env::temp_dir().join(format!("rl-jitter-test-{}.hist", std::process::id()));
        let a = args(&[
            "--policy",
            "other",
            "--no-mlock",
            "--no-cpu-latency-hint",
            "--cycles",
            "30",
            "--interval-us",
            "500",
            "--histogram-range-us",
            "100000",
            "--histogram",
            path.to_str().expect("utf-8 temp path"),
        ]);
        run_jitter(a).expect("measures at SCHED_OTHER without privileges");
        let text = std::fs::read_to_string(&path).expect("histogram written");
        let _ = std::fs::remove_file(&path);
        let in_bins: u64 = text
            .lines()
            .filter(|l| !l.starts_with('#'))
            .filter_map(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
            .sum();
        let overflow: u64 = text
            .lines()
            .find_map(|l| l.strip_prefix("# Histogram Overflows: "))
            .and_then(|n| n.trim().parse().ok())
            .expect("overflow line");
        assert_eq!(in_bins + overflow, 30);
        assert!(text.starts_with("# Histogram\n000000 "));
    }

    #[test]
    fn bad_priority_is_a_usage_error() {
        let e = run_jitter(args(&[
            "--policy",
            "other",
            "--priority",
            "5",
            "--cycles",
            "1",
        ]))
        .expect_err("SCHED_OTHER takes priority 0 only");
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("0..=0"), "{e}");
    }
}
