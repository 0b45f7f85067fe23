//! One segment of a mixed piecewise trajectory: a jerk-limited move at rest
//! ([`JerkLimited`]) or a polynomial of degree at most six ([`Polynomial<D, 7>`], the lines
//! and blends of [`spline::linear_with_blends`](super::spline::linear_with_blends)), so one
//! [`Piecewise`](super::Piecewise) can stop at some waypoints and blend through others.
//!
//! Evaluation is one `match` and the segment's own evaluation: no allocation.

use super::{JerkLimited, Polynomial, Sample, Trajectory};

/// A jerk-limited move or a polynomial (degree ≤ 6), played as one segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Segment<const D: usize> {
    /// A time-optimal jerk-limited move from rest to rest.
    JerkLimited(JerkLimited<D>),
    /// A polynomial: a constant-velocity line or a blend between two lines.
    Polynomial(Polynomial<D, 7>),
}

impl<const D: usize> From<JerkLimited<D>> for Segment<D> {
    fn from(m: JerkLimited<D>) -> Self {
        Self::JerkLimited(m)
    }
}

impl<const D: usize> From<Polynomial<D, 7>> for Segment<D> {
    fn from(p: Polynomial<D, 7>) -> Self {
        Self::Polynomial(p)
    }
}

impl<const D: usize> Trajectory<D> for Segment<D> {
    fn duration(&self) -> f64 {
        match self {
            Self::JerkLimited(m) => m.duration(),
            Self::Polynomial(p) => p.duration(),
        }
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; D] {
        match self {
            Self::JerkLimited(m) => m.derivative(t, order),
            Self::Polynomial(p) => p.derivative(t, order),
        }
    }

    #[inline]
    fn sample(&self, t: f64) -> Sample<D> {
        match self {
            Self::JerkLimited(m) => m.sample(t),
            Self::Polynomial(p) => p.sample(t),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::traj::{Limits, Piecewise};

    #[test]
    fn a_mixed_sequence_evaluates_each_segment_and_is_continuous() {
        let m = JerkLimited::new([0.0, 0.0], [1.0, 0.5], &Limits::uniform(1.0, 2.0, 10.0))
            .expect("move");
        let hold = Polynomial::<2, 7>::constant([1.0, 0.5], 0.25).expect("hold");
        let mut p: Piecewise<Segment<2>, 4> = Piecewise::new();
        p.push(Segment::from(m)).expect("room");
        p.push(Segment::from(hold)).expect("room");
        assert!((p.duration() - (m.duration() + 0.25)).abs() < 1e-12);
        assert_eq!(
            p.position(0.3 * m.duration()),
            m.position(0.3 * m.duration())
        );
        assert_eq!(p.position(p.duration()), [1.0, 0.5]);
        // Position, velocity and acceleration (a jerk-limited move ends with a jerk step).
        p.check_continuity(2, 1e-9)
            .expect("continuous at the boundary");
    }
}
