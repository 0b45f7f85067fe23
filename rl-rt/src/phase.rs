//! Phase-locking a loop to an external clock: a [`PhaseShift`] moves a running
//! [`CyclicLoop`](crate::CyclicLoop)'s grid of deadlines by what the step asks for, so the loop
//! can follow a device that runs its own cycle (a robot controller that answers at its own
//! ticks) instead of drifting against it. The grid moves; the period stays. Lock-free and
//! allocation-free.

use core::sync::atomic::{AtomicI64, Ordering};
use std::sync::Arc;

/// A pending shift of a loop's deadlines, in nanoseconds (positive: later). Cloning shares it.
#[derive(Clone, Debug, Default)]
pub struct PhaseShift(Arc<AtomicI64>);

impl PhaseShift {
    /// No shift pending.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks for the loop's next deadlines to come `ns` nanoseconds later (earlier if
    /// negative); shifts add up until the loop applies them before its next deadline.
    #[inline]
    pub fn shift(&self, ns: i64) {
        self.0.fetch_add(ns, Ordering::AcqRel);
    }

    /// Takes the pending shift (the loop calls this once per cycle).
    #[inline]
    pub(crate) fn take(&self) -> i64 {
        self.0.swap(0, Ordering::AcqRel)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifts_add_up_until_taken() {
        let p = PhaseShift::new();
        let q = p.clone();
        p.shift(300);
        q.shift(-100);
        assert_eq!(p.take(), 200);
        assert_eq!(q.take(), 0);
    }
}
