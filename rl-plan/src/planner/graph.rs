//! Shortest paths in a roadmap: A* (Hart, Nilsson and Raphael, 1968), Dijkstra when the
//! heuristic is zero. The PRM's query ([`super::Prm`]); public so it can be tested and used on
//! any graph.
//!
//! The graph is an adjacency list: `edges[u]` holds `(v, w)` for an edge `u → v` of
//! non-negative weight `w` (an undirected roadmap lists each edge both ways). With an admissible
//! and consistent heuristic (the metric to the goal, for edges weighted by the metric) the path
//! returned is a shortest one. Vertices are re-expanded when a cheaper way to them is found, so
//! an inconsistent (but admissible) heuristic still gives a shortest path. O((V + E) log V) for
//! a consistent heuristic.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// A shortest path from `start` to `goal` and its cost, or `None` when the goal cannot be
/// reached (or either vertex is not in the graph). `heuristic(v)` estimates the cost from `v` to
/// the goal (never above the true cost; `|_| 0.0` gives Dijkstra).
pub fn shortest_path(
    edges: &[Vec<(u32, f64)>],
    start: u32,
    goal: u32,
    heuristic: impl Fn(u32) -> f64,
) -> Option<(Vec<u32>, f64)> {
    /// An open vertex: (estimated total cost, vertex), ordered so the heap pops the cheapest.
    #[derive(PartialEq)]
    struct Open(f64, u32);
    impl Eq for Open {}
    impl PartialOrd for Open {
        fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for Open {
        fn cmp(&self, o: &Self) -> Ordering {
            o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
        }
    }
    let n = edges.len();
    if start as usize >= n || goal as usize >= n {
        return None;
    }
    let mut g = vec![f64::INFINITY; n];
    let mut pred = vec![u32::MAX; n];
    let mut open = BinaryHeap::new();
    g[start as usize] = 0.0;
    open.push(Open(heuristic(start), start));
    while let Some(Open(f, u)) = open.pop() {
        // A stale entry: a cheaper way to `u` was found after it was queued.
        if f > g[u as usize] + heuristic(u) {
            continue;
        }
        if u == goal {
            let mut chain = vec![goal];
            let mut v = goal;
            while v != start {
                v = pred[v as usize];
                chain.push(v);
            }
            chain.reverse();
            return Some((chain, g[goal as usize]));
        }
        for &(v, w) in &edges[u as usize] {
            let c = g[u as usize] + w;
            if (v as usize) < n && c < g[v as usize] {
                g[v as usize] = c;
                pred[v as usize] = u;
                open.push(Open(c + heuristic(v), v));
            }
        }
    }
    None
}
