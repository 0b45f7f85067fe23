//! The fast path's nearest-neighbour structure: a bucketed k-d tree over `f32` coordinates whose
//! leaves store their points coordinate by coordinate (structure of arrays), so a leaf's
//! [`BUCKET`] distances are computed in vector lanes — for spaces of intervals (weights
//! allowed), which is every arm of revolute and prismatic joints with limits.
//!
//! Grown by insertion: a point descends to its leaf; a full leaf splits at the median of its
//! widest coordinate. A query descends to the nearer side first and visits the other side only
//! when the box of that side can hold a closer point (the squared distance to a box is the sum
//! of per-axis squared gaps, and a split changes one of them: Arya & Mount's incremental
//! distance). Distances are compared in `f32` and ties broken by id, so the answer is the one a
//! linear `f32` scan gives (tested); the distance returned is recomputed in `f64` from the point
//! as inserted. Against linear search over `f64` the cost grows with the logarithm of the tree
//! instead of its size (VAMP uses nigh's GNAT for the same reason).

use super::{Best, NearestNeighbors, Neighbor, sorted};
use crate::error::PlanError;
use crate::space::{JointSpace, Topology};

/// Points per leaf (a multiple of 16, the widest vector of `f32`).
pub const BUCKET: usize = 32;

#[derive(Clone, Debug)]
enum Node {
    /// Leaf `i` of `leaves`.
    Leaf(u32),
    Split {
        axis: u32,
        value: f32,
        left: u32,
        right: u32,
    },
}

/// A leaf: blocks of [`BUCKET`] points (more than one block only when its points are all
/// equal and cannot be split), coordinate `d` of point `k` of block `b` at
/// `coords[(b * nq + d) * BUCKET + k]`.
#[derive(Clone, Debug)]
struct Leaf {
    coords: Vec<f32>,
    index: Vec<u32>,
}

/// The `f32` k-d tree (see the module docs).
#[derive(Clone, Debug)]
pub struct KdtreeF32 {
    nq: usize,
    /// Metric weight per coordinate (coordinates are stored multiplied by it).
    weight: Vec<f32>,
    /// The points as inserted (`f64`), for the returned distances.
    points: Vec<f64>,
    ids: Vec<usize>,
    nodes: Vec<Node>,
    leaves: Vec<Leaf>,
}

/// A leaf's squared distances to the scaled query `q`.
#[inline]
fn leaf_distances(coords: &[f32], nq: usize, q: &[f32], out: &mut [f32; BUCKET]) {
    *out = [0.0; BUCKET];
    for d in 0..nq {
        let col: &[f32; BUCKET] = coords[d * BUCKET..(d + 1) * BUCKET]
            .try_into()
            .expect("a leaf column holds BUCKET values");
        let x = q[d];
        for k in 0..BUCKET {
            let v = col[k] - x;
            out[k] += v * v;
        }
    }
}

impl KdtreeF32 {
    /// An empty tree for `space`: intervals only (circles and rotations: use
    /// [`super::Kdtree`] or [`super::Gnat`]).
    pub fn new(space: &JointSpace) -> Result<Self, PlanError> {
        if !space.is_vector()
            || space
                .coordinates()
                .iter()
                .any(|c| !matches!(c.topology, Topology::Interval { .. }))
        {
            return Err(PlanError::Unsupported(
                "the f32 k-d tree over circle or rotation coordinates; use the k-d tree or GNAT"
                    .into(),
            ));
        }
        Ok(Self {
            nq: space.nq(),
            weight: space
                .coordinates()
                .iter()
                .map(|c| c.weight as f32)
                .collect(),
            points: Vec::new(),
            ids: Vec::new(),
            nodes: vec![Node::Leaf(0)],
            leaves: vec![Leaf::new()],
        })
    }

    fn scaled(&self, q: &[f64], out: &mut [f32]) {
        for d in 0..self.nq {
            out[d] = q[d] as f32 * self.weight[d];
        }
    }

