//! The search tree of the RRT planners: vertices stored one after the other, parent links,
//! and a nearest-neighbour structure over them.

use crate::error::PlanError;
use crate::nn::{NearestNeighbors, Nn, NnKind};
use crate::path::Path;
use crate::space::JointSpace;

/// No parent: a root.
pub(crate) const NONE: u32 = u32::MAX;

pub(crate) struct Tree {
    nq: usize,
    points: Vec<f64>,
    parent: Vec<u32>,
    /// Dynamic-domain radius per vertex (∞: none yet).
    radius: Vec<f64>,
    nn: Nn,
}

impl Tree {
    pub(crate) fn new(space: &JointSpace, kind: NnKind) -> Result<Self, PlanError> {
        Ok(Self {
            nq: space.nq(),
            points: Vec::new(),
            parent: Vec::new(),
            radius: Vec::new(),
            nn: Nn::new(kind, space)?,
        })
    }

    pub(crate) fn clear(&mut self) {
        self.points.clear();
        self.parent.clear();
        self.radius.clear();
        self.nn.clear();
    }

    pub(crate) fn radius(&self, i: u32) -> f64 {
        self.radius[i as usize]
    }

    pub(crate) fn set_radius(&mut self, i: u32, r: f64) {
        self.radius[i as usize] = r;
    }

    pub(crate) fn len(&self) -> usize {
        self.parent.len()
    }

    pub(crate) fn q(&self, i: u32) -> &[f64] {
        let i = i as usize * self.nq;
        &self.points[i..i + self.nq]
    }

    pub(crate) fn add(&mut self, space: &JointSpace, q: &[f64], parent: u32) -> u32 {
        let i = self.parent.len() as u32;
        self.points.extend_from_slice(&q[..self.nq]);
        self.parent.push(parent);
        self.radius.push(f64::INFINITY);
        self.nn.insert(space, i as usize, q);
        i
    }

    /// The nearest vertex and its distance.
    pub(crate) fn nearest(&self, space: &JointSpace, q: &[f64]) -> Option<(u32, f64)> {
        self.nn
            .nearest_one(space, q)
            .map(|n| (n.id as u32, n.distance))
    }

    /// The vertices from the root to `i`.
    pub(crate) fn path_from_root(&self, i: u32) -> Path {
        let mut chain = vec![i];
        let mut v = i;
        while self.parent[v as usize] != NONE {
            v = self.parent[v as usize];
            chain.push(v);
        }
        let mut p = Path::new(self.nq);
        for &v in chain.iter().rev() {
            p.push(self.q(v));
        }
        p
    }
}

/// Joins a start-tree path (root = start … `a`) and a goal-tree path (root = goal … `b`):
/// when `a == b` the duplicate is dropped, otherwise the edge `a → b` stays (the caller has
/// verified it).
pub(crate) fn join(from_start: Path, mut from_goal: Path) -> Path {
    from_goal.reverse();
    let mut out = from_start;
    let skip = usize::from(
        !out.is_empty() && !from_goal.is_empty() && out.point(out.len() - 1) == from_goal.point(0),
    );
    for i in skip..from_goal.len() {
        out.push(from_goal.point(i));
    }
    out
}

/// The two trees of the bidirectional planners: `trees[0]` grows from the start, `trees[1]`
/// from the goal.
pub(crate) struct Pair {
    pub(crate) trees: [Tree; 2],
    /// The tree grown next.
    pub(crate) a: usize,
}

impl Pair {
    pub(crate) fn new(space: &JointSpace, kind: NnKind) -> Result<Self, PlanError> {
        Ok(Self {
            trees: [Tree::new(space, kind)?, Tree::new(space, kind)?],
            a: 0,
        })
    }

    pub(crate) fn reset(&mut self, space: &JointSpace, start: &[f64], goal: &[f64]) {
        for t in &mut self.trees {
            t.clear();
        }
        self.trees[0].add(space, start, NONE);
        self.trees[1].add(space, goal, NONE);
        self.a = 0;
    }

    /// Chooses the tree to grow next: the other one (RL), or with `balance` VAMP's rule —
    /// switch unless the other tree is at least twice as large.
    pub(crate) fn next(&mut self, balance: bool, first: bool) {
        if first {
            self.a = 0;
            return;
        }
        let (na, nb) = (
            self.trees[self.a].len() as f64,
            self.trees[1 - self.a].len() as f64,
        );
        if !balance || (na - nb).abs() / na < 1.0 {
            self.a = 1 - self.a;
        }
    }

    /// Mutable access to the growing tree and the other one.
    pub(crate) fn split(&mut self) -> (&mut Tree, &mut Tree) {
        let [t0, t1] = &mut self.trees;
        if self.a == 0 { (t0, t1) } else { (t1, t0) }
    }

    /// The path through vertex `va` of the growing tree and `vb` of the other one.
    pub(crate) fn path(&self, va: u32, vb: u32) -> Path {
        let (v0, v1) = if self.a == 0 { (va, vb) } else { (vb, va) };
        join(
            self.trees[0].path_from_root(v0),
            self.trees[1].path_from_root(v1),
        )
    }

    pub(crate) fn vertices(&self) -> usize {
        self.trees[0].len() + self.trees[1].len()
    }
}
