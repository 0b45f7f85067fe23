//! GNAT, the geometric near-neighbour access tree (Brin, "Near neighbor search in large metric
//! spaces", VLDB 1995; RL's `GnatNearestNeighbors`), for any metric — it needs nothing but
//! distances, so it serves spaces with rotations.
//!
//! An inner node has up to [`DEGREE`] split points `p₁…p_m`, each owning a subtree `Dⱼ`
//! (the points nearer to `pⱼ` than to the other split points), and a table of distance
//! ranges `[min, max]` of `d(pᵢ, x)` over `x ∈ Dⱼ ∪ {pⱼ}`. A query of radius `r` at distance
//! `dᵢ = d(q, pᵢ)` from a split point drops every subtree `j` whose range does not meet
//! `[dᵢ − r, dᵢ + r]` (triangle inequality). Leaves hold up to [`BUCKET`] points; a fuller
//! leaf picks split points farthest-first. Insertion descends to the nearest split point,
//! widening the ranges on the way.

use super::{Best, NearestNeighbors, Neighbor, sorted};
use crate::space::JointSpace;

/// Split points per inner node.
pub const DEGREE: usize = 8;
/// Points a leaf holds before it splits.
pub const BUCKET: usize = 32;

#[derive(Clone, Debug)]
struct Node {
    /// The split point that owns this node (none for the root).
    pivot: Option<u32>,
    /// Points of a leaf (not the pivot).
    bucket: Vec<u32>,
    /// Child nodes (their pivots are this node's split points).
    children: Vec<u32>,
    /// `table[i * m + j]`: range of `d(pivot of child i, x)` over child `j`'s points.
    table: Vec<(f64, f64)>,
}

impl Node {
    fn leaf(pivot: Option<u32>) -> Self {
        Self {
            pivot,
            bucket: Vec::new(),
            children: Vec::new(),
            table: Vec::new(),
        }
    }
}

/// The GNAT.
#[derive(Clone, Debug)]
pub struct Gnat {
    nq: usize,
    points: Vec<f64>,
    ids: Vec<usize>,
    nodes: Vec<Node>,
}

fn widen(r: &mut (f64, f64), d: f64) {
    r.0 = r.0.min(d);
    r.1 = r.1.max(d);
}

impl Gnat {
    /// An empty tree for `space`.
    pub fn new(space: &JointSpace) -> Self {
        Self {
            nq: space.nq(),
            points: Vec::new(),
            ids: Vec::new(),
            nodes: vec![Node::leaf(None)],
        }
    }

    fn point(&self, i: u32) -> &[f64] {
        let i = i as usize * self.nq;
        &self.points[i..i + self.nq]
    }

    fn dist(&self, space: &JointSpace, a: u32, b: u32) -> f64 {
        space.distance(self.point(a), self.point(b))
    }

    /// Turns leaf `n` into an inner node with split points chosen farthest-first.
    fn split(&mut self, space: &JointSpace, n: usize) {
        let items = std::mem::take(&mut self.nodes[n].bucket);
        let m = DEGREE.min(items.len());
        // Farthest-first: start with the point farthest from the node's pivot (or the first).
        let mut pivots: Vec<u32> = Vec::with_capacity(m);
        let first = match self.nodes[n].pivot {
            Some(p) => *items
                .iter()
                .max_by(|&&a, &&b| {
                    self.dist(space, p, a)
                        .total_cmp(&self.dist(space, p, b))
                        .then(b.cmp(&a))
                })
                .expect("non-empty"),
            None => items[0],
        };
        pivots.push(first);
        let mut near: Vec<f64> = items.iter().map(|&x| self.dist(space, first, x)).collect();
        while pivots.len() < m {
            let (k, _) = near
                .iter()
                .enumerate()
                .filter(|(k, _)| !pivots.contains(&items[*k]))
                .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
                .expect("more items than pivots");
            let p = items[k];
            pivots.push(p);
            for (j, &x) in items.iter().enumerate() {
                near[j] = near[j].min(self.dist(space, p, x));
            }
        }
        let base = self.nodes.len() as u32;
        for &p in &pivots {
            self.nodes.push(Node::leaf(Some(p)));
        }
        let mut table = vec![(f64::INFINITY, f64::NEG_INFINITY); m * m];
        for &x in &items {
            let ds: Vec<f64> = pivots.iter().map(|&p| self.dist(space, p, x)).collect();
            let j = if let Some(j) = pivots.iter().position(|&p| p == x) {
                j
            } else {
                let j = nearest_index(&ds);
                self.nodes[base as usize + j].bucket.push(x);
                j
            };
            for i in 0..m {
                widen(&mut table[i * m + j], ds[i]);
            }
        }
        self.nodes[n].children = (base..base + m as u32).collect();
        self.nodes[n].table = table;
        for j in 0..m {
            if self.nodes[base as usize + j].bucket.len() > BUCKET {
                self.split(space, base as usize + j);
            }
        }
    }

