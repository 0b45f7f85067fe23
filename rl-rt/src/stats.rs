//! Allocation-free latency statistics: a fixed histogram of 1 µs bins, like cyclictest's `-h`.
//!
//! The bins are allocated once when a [`Histogram`] is made; [`Histogram::record`] only
//! increments counters, so it is safe to call every cycle of a real-time loop. Min, max and
//! mean are exact (nanoseconds); percentiles have the bin resolution (1 µs), and a percentile
//! that falls beyond the histogram's range is reported as the exact maximum, an upper bound,
//! with the overflow count alongside so the reader knows.

use core::fmt;
use std::io;

/// Nanoseconds per histogram bin: 1 µs, cyclictest's resolution.
pub const BIN_NS: u64 = 1_000;

/// Why two statistics cannot be merged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StatsError {
    /// The histograms cover different ranges (in µs), so their bins do not line up.
    RangeMismatch {
        /// Range of the histogram merged into.
        ours_us: usize,
        /// Range of the histogram merged from.
        theirs_us: usize,
    },
}

impl fmt::Display for StatsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::RangeMismatch { ours_us, theirs_us } => write!(
                f,
                "cannot merge histograms of different range ({ours_us} µs and {theirs_us} µs); \
                 make both with the same range"
            ),
        }
    }
}

impl std::error::Error for StatsError {}

/// A latency histogram with 1 µs bins from 0 to its range, plus an overflow count.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Histogram {
    bins: Box<[u64]>,
    overflow: u64,
    count: u64,
    sum_ns: u128,
    min_ns: u64,
    max_ns: u64,
}

impl Histogram {
    /// A histogram with `range_us` bins of 1 µs (at least one); samples of `range_us` µs or more
    /// go to the overflow count. Allocates the bins here, never afterwards.
    pub fn new(range_us: usize) -> Self {
        Self {
            bins: vec![0; range_us.max(1)].into_boxed_slice(),
            overflow: 0,
            count: 0,
            sum_ns: 0,
            min_ns: u64::MAX,
            max_ns: 0,
        }
    }

    /// Adds one sample in nanoseconds. Allocation-free, O(1).
    #[inline]
    pub fn record(&mut self, ns: u64) {
        let bin = ns / BIN_NS;
        match usize::try_from(bin).ok().and_then(|b| self.bins.get_mut(b)) {
            Some(slot) => *slot += 1,
            None => self.overflow += 1,
        }
        self.count += 1;
        self.sum_ns += u128::from(ns);
        self.min_ns = self.min_ns.min(ns);
        self.max_ns = self.max_ns.max(ns);
    }

    /// Forgets all samples, keeping the bins' storage.
    pub fn clear(&mut self) {
        self.bins.fill(0);
        self.overflow = 0;
        self.count = 0;
        self.sum_ns = 0;
        self.min_ns = u64::MAX;
        self.max_ns = 0;
    }

    /// Adds all samples of `other`, which must have the same range.
    pub fn merge(&mut self, other: &Histogram) -> Result<(), StatsError> {
        if self.bins.len() != other.bins.len() {
            return Err(StatsError::RangeMismatch {
                ours_us: self.bins.len(),
                theirs_us: other.bins.len(),
            });
        }
        for (a, b) in self.bins.iter_mut().zip(other.bins.iter()) {
            *a += *b;
        }
        self.overflow += other.overflow;
        self.count += other.count;
        self.sum_ns += other.sum_ns;
        self.min_ns = self.min_ns.min(other.min_ns);
        self.max_ns = self.max_ns.max(other.max_ns);
        Ok(())
    }

    /// The range in µs: samples at or beyond it are counted as overflow.
    pub fn range_us(&self) -> usize {
        self.bins.len()
    }

    /// The bin counts; bin `i` holds samples from `i` µs up to `i + 1` µs.
    pub fn bins(&self) -> &[u64] {
        &self.bins
    }

    /// Number of samples.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Number of samples at or beyond the range.
    pub fn overflow(&self) -> u64 {
        self.overflow
    }

