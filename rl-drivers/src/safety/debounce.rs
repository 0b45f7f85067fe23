//! Cycle-count debouncing of one input with different delays for opening and closing
//! ([`DebounceConfig`]). `no_std`, no allocation, no panics.

use super::config::DebounceConfig;

/// The debounced state of one input. It starts **open**: a chain knows nothing before it has
/// read the input closed for `close_cycles` cycles, and so does not allow motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Debouncer {
    closed: bool,
    /// Consecutive readings that disagree with `closed`.
    disagreeing: u16,
    open_cycles: u16,
    close_cycles: u16,
}

impl Debouncer {
    /// An open input debounced after `config` (0 cycles are read as 1).
    pub const fn new(config: DebounceConfig) -> Self {
        Self {
            closed: false,
            disagreeing: 0,
            open_cycles: if config.open_cycles == 0 {
                1
            } else {
                config.open_cycles
            },
            close_cycles: if config.close_cycles == 0 {
                1
            } else {
                config.close_cycles
            },
        }
    }

    /// Feeds one reading (`true` = closed) and returns the debounced state.
    pub fn update(&mut self, closed_now: bool) -> bool {
        if closed_now == self.closed {
            self.disagreeing = 0;
            return self.closed;
        }
        self.disagreeing = self.disagreeing.saturating_add(1);
        let needed = if closed_now {
            self.close_cycles
        } else {
            self.open_cycles
        };
        if self.disagreeing >= needed {
            self.closed = closed_now;
            self.disagreeing = 0;
        }
        self.closed
    }

    /// The debounced state: `true` = closed.
    pub const fn is_closed(&self) -> bool {
        self.closed
    }

    /// Forces the debounced state to open (after a fresh reading found the input open).
    pub fn force_open(&mut self) {
        self.closed = false;
        self.disagreeing = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn debouncer(open_cycles: u16, close_cycles: u16) -> Debouncer {
        Debouncer::new(DebounceConfig {
            open_cycles,
            close_cycles,
        })
    }

    #[test]
    fn starts_open_and_closes_after_close_cycles() {
        let mut d = debouncer(1, 3);
        assert!(!d.is_closed());
        assert!(!d.update(true));
        assert!(!d.update(true));
        assert!(d.update(true));
    }

    #[test]
    fn opens_at_once_with_one_open_cycle() {
        let mut d = debouncer(1, 1);
        assert!(d.update(true));
        assert!(!d.update(false));
    }

    #[test]
    fn a_one_cycle_glitch_is_ridden_out_with_two_open_cycles() {
        let mut d = debouncer(2, 1);
        assert!(d.update(true));
        assert!(d.update(false)); // glitch
        assert!(d.update(true)); // count restarts
        assert!(d.update(false));
        assert!(!d.update(false)); // two in a row: open
    }

    #[test]
    fn a_bounce_restarts_the_close_count() {
        let mut d = debouncer(1, 3);
        d.update(true);
        d.update(true);
        d.update(false); // bounce
        d.update(true);
        d.update(true);
        assert!(!d.is_closed());
        assert!(d.update(true));
    }

    #[test]
    fn zero_cycles_are_read_as_one() {
        let mut d = debouncer(0, 0);
        assert!(d.update(true));
        assert!(!d.update(false));
    }
}
