//! A time budget (and optional iteration cap) for every planning call: planners, samplers and
//! optimisers stop when it runs out instead of looping forever (RL's `duration`). A [`Cancel`]
//! ends it early from another thread (a controller's Ctrl-C while it plans).

use std::fmt;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A request to end planning early, asked by a predicate another thread can make true (e.g. a
/// stop flag raised by Ctrl-C). A cancelled budget counts as expired, so every loop that keeps
/// its budget ends within one of its iterations.
#[derive(Clone)]
pub struct Cancel(Arc<dyn Fn() -> bool + Send + Sync>);

impl Cancel {
    /// Cancels once `requested` returns `true` (it is called about every fourth iteration: keep
    /// it to an atomic load).
    pub fn when(requested: impl Fn() -> bool + Send + Sync + 'static) -> Self {
        Self(Arc::new(requested))
    }

    /// Whether cancelling was requested.
    #[inline]
    pub fn is_requested(&self) -> bool {
        (self.0)()
    }
}

impl fmt::Debug for Cancel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("Cancel").field(&self.is_requested()).finish()
    }
}

/// When a call must stop.
#[derive(Clone, Debug)]
pub struct Budget {
    start: Instant,
    deadline: Instant,
    max_iterations: u64,
    cancel: Option<Cancel>,
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
            cancel: None,
        }
    }

    /// The same budget, ended early when `cancel` is requested.
    pub fn with_cancel(mut self, cancel: Option<Cancel>) -> Self {
        self.cancel = cancel;
        self
    }

    /// Whether it was cancelled.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.as_ref().is_some_and(Cancel::is_requested)
    }

    /// The same budget with at most `n` planner iterations.
    pub fn with_max_iterations(mut self, n: u64) -> Self {
        self.max_iterations = n;
        self
    }

    /// Whether the time is up (or the budget was cancelled).
    #[inline]
    pub fn expired(&self) -> bool {
        Instant::now() >= self.deadline || self.is_cancelled()
    }

    /// Whether iteration `i` (0-based) may run: under the cap and, checked every fourth
    /// iteration (reading the clock costs tens of nanoseconds, a fast iteration well under a
    /// microsecond), within the time.
    #[inline]
    pub fn allows(&self, i: u64) -> bool {
        i < self.max_iterations && (!i.is_multiple_of(4) || !self.expired())
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
