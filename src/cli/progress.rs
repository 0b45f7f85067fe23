//! Progress of long work on standard error, in one place for every subcommand (`rl run`, `rl
//! plan`'s certification, `rl plan bench`, `rl scene bench`, `rl jitter`).
//!
//! On a terminal, one line updated in place (`\r`, the line cleared, the new text) at most
//! every [`LIVE_INTERVAL`]; when standard error is not a terminal (a pipe, a file, a test
//! harness), nothing — unless the command asks for a plain line every so often
//! ([`ProgressLine::with_piped_lines`], `rl run`'s one line per second). Standard output is
//! never touched, so it stays the command's result.
//!
//! The computations do not print: they take a callback (or report steps) and the command turns
//! what it is told into a line here. The clock is the caller's (`update_at` takes the elapsed
//! time), so the throttling is tested without waiting.

use std::io::{self, IsTerminal, Write};
use std::time::{Duration, Instant};

/// How often a live line is redrawn at most.
pub const LIVE_INTERVAL: Duration = Duration::from_millis(100);

/// A throttled progress line (see the module docs).
pub struct ProgressLine<W: Write = io::Stderr> {
    out: W,
    /// Standard error is a terminal: one line redrawn in place.
    live: bool,
    /// Not a terminal: a plain line this often, starting with `prefix` (`None`: quiet).
    piped_every: Option<Duration>,
    prefix: &'static str,
    /// The earliest elapsed time of the next line.
    next: Duration,
    /// A live line is on the screen.
    shown: bool,
    started: Instant,
}

impl ProgressLine<io::Stderr> {
    /// Progress on standard error: live on a terminal, quiet otherwise. `prefix` (e.g.
    /// `"rl plan: "`) starts every line.
    pub fn stderr(prefix: &'static str) -> Self {
        Self::new(io::stderr(), io::stderr().is_terminal(), prefix)
    }
}

impl<W: Write> ProgressLine<W> {
    /// Progress written to `out`, live (a terminal) or not.
    pub fn new(out: W, live: bool, prefix: &'static str) -> Self {
        Self {
            out,
            live,
            piped_every: None,
            prefix,
            next: Duration::ZERO,
            shown: false,
            started: Instant::now(),
        }
    }

    /// When not live, a plain line every `every` instead of nothing.
    pub fn with_piped_lines(mut self, every: Duration) -> Self {
        self.piped_every = Some(every);
        self
    }

    /// Whether anything will ever be written (callers may skip work that only feeds the line).
    pub fn is_active(&self) -> bool {
        self.live || self.piped_every.is_some()
    }

    /// Shows `line()` if it is time to, by the clock of this line.
    pub fn update(&mut self, line: impl FnOnce() -> String) {
        let now = self.started.elapsed();
        self.update_at(now, line);
    }

    /// Shows `line()` if it is time to at `elapsed` (the caller's clock); `line` is called only
    /// then.
    pub fn update_at(&mut self, elapsed: Duration, line: impl FnOnce() -> String) {
        let every = match (self.live, self.piped_every) {
            (true, _) => LIVE_INTERVAL,
            (false, Some(every)) => every,
            (false, None) => return,
        };
        if elapsed < self.next {
            return;
        }
        self.next = elapsed + every;
        let text = line();
        // Progress that cannot be shown must not stop the work.
        let _ = if self.live {
            self.shown = true;
            write!(self.out, "\r\x1b[2K{}{text}", self.prefix)
        } else {
            writeln!(self.out, "{}{text}", self.prefix)
        };
        let _ = self.out.flush();
    }

    /// Ends a live line, leaving its last text on the screen.
    pub fn finish(&mut self) {
        if self.live && self.shown {
            let _ = writeln!(self.out);
            let _ = self.out.flush();
            self.shown = false;
        }
    }

    /// Erases a live line (the command's own output follows).
    pub fn clear(&mut self) {
        if self.live && self.shown {
            let _ = write!(self.out, "\r\x1b[2K");
            let _ = self.out.flush();
            self.shown = false;
        }
    }
}

impl<W: Write> Drop for ProgressLine<W> {
    /// A live line left on the screen is erased, so that an error message after it starts on
    /// a clean line.
    fn drop(&mut self) {
        self.clear();
    }
}

/// `done` of `total` as `"12/40 (30 %)"`.
pub fn fraction(done: usize, total: usize) -> String {
    if total == 0 {
        return format!("{done}/0");
    }
    format!(
        "{done}/{total} ({:.0} %)",
        100.0 * done as f64 / total as f64
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    fn text(p: ProgressLine<Vec<u8>>) -> String {
        let mut p = std::mem::ManuallyDrop::new(p);
        let out = std::mem::take(&mut p.out);
        String::from_utf8(out).expect("utf-8")
    }

    #[test]
    fn live_lines_are_redrawn_in_place_at_most_every_100_ms() {
        let mut p = ProgressLine::new(Vec::new(), true, "rl x: ");
        let mut asked = 0;
        for t in [0, 30, 99, 100, 150, 250] {
            p.update_at(ms(t), || {
                asked += 1;
                format!("t {t}")
            });
        }
        // Shown at 0, 100 and 250 ms; the text is made only when shown.
        assert_eq!(asked, 3);
        p.finish();
        assert_eq!(
            text(p),
            "\r\x1b[2Krl x: t 0\r\x1b[2Krl x: t 100\r\x1b[2Krl x: t 250\n"
        );
    }

    #[test]
    fn nothing_when_piped_unless_asked() {
        let mut p = ProgressLine::new(Vec::new(), false, "rl x: ");
        assert!(!p.is_active());
        for t in 0..50 {
            p.update_at(ms(t * 100), || panic!("the line is not made when quiet"));
        }
        p.finish();
        p.clear();
        assert_eq!(text(p), "");
    }

    #[test]
    fn piped_lines_are_plain_and_spaced() {
        let mut p = ProgressLine::new(Vec::new(), false, "rl run: ").with_piped_lines(ms(1000));
        assert!(p.is_active());
        for t in [0, 500, 999, 1000, 1999, 2500] {
            p.update_at(ms(t), || format!("t {t}"));
        }
        p.finish();
        assert_eq!(text(p), "rl run: t 0\nrl run: t 1000\nrl run: t 2500\n");
    }

    #[test]
    fn clear_erases_and_drop_clears_a_live_line() {
        let mut p = ProgressLine::new(Vec::new(), true, "");
        p.update_at(ms(0), || "a".into());
        p.clear();
        p.clear();
        assert_eq!(text(p), "\r\x1b[2Ka\r\x1b[2K");
        let mut out = Vec::new();
        {
            let mut p = ProgressLine::new(&mut out, true, "");
            p.update_at(ms(0), || "b".into());
        }
        assert_eq!(
            String::from_utf8(out).expect("utf-8"),
            "\r\x1b[2Kb\r\x1b[2K"
        );
    }

    #[test]
    fn fractions() {
        assert_eq!(fraction(3, 12), "3/12 (25 %)");
        assert_eq!(fraction(0, 0), "0/0");
    }
}
