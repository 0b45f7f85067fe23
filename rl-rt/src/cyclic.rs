//! The periodic loop: wake on absolute deadlines, run a step, measure, handle overruns.
//!
//! Deadline `k` is `start + k · period`, computed in integer nanoseconds and slept to with
//! `clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)`, so lateness in one cycle never shifts
//! the next (no drift). Each cycle records its wake-up latency (woke − deadline) and the step's
//! duration (return − woke) in a [`LoopStats`]. A cycle *overruns* when its step returns after
//! the next deadline; the [`OverrunPolicy`] decides what happens then, and the statistics count
//! it either way.
//!
//! ```no_run
//! use std::ops::ControlFlow;
//! use std::time::Duration;
//! use rl_rt::{CyclicLoop, OverrunPolicy};
//!
//! let report = CyclicLoop::new(Duration::from_millis(1))?
//!     .overrun_policy(OverrunPolicy::Skip)
//!     .max_cycles(1000)
//!     .run(|cycle| {
//!         // read sensors, compute, write actuators ...
//!         let _ = cycle.index;
//!         ControlFlow::Continue(())
//!     })?;
//! println!("{}", report.stats);
//! # Ok::<(), rl_rt::LoopError>(())
//! ```

use core::fmt;
use core::ops::ControlFlow;
use core::time::Duration;

use crate::clock::{MonoTime, duration_to_nanos};
use crate::phase::PhaseShift;
use crate::stats::LoopStats;
use crate::stop::StopFlag;
use crate::thread::ThreadCounters;
use nix::errno::Errno;

/// Default histogram range of a loop's statistics: 10 ms in 1 µs bins.
pub const DEFAULT_HISTOGRAM_RANGE_US: usize = 10_000;

/// What the loop does when a step returns after the next deadline.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum OverrunPolicy {
    /// Pass over every deadline already gone and wake at the first future one, as cyclictest
    /// does. Cycles stay on the grid; the skipped deadlines are counted as missed.
    #[default]
    Skip,
    /// Run a cycle for every deadline, late ones back to back, until the loop has caught up.
    /// No deadline is missed, but the late cycles show large wake-up latencies.
    CatchUp,
    /// End the loop with [`LoopError::Overrun`].
    Stop,
}

impl fmt::Display for OverrunPolicy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Skip => "skip",
            Self::CatchUp => "catch-up",
            Self::Stop => "stop",
        })
    }
}

/// What the step is told about the cycle it runs in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cycle {
    /// Cycles run before this one (0 for the first).
    pub index: u64,
    /// Number of this cycle's deadline on the grid (`deadline = start + deadline_index ·
    /// period`); ahead of `index` by the deadlines skipped so far.
    pub deadline_index: u64,
    /// The absolute deadline this cycle was due at.
    pub deadline: MonoTime,
    /// When the loop woke for it.
    pub woke: MonoTime,
    /// `woke − deadline` in ns.
    pub wakeup_latency_ns: u64,
    /// Deadlines skipped right before this cycle (policy [`OverrunPolicy::Skip`]).
    pub skipped_before: u64,
}

/// Why a loop ended normally.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoopEnd {
    /// It ran the number of cycles set by [`CyclicLoop::max_cycles`].
    CycleLimit,
    /// Its [`StopFlag`] was raised.
    StopRequested,
    /// The step returned [`ControlFlow::Break`].
    StepBreak,
}

/// Why a loop could not run or ended abnormally.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoopError {
    /// The period is zero or too long to express in `u64` nanoseconds.
    InvalidPeriod {
        /// The period given.
        period: Duration,
    },
    /// The statistics handed to [`CyclicLoop::run_into`] were not made for this loop.
    StatsMismatch,
    /// A step overran under [`OverrunPolicy::Stop`].
    Overrun {
        /// Index of the cycle that overran.
        cycle: u64,
        /// How far past the next deadline its step returned, in ns.
        late_by_ns: u64,
    },
    /// `clock_nanosleep` failed (it does not for valid input; reported, not hidden).
    Sleep(Errno),
    /// The deadline grid ran past the end of `u64` nanoseconds.
    TimeOverflow,
}

impl fmt::Display for LoopError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::InvalidPeriod { period } => write!(
                f,
                "invalid loop period {period:?}: it must be above zero and below 584 years"
            ),
            Self::StatsMismatch => f.write_str(
                "the statistics passed to run_into were made for another period; \
                 make them with CyclicLoop::new_stats",
            ),
            Self::Overrun { cycle, late_by_ns } => write!(
                f,
                "cycle {cycle} overran: its step returned {:.1} µs after the next deadline \
                 (overrun policy `stop`; use `skip` or `catch-up` to continue, or shorten the step)",
                *late_by_ns as f64 / 1_000.0
            ),
            Self::Sleep(e) => write!(
                f,
                "clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME) failed: {e}"
            ),
            Self::TimeOverflow => f.write_str("the loop's deadlines overflowed u64 nanoseconds"),
        }
    }
}

