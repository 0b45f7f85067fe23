//! The periodic loop against the clock: cycle count, the absolute deadline grid (no drift),
//! statistics that agree with an independent recomputation, overrun policies, stop flag.

mod support;

use std::ops::ControlFlow;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rl_rt::{CyclicLoop, LoopEnd, LoopError, MonoTime, OverrunPolicy, StopFlag};

#[derive(Clone, Copy, Debug)]
struct Seen {
    index: u64,
    deadline_index: u64,
    deadline: MonoTime,
    woke: MonoTime,
    latency_ns: u64,
    skipped_before: u64,
    checked_at: MonoTime,
    step_end: MonoTime,
}

/// Runs a loop on the loop thread, recording what every cycle saw; `inject` returns how long
/// to busy-wait/sleep in the step of a given cycle index.
fn record(
    looped: CyclicLoop,
    cycles_hint: usize,
    inject: fn(u64) -> Duration,
) -> (
    Result<rl_rt::LoopReport, LoopError>,
    Vec<Seen>,
    rl_rt::LoopStats,
) {
    support::on_loop_thread(move || {
        let mut seen = Vec::with_capacity(cycles_hint);
        let mut stats = looped.new_stats();
        let start_guess = MonoTime::now();
        let result = looped.run_into(&mut stats, |c| {
            let checked_at = MonoTime::now();
            let extra = inject(c.index);
            if !extra.is_zero() {
                std::thread::sleep(extra);
            }
            seen.push(Seen {
                index: c.index,
                deadline_index: c.deadline_index,
                deadline: c.deadline,
                woke: c.woke,
                latency_ns: c.wakeup_latency_ns,
                skipped_before: c.skipped_before,
                checked_at,
                step_end: MonoTime::now(),
            });
            ControlFlow::Continue(())
        });
        let report = result.map(|end| rl_rt::LoopReport {
            stats: stats.clone(),
            end,
            policy: OverrunPolicy::Skip,
            start: start_guess,
            finished: MonoTime::now(),
            counters: None,
        });
        (report, seen, stats)
    })
}

fn no_injection(_: u64) -> Duration {
    Duration::ZERO
}

#[test]
fn one_kilohertz_loop_keeps_count_grid_and_consistent_stats() {
    const N: u64 = 1500;
    let period = Duration::from_millis(1);
    let t0 = Instant::now();
    let looped = CyclicLoop::new(period).expect("valid").max_cycles(N);
    let (report, seen, stats) = record(looped, N as usize, no_injection);
    let elapsed = t0.elapsed();
    let report = report.expect("loop runs");
    assert_eq!(report.end, LoopEnd::CycleLimit);
    assert_eq!(stats.cycles(), N);
    assert_eq!(seen.len() as u64, N);

    // The grid: every deadline is deadline_0 + k * period exactly, k only grows, never early.
    let d0 = seen[0].deadline;
    let mut prev_k = None;
    for s in &seen {
        let expected = d0.as_nanos() + (s.deadline_index - seen[0].deadline_index) * 1_000_000;
        assert_eq!(
            s.deadline.as_nanos(),
            expected,
            "cycle {} off the grid",
            s.index
        );
        assert!(
            prev_k.is_none_or(|k| s.deadline_index > k),
            "deadline index must grow"
        );
        prev_k = Some(s.deadline_index);
        assert!(
            s.woke >= s.deadline,
            "cycle {} woke before its deadline",
            s.index
        );
        assert!(s.checked_at >= s.woke);
        assert_eq!(s.latency_ns, s.woke.nanos_since(s.deadline));
    }
    assert_eq!(
        seen.iter().map(|s| s.index).collect::<Vec<_>>(),
        (0..N).collect::<Vec<_>>()
    );
    // Deadlines skipped are exactly the gaps in the grid indices.
    let last = seen[seen.len() - 1];
    assert_eq!(last.deadline_index - (N - 1), stats.missed_deadlines);
    assert_eq!(
        seen.iter().map(|s| s.skipped_before).sum::<u64>(),
        stats.missed_deadlines
    );
    // No drift: the run took at least as long as its grid says (relative sleeps would take
    // longer still; absolute ones cannot finish early).
    let grid_ns = (last.deadline_index + 1) * 1_000_000;
    assert!(
        elapsed.as_nanos() >= u128::from(grid_ns),
        "{elapsed:?} shorter than the grid"
    );

    // Statistics agree with a recomputation from what the steps saw.
    let lat: Vec<u64> = seen.iter().map(|s| s.latency_ns).collect();
    let w = stats.wakeup.summary();
    assert_eq!(w.count, N);
    assert_eq!(w.min_ns, *lat.iter().min().expect("samples"));
    assert_eq!(w.max_ns, *lat.iter().max().expect("samples"));
    assert_eq!(w.mean_ns, lat.iter().sum::<u64>() / N);
    let mut sorted = lat.clone();
    sorted.sort_unstable();
    let p99_rank = (0.99 * N as f64).ceil() as usize; // 1-based
    assert_eq!(
        w.p99_ns / 1000,
        (sorted[p99_rank - 1] / 1000).max(w.min_ns / 1000)
    );
    assert!(w.min_ns <= w.p50_ns && w.p50_ns <= w.p99_ns && w.p99_ns <= w.p999_ns);
    assert!(w.p999_ns <= w.p9999_ns && w.p9999_ns <= w.max_ns);
    assert!(w.min_ns <= w.mean_ns && w.mean_ns <= w.max_ns);
    assert_eq!(
        stats.wakeup.bins().iter().sum::<u64>() + stats.wakeup.overflow(),
        N
    );
    assert_eq!(stats.step.count(), N);
    // Each step's duration was measured after it returned, so it covers our recorded span.
    let longest_seen_step = seen
        .iter()
        .map(|s| s.step_end.nanos_since(s.woke))
        .max()
        .unwrap_or(0);
    assert!(stats.step.max_ns().expect("samples") >= longest_seen_step);
    eprintln!("1 kHz x {N}: {stats}");
}