    /// Splits leaf `l` (node `n`) at the median of its widest coordinate; `false` when its
    /// points are all equal.
    fn split(&mut self, n: usize, l: usize) -> bool {
        let leaf = &self.leaves[l];
        let count = leaf.index.len();
        let mut best: Option<(f32, usize)> = None;
        for d in 0..self.nq {
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for k in 0..count {
                let x = leaf.get(self.nq, d, k);
                lo = lo.min(x);
                hi = hi.max(x);
            }
            if hi > lo && best.is_none_or(|(s, _)| hi - lo > s) {
                best = Some((hi - lo, d));
            }
        }
        let Some((_, axis)) = best else {
            return false;
        };
        let mut xs: Vec<f32> = (0..count).map(|k| leaf.get(self.nq, axis, k)).collect();
        xs.sort_by(f32::total_cmp);
        let mut value = xs[count / 2];
        if value <= xs[0] {
            value = *xs.iter().find(|&&x| x > xs[0]).expect("spread > 0");
        }
        let old = std::mem::replace(&mut self.leaves[l], Leaf::new());
        let right = self.leaves.len();
        self.leaves.push(Leaf::new());
        let mut p = vec![0.0f32; self.nq];
        for k in 0..count {
            for (d, x) in p.iter_mut().enumerate() {
                *x = old.get(self.nq, d, k);
            }
            let target = if p[axis] < value { l } else { right };
            self.leaves[target].push(&p, old.index[k]);
        }
        let (ln, rn) = (self.nodes.len() as u32, self.nodes.len() as u32 + 1);
        self.nodes.push(Node::Leaf(l as u32));
        self.nodes.push(Node::Leaf(right as u32));
        self.nodes[n] = Node::Split {
            axis: axis as u32,
            value,
            left: ln,
            right: rn,
        };
        true
    }

    /// Visits node `n` whose box is at squared distance `rd` from `q`: every point of a leaf
    /// goes to `v`, and a far side only when its box is within `v`'s bound.
    fn visit<V: Visitor>(&self, n: u32, rd: f32, q: &[f32], off: &mut [f32], v: &mut V) {
        match self.nodes[n as usize] {
            Node::Leaf(l) => {
                let leaf = &self.leaves[l as usize];
                let mut d2 = [0.0f32; BUCKET];
                let block = self.nq * BUCKET;
                for (b, index) in leaf.index.chunks(BUCKET).enumerate() {
                    leaf_distances(
                        &leaf.coords[b * block..(b + 1) * block],
                        self.nq,
                        q,
                        &mut d2,
                    );
                    for (k, &i) in index.iter().enumerate() {
                        v.found(d2[k], i);
                    }
                }
            }
            Node::Split {
                axis,
                value,
                left,
                right,
            } => {
                let a = axis as usize;
                let diff = q[a] - value;
                let (near, far) = if diff < 0.0 {
                    (left, right)
                } else {
                    (right, left)
                };
                self.visit(near, rd, q, off, v);
                let old = off[a];
                let rf = rd - old * old + diff * diff;
                if rf <= v.bound() {
                    off[a] = diff;
                    self.visit(far, rf, q, off, v);
                    off[a] = old;
                }
            }
        }
    }

    fn neighbor(&self, space: &JointSpace, q: &[f64], i: u32) -> Neighbor {
        let i = i as usize;
        Neighbor {
            distance: space.distance(q, &self.points[i * self.nq..(i + 1) * self.nq]),
            id: self.ids[i],
        }
    }
}

/// What a query keeps of the points it visits.
trait Visitor {
    /// Point `i` at squared distance `d2`.
    fn found(&mut self, d2: f32, i: u32);
    /// The squared distance a subtree's box must be within to be visited.
    fn bound(&self) -> f32;
}

/// The nearest point: (squared distance, index), ties to the smaller index.
struct One(f32, u32);

impl Visitor for One {
    #[inline]
    fn found(&mut self, d2: f32, i: u32) {
        if d2 < self.0 || (d2 == self.0 && i < self.1) {
            *self = One(d2, i);
        }
    }
    #[inline]
    fn bound(&self) -> f32 {
        self.0
    }
}

/// The `k` nearest points.
struct Nearest(Best);

impl Visitor for Nearest {
    fn found(&mut self, d2: f32, i: u32) {
        self.0.offer(f64::from(d2), i as usize);
    }
    fn bound(&self) -> f32 {
        self.0.bound() as f32
    }
}

/// Every point within a squared distance.
struct Within(f32, Vec<u32>);

impl Visitor for Within {
    fn found(&mut self, d2: f32, i: u32) {
        if d2 <= self.0 {
            self.1.push(i);
        }
    }
    fn bound(&self) -> f32 {
        self.0
    }
}

