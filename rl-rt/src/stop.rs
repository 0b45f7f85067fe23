//! The two-level stop request a controller needs: the first request asks to come to rest (a
//! robot is brought to a standstill along its path), the second to stop now. [`StopFlag`] is
//! shared between threads by cloning; raising it is a single atomic operation, so a signal
//! watcher, a user interface or the real-time thread itself can raise it, and the real-time
//! thread reads it without a lock.
//!
//! ```
//! use rl_rt::{StopFlag, StopLevel};
//!
//! let stop = StopFlag::new();
//! assert_eq!(stop.level(), StopLevel::None);
//! stop.request_stop(); // Ctrl-C: come to rest
//! assert_eq!(stop.level(), StopLevel::Rest);
//! stop.request_stop(); // Ctrl-C again: stop now
//! assert_eq!(stop.level(), StopLevel::Now);
//! ```

use core::fmt;
use core::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

use nix::errno::Errno;

/// How urgently a stop was asked for, in increasing order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum StopLevel {
    /// No stop requested.
    #[default]
    None,
    /// Come to rest: finish the motion gently (a controller slows down along its path), then
    /// end.
    Rest,
    /// Stop now, without slowing down.
    Now,
}

impl StopLevel {
    const fn from_u8(v: u8) -> Self {
        match v {
            0 => StopLevel::None,
            1 => StopLevel::Rest,
            _ => StopLevel::Now,
        }
    }
}

impl fmt::Display for StopLevel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            StopLevel::None => "none",
            StopLevel::Rest => "come to rest",
            StopLevel::Now => "stop now",
        })
    }
}

/// A stop request another thread raises; a loop given the flag
/// ([`CyclicLoop::stop_flag`](crate::CyclicLoop::stop_flag)) ends on its next wake-up, so
/// within one period. Each [`request_stop`](Self::request_stop) raises the level by one
/// ([`StopLevel::Rest`], then [`StopLevel::Now`]). Cloning shares the flag.
#[derive(Clone, Debug, Default)]
pub struct StopFlag(Arc<AtomicU8>);

impl StopFlag {
    /// A new, lowered flag.
    pub fn new() -> Self {
        Self::default()
    }

    /// Raises the request by one level: the first call asks to come to rest, the second (and
    /// any later one) to stop now. Returns the level now in force.
    pub fn request_stop(&self) -> StopLevel {
        let before = self
            .0
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |v| {
                Some(v.saturating_add(1).min(2))
            })
            .unwrap_or(2);
        StopLevel::from_u8(before.saturating_add(1))
    }

    /// Raises the request to at least `level` (never lowers it).
    pub fn request(&self, level: StopLevel) {
        self.0.fetch_max(level as u8, Ordering::AcqRel);
    }

    /// The level requested so far.
    #[inline]
    pub fn level(&self) -> StopLevel {
        StopLevel::from_u8(self.0.load(Ordering::Acquire))
    }

    /// Whether any stop was requested.
    #[inline]
    pub fn is_stop_requested(&self) -> bool {
        self.level() != StopLevel::None
    }

    /// Raises this flag on SIGINT or SIGTERM (Ctrl-C, `kill`, systemd stop): the first signal
    /// asks to come to rest, the second to stop now, so a controller brings the arm to rest
    /// and reports instead of dying mid-cycle.
    ///
    /// Blocks both signals in the calling thread, and so in every thread it spawns afterwards
    /// (call it early in `main`, before starting the real-time thread); a small watcher thread
    /// takes them with `sigwait` until the level is [`StopLevel::Now`]. No signal handler runs,
    /// so nothing is interrupted.
    pub fn raise_on_termination_signals(&self) -> Result<std::thread::JoinHandle<()>, Errno> {
        use nix::sys::signal::{SigSet, Signal};
        let mut set = SigSet::empty();
        set.add(Signal::SIGINT);
        set.add(Signal::SIGTERM);
        set.thread_block()?;
        let flag = self.clone();
        std::thread::Builder::new()
            .name("rl-rt-signals".into())
            .stack_size(64 << 10)
            .spawn(move || {
                while flag.level() < StopLevel::Now {
                    if set.wait().is_err() {
                        return;
                    }
                    flag.request_stop();
                }
            })
            .map_err(|e| {
                e.raw_os_error()
                    .map_or(Errno::UnknownErrno, Errno::from_raw)
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_escalate_and_never_go_back() {
        let f = StopFlag::new();
        let shared = f.clone();
        assert!(!f.is_stop_requested());
        assert_eq!(shared.request_stop(), StopLevel::Rest);
        assert!(f.is_stop_requested());
        f.request(StopLevel::Rest);
        assert_eq!(f.level(), StopLevel::Rest);
        assert_eq!(f.request_stop(), StopLevel::Now);
        assert_eq!(f.request_stop(), StopLevel::Now);
        f.request(StopLevel::None);
        assert_eq!(shared.level(), StopLevel::Now);

        let g = StopFlag::new();
        g.request(StopLevel::Now);
        assert_eq!(g.level(), StopLevel::Now);
    }
}