    /// Smallest sample in ns, `None` without samples.
    pub fn min_ns(&self) -> Option<u64> {
        (self.count > 0).then_some(self.min_ns)
    }

    /// Largest sample in ns, `None` without samples.
    pub fn max_ns(&self) -> Option<u64> {
        (self.count > 0).then_some(self.max_ns)
    }

    /// Arithmetic mean in ns (rounded down), `None` without samples.
    pub fn mean_ns(&self) -> Option<u64> {
        if self.count == 0 {
            return None;
        }
        u64::try_from(self.sum_ns / u128::from(self.count)).ok()
    }

    /// The `q`-quantile (`q` in 0..=1, e.g. 0.999) in ns at 1 µs resolution: the lower edge of
    /// the bin holding the sample of rank ⌈q·count⌉, clamped into [min, max] so percentiles
    /// and extremes stay ordered. If that sample lies in the overflow, returns the exact max
    /// (an upper bound). `None` without samples.
    pub fn quantile_ns(&self, q: f64) -> Option<u64> {
        if self.count == 0 {
            return None;
        }
        let q = if q.is_nan() { 1.0 } else { q.clamp(0.0, 1.0) };
        // Rank of the wanted sample, 1-based; f64 holds counts up to 2^53 exactly.
        let rank = ((q * self.count as f64).ceil() as u64).clamp(1, self.count);
        let mut seen = 0u64;
        for (bin, n) in self.bins.iter().enumerate() {
            seen += n;
            if seen >= rank {
                let edge = bin as u64 * BIN_NS;
                return Some(edge.clamp(self.min_ns, self.max_ns));
            }
        }
        Some(self.max_ns)
    }

    /// Min, mean, percentiles and max in one value.
    pub fn summary(&self) -> Summary {
        Summary {
            count: self.count,
            overflow: self.overflow,
            min_ns: self.min_ns().unwrap_or(0),
            mean_ns: self.mean_ns().unwrap_or(0),
            p50_ns: self.quantile_ns(0.50).unwrap_or(0),
            p99_ns: self.quantile_ns(0.99).unwrap_or(0),
            p999_ns: self.quantile_ns(0.999).unwrap_or(0),
            p9999_ns: self.quantile_ns(0.9999).unwrap_or(0),
            max_ns: self.max_ns().unwrap_or(0),
        }
    }

    /// Writes the histogram in cyclictest's `-h` output format (one thread), so tools made for
    /// cyclictest (and `scripts/jitter-vs-cyclictest`) read it unchanged. Values are whole µs,
    /// truncated as cyclictest does.
    pub fn write_cyclictest<W: io::Write>(&self, mut w: W) -> io::Result<()> {
        writeln!(w, "# Histogram")?;
        for (i, n) in self.bins.iter().enumerate() {
            writeln!(w, "{i:06} {n:06}")?;
        }
        let in_range: u64 = self.bins.iter().sum();
        let s = self.summary();
        writeln!(w, "# Total: {in_range:09}")?;
        writeln!(w, "# Min Latencies: {:05}", s.min_ns / BIN_NS)?;
        writeln!(w, "# Avg Latencies: {:05}", s.mean_ns / BIN_NS)?;
        writeln!(w, "# Max Latencies: {:05}", s.max_ns / BIN_NS)?;
        writeln!(w, "# Histogram Overflows: {:05}", self.overflow)?;
        writeln!(w, "# Histogram Overflow at cycle number:")?;
        writeln!(w, "# Thread 0:")?;
        Ok(())
    }
}

/// A histogram's figures, all in nanoseconds (percentiles at 1 µs resolution).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Number of samples.
    pub count: u64,
    /// Samples beyond the histogram's range (their percentiles are reported as `max_ns`).
    pub overflow: u64,
    /// Smallest sample.
    pub min_ns: u64,
    /// Mean, rounded down.
    pub mean_ns: u64,
    /// Median.
    pub p50_ns: u64,
    /// 99th percentile.
    pub p99_ns: u64,
    /// 99.9th percentile.
    pub p999_ns: u64,
    /// 99.99th percentile.
    pub p9999_ns: u64,
    /// Largest sample.
    pub max_ns: u64,
}

