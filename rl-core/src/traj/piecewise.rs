//! Piecewise composition in time: segments of any [`Trajectory`] one after another (a spline of
//! polynomials, a sequence of jerk-limited moves), with fixed capacity and a continuity check at
//! every boundary.

use heapless::Vec;

use super::{Discontinuity, Sample, Trajectory, TrajectoryError, clamp_time};

/// Up to `MAX` segments of type `F` played one after another; segment `i` starts when segment
/// `i - 1` ends. Evaluation finds the segment by binary search.
#[derive(Clone, Debug)]
pub struct Piecewise<F, const MAX: usize> {
    segments: Vec<F, MAX>,
    starts: [f64; MAX],
    duration: f64,
}

impl<F, const MAX: usize> Default for Piecewise<F, MAX> {
    fn default() -> Self {
        Self::new()
    }
}

impl<F, const MAX: usize> Piecewise<F, MAX> {
    /// An empty sequence (evaluates to zeros until a segment is pushed).
    pub const fn new() -> Self {
        Self {
            segments: Vec::new(),
            starts: [0.0; MAX],
            duration: 0.0,
        }
    }

    /// Number of segments.
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    /// `true` when there is no segment.
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// The segments in order.
    pub fn segments(&self) -> &[F] {
        &self.segments
    }

    /// Start time of each segment.
    pub fn starts(&self) -> &[f64] {
        &self.starts[..self.segments.len()]
    }

    /// Removes every segment.
    pub fn clear(&mut self) {
        self.segments.clear();
        self.duration = 0.0;
    }

    /// Appends a segment after the last one.
    pub fn push<const D: usize>(&mut self, segment: F) -> Result<(), TrajectoryError>
    where
        F: Trajectory<D>,
    {
        let d = segment.duration();
        if !d.is_finite() || d < 0.0 {
            return Err(TrajectoryError::BadDuration);
        }
        let index = self.segments.len();
        if self.segments.push(segment).is_err() {
            return Err(TrajectoryError::Capacity {
                capacity: MAX,
                requested: index + 1,
            });
        }
        self.starts[index] = self.duration;
        self.duration += d;
        Ok(())
    }

    /// Segment index and local time for `t`.
    #[inline]
    fn locate(&self, t: f64) -> Option<(&F, f64)> {
        let n = self.segments.len();
        if n == 0 {
            return None;
        }
        let t = clamp_time(t, self.duration);
        let i = self.starts[1..n].partition_point(|&s| s <= t);
        Some((&self.segments[i], t - self.starts[i]))
    }

    /// Checks derivatives `0..=max_order` of every axis at **every** boundary between segments.
    /// A jump may be at most `tolerance · (1 + m)`, where `m` is the largest magnitude of that
    /// derivative at the boundary and inside the two segments (at 70 % of the left one and 30 %
    /// of the right one, off the symmetric points where blend derivatives vanish): the scale of
    /// the quantity there, so rounding in steep segments is not taken for a jump. Returns the
    /// first jump found.
    pub fn check_continuity<const D: usize>(
        &self,
        max_order: usize,
        tolerance: f64,
    ) -> Result<(), Discontinuity>
    where
        F: Trajectory<D>,
    {
        for (boundary, pair) in self.segments.windows(2).enumerate() {
            let (a, b) = (&pair[0], &pair[1]);
            for order in 0..=max_order {
                let left = a.derivative(a.duration(), order);
                let right = b.derivative(0.0, order);
                let left_mid = a.derivative(0.7 * a.duration(), order);
                let right_mid = b.derivative(0.3 * b.duration(), order);
                for axis in 0..D {
                    let jump = right[axis] - left[axis];
                    let scale = libm::fabs(left[axis])
                        .max(libm::fabs(right[axis]))
                        .max(libm::fabs(left_mid[axis]))
                        .max(libm::fabs(right_mid[axis]));
                    if !(libm::fabs(jump) <= tolerance * (1.0 + scale)) {
                        return Err(Discontinuity {
                            boundary,
                            order,
                            axis,
                            jump,
                        });
                    }
                }
            }
        }
        Ok(())
    }
}

impl<const D: usize, F: Trajectory<D>, const MAX: usize> Trajectory<D> for Piecewise<F, MAX> {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; D] {
        match self.locate(t) {
            Some((f, local)) => f.derivative(local, order),
            None => [0.0; D],
        }
    }

    #[inline]
    fn sample(&self, t: f64) -> Sample<D> {
        match self.locate(t) {
            Some((f, local)) => f.sample(local),
            None => Sample {
                position: [0.0; D],
                velocity: [0.0; D],
                acceleration: [0.0; D],
                jerk: [0.0; D],
            },
        }
    }
}