impl std::error::Error for LoopError {}

/// The result of a finished loop.
#[derive(Clone, Debug)]
pub struct LoopReport {
    /// Wake-up latency, step duration, overruns and missed deadlines.
    pub stats: LoopStats,
    /// Why the loop ended.
    pub end: LoopEnd,
    /// The overrun policy it ran with.
    pub policy: OverrunPolicy,
    /// Deadline 0 of the grid.
    pub start: MonoTime,
    /// When the loop returned.
    pub finished: MonoTime,
    /// Page faults and context switches of the loop's thread during the run (`None` if
    /// `getrusage` failed). On a tuned machine: no faults, no involuntary switches, and one
    /// voluntary switch per cycle (the sleep).
    pub counters: Option<ThreadCounters>,
}

/// A periodic loop on absolute deadlines. Configure with the builder methods, then [`run`]
/// (allocates its statistics once) or [`run_into`] (allocates nothing).
///
/// [`run`]: CyclicLoop::run
/// [`run_into`]: CyclicLoop::run_into
#[derive(Clone, Debug)]
pub struct CyclicLoop {
    period_ns: u64,
    policy: OverrunPolicy,
    stop: Option<StopFlag>,
    phase: Option<PhaseShift>,
    max_cycles: Option<u64>,
    range_us: usize,
    start: Option<MonoTime>,
}

impl CyclicLoop {
    /// A loop with this period, overrun policy [`OverrunPolicy::Skip`], no cycle limit, no stop
    /// flag, and a 10 ms histogram range.
    pub fn new(period: Duration) -> Result<Self, LoopError> {
        let period_ns = duration_to_nanos(period)
            .filter(|&ns| ns > 0)
            .ok_or(LoopError::InvalidPeriod { period })?;
        Ok(Self {
            period_ns,
            policy: OverrunPolicy::default(),
            stop: None,
            phase: None,
            max_cycles: None,
            range_us: DEFAULT_HISTOGRAM_RANGE_US,
            start: None,
        })
    }

    /// The period.
    pub fn period(&self) -> Duration {
        Duration::from_nanos(self.period_ns)
    }

    /// What to do when a step returns after the next deadline.
    pub fn overrun_policy(mut self, policy: OverrunPolicy) -> Self {
        self.policy = policy;
        self
    }

    /// End the loop when `flag` is raised (checked on every wake-up, before the step).
    pub fn stop_flag(mut self, flag: &StopFlag) -> Self {
        self.stop = Some(flag.clone());
        self
    }

    /// Moves the grid of deadlines by what is asked through `phase` (applied before each
    /// next deadline), to phase-lock the loop to an external clock.
    pub fn phase_shift(mut self, phase: &PhaseShift) -> Self {
        self.phase = Some(phase.clone());
        self
    }

    /// End the loop after this many cycles.
    pub fn max_cycles(mut self, cycles: u64) -> Self {
        self.max_cycles = Some(cycles);
        self
    }

    /// Range of the statistics' histograms (1 µs bins; longer samples count as overflow).
    pub fn histogram_range(mut self, range: Duration) -> Self {
        self.range_us = usize::try_from(range.as_micros())
            .unwrap_or(usize::MAX)
            .max(1);
        self
    }

    /// Put deadline 0 at this absolute time (default: one period after the loop starts), e.g.
    /// to phase-align several loops.
    pub fn start_at(mut self, start: MonoTime) -> Self {
        self.start = Some(start);
        self
    }

    /// Empty statistics shaped for this loop, for [`run_into`](Self::run_into).
    pub fn new_stats(&self) -> LoopStats {
        LoopStats::new(self.period_ns, self.range_us)
    }

    /// Runs the loop, calling `step` once per cycle, until the cycle limit, the stop flag or
    /// the step's `Break`. Allocates its statistics before the first cycle, nothing after.
    pub fn run<F>(&self, step: F) -> Result<LoopReport, LoopError>
    where
        F: FnMut(&Cycle) -> ControlFlow<()>,
    {
        let mut stats = self.new_stats();
        let start = self.first_deadline()?;
        let before = ThreadCounters::current().ok();
        let end = self.run_from(start, &mut stats, step)?;
        let finished = MonoTime::now();
        let counters = before.and_then(|b| Some(ThreadCounters::current().ok()?.since(&b)));
        Ok(LoopReport {
            stats,
            end,
            policy: self.policy,
            start,
            finished,
            counters,
        })
    }

