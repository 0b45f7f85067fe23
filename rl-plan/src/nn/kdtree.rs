//! A bucketed k-d tree grown by insertion (RL's `KdtreeNearestNeighbors`), for spaces of
//! intervals and circles.
//!
//! A leaf holds up to [`BUCKET`] points; a fuller leaf splits at the median of its widest
//! coordinate (weighted). A query descends to the nearer side first and visits the other side
//! only if the distance from the query to that side's box can beat the current `k`-th distance
//! (Arya & Mount's incremental distance: the squared distance to a box is the sum of per-axis
//! squared gaps, and a split changes one of them). Along a circle coordinate the gap to an arc
//! `[lo, hi]` is measured around the circle, so points across `±π` are found.

use super::{Best, NearestNeighbors, Neighbor, sorted};
use crate::error::PlanError;
use crate::space::{JointSpace, Topology, wrap_angle};

/// Points a leaf holds before it splits.
pub const BUCKET: usize = 12;

#[derive(Clone, Debug)]
enum Node {
    Leaf(Vec<u32>),
    Split {
        axis: u32,
        value: f64,
        left: u32,
        right: u32,
    },
}

/// The k-d tree.
#[derive(Clone, Debug)]
pub struct Kdtree {
    nq: usize,
    /// Per axis: whether it is a circle, and its metric weight.
    circle: Vec<bool>,
    weight: Vec<f64>,
    points: Vec<f64>,
    ids: Vec<usize>,
    nodes: Vec<Node>,
}

const PI: f64 = std::f64::consts::PI;

/// The gap from `x` to the interval (or, on the circle, the arc) `[lo, hi]`.
#[inline]
fn gap(x: f64, lo: f64, hi: f64, circle: bool) -> f64 {
    if x >= lo && x <= hi {
        0.0
    } else if circle {
        wrap_angle(x - lo).abs().min(wrap_angle(x - hi).abs())
    } else if x < lo {
        lo - x
    } else {
        x - hi
    }
}

struct Query<'a> {
    q: &'a [f64],
    lo: Vec<f64>,
    hi: Vec<f64>,
    off: Vec<f64>,
}

impl Kdtree {
    /// An empty tree for `space` (an error for spaces with rotations: use [`super::Gnat`]).
    pub fn new(space: &JointSpace) -> Result<Self, PlanError> {
        if !space.is_vector() {
            return Err(PlanError::Unsupported(
                "a k-d tree over rotations (quaternion coordinates); use GNAT or linear search"
                    .into(),
            ));
        }
        let circle = space
            .coordinates()
            .iter()
            .map(|c| c.topology == Topology::Circle)
            .collect();
        let weight = space.coordinates().iter().map(|c| c.weight).collect();
        Ok(Self {
            nq: space.nq(),
            circle,
            weight,
            points: Vec::new(),
            ids: Vec::new(),
            nodes: vec![Node::Leaf(Vec::new())],
        })
    }

    fn point(&self, i: u32) -> &[f64] {
        let i = i as usize * self.nq;
        &self.points[i..i + self.nq]
    }

    /// Splits leaf `n` if it is over full and its points differ.
    fn split(&mut self, n: usize) {
        let Node::Leaf(items) = &self.nodes[n] else {
            return;
        };
        let items = items.clone();
        // Widest axis (weighted spread).
        let mut best: Option<(f64, usize)> = None;
        for a in 0..self.nq {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for &i in &items {
                let x = self.point(i)[a];
                lo = lo.min(x);
                hi = hi.max(x);
            }
            let spread = (hi - lo) * self.weight[a];
            if spread > 0.0 && best.is_none_or(|(s, _)| spread > s) {
                best = Some((spread, a));
            }
        }
        let Some((_, axis)) = best else {
            return; // all points equal: keep the big leaf
        };
        let mut xs: Vec<f64> = items.iter().map(|&i| self.point(i)[axis]).collect();
        xs.sort_by(f64::total_cmp);
        let mut value = xs[xs.len() / 2];
        if value <= xs[0] {
            // Many equal values at the bottom: split just above them.
            value = *xs.iter().find(|&&x| x > xs[0]).expect("spread > 0");
        }
        let (l, r): (Vec<u32>, Vec<u32>) =
            items.iter().partition(|&&i| self.point(i)[axis] < value);
        let left = self.nodes.len() as u32;
        self.nodes.push(Node::Leaf(l));
        self.nodes.push(Node::Leaf(r));
        self.nodes[n] = Node::Split {
            axis: axis as u32,
            value,
            left,
            right: left + 1,
        };
    }

