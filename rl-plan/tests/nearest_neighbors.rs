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

/// The `f32` k-d tree against a linear `f32` scan written here (the same rounding: coordinates
/// to `f32`, times the weight) and against linear `f64` search where the two nearest are not
/// tied within `f32` precision; points inserted one by one, many of them repeated (a leaf of
/// equal points cannot split).
#[test]
fn f32_kdtree_finds_what_a_linear_f32_scan_finds() {
    use rl_plan::nn::KdtreeF32;
    let mut coords: Vec<(String, Topology)> =
        (0..7).map(|i| (format!("q{i}"), interval())).collect();
    coords[0].1 = Topology::Interval {
        lower: -3.0,
        upper: 3.0,
    };
    let mut space = JointSpace::new(coords).unwrap();
    let w = [1.0f32, 0.5, 1.0, 2.0, 1.0, 1.0, 0.25];
    for (i, &x) in w.iter().enumerate() {
        space.set_weight(i, f64::from(x)).unwrap();
    }
    let mut rng = Rng::seed_from(41);
    let mut tree = KdtreeF32::new(&space).unwrap();
    let mut linear = Linear::new(&space);
    let mut points: Vec<Vec<f64>> = Vec::new();
    let mut q = vec![0.0; 7];
    let f32_nearest = |points: &[Vec<f64>], q: &[f64]| {
        let mut best = (f32::INFINITY, usize::MAX);
        for (i, p) in points.iter().enumerate() {
            let mut d2 = 0.0f32;
            for d in 0..7 {
                let v = p[d] as f32 * w[d] - q[d] as f32 * w[d];
                d2 += v * v;
            }
            if d2 < best.0 {
                best = (d2, i);
            }
        }
        best.1
    };
    let (mut compared, mut untied) = (0, 0);
    for n in 0..3000 {
        if n % 10 == 9 {
            // A repeat of an earlier point (and 40 copies of one point in a row).
            let again = points[n / 3].clone();
            points.push(again);
        } else if (1000..1040).contains(&n) {
            points.push(vec![0.25; 7]);
        } else {
            space.sample_uniform(&mut rng, &mut q);
            points.push(q.clone());
        }
        tree.insert(&space, n, &points[n]);
        linear.insert(&space, n, &points[n]);
        if n % 7 == 0 {
            space.sample_uniform(&mut rng, &mut q);
            let got = tree.nearest_one(&space, &q).unwrap();
            assert_eq!(got.id, f32_nearest(&points, &q), "after {n} points");
            assert!((got.distance - space.distance(&q, &points[got.id])).abs() < 1e-12);
            let want = linear.nearest(&space, &q, 2);
            if want.len() == 2 && want[1].distance - want[0].distance > 1e-5 {
                assert_eq!(got.id, want[0].id);
                untied += 1;
            }
            // k nearest and radius: the same sets as linear f64 search, away from ties.
            let k = tree.nearest(&space, &q, 5);
            let lk = linear.nearest(&space, &q, 6);
            if lk.len() == 6 && lk[5].distance - lk[4].distance > 1e-5 {
                let mut a: Vec<usize> = k.iter().map(|x| x.id).collect();
                let mut b: Vec<usize> = lk[..5].iter().map(|x| x.id).collect();
                a.sort_unstable();
                b.sort_unstable();
                assert_eq!(a, b, "k nearest after {n} points");
            }
            let r = 0.6;
            let within: Vec<usize> = tree.within(&space, &q, r).iter().map(|x| x.id).collect();
            let lw: Vec<usize> = linear.within(&space, &q, r).iter().map(|x| x.id).collect();
            assert_eq!(within, lw, "within {r} after {n} points");
            compared += 1;
        }
    }
    assert!(
        compared > 400 && untied > 300,
        "{compared} queries, {untied} untied"
    );
    tree.clear();
    assert!(tree.is_empty() && tree.nearest_one(&space, &q).is_none());
}
