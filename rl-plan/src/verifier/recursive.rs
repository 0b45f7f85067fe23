//! The bisection order (RL's `RecursiveVerifier`): the middle interior point first, then the
//! middles of the two halves, breadth first, so the first points checked are spread over the
//! whole edge.

use std::collections::VecDeque;

/// Appends `j / n` for `j = 1 … n−1` in breadth-first bisection order.
pub fn fractions(n: usize, out: &mut Vec<f64>, queue: &mut VecDeque<(usize, usize)>) {
    if n < 2 {
        return;
    }
    queue.clear();
    queue.push_back((1, n - 1));
    while let Some((lo, hi)) = queue.pop_front() {
        let mid = (lo + hi) / 2;
        out.push(mid as f64 / n as f64);
        if lo < mid {
            queue.push_back((lo, mid - 1));
        }
        if mid < hi {
            queue.push_back((mid + 1, hi));
        }
    }
}