    fn query<'a>(&self, q: &'a [f64]) -> Query<'a> {
        let lo = self
            .circle
            .iter()
            .map(|&c| if c { -PI } else { f64::NEG_INFINITY })
            .collect();
        let hi = self
            .circle
            .iter()
            .map(|&c| if c { PI } else { f64::INFINITY })
            .collect();
        Query {
            q,
            lo,
            hi,
            off: vec![0.0; self.nq],
        }
    }

    /// Visits node `n` whose box is at squared distance `rd` from the query; `bound()` gives
    /// the squared distance a subtree must be able to beat.
    fn visit(
        &self,
        space: &JointSpace,
        n: u32,
        rd: f64,
        query: &mut Query,
        found: &mut dyn FnMut(f64, usize),
        bound: &dyn Fn() -> f64,
    ) {
        match &self.nodes[n as usize] {
            Node::Leaf(items) => {
                for &i in items {
                    found(
                        space.distance_squared(query.q, self.point(i)),
                        self.ids[i as usize],
                    );
                }
            }
            Node::Split {
                axis,
                value,
                left,
                right,
            } => {
                let a = *axis as usize;
                let x = query.q[a];
                let (lo, hi) = (query.lo[a], query.hi[a]);
                let w = self.weight[a];
                let c = self.circle[a];
                let dl = w * gap(x, lo, *value, c);
                let dr = w * gap(x, *value, hi, c);
                let old = query.off[a];
                let rl = rd - old * old + dl * dl;
                let rr = rd - old * old + dr * dr;
                let sides = if rl <= rr {
                    [(*left, rl, dl, true), (*right, rr, dr, false)]
                } else {
                    [(*right, rr, dr, false), (*left, rl, dl, true)]
                };
                for (child, r, d, is_left) in sides {
                    if r > bound() {
                        continue;
                    }
                    let saved = if is_left {
                        std::mem::replace(&mut query.hi[a], *value)
                    } else {
                        std::mem::replace(&mut query.lo[a], *value)
                    };
                    query.off[a] = d;
                    self.visit(space, child, r, query, found, bound);
                    query.off[a] = old;
                    if is_left {
                        query.hi[a] = saved;
                    } else {
                        query.lo[a] = saved;
                    }
                }
            }
        }
    }

    fn canonical(&self, q: &[f64]) -> Vec<f64> {
        q[..self.nq]
            .iter()
            .zip(&self.circle)
            .map(|(&x, &c)| if c { wrap_angle(x) } else { x })
            .collect()
    }
}

impl NearestNeighbors for Kdtree {
    fn insert(&mut self, _space: &JointSpace, id: usize, q: &[f64]) {
        let q = self.canonical(q);
        let index = self.ids.len() as u32;
        self.points.extend_from_slice(&q);
        self.ids.push(id);
        let mut n = 0usize;
        loop {
            match &mut self.nodes[n] {
                Node::Split {
                    axis,
                    value,
                    left,
                    right,
                } => {
                    n = if q[*axis as usize] < *value {
                        *left as usize
                    } else {
                        *right as usize
                    };
                }
                Node::Leaf(items) => {
                    items.push(index);
                    if items.len() > BUCKET {
                        self.split(n);
                    }
                    return;
                }
            }
        }
    }

    fn nearest(&self, space: &JointSpace, q: &[f64], k: usize) -> Vec<Neighbor> {
        let qc = self.canonical(q);
        let best = std::cell::RefCell::new(Best::new(k));
        let mut query = self.query(&qc);
        self.visit(
            space,
            0,
            0.0,
            &mut query,
            &mut |d2, id| best.borrow_mut().offer(d2, id),
            &|| best.borrow().bound(),
        );
        best.into_inner().into_neighbors()
    }

    fn within(&self, space: &JointSpace, q: &[f64], radius: f64) -> Vec<Neighbor> {
        let qc = self.canonical(q);
        let r2 = radius * radius;
        let mut out = Vec::new();
        let mut query = self.query(&qc);
        self.visit(
            space,
            0,
            0.0,
            &mut query,
            &mut |d2, id| {
                if d2 <= r2 {
                    out.push((d2, id));
                }
            },
            &|| r2,
        );
        sorted(out)
    }

    fn len(&self) -> usize {
        self.ids.len()
    }

    fn clear(&mut self) {
        self.points.clear();
        self.ids.clear();
        self.nodes = vec![Node::Leaf(Vec::new())];
    }
}
