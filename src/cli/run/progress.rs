//! Progress while the loop runs: a live status line on a terminal, a plain line per second
//! otherwise; both on standard error, so standard output stays the report. The line itself is
//! [`super::super::progress::ProgressLine`], shared with the other subcommands.

use std::time::Duration;

pub use rl::controller::Progress;

use crate::cli::progress::ProgressLine;

/// Prints progress at a rate that suits where standard error goes.
pub struct ProgressDisplay {
    line: ProgressLine,
    plan_s: f64,
}

impl ProgressDisplay {
    /// A display for a plan of `plan_s` seconds.
    pub fn new(plan_s: f64) -> Self {
        Self {
            line: ProgressLine::stderr("rl run: ").with_piped_lines(Duration::from_secs(1)),
            plan_s,
        }
    }

    /// Shows `p` if it is time to.
    pub fn update(&mut self, p: &Progress, elapsed: Duration) {
        self.line.update_at(elapsed, || {
            // A law without a duration (streamed targets): the time alone.
            let of = if self.plan_s > 0.0 {
                format!("/{:.2}", self.plan_s)
            } else {
                String::new()
            };
            format!(
                "t {:5.2}{of} s  cycle {:6}  tracking error max {:7.3} mrad  worst latency {:7.1} µs  lost {}{}",
                p.time_s,
                p.cycle,
                p.error_max_rad * 1e3,
                p.worst_latency_ns as f64 / 1e3,
                p.lost,
                if p.halting { "  (stopping)" } else { "" }
            )
        });
    }

    /// Ends the live line.
    pub fn finish(&mut self) {
        self.line.finish();
    }
}