fn sleep_35ms_at_5(index: u64) -> Duration {
    if index == 5 {
        Duration::from_millis(35)
    } else {
        Duration::ZERO
    }
}

const PERIOD_10MS: Duration = Duration::from_millis(10);

#[test]
fn overrun_skip_jumps_to_the_next_future_deadline() {
    let looped = CyclicLoop::new(PERIOD_10MS)
        .expect("valid")
        .max_cycles(10)
        .overrun_policy(OverrunPolicy::Skip);
    let (report, seen, stats) = record(looped, 10, sleep_35ms_at_5);
    assert_eq!(report.expect("skip keeps running").end, LoopEnd::CycleLimit);
    assert_eq!(stats.cycles(), 10, "cycles run, not deadlines passed");
    assert!(stats.overruns >= 1);
    let (late, after) = (seen[5], seen[6]);
    // The step of cycle 5 ended >= 35 ms after its deadline: deadlines 6, 7, 8 are gone.
    assert!(after.skipped_before >= 3, "{after:?}");
    assert!(after.deadline_index >= late.deadline_index + 4);
    assert!(
        after.deadline > late.step_end,
        "resumed on a deadline still ahead"
    );
    assert!(stats.missed_deadlines >= 3);
    assert!(
        stats.overrun_log().iter().any(|o| o.cycle == 5),
        "{:?}",
        stats.overrun_log()
    );
    assert!(after.latency_ns < PERIOD_10MS.as_nanos() as u64 || stats.overruns > 1);
}

#[test]
fn overrun_catch_up_runs_every_deadline_late() {
    let looped = CyclicLoop::new(PERIOD_10MS)
        .expect("valid")
        .max_cycles(10)
        .overrun_policy(OverrunPolicy::CatchUp);
    let (report, seen, stats) = record(looped, 10, sleep_35ms_at_5);
    assert_eq!(
        report.expect("catch-up keeps running").end,
        LoopEnd::CycleLimit
    );
    assert_eq!(stats.missed_deadlines, 0);
    assert!(
        seen.iter().all(|s| s.deadline_index == s.index),
        "no deadline skipped"
    );
    assert!(stats.overruns >= 1);
    // Cycle 6 was due 10 ms after cycle 5 but could only start after its 35 ms step.
    assert!(seen[6].latency_ns >= 25_000_000, "{:?}", seen[6]);
    assert!(seen[7].latency_ns >= 15_000_000, "{:?}", seen[7]);
}

