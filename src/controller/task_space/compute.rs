//! The law's compute time per cycle, in a fixed histogram (no allocation after construction).

/// Bin width, ns.
const BIN_NS: u64 = 100;
/// Bins: 0.1 µs each up to 1 ms.
const BINS: usize = 10_000;

/// Compute times per cycle: 0.1-µs bins up to 1 ms, and the longest.
#[derive(Clone, Debug)]
pub struct ComputeTimes {
    bins: Box<[u32; BINS]>,
    over: u64,
    count: u64,
    max_ns: u64,
}

impl Default for ComputeTimes {
    fn default() -> Self {
        Self::new()
    }
}

impl ComputeTimes {
    /// Empty (allocates its bins here, never afterwards).
    pub fn new() -> Self {
        Self {
            bins: Box::new([0; BINS]),
            over: 0,
            count: 0,
            max_ns: 0,
        }
    }

    /// Forgets every sample.
    pub fn clear(&mut self) {
        self.bins.fill(0);
        (self.over, self.count, self.max_ns) = (0, 0, 0);
    }

    /// Records one cycle of `ns`.
    pub fn record(&mut self, ns: u64) {
        match self.bins.get_mut((ns / BIN_NS) as usize) {
            Some(b) => *b = b.saturating_add(1),
            None => self.over += 1,
        }
        self.count += 1;
        self.max_ns = self.max_ns.max(ns);
    }

    /// Cycles recorded.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The `q` quantile, µs (the upper edge of its bin; the maximum beyond the bins), or `None`
    /// without samples.
    pub fn quantile_us(&self, q: f64) -> Option<f64> {
        if self.count == 0 {
            return None;
        }
        let rank = ((q.clamp(0.0, 1.0) * self.count as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, &b) in self.bins.iter().enumerate() {
            seen += u64::from(b);
            if seen >= rank {
                return Some(((i as u64 + 1) * BIN_NS).min(self.max_ns) as f64 / 1e3);
            }
        }
        Some(self.max_us())
    }

    /// The longest, µs.
    pub fn max_us(&self) -> f64 {
        self.max_ns as f64 / 1e3
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_come_from_the_bins_and_the_maximum_from_the_samples() {
        let mut c = ComputeTimes::new();
        assert_eq!(c.quantile_us(0.5), None);
        for ns in [1_000, 2_050, 2_060, 3_000, 2_000_000] {
            c.record(ns);
        }
        assert_eq!(c.count(), 5);
        assert_eq!(c.quantile_us(0.5), Some(2.1));
        assert_eq!(c.quantile_us(0.0), Some(1.1));
        assert_eq!(c.quantile_us(0.8), Some(3.1));
        // Beyond the bins: the maximum.
        assert_eq!(c.quantile_us(1.0), Some(2000.0));
        assert_eq!(c.max_us(), 2000.0);
        c.clear();
        assert_eq!(c.count(), 0);
    }
}