    /// Runs the loop like [`run`](Self::run), adding to `stats` (made by
    /// [`new_stats`](Self::new_stats)); allocates nothing. On an error the statistics up to
    /// that point stay in `stats`.
    pub fn run_into<F>(&self, stats: &mut LoopStats, step: F) -> Result<LoopEnd, LoopError>
    where
        F: FnMut(&Cycle) -> ControlFlow<()>,
    {
        if stats.period_ns != self.period_ns {
            return Err(LoopError::StatsMismatch);
        }
        let start = self.first_deadline()?;
        self.run_from(start, stats, step)
    }

    fn first_deadline(&self) -> Result<MonoTime, LoopError> {
        match self.start {
            Some(t) => Ok(t),
            None => MonoTime::now()
                .checked_add_nanos(self.period_ns)
                .ok_or(LoopError::TimeOverflow),
        }
    }

    fn deadline(&self, start: MonoTime, index: u64) -> Result<MonoTime, LoopError> {
        index
            .checked_mul(self.period_ns)
            .and_then(|offset| start.checked_add_nanos(offset))
            .ok_or(LoopError::TimeOverflow)
    }

    fn run_from<F>(
        &self,
        start: MonoTime,
        stats: &mut LoopStats,
        mut step: F,
    ) -> Result<LoopEnd, LoopError>
    where
        F: FnMut(&Cycle) -> ControlFlow<()>,
    {
        let stop_requested = || self.stop.as_ref().is_some_and(StopFlag::is_stop_requested);
        let mut start = start;
        let mut deadline_index = 0u64;
        let mut index = 0u64;
        let mut skipped_before = 0u64;
        loop {
            if self.max_cycles.is_some_and(|max| index >= max) {
                return Ok(LoopEnd::CycleLimit);
            }
            if stop_requested() {
                return Ok(LoopEnd::StopRequested);
            }
            if let Some(shift) = self.phase.as_ref().map(PhaseShift::take) {
                // The whole grid moves, so later deadlines stay a period apart.
                let moved = if shift >= 0 {
                    start.checked_add_nanos(shift.unsigned_abs())
                } else {
                    start
                        .as_nanos()
                        .checked_sub(shift.unsigned_abs())
                        .map(MonoTime::from_nanos)
                };
                start = moved.ok_or(LoopError::TimeOverflow)?;
            }
            let deadline = self.deadline(start, deadline_index)?;
            deadline.sleep_until().map_err(LoopError::Sleep)?;
            let woke = MonoTime::now();
            if stop_requested() {
                return Ok(LoopEnd::StopRequested);
            }
            let cycle = Cycle {
                index,
                deadline_index,
                deadline,
                woke,
                wakeup_latency_ns: woke.nanos_since(deadline),
                skipped_before,
            };
            let flow = step(&cycle);
            let done = MonoTime::now();
            stats.record_cycle(cycle.wakeup_latency_ns, done.nanos_since(woke));
            index += 1;
            skipped_before = 0;
            if flow.is_break() {
                return Ok(LoopEnd::StepBreak);
            }
            let next = deadline_index + 1;
            let next_deadline = self.deadline(start, next)?;
            if done <= next_deadline {
                deadline_index = next;
                continue;
            }
            stats.record_overrun(cycle.index, done.nanos_since(next_deadline));
            match self.policy {
                OverrunPolicy::Stop => {
                    return Err(LoopError::Overrun {
                        cycle: cycle.index,
                        late_by_ns: done.nanos_since(next_deadline),
                    });
                }
                OverrunPolicy::CatchUp => deadline_index = next,
                OverrunPolicy::Skip => {
                    // First grid point strictly after `done`.
                    let future = done.nanos_since(start) / self.period_ns + 1;
                    skipped_before = future - next;
                    stats.missed_deadlines += skipped_before;
                    deadline_index = future;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_period_is_refused() {
        assert_eq!(
            CyclicLoop::new(Duration::ZERO).err(),
            Some(LoopError::InvalidPeriod {
                period: Duration::ZERO
            })
        );
        assert!(CyclicLoop::new(Duration::MAX).is_err());
    }

    #[test]
    fn stats_of_another_period_are_refused() {
        let a = CyclicLoop::new(Duration::from_millis(1)).expect("valid");
        let b = CyclicLoop::new(Duration::from_millis(2)).expect("valid");
        let mut stats = b.new_stats();
        assert_eq!(
            a.run_into(&mut stats, |_| ControlFlow::Continue(())),
            Err(LoopError::StatsMismatch)
        );
    }

    #[test]
    fn break_ends_after_that_cycle() {
        let l = CyclicLoop::new(Duration::from_micros(200)).expect("valid");
        let report = l
            .run(|c| {
                if c.index == 4 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            })
            .expect("runs");
        assert_eq!(report.end, LoopEnd::StepBreak);
        assert_eq!(report.stats.cycles(), 5);
    }
}
