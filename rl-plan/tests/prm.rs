//! The PRM with a radius neighbourhood, and its A* query on its own: on a problem whose path is
//! known to exist (a wall with one gap) the radius PRM finds a valid path made of roadmap edges
//! no longer than the radius; A* returns shortest paths (the same cost as Dijkstra and as
//! Bellman–Ford on random geometric graphs, and the known answer on a graph built to mislead a
//! greedy search).

use std::time::Duration;

use rl_plan::nn::NnKind;
use rl_plan::optimizer::OptimizerKind;
use rl_plan::planner::graph::shortest_path;
use rl_plan::planner::{PlannerKind, PrmSettings};
use rl_plan::sampler::SamplerKind;
use rl_plan::solve::path_valid;
use rl_plan::validity::FnValidity;
use rl_plan::verifier::Verifier;
use rl_plan::{JointSpace, PlanOptions, Rng, Topology, plan};

/// [0, 10]² with a wall at x ∈ [4, 6] except a gap at y ∈ [7, 8.5].
fn wall() -> (JointSpace, impl FnMut(&[f64]) -> bool + Clone) {
    let i = Topology::Interval {
        lower: 0.0,
        upper: 10.0,
    };
    let space = JointSpace::new(vec![("x".into(), i), ("y".into(), i)]).unwrap();
    let free = |q: &[f64]| !(4.0..=6.0).contains(&q[0]) || (7.0..=8.5).contains(&q[1]);
    (space, free)
}

fn prm(settings: PrmSettings, seed: u64) -> PlanOptions {
    PlanOptions {
        planner: PlannerKind::Prm(settings),
        sampler: SamplerKind::Uniform,
        verifier: Verifier::recursive(0.05),
        optimizer: OptimizerKind::None,
        optimizer_verifier: None,
        seed,
        time: Duration::from_secs(10),
        optimize_time: Duration::from_secs(1),
        try_direct: true,
    }
}

#[test]
fn radius_prm_finds_a_valid_path_of_short_edges_through_the_gap() {
    let (space, free) = wall();
    let (start, goal) = ([1.0, 1.0], [9.0, 1.0]);
    for (radius, k, nn) in [
        (1.5, usize::MAX, NnKind::Linear),
        (1.5, usize::MAX, NnKind::Kdtree),
        (2.0, 5, NnKind::Gnat),
    ] {
        let settings = PrmSettings {
            k,
            radius,
            nn,
            ..Default::default()
        };
        let mut check = FnValidity::new(free.clone());
        let r = plan(&space, &mut check, &start, &goal, &prm(settings.clone(), 5)).unwrap();
        assert!(r.solved, "radius {radius}, k {k}, {nn:?}: not solved");
        assert_eq!(r.planner, "PRM");
        let p = r.path.unwrap();
        assert_eq!(p.point(0), &start[..]);
        assert_eq!(p.point(p.len() - 1), &goal[..]);
        // Roadmap edges only: none longer than the radius.
        for i in 1..p.len() {
            let d = space.distance(p.point(i - 1), p.point(i));
            assert!(d <= radius, "edge {i} is {d} long, radius {radius}");
        }
        // Through the gap, checked ten times finer than the planner.
        let mut fine = FnValidity::new(free.clone());
        assert!(path_valid(
            &space,
            &mut fine,
            &p,
            &Verifier::sequential(0.005)
        ));
        assert!(
            p.length(&space) > 10.0,
            "too short to have gone through the gap"
        );
        // The same seed gives the same roadmap and path.
        let mut again = FnValidity::new(free.clone());
        let r2 = plan(&space, &mut again, &start, &goal, &prm(settings, 5)).unwrap();
        assert_eq!(r2.path.unwrap(), p);
    }
}

/// Shortest-path costs by Bellman–Ford, the oracle for A*.
fn bellman_ford(edges: &[Vec<(u32, f64)>], start: u32) -> Vec<f64> {
    let mut d = vec![f64::INFINITY; edges.len()];
    d[start as usize] = 0.0;
    for _ in 0..edges.len() {
        for (u, out) in edges.iter().enumerate() {
            for &(v, w) in out {
                if d[u] + w < d[v as usize] {
                    d[v as usize] = d[u] + w;
                }
            }
        }
    }
    d
}

