//! Summary statistics as pandas' `describe` computes them (VAMP's table): mean, sample
//! standard deviation, min, quartiles and 95th percentile by linear interpolation between
//! order statistics, max.

/// Summary of a sample.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Summary {
    /// Number of values.
    pub count: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (n − 1).
    pub std: f64,
    /// Smallest.
    pub min: f64,
    /// 25th percentile.
    pub q25: f64,
    /// Median.
    pub median: f64,
    /// 75th percentile.
    pub q75: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Largest.
    pub max: f64,
}

/// The `p`-quantile of sorted `v` (linear interpolation, pandas' default).
pub fn quantile(v: &[f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let h = (v.len() - 1) as f64 * p;
    let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
    v[lo] + (h - lo as f64) * (v[hi] - v[lo])
}

impl Summary {
    /// The summary of `values` (NaN fields when empty).
    pub fn of(values: &[f64]) -> Self {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n == 0 {
            return Self {
                count: 0,
                mean: f64::NAN,
                std: f64::NAN,
                min: f64::NAN,
                q25: f64::NAN,
                median: f64::NAN,
                q75: f64::NAN,
                p95: f64::NAN,
                max: f64::NAN,
            };
        }
        let mean = v.iter().sum::<f64>() / n as f64;
        let var = if n > 1 {
            v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64
        } else {
            0.0
        };
        Self {
            count: n,
            mean,
            std: var.sqrt(),
            min: v[0],
            q25: quantile(&v, 0.25),
            median: quantile(&v, 0.5),
            q75: quantile(&v, 0.75),
            p95: quantile(&v, 0.95),
            max: v[n - 1],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_pandas_describe() {
        // pandas: pd.Series([1, 2, 3, 4, 10]).describe(percentiles=[.25, .5, .75, .95])
        let s = Summary::of(&[4.0, 1.0, 10.0, 2.0, 3.0]);
        assert_eq!(s.count, 5);
        assert_eq!(s.mean, 4.0);
        assert!((s.std - 3.535_533_905_932_738).abs() < 1e-12);
        assert_eq!(
            (s.min, s.q25, s.median, s.q75, s.max),
            (1.0, 2.0, 3.0, 4.0, 10.0)
        );
        assert!((s.p95 - 8.8).abs() < 1e-12);
        assert!(Summary::of(&[]).mean.is_nan());
    }
}