#[test]
fn overrun_stop_ends_with_an_error_and_keeps_the_stats() {
    let looped = CyclicLoop::new(PERIOD_10MS)
        .expect("valid")
        .max_cycles(10)
        .overrun_policy(OverrunPolicy::Stop);
    let (report, seen, stats) = record(looped, 10, sleep_35ms_at_5);
    match report {
        Err(LoopError::Overrun { cycle, late_by_ns }) => {
            assert_eq!(cycle, 5);
            assert!(late_by_ns >= 25_000_000, "late by {late_by_ns} ns");
            let text = LoopError::Overrun { cycle, late_by_ns }.to_string();
            assert!(text.contains("cycle 5 overran"), "{text}");
        }
        other => panic!("expected an overrun error, got {other:?}"),
    }
    assert_eq!(seen.len(), 6);
    assert_eq!(
        stats.cycles(),
        6,
        "the overrunning cycle is in the statistics"
    );
    assert_eq!(stats.overruns, 1);
    assert_eq!(stats.overrun_log().len(), 1);
    assert_eq!(
        stats.overrun_log()[0].cycle,
        5,
        "the log names the cycle that overran"
    );
    assert!(stats.overrun_log()[0].late_by_ns >= 25_000_000);
}

#[test]
fn stop_flag_ends_the_loop_within_one_period() {
    let period = Duration::from_millis(20);
    let stop = StopFlag::new();
    let looped = CyclicLoop::new(period).expect("valid").stop_flag(&stop);
    let deadlines = Arc::new(Mutex::new(Vec::with_capacity(64)));
    let (d, s) = (Arc::clone(&deadlines), stop.clone());
    let runner = std::thread::spawn(move || {
        support::on_loop_thread(move || {
            looped.run(|c| {
                d.lock().expect("not poisoned").push(c.deadline);
                ControlFlow::Continue(())
            })
        })
    });
    std::thread::sleep(Duration::from_millis(110));
    s.request_stop();
    let requested = MonoTime::now();
    let report = runner.join().expect("runner").expect("loop ends cleanly");
    assert_eq!(report.end, LoopEnd::StopRequested);
    let deadlines = deadlines.lock().expect("not poisoned");
    assert!(deadlines.len() >= 2, "ran before the stop");
    assert_eq!(report.stats.cycles() as usize, deadlines.len());
    // No step ran for a deadline after the request.
    assert!(
        deadlines.iter().all(|&d| d <= requested),
        "a step ran after the stop request"
    );
    // It returned on the first wake-up after the request: at most one period later, plus the
    // wake-up latency (generous bound for a loaded shared VM).
    let stop_latency = report.finished.nanos_since(requested);
    eprintln!(
        "stop took {} µs after the request (period 20 ms)",
        stop_latency / 1000
    );
    assert!(
        stop_latency < 2 * period.as_nanos() as u64,
        "stop took {stop_latency} ns"
    );
}

#[test]
fn a_phase_shift_moves_the_grid_and_keeps_the_period() {
    let period = Duration::from_millis(4);
    let phase = rl_rt::PhaseShift::new();
    let looped = CyclicLoop::new(period)
        .expect("valid")
        .max_cycles(8)
        .phase_shift(&phase);
    let (deadlines, report) = support::on_loop_thread(move || {
        let mut deadlines = Vec::with_capacity(8);
        let report = looped.run(|c| {
            deadlines.push(c.deadline);
            if c.index == 3 {
                phase.shift(1_500_000);
            }
            if c.index == 5 {
                phase.shift(-500_000);
            }
            ControlFlow::Continue(())
        });
        (deadlines, report)
    });
    assert_eq!(report.expect("runs").stats.cycles(), 8);
    let gaps: Vec<u64> = deadlines
        .windows(2)
        .map(|w| w[1].nanos_since(w[0]))
        .collect();
    assert_eq!(
        gaps,
        [
            4_000_000, 4_000_000, 4_000_000, 5_500_000, 4_000_000, 3_500_000, 4_000_000
        ]
    );
}