#[test]
fn astar_returns_shortest_paths_on_random_geometric_graphs() {
    let mut rng = Rng::seed_from(11);
    for graph in 0..40 {
        let n = 60;
        let points: Vec<[f64; 2]> = (0..n)
            .map(|_| [rng.uniform() * 10.0, rng.uniform() * 10.0])
            .collect();
        let dist = |a: usize, b: usize| {
            ((points[a][0] - points[b][0]).powi(2) + (points[a][1] - points[b][1]).powi(2)).sqrt()
        };
        // Undirected edges between points closer than 2.5 (some graphs are disconnected).
        let mut edges = vec![Vec::new(); n];
        for a in 0..n {
            for b in a + 1..n {
                if dist(a, b) < 2.5 {
                    edges[a].push((b as u32, dist(a, b)));
                    edges[b].push((a as u32, dist(a, b)));
                }
            }
        }
        let oracle = bellman_ford(&edges, 0);
        for goal in 1..n as u32 {
            let astar = shortest_path(&edges, 0, goal, |v| dist(v as usize, goal as usize));
            let dijkstra = shortest_path(&edges, 0, goal, |_| 0.0);
            let want = oracle[goal as usize];
            match (astar, dijkstra) {
                (None, None) => assert!(want.is_infinite(), "graph {graph}: {goal} missed"),
                (Some((chain, cost)), Some((_, cost_d))) => {
                    assert!(
                        (cost - want).abs() < 1e-9,
                        "graph {graph}: {cost} vs {want}"
                    );
                    assert!((cost_d - want).abs() < 1e-9);
                    // The chain is a path of the graph whose edges add up to the cost.
                    assert_eq!((chain[0], *chain.last().unwrap()), (0, goal));
                    let sum: f64 = chain
                        .windows(2)
                        .map(|w| {
                            edges[w[0] as usize]
                                .iter()
                                .find(|e| e.0 == w[1])
                                .expect("an edge of the graph")
                                .1
                        })
                        .sum();
                    assert!((sum - cost).abs() < 1e-9);
                }
                (a, d) => panic!("graph {graph}, goal {goal}: A* {a:?}, Dijkstra {d:?}"),
            }
        }
    }
}

#[test]
fn astar_is_not_misled_by_a_short_looking_dead_end() {
    // 0 at the origin, the goal 3 at (10, 0). The straight way 0 → 1 → 3 looks best to the
    // heuristic but its last edge is expensive (a detour the metric does not see); the way
    // through 2 is cheaper.
    let pos: [[f64; 2]; 4] = [[0.0, 0.0], [5.0, 0.0], [5.0, 3.0], [10.0, 0.0]];
    let d = |a: usize, b: usize| -> f64 { (pos[a][0] - pos[b][0]).hypot(pos[a][1] - pos[b][1]) };
    let mut edges: Vec<Vec<(u32, f64)>> = vec![Vec::new(); 4];
    let mut add = |a: usize, b: usize, w: f64| {
        edges[a].push((b as u32, w));
        edges[b].push((a as u32, w));
    };
    add(0, 1, d(0, 1));
    add(1, 3, 20.0);
    add(0, 2, d(0, 2));
    add(2, 3, d(2, 3));
    let (chain, cost) = shortest_path(&edges, 0, 3, |v| d(v as usize, 3)).unwrap();
    assert_eq!(chain, vec![0, 2, 3]);
    assert!((cost - 2.0 * 34f64.sqrt()).abs() < 1e-12);
    // Start = goal, an unreachable goal and a vertex out of range.
    assert_eq!(shortest_path(&edges, 1, 1, |_| 0.0), Some((vec![1], 0.0)));
    let mut island = edges.clone();
    island.push(Vec::new());
    assert_eq!(shortest_path(&island, 0, 4, |_| 0.0), None);
    assert_eq!(shortest_path(&edges, 0, 9, |_| 0.0), None);
}