fn us(ns: u64) -> f64 {
    ns as f64 / 1_000.0
}

impl Summary {
    /// JSON object with the keys of `rl jitter --json`: `min_us`, `mean_us`, `p50_us`, `p99_us`,
    /// `p999_us`, `p9999_us`, `max_us` (µs with ns precision), plus `count` and `overflow`.
    pub fn to_json(&self) -> String {
        format!(
            "{{\"count\":{},\"overflow\":{},\"min_us\":{:.3},\"mean_us\":{:.3},\"p50_us\":{:.3},\
             \"p99_us\":{:.3},\"p999_us\":{:.3},\"p9999_us\":{:.3},\"max_us\":{:.3}}}",
            self.count,
            self.overflow,
            us(self.min_ns),
            us(self.mean_ns),
            us(self.p50_ns),
            us(self.p99_ns),
            us(self.p999_ns),
            us(self.p9999_ns),
            us(self.max_ns)
        )
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "n {}  min {:.1}  mean {:.1}  p50 {:.0}  p99 {:.0}  p99.9 {:.0}  p99.99 {:.0}  \
             max {:.1} µs",
            self.count,
            us(self.min_ns),
            us(self.mean_ns),
            us(self.p50_ns),
            us(self.p99_ns),
            us(self.p999_ns),
            us(self.p9999_ns),
            us(self.max_ns)
        )?;
        if self.overflow > 0 {
            write!(
                f,
                "  ({} beyond the histogram; percentiles there shown as max)",
                self.overflow
            )?;
        }
        Ok(())
    }
}

/// How many overruns a [`LoopStats`] remembers individually (the first ones); all are counted.
pub const OVERRUN_LOG_LEN: usize = 16;

/// One overrun: which cycle, and how far past the next deadline its step returned.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overrun {
    /// Index of the cycle (0-based, counting cycles run).
    pub cycle: u64,
    /// Lateness of the step's return after the next deadline, ns.
    pub late_by_ns: u64,
}

/// What a periodic loop measured: wake-up latency and step duration per cycle, overruns and
/// deadlines skipped. Mergeable, so per-run or per-thread statistics can be combined.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoopStats {
    /// Period of the loop in ns (0 when merged from loops of different periods).
    pub period_ns: u64,
    /// How late each cycle woke after its deadline.
    pub wakeup: Histogram,
    /// How long each step ran (from wake-up to the step's return).
    pub step: Histogram,
    /// Cycles whose step ended after the next deadline (or that woke after it).
    pub overruns: u64,
    /// Deadlines passed over without a cycle (overrun policy `Skip`).
    pub missed_deadlines: u64,
    overrun_log: [Overrun; OVERRUN_LOG_LEN],
    overrun_logged: usize,
}

impl LoopStats {
    /// Empty statistics for a loop of `period_ns` with histograms of `range_us` 1-µs bins.
    pub fn new(period_ns: u64, range_us: usize) -> Self {
        Self {
            period_ns,
            wakeup: Histogram::new(range_us),
            step: Histogram::new(range_us),
            overruns: 0,
            missed_deadlines: 0,
            overrun_log: [Overrun::default(); OVERRUN_LOG_LEN],
            overrun_logged: 0,
        }
    }

    /// Counts an overrun of `cycle` and remembers it if the log has room. Allocation-free.
    #[inline]
    pub fn record_overrun(&mut self, cycle: u64, late_by_ns: u64) {
        self.overruns += 1;
        self.log_overrun(Overrun { cycle, late_by_ns });
    }

    fn log_overrun(&mut self, overrun: Overrun) {
        if let Some(slot) = self.overrun_log.get_mut(self.overrun_logged) {
            *slot = overrun;
            self.overrun_logged += 1;
        }
    }

    /// The first [`OVERRUN_LOG_LEN`] overruns recorded with
    /// [`record_overrun`](Self::record_overrun): which cycles overran and by how much.
    pub fn overrun_log(&self) -> &[Overrun] {
        &self.overrun_log[..self.overrun_logged]
    }

