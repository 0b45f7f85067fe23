//! Linear search (RL's `LinearNearestNeighbors`): every point is compared with the query.

use super::{Best, NearestNeighbors, Neighbor, sorted};
use crate::space::JointSpace;

/// Points in insertion order.
#[derive(Clone, Debug)]
pub struct Linear {
    nq: usize,
    points: Vec<f64>,
    ids: Vec<usize>,
}

impl Linear {
    /// An empty set for `space`.
    pub fn new(space: &JointSpace) -> Self {
        Self {
            nq: space.nq(),
            points: Vec::new(),
            ids: Vec::new(),
        }
    }

    fn iter(&self) -> impl Iterator<Item = (&[f64], usize)> {
        self.points
            .chunks_exact(self.nq.max(1))
            .zip(self.ids.iter().copied())
    }
}

impl NearestNeighbors for Linear {
    fn insert(&mut self, _space: &JointSpace, id: usize, q: &[f64]) {
        self.points.extend_from_slice(&q[..self.nq]);
        self.ids.push(id);
    }

    fn nearest(&self, space: &JointSpace, q: &[f64], k: usize) -> Vec<Neighbor> {
        let mut best = Best::new(k);
        for (p, id) in self.iter() {
            best.offer(space.distance_squared(q, p), id);
        }
        best.into_neighbors()
    }

    fn within(&self, space: &JointSpace, q: &[f64], radius: f64) -> Vec<Neighbor> {
        let r2 = radius * radius;
        sorted(
            self.iter()
                .map(|(p, id)| (space.distance_squared(q, p), id))
                .filter(|&(d2, _)| d2 <= r2)
                .collect(),
        )
    }

    fn nearest_one(&self, space: &JointSpace, q: &[f64]) -> Option<Neighbor> {
        if space.is_plain() {
            // Plain Euclidean metric: a tight loop the compiler vectorises.
            let n = self.nq.max(1);
            let q = &q[..n];
            let mut best = (f64::INFINITY, usize::MAX);
            for (k, p) in self.points.chunks_exact(n).enumerate() {
                let mut d2 = 0.0;
                for (a, b) in p.iter().zip(q) {
                    d2 += (a - b) * (a - b);
                }
                if d2 < best.0 {
                    best = (d2, k);
                }
            }
            return (best.1 != usize::MAX).then(|| Neighbor {
                distance: best.0.sqrt(),
                id: self.ids[best.1],
            });
        }
        let mut best: Option<(f64, usize)> = None;
        for (p, id) in self.iter() {
            let d2 = space.distance_squared(q, p);
            if best.is_none_or(|(b, bid)| (d2, id) < (b, bid)) {
                best = Some((d2, id));
            }
        }
        best.map(|(d2, id)| Neighbor {
            distance: d2.sqrt(),
            id,
        })
    }

    fn len(&self) -> usize {
        self.ids.len()
    }

    fn clear(&mut self) {
        self.points.clear();
        self.ids.clear();
    }
}
