//! Edge verifiers (RL's `Verifier`): whether the straight motion between two valid
//! configurations stays valid, checked at points no more than `delta` apart in the space's
//! metric.
//!
//! An edge of length `d` is cut into `n = ⌈d / delta⌉` steps; the interior points
//! `t = j / n, j = 1 … n−1` are checked (the end points are valid by assumption, as in RL),
//! plus the end `t = 1` when asked (an RRT's new vertex). The two verifiers differ only in the
//! order of the points:
//!
//! - [`sequential`]: from the start to the end (RL's `SequentialVerifier`);
//! - [`recursive`]: bisection, the midpoint first, then the quarter points, … (RL's
//!   `RecursiveVerifier`), which finds a collision in the middle of an edge sooner.
//!
//! Points go to the checker in batches of its [`Validity::lanes`] (one for a mesh checker,
//! eight for the SIMD sphere checker), in that order, so a batch is spread over the whole edge
//! and the check stops at the first batch that holds an invalid point.

pub mod recursive;
pub mod sequential;

use crate::space::JointSpace;
use crate::validity::Validity;

/// The order in which an edge's points are checked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// Start to end.
    Sequential,
    /// Bisection.
    Recursive,
}

/// An edge verifier: an order and a resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verifier {
    /// The order of the points.
    pub order: Order,
    /// The largest distance between checked points (in the space's metric).
    pub delta: f64,
}

/// Step counts up to which bisection orders are kept.
const MAX_CACHED_STEPS: usize = 4096;

/// Reusable buffers of a verifier (so verifying allocates only while they grow).
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    ts: Vec<f64>,
    queue: std::collections::VecDeque<(usize, usize)>,
    q: Vec<f64>,
    /// Bisection orders by step count, computed once each (`orders[n]`).
    orders: Vec<Vec<f64>>,
}

impl Verifier {
    /// A sequential verifier of resolution `delta`.
    pub fn sequential(delta: f64) -> Self {
        Self {
            order: Order::Sequential,
            delta,
        }
    }

    /// A recursive (bisection) verifier of resolution `delta`.
    pub fn recursive(delta: f64) -> Self {
        Self {
            order: Order::Recursive,
            delta,
        }
    }

    /// The number of steps an edge of length `d` is cut into (at least 1).
    #[inline]
    pub fn steps(&self, d: f64) -> usize {
        if d.is_finite() && d > 0.0 {
            ((d / self.delta).ceil() as usize).max(1)
        } else {
            1
        }
    }

    /// The fractions `t` an edge of length `d` is checked at, in this verifier's order (with
    /// `t = 1` first when `include_end`).
    pub fn fractions(&self, d: f64, include_end: bool, scratch: &mut Scratch) -> usize {
        let n = self.steps(d);
        scratch.ts.clear();
        if include_end {
            scratch.ts.push(1.0);
        }
        match self.order {
            Order::Sequential => sequential::fractions(n, &mut scratch.ts),
            Order::Recursive if n <= MAX_CACHED_STEPS => {
                if scratch.orders.len() <= n {
                    scratch.orders.resize(n + 1, Vec::new());
                }
                if n >= 2 && scratch.orders[n].is_empty() {
                    let mut order = Vec::with_capacity(n);
                    recursive::fractions(n, &mut order, &mut scratch.queue);
                    scratch.orders[n] = order;
                }
                scratch.ts.extend_from_slice(&scratch.orders[n]);
            }
            Order::Recursive => recursive::fractions(n, &mut scratch.ts, &mut scratch.queue),
        }
        scratch.ts.len()
    }

    /// Whether the motion from `a` to `b` is valid: every point of [`Verifier::fractions`]
    /// passes `validity` (the end `b` too when `include_end`).
    pub fn is_valid(
        &self,
        space: &JointSpace,
        validity: &mut dyn Validity,
        (a, b): (&[f64], &[f64]),
        include_end: bool,
        scratch: &mut Scratch,
    ) -> bool {
        self.fractions(space.distance(a, b), include_end, scratch);
        let lanes = validity.lanes().max(1);
        let Scratch { ts, q, .. } = scratch;
        ts.chunks(lanes)
            .all(|batch| validity.segment_valid(space, a, b, batch, q))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::space::Topology;
    use crate::validity::FnValidity;

    fn line() -> JointSpace {
        JointSpace::new(vec![(
            "x".into(),
            Topology::Interval {
                lower: 0.0,
                upper: 10.0,
            },
        )])
        .unwrap()
    }

    #[test]
    fn both_orders_check_the_same_points_at_the_resolution() {
        let mut s = Scratch::default();
        for order in [Order::Sequential, Order::Recursive] {
            let v = Verifier { order, delta: 0.1 };
            for d in [0.05, 0.1, 0.25, 1.0, 3.33] {
                let n = v.steps(d);
                assert!(d / n as f64 <= 0.1 + 1e-12);
                v.fractions(d, false, &mut s);
                let mut ts = s.ts.clone();
                ts.sort_by(f64::total_cmp);
                let want: Vec<f64> = (1..n).map(|j| j as f64 / n as f64).collect();
                assert_eq!(ts, want, "{order:?} d={d}");
            }
        }
        let v = Verifier::recursive(0.1);
        v.fractions(1.0, true, &mut s);
        assert_eq!(&s.ts[..2], &[1.0, 0.5]);
    }

    #[test]
    fn an_obstacle_between_samples_wider_than_delta_is_found() {
        // Invalid region [4.00, 4.12): wider than delta = 0.1, so some point lands in it.
        let space = line();
        let mut s = Scratch::default();
        for order in [Order::Sequential, Order::Recursive] {
            let v = Verifier { order, delta: 0.1 };
            let mut check = FnValidity::new(|q: &[f64]| !(4.0..4.12).contains(&q[0]));
            assert!(!v.is_valid(&space, &mut check, (&[1.0], &[9.0]), false, &mut s));
            assert!(v.is_valid(&space, &mut check, (&[5.0], &[9.0]), true, &mut s));
        }
    }
}