    /// Cycles run (each has one wake-up and one step sample).
    pub fn cycles(&self) -> u64 {
        self.wakeup.count()
    }

    /// Records one cycle. Allocation-free.
    #[inline]
    pub fn record_cycle(&mut self, wakeup_latency_ns: u64, step_ns: u64) {
        self.wakeup.record(wakeup_latency_ns);
        self.step.record(step_ns);
    }

    /// Forgets all samples and counts, keeping storage.
    pub fn clear(&mut self) {
        self.wakeup.clear();
        self.step.clear();
        self.overruns = 0;
        self.missed_deadlines = 0;
        self.overrun_logged = 0;
    }

    /// Adds another loop's statistics (same histogram range).
    pub fn merge(&mut self, other: &LoopStats) -> Result<(), StatsError> {
        self.wakeup.merge(&other.wakeup)?;
        self.step.merge(&other.step)?;
        self.overruns += other.overruns;
        self.missed_deadlines += other.missed_deadlines;
        for &o in other.overrun_log() {
            self.log_overrun(o);
        }
        if self.period_ns != other.period_ns {
            self.period_ns = 0;
        }
        Ok(())
    }

    /// The whole record as JSON: `period_ns`, `cycles`, `overruns`, `missed_deadlines`,
    /// `overrun_log` (`[{cycle, late_by_us}]`), `wakeup` and `step` (each a
    /// [`Summary::to_json`] object).
    pub fn to_json(&self) -> String {
        let log: Vec<String> = self
            .overrun_log()
            .iter()
            .map(|o| {
                format!(
                    "{{\"cycle\":{},\"late_by_us\":{:.3}}}",
                    o.cycle,
                    us(o.late_by_ns)
                )
            })
            .collect();
        format!(
            "{{\"period_ns\":{},\"cycles\":{},\"overruns\":{},\"missed_deadlines\":{},\
             \"overrun_log\":[{}],\"wakeup\":{},\"step\":{}}}",
            self.period_ns,
            self.cycles(),
            self.overruns,
            self.missed_deadlines,
            log.join(","),
            self.wakeup.summary().to_json(),
            self.step.summary().to_json()
        )
    }
}

