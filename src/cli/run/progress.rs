//! Progress while the loop runs: a live status line on a terminal, a plain line per second
//! otherwise; both on standard error, so standard output stays the report.

use std::io::{IsTerminal, Write};
use std::time::Duration;

pub use rl::controller::Progress;

/// Prints progress at a rate that suits where standard error goes.
pub struct ProgressDisplay {
    tty: bool,
    plan_s: f64,
    next: Duration,
    shown: bool,
}

impl ProgressDisplay {
    /// A display for a plan of `plan_s` seconds.
    pub fn new(plan_s: f64) -> Self {
        Self {
            tty: std::io::stderr().is_terminal(),
            plan_s,
            next: Duration::ZERO,
            shown: false,
        }
    }

    /// Shows `p` if it is time to.
    pub fn update(&mut self, p: &Progress, elapsed: Duration) {
        if elapsed < self.next {
            return;
        }
        let line = format!(
            "t {:5.2}/{:.2} s  cycle {:6}  tracking error max {:7.3} mrad  worst latency {:7.1} µs  lost {}{}",
            p.time_s,
            self.plan_s,
            p.cycle,
            p.error_max_rad * 1e3,
            p.worst_latency_ns as f64 / 1e3,
            p.lost,
            if p.halting { "  (stopping)" } else { "" }
        );
        let mut err = std::io::stderr().lock();
        if self.tty {
            let _ = write!(err, "\r\x1b[2K{line}");
            let _ = err.flush();
            self.next = elapsed + Duration::from_millis(100);
        } else {
            let _ = writeln!(err, "rl run: {line}");
            self.next = elapsed + Duration::from_secs(1);
        }
        self.shown = true;
    }

    /// Ends the live line.
    pub fn finish(&mut self) {
        if self.tty && self.shown {
            eprintln!();
        }
    }
}
