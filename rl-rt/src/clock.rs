//! Monotonic time as integer nanoseconds.
//!
//! Deadlines are computed as `start + n * period` in `u64` nanoseconds: no floating point and
//! no accumulated rounding, so a loop never drifts from its grid however long it runs.

use core::fmt;
use core::time::Duration;

use nix::errno::Errno;

use crate::sys;

/// A point on `CLOCK_MONOTONIC`, in nanoseconds since an arbitrary (boot-time) origin.
///
/// Unlike [`std::time::Instant`] its value is visible, so deadlines can be stored, compared
/// and printed exactly, and it is the clock `clock_nanosleep` sleeps on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MonoTime(u64);

impl MonoTime {
    /// The current time on `CLOCK_MONOTONIC`. Allocation-free, never fails.
    #[inline]
    pub fn now() -> Self {
        Self(sys::monotonic_ns())
    }

    /// The time `nanos` nanoseconds after the clock's origin.
    pub const fn from_nanos(nanos: u64) -> Self {
        Self(nanos)
    }

    /// Nanoseconds since the clock's origin.
    pub const fn as_nanos(self) -> u64 {
        self.0
    }

    /// `self + nanos`, or `None` if that would overflow (after ~584 years of uptime).
    pub const fn checked_add_nanos(self, nanos: u64) -> Option<Self> {
        match self.0.checked_add(nanos) {
            Some(t) => Some(Self(t)),
            None => None,
        }
    }

    /// Nanoseconds from `earlier` to `self`, 0 if `earlier` is later.
    pub const fn nanos_since(self, earlier: Self) -> u64 {
        self.0.saturating_sub(earlier.0)
    }

    /// The span from `earlier` to `self` as a [`Duration`], zero if `earlier` is later.
    pub const fn duration_since(self, earlier: Self) -> Duration {
        Duration::from_nanos(self.nanos_since(earlier))
    }

    /// Sleeps until this absolute time with `clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)`.
    /// Returns at once if the time has passed; restarts after signals.
    pub fn sleep_until(self) -> Result<(), Errno> {
        sys::sleep_until_monotonic_ns(self.0)
    }
}

impl fmt::Display for MonoTime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}.{:09} s",
            self.0 / 1_000_000_000,
            self.0 % 1_000_000_000
        )
    }
}

/// A [`Duration`] as whole nanoseconds, or `None` if it does not fit a `u64` (> 584 years).
pub fn duration_to_nanos(d: Duration) -> Option<u64> {
    u64::try_from(d.as_nanos()).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn now_is_monotonic_and_sleep_until_is_never_early() {
        let a = MonoTime::now();
        let target = a.checked_add_nanos(2_000_000).expect("no overflow");
        target.sleep_until().expect("clock_nanosleep");
        let b = MonoTime::now();
        assert!(b >= target, "woke at {b}, before the deadline {target}");
        assert!(b.nanos_since(a) >= 2_000_000);
        assert_eq!(a.nanos_since(b), 0, "saturates instead of wrapping");
    }

    #[test]
    fn past_deadline_returns_at_once() {
        let past = MonoTime::from_nanos(1);
        past.sleep_until().expect("a past deadline is not an error");
    }

    #[test]
    fn arithmetic_is_exact_and_checked() {
        let t = MonoTime::from_nanos(1_500_000_001);
        assert_eq!(t.to_string(), "1.500000001 s");
        assert_eq!(MonoTime::from_nanos(u64::MAX).checked_add_nanos(1), None);
        assert_eq!(duration_to_nanos(Duration::from_micros(250)), Some(250_000));
        assert_eq!(duration_to_nanos(Duration::MAX), None);
    }
}