impl fmt::Display for LoopStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "cycles {}  period {} µs  overruns {}  missed deadlines {}",
            self.cycles(),
            us(self.period_ns),
            self.overruns,
            self.missed_deadlines
        )?;
        writeln!(f, "wake-up latency: {}", self.wakeup.summary())?;
        write!(f, "step duration:   {}", self.step.summary())?;
        if !self.overrun_log().is_empty() {
            write!(f, "\noverran (cycle: late by):")?;
            for o in self.overrun_log() {
                write!(f, " {}: {:.1} µs", o.cycle, us(o.late_by_ns))?;
            }
            if self.overruns > self.overrun_log().len() as u64 {
                write!(f, " ... ({} in all)", self.overruns)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_extremes_and_binned_percentiles() {
        let mut h = Histogram::new(100);
        // 1..=1000 ns in 1 ns steps would all land in bin 0; use µs-spread samples instead.
        for i in 1..=100u64 {
            h.record(i * 1_000 - 500); // 0.5 µs, 1.5 µs, ..., 99.5 µs
        }
        let s = h.summary();
        assert_eq!(s.count, 100);
        assert_eq!(s.min_ns, 500);
        assert_eq!(s.max_ns, 99_500);
        assert_eq!(s.mean_ns, 50_000);
        assert_eq!(s.p50_ns, 49_000, "50th sample is 49.5 µs, in bin 49");
        assert_eq!(s.p99_ns, 98_000);
        assert_eq!(
            s.p999_ns, 99_000,
            "rank ceil(99.9) = 100, the last sample, bin 99"
        );
        assert_eq!(s.overflow, 0);
        assert_eq!(h.bins().iter().sum::<u64>(), 100);
    }

    #[test]
    fn overflow_is_counted_and_percentile_falls_back_to_max() {
        let mut h = Histogram::new(10);
        for _ in 0..9 {
            h.record(3_000);
        }
        h.record(1_000_000); // 1 ms, beyond 10 µs
        assert_eq!(h.overflow(), 1);
        assert_eq!(h.quantile_ns(0.5), Some(3_000));
        assert_eq!(h.quantile_ns(0.99), Some(1_000_000));
        assert_eq!(h.bins().iter().sum::<u64>() + h.overflow(), h.count());
    }

    #[test]
    fn empty_histogram_has_no_figures() {
        let h = Histogram::new(10);
        assert_eq!(h.min_ns(), None);
        assert_eq!(h.quantile_ns(0.5), None);
        assert_eq!(h.summary(), Summary::default());
    }

    #[test]
    fn merge_adds_and_refuses_other_ranges() {
        let mut a = Histogram::new(50);
        let mut b = Histogram::new(50);
        a.record(2_000);
        b.record(40_000);
        b.record(60_000);
        a.merge(&b).expect("same range");
        assert_eq!(a.count(), 3);
        assert_eq!(a.overflow(), 1);
        assert_eq!(a.min_ns(), Some(2_000));
        assert_eq!(a.max_ns(), Some(60_000));
        let c = Histogram::new(10);
        assert_eq!(
            a.merge(&c),
            Err(StatsError::RangeMismatch {
                ours_us: 50,
                theirs_us: 10
            })
        );
    }

    #[test]
    fn cyclictest_format_round_trips_counts() {
        let mut h = Histogram::new(5);
        for ns in [1_200, 1_900, 3_100, 9_000] {
            h.record(ns);
        }
        let mut out = Vec::new();
        h.write_cyclictest(&mut out).expect("write to Vec");
        let text = String::from_utf8(out).expect("utf8");
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "# Histogram");
        assert_eq!(lines[1], "000000 000000");
        assert_eq!(lines[2], "000001 000002");
        assert_eq!(lines[4], "000003 000001");
        assert!(text.contains("# Total: 000000003\n"));
        assert!(text.contains("# Min Latencies: 00001\n"));
        assert!(text.contains("# Max Latencies: 00009\n"));
        assert!(text.contains("# Histogram Overflows: 00001\n"));
    }

    #[test]
    fn overrun_log_keeps_the_first_and_counts_all() {
        let mut s = LoopStats::new(1_000_000, 10);
        for cycle in 0..(OVERRUN_LOG_LEN as u64 + 4) {
            s.record_overrun(cycle * 10, 1_000);
        }
        assert_eq!(s.overruns, OVERRUN_LOG_LEN as u64 + 4);
        assert_eq!(s.overrun_log().len(), OVERRUN_LOG_LEN);
        assert_eq!(
            s.overrun_log()[3],
            Overrun {
                cycle: 30,
                late_by_ns: 1_000
            }
        );
        assert!(s.to_string().contains("(20 in all)"), "{s}");
        s.clear();
        assert!(s.overrun_log().is_empty());
    }

    #[test]
    fn loop_stats_merge_and_json() {
        let mut a = LoopStats::new(1_000_000, 100);
        a.record_cycle(5_000, 1_000);
        a.record_overrun(0, 1_500);
        let mut b = LoopStats::new(1_000_000, 100);
        b.record_cycle(7_000, 2_000);
        b.missed_deadlines = 3;
        a.merge(&b).expect("same range");
        assert_eq!(a.cycles(), 2);
        assert_eq!(
            (a.overruns, a.missed_deadlines, a.period_ns),
            (1, 3, 1_000_000)
        );
        let json = a.to_json();
        assert!(json.starts_with("{\"period_ns\":1000000,\"cycles\":2,\"overruns\":1,"));
        assert!(
            json.contains("\"overrun_log\":[{\"cycle\":0,\"late_by_us\":1.500}]"),
            "{json}"
        );
        assert!(json.contains("\"wakeup\":{\"count\":2,\"overflow\":0,\"min_us\":5.000,"));
        assert!(json.contains("\"max_us\":7.000"));
    }
}
