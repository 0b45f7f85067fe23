//! RL's nearest-neighbour test (tests/rlNearestNeighborsTest): every structure returns the same
//! k nearest points as linear search — here also the same points within a radius, on spaces
//! with wrap-around joints, built point by point (as a planner builds them).

use rl_plan::nn::{Gnat, Kdtree, Linear, NearestNeighbors, Neighbor};
use rl_plan::{JointSpace, Rng, Topology};

fn interval() -> Topology {
    Topology::Interval {
        lower: -1.0,
        upper: 1.0,
    }
}

fn check(space: &JointSpace, points: &[Vec<f64>], queries: &[Vec<f64>], k: usize, radius: f64) {
    let mut linear = Linear::new(space);
    let mut kd = Kdtree::new(space).ok();
    let mut gnat = Gnat::new(space);
    for (i, p) in points.iter().enumerate() {
        linear.insert(space, i, p);
        if let Some(kd) = kd.as_mut() {
            kd.insert(space, i, p);
        }
        gnat.insert(space, i, p);
    }
    let ids = |v: &[Neighbor]| v.iter().map(|n| n.id).collect::<Vec<_>>();
    let mut found_within = 0;
    for q in queries {
        let want = linear.nearest(space, q, k);
        assert_eq!(want.len(), k.min(points.len()));
        assert!(want.windows(2).all(|w| w[0].distance <= w[1].distance));
        assert_eq!(
            ids(&gnat.nearest(space, q, k)),
            ids(&want),
            "GNAT k-nearest at {q:?}"
        );
        let one = linear.nearest_one(space, q).unwrap();
        assert_eq!(one.id, want[0].id);
        let want_r = linear.within(space, q, radius);
        found_within += want_r.len();
        assert!(want_r.iter().all(|n| n.distance <= radius));
        assert_eq!(
            ids(&gnat.within(space, q, radius)),
            ids(&want_r),
            "GNAT radius"
        );
        if let Some(kd) = &kd {
            assert_eq!(
                ids(&kd.nearest(space, q, k)),
                ids(&want),
                "k-d tree k-nearest at {q:?}"
            );
            assert_eq!(kd.nearest_one(space, q).unwrap().id, one.id);
            assert_eq!(
                ids(&kd.within(space, q, radius)),
                ids(&want_r),
                "k-d tree radius"
            );
        }
    }
    // The radius queries must have found something to compare.
    assert!(found_within > 0);
}

#[test]
fn rl_example_points() {
    // RL's first case: the six 2-D points of the classic k-d tree example, query (9, 2).
    let space = JointSpace::new(vec![
        (
            "x".into(),
            Topology::Interval {
                lower: 0.0,
                upper: 10.0,
            },
        ),
        (
            "y".into(),
            Topology::Interval {
                lower: 0.0,
                upper: 10.0,
            },
        ),
    ])
    .unwrap();
    let pts: Vec<Vec<f64>> = [(2., 3.), (5., 4.), (9., 6.), (4., 8.), (8., 1.), (7., 2.)]
        .iter()
        .map(|&(x, y)| vec![x, y])
        .collect();
    let mut linear = Linear::new(&space);
    for (i, p) in pts.iter().enumerate() {
        linear.insert(&space, i, p);
    }
    let n = linear.nearest(&space, &[9.0, 2.0], 1);
    assert_eq!(n[0].id, 4); // (8, 1)
    check(&space, &pts, &[vec![9.0, 2.0], vec![3.0, 7.0]], 3, 3.0);
}

#[test]
fn random_points_six_dimensions() {
    // RL's second case, smaller: random points in 6-D, k = 30.
    let space = JointSpace::new((0..6).map(|i| (format!("q{i}"), interval())).collect()).unwrap();
    let mut rng = Rng::seed_from(11);
    let mut draw = |n: usize| -> Vec<Vec<f64>> {
        (0..n)
            .map(|_| (0..6).map(|_| rng.uniform_in(-1.0, 1.0)).collect())
            .collect()
    };
    let (points, queries) = (draw(5000), draw(40));
    check(&space, &points, &queries, 30, 0.45);
}

#[test]
fn wrap_around_joints_are_near_across_pi() {
    // Three circles and three intervals; queries next to ±π find points on the other side.
    let mut coords: Vec<(String, Topology)> = (0..3)
        .map(|i| (format!("c{i}"), Topology::Circle))
        .collect();
    coords.extend((0..3).map(|i| (format!("q{i}"), interval())));
    let space = JointSpace::new(coords).unwrap();
    let mut rng = Rng::seed_from(5);
    let mut points = Vec::new();
    let mut q = vec![0.0; 6];
    for _ in 0..4000 {
        space.sample_uniform(&mut rng, &mut q);
        points.push(q.clone());
    }
    let mut queries = Vec::new();
    for i in 0..40 {
        space.sample_uniform(&mut rng, &mut q);
        q[i % 3] = if i % 2 == 0 { 3.1 } else { -3.1 };
        queries.push(q.clone());
    }
    check(&space, &points, &queries, 20, 0.8);
    // The nearest point to (π − ε, …) may well sit at (−π + ε, …): the metric wraps.
    let mut linear = Linear::new(&space);
    linear.insert(&space, 0, &[-3.1, 0.0, 0.0, 0.0, 0.0, 0.0]);
    linear.insert(&space, 1, &[2.5, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let n = linear
        .nearest_one(&space, &[3.1, 0.0, 0.0, 0.0, 0.0, 0.0])
        .unwrap();
    assert_eq!(n.id, 0);
    assert!((n.distance - (2.0 * std::f64::consts::PI - 6.2)).abs() < 1e-12);
}

#[test]
fn gnat_serves_rotations_and_kdtree_refuses_them() {
    let space = JointSpace::new(vec![
        ("x".into(), interval()),
        ("r".into(), Topology::Rotation),
    ])
    .unwrap();
    assert!(Kdtree::new(&space).is_err());
    let mut rng = Rng::seed_from(9);
    let mut points = Vec::new();
    let mut q = vec![0.0; 5];
    for _ in 0..2000 {
        space.sample_uniform(&mut rng, &mut q);
        points.push(q.clone());
    }
    let queries: Vec<Vec<f64>> = (0..30)
        .map(|_| {
            space.sample_uniform(&mut rng, &mut q);
            q.clone()
        })
        .collect();
    check(&space, &points, &queries, 10, 0.9);
}
