//! How well the robot followed: tracking error per joint (max and RMS), peak feed-forward
//! torque per joint, and limit checks of the measured motion. Allocation-free.

use super::DEFAULT_JOINTS;

/// A limit the measured motion crossed (the first one is kept).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Violation {
    /// Cycle it happened in.
    pub cycle: u64,
    /// Joint index.
    pub joint: usize,
    /// `"position"` or `"speed"`.
    pub quantity: &'static str,
    /// The measured value (position, or speed from two consecutive fresh measurements).
    pub value: f64,
    /// The limit.
    pub limit: f64,
}

/// Tracking and limit statistics of a run for up to `J` joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tracking<const J: usize = DEFAULT_JOINTS> {
    dof: usize,
    samples: u64,
    max_abs: [f64; J],
    sum_sq: [f64; J],
    last: [f64; J],
    peak_feed_forward: [f64; J],
    violations: u64,
    first_violation: Option<Violation>,
}

impl<const J: usize> Tracking<J> {
    /// Empty statistics for `dof` joints.
    pub fn new(dof: usize) -> Self {
        Self {
            dof: dof.min(J),
            samples: 0,
            max_abs: [0.0; J],
            sum_sq: [0.0; J],
            last: [0.0; J],
            peak_feed_forward: [0.0; J],
            violations: 0,
            first_violation: None,
        }
    }

    /// Records one cycle's error `commanded − measured`.
    #[inline]
    pub fn record_error(&mut self, commanded: &[f64], measured: &[f64]) {
        for k in 0..self.dof {
            let e = commanded[k] - measured[k];
            self.last[k] = e;
            self.max_abs[k] = self.max_abs[k].max(e.abs());
            self.sum_sq[k] += e * e;
        }
        self.samples += 1;
    }

    /// Records the feed-forward torques of one cycle.
    #[inline]
    pub fn record_feed_forward(&mut self, tau: &[f64]) {
        for (peak, t) in self.peak_feed_forward[..self.dof].iter_mut().zip(tau) {
            *peak = peak.max(t.abs());
        }
    }

    /// Counts a crossed limit.
    #[inline]
    pub fn record_violation(&mut self, v: Violation) {
        self.violations += 1;
        if self.first_violation.is_none() {
            self.first_violation = Some(v);
        }
    }

    /// Joints.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Cycles recorded.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Largest absolute error per joint.
    pub fn max_per_joint(&self) -> &[f64] {
        &self.max_abs[..self.dof]
    }

    /// RMS error per joint.
    pub fn rms_per_joint(&self) -> [f64; J] {
        let n = self.samples.max(1) as f64;
        core::array::from_fn(|k| (self.sum_sq[k] / n).sqrt())
    }

    /// Largest absolute error of any joint.
    pub fn max_error(&self) -> f64 {
        self.max_per_joint().iter().fold(0.0, |a, &b| a.max(b))
    }

    /// RMS error over all joints and cycles.
    pub fn rms_error(&self) -> f64 {
        let n = (self.samples.max(1) * self.dof.max(1) as u64) as f64;
        (self.sum_sq[..self.dof].iter().sum::<f64>() / n).sqrt()
    }

    /// Error of the last cycle per joint.
    pub fn last_error(&self) -> &[f64] {
        &self.last[..self.dof]
    }

    /// Largest absolute feed-forward torque per joint (N·m or N).
    pub fn peak_feed_forward(&self) -> &[f64] {
        &self.peak_feed_forward[..self.dof]
    }

    /// Limits crossed by the measured motion.
    pub fn violations(&self) -> u64 {
        self.violations
    }

    /// The first crossed limit.
    pub fn first_violation(&self) -> Option<Violation> {
        self.first_violation
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_and_rms_per_joint() {
        let mut t = Tracking::<8>::new(2);
        t.record_error(&[1.0, 0.0], &[0.0, 0.0]);
        t.record_error(&[0.0, 0.0], &[1.0, 0.5]);
        assert_eq!(t.max_per_joint(), &[1.0, 0.5]);
        assert_eq!(t.rms_per_joint()[0], 1.0);
        assert!((t.rms_per_joint()[1] - (0.125f64).sqrt()).abs() < 1e-15);
        assert_eq!(t.max_error(), 1.0);
        assert!((t.rms_error() - (2.25f64 / 4.0).sqrt()).abs() < 1e-15);
    }
}
