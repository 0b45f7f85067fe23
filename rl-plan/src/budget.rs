//! A time budget (and optional iteration cap) for every planning call: planners, samplers and
//! optimisers stop when it runs out instead of looping forever (RL's `duration`).

use std::time::{Duration, Instant};

/// When a call must stop.
#[derive(Clone, Copy, Debug)]
pub struct Budget {
    start: Instant,
    deadline: Instant,
    max_iterations: u64,
}

impl Budget {
    /// A budget of `time` from now, with no iteration cap.
    pub fn new(time: Duration) -> Self {
        let start = Instant::now();
        Self {
            start,
            deadline: start
                .checked_add(time)
                .unwrap_or(start + Duration::from_secs(86_400 * 365)),
            max_iterations: u64::MAX,
        }
    }

    /// The same budget with at most `n` planner iterations.
    pub fn with_max_iterations(mut self, n: u64) -> Self {
        self.max_iterations = n;
        self
    }

    /// Whether the time is up.
    #[inline]
    pub fn expired(&self) -> bool {
        Instant::now() >= self.deadline
    }

    /// Whether iteration `i` (0-based) may run: under the cap and, checked every fourth
    /// iteration (reading the clock costs tens of nanoseconds, a fast iteration well under a
    /// microsecond), within the time.
    #[inline]
    pub fn allows(&self, i: u64) -> bool {
        i < self.max_iterations && (i % 4 != 0 || !self.expired())
    }

    /// Time since the budget started.
    pub fn elapsed(&self) -> Duration {
        self.start.elapsed()
    }

    /// The iteration cap.
    pub fn max_iterations(&self) -> u64 {
        self.max_iterations
    }
}
