//! Trajectory time, advanced one control period per cycle, and the controlled stop.
//!
//! Time advances by one period per executed cycle, not by wall time: a cycle that wakes late
//! or a deadline the loop skips slows the motion down instead of making the next commanded
//! step longer, so every step the robot is sent stays within the planned speed.
//!
//! A stop (Ctrl-C, or the end of `--duration`) does not cut the motion: the rate at which
//! trajectory time passes ramps from 1 to 0 along a half cosine over the halt time, so the arm
//! slows down on its path and comes to rest. With rate `r(t)` the commanded derivatives are
//! `q̇ = q'(τ)·r` and `q̈ = q''(τ)·r² + q'(τ)·ṙ`; the ramp is long enough that `|q'·ṙ|` stays
//! within the planned acceleration.

use core::f64::consts::PI;

/// Why the clock is bringing the motion to rest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HaltReason {
    /// Someone asked (Ctrl-C).
    Requested,
    /// The run's cycle budget (`--duration`) ends.
    CycleLimit,
    /// The supervisor found a fault that allows coming to rest.
    Fault,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Halt {
    reason: HaltReason,
    /// Cycles into the ramp.
    step: u64,
    /// Length of the ramp in cycles (0: stop at once).
    cycles: u64,
    /// Rate when the ramp began.
    from_rate: f64,
}

/// Trajectory time with a rate in `[0, 1]` that a halt ramps down to rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrajectoryClock {
    period_s: f64,
    duration_s: f64,
    halt_cycles: u64,
    cycle_limit: Option<u64>,
    cycle: u64,
    time_s: f64,
    rate: f64,
    rate_dot: f64,
    halt: Option<Halt>,
}

impl TrajectoryClock {
    /// A clock over a trajectory of `duration_s`, advancing `period_s` per cycle; halts take
    /// `halt_cycles`; with `cycle_limit` the run is at rest by cycle `cycle_limit - 1`.
    pub fn new(period_s: f64, duration_s: f64, halt_cycles: u64, cycle_limit: Option<u64>) -> Self {
        let mut clock = Self {
            period_s,
            duration_s,
            halt_cycles,
            cycle_limit,
            cycle: 0,
            time_s: 0.0,
            rate: 1.0,
            rate_dot: 0.0,
            halt: None,
        };
        clock.apply_cycle_limit();
        clock
    }

    /// Cycle index (0 for the first).
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// Trajectory time at this cycle, s.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Rate of trajectory time per wall time at this cycle.
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// Derivative of the rate, 1/s.
    pub fn rate_dot(&self) -> f64 {
        self.rate_dot
    }

    /// Why it is halting, if it is.
    pub fn halting(&self) -> Option<HaltReason> {
        self.halt.map(|h| h.reason)
    }

    /// Whether the motion is over: the trajectory's end is reached or a halt came to rest.
    pub fn is_finished(&self) -> bool {
        self.time_s >= self.duration_s || self.halt.is_some_and(|h| h.step >= h.cycles)
    }

    /// Starts a halt now (no effect if one is running).
    pub fn request_halt(&mut self) {
        self.begin_halt(HaltReason::Requested, self.halt_cycles);
    }

    /// Starts a halt now for `reason` (no effect if one is running).
    pub fn request_halt_for(&mut self, reason: HaltReason) {
        self.begin_halt(reason, self.halt_cycles);
    }

    fn begin_halt(&mut self, reason: HaltReason, cycles: u64) {
        if self.halt.is_none() {
            self.halt = Some(Halt {
                reason,
                step: 0,
                cycles,
                from_rate: self.rate,
            });
        }
    }

    /// With a cycle limit, starts the halt early enough to be at rest on the last cycle.
    fn apply_cycle_limit(&mut self) {
        if let Some(limit) = self.cycle_limit {
            let last = limit.saturating_sub(1);
            if self.cycle + self.halt_cycles >= last {
                self.begin_halt(HaltReason::CycleLimit, last.saturating_sub(self.cycle));
            }
        }
    }

    /// Moves to the next cycle.
    pub fn advance(&mut self) {
        let old_rate = self.rate;
        if let Some(h) = &mut self.halt {
            h.step = (h.step + 1).min(h.cycles);
            let (rate, rate_dot) = if h.cycles == 0 {
                (0.0, 0.0)
            } else {
                let x = PI * h.step as f64 / h.cycles as f64;
                let span = h.cycles as f64 * self.period_s;
                (
                    h.from_rate * 0.5 * (1.0 + x.cos()),
                    -h.from_rate * 0.5 * PI / span * x.sin(),
                )
            };
            self.rate = rate;
            self.rate_dot = rate_dot;
        }
        self.time_s =
            (self.time_s + 0.5 * (old_rate + self.rate) * self.period_s).min(self.duration_s);
        if self.halt.is_none() {
            // On the plain grid, exact multiples of the period (no accumulated rounding).
            self.time_s = ((self.cycle + 1) as f64 * self.period_s).min(self.duration_s);
        }
        self.cycle += 1;
        self.apply_cycle_limit();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_to_the_end_on_the_grid() {
        let mut c = TrajectoryClock::new(0.01, 0.1, 20, None);
        let mut n = 0;
        while !c.is_finished() {
            c.advance();
            n += 1;
        }
        assert_eq!(n, 10);
        assert_eq!(c.time_s(), 0.1);
    }

    #[test]
    fn a_halt_slows_to_rest_smoothly() {
        let mut c = TrajectoryClock::new(0.01, 100.0, 50, None);
        for _ in 0..10 {
            c.advance();
        }
        c.request_halt();
        let mut last = c.rate();
        let mut n = 0;
        while !c.is_finished() {
            c.advance();
            assert!(c.rate() <= last && c.rate_dot() <= 0.0);
            last = c.rate();
            n += 1;
        }
        assert_eq!(n, 50);
        assert_eq!(c.rate(), 0.0);
        // Trajectory time covered during the ramp: about half the ramp's length.
        assert!((c.time_s() - (0.1 + 0.25)).abs() < 0.01, "{}", c.time_s());
    }

    #[test]
    fn a_cycle_limit_is_at_rest_on_its_last_cycle() {
        let mut c = TrajectoryClock::new(0.01, 100.0, 30, Some(100));
        let mut cycles = 1;
        while !c.is_finished() {
            c.advance();
            cycles += 1;
        }
        assert_eq!(cycles, 100);
        assert_eq!(c.halting(), Some(HaltReason::CycleLimit));
        assert_eq!(c.rate(), 0.0);
        let mut short = TrajectoryClock::new(0.01, 100.0, 30, Some(1));
        assert!(short.is_finished());
        short.advance();
        assert!(short.is_finished());
    }
}
