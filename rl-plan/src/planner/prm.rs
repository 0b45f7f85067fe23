//! The probabilistic roadmap (Kavraki, Švestka, Latombe and Overmars, 1996; RL's `Prm`).
//!
//! The start and the goal are inserted first; then valid samples are added until both lie in
//! one connected component or the budget runs out. A new vertex is joined to its `k` nearest
//! neighbours, or with a finite `radius` to its neighbours within it (the nearest `k` of them:
//! set `k` to `usize::MAX` for the whole neighbourhood; each vertex at most `degree` edges),
//! when they lie in another component and the edge is valid — so, as in RL, the roadmap stays
//! a forest and components are tracked with a union–find. The path is then found by A* (the metric to the goal is the
//! heuristic; RL's default) or Dijkstra.

use std::cmp::Ordering;

use super::graph::shortest_path;
use super::{Context, Planner, Stats};
use crate::error::PlanError;
use crate::nn::{NearestNeighbors, Nn, NnKind};
use crate::path::Path;
use crate::space::JointSpace;

/// PRM settings (RL's defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct PrmSettings {
    /// Neighbours tried per new vertex (RL: 30).
    pub k: usize,
    /// Largest edge length (RL: unbounded).
    pub radius: f64,
    /// Most edges per vertex (RL: unbounded).
    pub degree: usize,
    /// A* (true, RL's default) or Dijkstra.
    pub astar: bool,
    /// The nearest-neighbour structure.
    pub nn: NnKind,
}

impl Default for PrmSettings {
    fn default() -> Self {
        Self {
            k: 30,
            radius: f64::INFINITY,
            degree: usize::MAX,
            astar: true,
            nn: NnKind::Linear,
        }
    }
}

/// RL's `Prm`.
pub struct Prm {
    settings: PrmSettings,
    nq: usize,
    points: Vec<f64>,
    edges: Vec<Vec<(u32, f64)>>,
    parent: Vec<u32>,
    rank: Vec<u8>,
    nn: Nn,
    stats: Stats,
}

impl Prm {
    /// A planner for `space`.
    pub fn new(space: &JointSpace, settings: PrmSettings) -> Result<Self, PlanError> {
        if settings.radius.is_nan() || settings.radius <= 0.0 {
            return Err(PlanError::setting("radius", "must be positive"));
        }
        Ok(Self {
            nq: space.nq(),
            nn: Nn::new(settings.nn, space)?,
            settings,
            points: Vec::new(),
            edges: Vec::new(),
            parent: Vec::new(),
            rank: Vec::new(),
            stats: Stats::default(),
        })
    }

    fn q(&self, i: u32) -> &[f64] {
        &self.points[i as usize * self.nq..(i as usize + 1) * self.nq]
    }

    fn find(&mut self, mut i: u32) -> u32 {
        while self.parent[i as usize] != i {
            let p = self.parent[i as usize];
            self.parent[i as usize] = self.parent[p as usize];
            i = p;
        }
        i
    }

    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return;
        }
        match self.rank[ra as usize].cmp(&self.rank[rb as usize]) {
            Ordering::Less => self.parent[ra as usize] = rb,
            Ordering::Greater => self.parent[rb as usize] = ra,
            Ordering::Equal => {
                self.parent[rb as usize] = ra;
                self.rank[ra as usize] += 1;
            }
        }
    }

    /// Adds `q` as a vertex and joins it to its neighbours (RL's `insert`).
    fn insert(&mut self, ctx: &mut Context, q: &[f64]) -> u32 {
        let v = self.edges.len() as u32;
        self.points.extend_from_slice(q);
        self.edges.push(Vec::new());
        self.parent.push(v);
        self.rank.push(0);
        // The k nearest, or with a finite radius the (at most k) nearest within it.
        let neighbors = if self.settings.radius.is_finite() {
            let mut within = self.nn.within(ctx.space, q, self.settings.radius);
            within.sort_by(|a, b| a.distance.total_cmp(&b.distance));
            within.truncate(self.settings.k);
            within
        } else {
            self.nn.nearest(ctx.space, q, self.settings.k)
        };
        for n in neighbors {
            if self.edges[v as usize].len() >= self.settings.degree {
                break;
            }
            let u = n.id as u32;
            if self.edges[u as usize].len() >= self.settings.degree
                || n.distance > self.settings.radius
                || self.find(u) == self.find(v)
            {
                continue;
            }
            let (qu, qv) = (self.q(u).to_vec(), self.q(v).to_vec());
            if ctx.motion_valid(&qu, &qv, false) {
                self.edges[u as usize].push((v, n.distance));
                self.edges[v as usize].push((u, n.distance));
                self.union(u, v);
            }
        }
        self.nn.insert(ctx.space, v as usize, q);
        v
    }

    /// A* (or Dijkstra) from vertex 0 to vertex 1 ([`shortest_path`]).
    fn search(&self, space: &JointSpace) -> Option<Vec<u32>> {
        let goal = 1u32;
        let astar = self.settings.astar;
        let h = |v: u32| {
            if astar {
                space.distance(self.q(v), self.q(goal))
            } else {
                0.0
            }
        };
        shortest_path(&self.edges, 0, goal, h).map(|(chain, _)| chain)
    }
}

impl Planner for Prm {
    fn name(&self) -> &'static str {
        "PRM"
    }

    fn solve(&mut self, ctx: &mut Context, start: &[f64], goal: &[f64]) -> Option<Path> {
        self.points.clear();
        self.edges.clear();
        self.parent.clear();
        self.rank.clear();
        self.nn.clear();
        self.insert(ctx, start);
        self.insert(ctx, goal);
        let mut q = vec![0.0; self.nq];
        let mut i = 0u64;
        while self.find(0) != self.find(1) {
            if !ctx.budget.allows(i) {
                break;
            }
            i += 1;
            if !ctx.sample_valid(&mut q) {
                break;
            }
            self.insert(ctx, &q);
        }
        let vertices = self.edges.len();
        self.stats = Stats {
            iterations: i,
            vertices,
            edges: self.edges.iter().map(Vec::len).sum::<usize>() / 2,
        };
        if self.find(0) != self.find(1) {
            return None;
        }
        let chain = self.search(ctx.space)?;
        let mut p = Path::new(self.nq);
        for v in chain {
            p.push(self.q(v));
        }
        Some(p)
    }

    fn stats(&self) -> Stats {
        self.stats
    }
}