impl Leaf {
    fn new() -> Self {
        Self {
            coords: Vec::new(),
            index: Vec::with_capacity(BUCKET),
        }
    }

    /// Coordinate `d` of point `k`.
    #[inline]
    fn get(&self, nq: usize, d: usize, k: usize) -> f32 {
        self.coords[((k / BUCKET) * nq + d) * BUCKET + k % BUCKET]
    }

    fn push(&mut self, p: &[f32], i: u32) {
        let nq = p.len();
        let k = self.index.len();
        if k.is_multiple_of(BUCKET) {
            self.coords.resize(self.coords.len() + nq * BUCKET, 0.0);
        }
        for (d, &x) in p.iter().enumerate() {
            self.coords[((k / BUCKET) * nq + d) * BUCKET + k % BUCKET] = x;
        }
        self.index.push(i);
    }
}

impl NearestNeighbors for KdtreeF32 {
    fn insert(&mut self, _space: &JointSpace, id: usize, q: &[f64]) {
        let index = self.ids.len() as u32;
        self.points.extend_from_slice(&q[..self.nq]);
        self.ids.push(id);
        let mut buf = [0.0f32; 32];
        let mut heap = Vec::new();
        let p: &mut [f32] = if self.nq <= buf.len() {
            &mut buf[..self.nq]
        } else {
            heap.resize(self.nq, 0.0);
            &mut heap
        };
        self.scaled(q, p);
        let mut n = 0usize;
        loop {
            match self.nodes[n] {
                Node::Split {
                    axis,
                    value,
                    left,
                    right,
                } => {
                    n = if p[axis as usize] < value {
                        left
                    } else {
                        right
                    } as usize;
                }
                Node::Leaf(l) => {
                    let l = l as usize;
                    let len = self.leaves[l].index.len();
                    if len >= BUCKET && len.is_multiple_of(BUCKET) && self.split(n, l) {
                        continue;
                    }
                    self.leaves[l].push(p, index);
                    return;
                }
            }
        }
    }

    fn nearest(&self, space: &JointSpace, q: &[f64], k: usize) -> Vec<Neighbor> {
        let mut qs = vec![0.0f32; self.nq];
        self.scaled(q, &mut qs);
        let mut off = vec![0.0f32; self.nq];
        let mut v = Nearest(Best::new(k));
        self.visit(0, 0.0, &qs, &mut off, &mut v);
        let mut out: Vec<Neighbor> =
            v.0.into_neighbors()
                .into_iter()
                .map(|n| self.neighbor(space, q, n.id as u32))
                .collect();
        out.sort_by(|a, b| a.distance.total_cmp(&b.distance).then(a.id.cmp(&b.id)));
        out
    }

    fn within(&self, space: &JointSpace, q: &[f64], radius: f64) -> Vec<Neighbor> {
        let mut qs = vec![0.0f32; self.nq];
        self.scaled(q, &mut qs);
        let mut off = vec![0.0f32; self.nq];
        // Candidates by the f32 distance with a little slack, decided in f64.
        let mut v = Within((radius * radius) as f32 * (1.0 + 1e-5) + 1e-12, Vec::new());
        self.visit(0, 0.0, &qs, &mut off, &mut v);
        sorted(
            v.1.into_iter()
                .map(|i| self.neighbor(space, q, i))
                .filter(|n| n.distance <= radius)
                .map(|n| (n.distance * n.distance, n.id))
                .collect(),
        )
    }

    fn nearest_one(&self, space: &JointSpace, q: &[f64]) -> Option<Neighbor> {
        if self.ids.is_empty() {
            return None;
        }
        let mut qs = [0.0f32; 32];
        let mut off = [0.0f32; 32];
        if self.nq > qs.len() {
            return self.nearest(space, q, 1).first().copied();
        }
        self.scaled(q, &mut qs);
        let mut v = One(f32::INFINITY, u32::MAX);
        self.visit(0, 0.0, &qs[..self.nq], &mut off[..self.nq], &mut v);
        Some(self.neighbor(space, q, v.1))
    }

    fn len(&self) -> usize {
        self.ids.len()
    }

    fn clear(&mut self) {
        self.points.clear();
        self.ids.clear();
        self.nodes.clear();
        self.nodes.push(Node::Leaf(0));
        self.leaves.truncate(1);
        self.leaves[0].index.clear();
        self.leaves[0].coords.clear();
    }
}