    /// Visits node `n`: its split points (each a candidate itself) and the subtrees the
    /// ranges cannot rule out.
    fn visit(
        &self,
        space: &JointSpace,
        n: usize,
        q: &[f64],
        found: &mut dyn FnMut(f64, usize),
        radius: &dyn Fn() -> f64,
    ) {
        let node = &self.nodes[n];
        for &x in &node.bucket {
            found(
                space.distance_squared(q, self.point(x)),
                self.ids[x as usize],
            );
        }
        let m = node.children.len();
        if m == 0 {
            return;
        }
        let mut d = [0.0f64; DEGREE];
        let mut alive = [true; DEGREE];
        for i in 0..m {
            let p = self.nodes[node.children[i] as usize]
                .pivot
                .expect("children have pivots");
            let d2 = space.distance_squared(q, self.point(p));
            found(d2, self.ids[p as usize]);
            d[i] = d2.sqrt();
        }
        let prune = |alive: &mut [bool; DEGREE], r: f64| {
            // Slack for rounding in the stored and computed distances.
            let r = r * (1.0 + 1e-12) + 1e-12;
            for i in 0..m {
                for j in 0..m {
                    if alive[j] {
                        let (lo, hi) = node.table[i * m + j];
                        if d[i] + r < lo || d[i] - r > hi {
                            alive[j] = false;
                        }
                    }
                }
            }
        };
        prune(&mut alive, radius());
        let mut order: Vec<usize> = (0..m).filter(|&j| alive[j]).collect();
        order.sort_by(|&a, &b| d[a].total_cmp(&d[b]));
        for j in order {
            // The radius may have shrunk since the first pruning.
            prune(&mut alive, radius());
            if alive[j] {
                self.visit(space, node.children[j] as usize, q, found, radius);
            }
        }
    }
}

fn nearest_index(ds: &[f64]) -> usize {
    let mut best = 0;
    for (i, d) in ds.iter().enumerate() {
        if *d < ds[best] {
            best = i;
        }
    }
    best
}

impl NearestNeighbors for Gnat {
    fn insert(&mut self, space: &JointSpace, id: usize, q: &[f64]) {
        let x = self.ids.len() as u32;
        self.points.extend_from_slice(&q[..self.nq]);
        self.ids.push(id);
        let mut n = 0usize;
        loop {
            let m = self.nodes[n].children.len();
            if m == 0 {
                self.nodes[n].bucket.push(x);
                if self.nodes[n].bucket.len() > BUCKET {
                    self.split(space, n);
                }
                return;
            }
            let ds: Vec<f64> = self.nodes[n]
                .children
                .iter()
                .map(|&c| self.dist(space, self.nodes[c as usize].pivot.expect("pivot"), x))
                .collect();
            let j = nearest_index(&ds);
            for (i, d) in ds.iter().enumerate() {
                widen(&mut self.nodes[n].table[i * m + j], *d);
            }
            n = self.nodes[n].children[j] as usize;
        }
    }

    fn nearest(&self, space: &JointSpace, q: &[f64], k: usize) -> Vec<Neighbor> {
        let best = std::cell::RefCell::new(Best::new(k));
        self.visit(
            space,
            0,
            q,
            &mut |d2, id| best.borrow_mut().offer(d2, id),
            &|| best.borrow().bound().sqrt(),
        );
        best.into_inner().into_neighbors()
    }

    fn within(&self, space: &JointSpace, q: &[f64], radius: f64) -> Vec<Neighbor> {
        let r2 = radius * radius;
        let mut out = Vec::new();
        self.visit(
            space,
            0,
            q,
            &mut |d2, id| {
                if d2 <= r2 {
                    out.push((d2, id));
                }
            },
            &|| radius,
        );
        sorted(out)
    }

    fn len(&self) -> usize {
        self.ids.len()
    }

    fn clear(&mut self) {
        self.points.clear();
        self.ids.clear();
        self.nodes = vec![Node::leaf(None)];
    }
}
