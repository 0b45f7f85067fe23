//! Every planner on small problems with a known answer: paths from start to goal whose every
//! edge is valid at a resolution ten times finer than the planner's, the same path for the same
//! seed, a time budget that is kept, optimisers that shorten without breaking validity, and
//! wrap-around joints crossed the short way.

use std::time::{Duration, Instant};

use rl_plan::optimizer::OptimizerKind;
use rl_plan::planner::{PlannerKind, PrmSettings};
use rl_plan::sampler::SamplerKind;
use rl_plan::solve::path_valid;
use rl_plan::validity::FnValidity;
use rl_plan::verifier::Verifier;
use rl_plan::{JointSpace, PlanError, PlanOptions, Topology, plan};

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

fn options(planner: PlannerKind, seed: u64) -> PlanOptions {
    PlanOptions {
        planner,
        sampler: SamplerKind::Uniform,
        verifier: Verifier::recursive(0.05),
        optimizer: OptimizerKind::None,
        optimizer_verifier: None,
        seed,
        time: Duration::from_secs(5),
        optimize_time: Duration::from_secs(5),
        try_direct: true,
    }
}

fn all_planners() -> Vec<PlannerKind> {
    let mut v: Vec<PlannerKind> = ["rrt-connect", "rrt-con-con", "rrt-ext-ext", "rrt-dual"]
        .iter()
        .map(|n| PlannerKind::parse(n).unwrap())
        .collect();
    for p in &mut v {
        p.rrt_settings_mut().unwrap().delta = 0.5;
    }
    // Single-tree RRTs end near the goal: epsilon sized to the step.
    let mut rrt = PlannerKind::parse("rrt").unwrap();
    let s = rrt.rrt_settings_mut().unwrap();
    s.delta = 0.3;
    s.epsilon = 0.3;
    v.push(rrt);
    let mut gb = PlannerKind::parse("rrt-goal-bias").unwrap();
    gb.rrt_settings_mut().unwrap().delta = 0.3;
    v.push(gb);
    v.push(PlannerKind::Prm(PrmSettings {
        k: 10,
        ..Default::default()
    }));
    v
}

#[test]
fn every_planner_finds_a_valid_path_through_the_gap() {
    let (space, free) = wall();
    let (start, goal) = ([1.0, 1.0], [9.0, 1.0]);
    for planner in all_planners() {
        let mut check = FnValidity::new(free.clone());
        let r = plan(
            &space,
            &mut check,
            &start,
            &goal,
            &options(planner.clone(), 3),
        )
        .unwrap();
        assert!(r.solved, "{planner:?} did not solve");
        let p = r.path.unwrap();
        assert_eq!(p.point(0), &start[..]);
        assert_eq!(p.point(p.len() - 1), &goal[..], "{planner:?}");
        // Independent check at a tenth of the resolution.
        let mut fine = FnValidity::new(free.clone());
        assert!(
            path_valid(&space, &mut fine, &p, &Verifier::sequential(0.005)),
            "{planner:?}: path crosses the wall"
        );
        // It went through the gap: some waypoint or edge passes y ≥ 7 near x = 5.
        assert!(
            p.length(&space) > 8.0 + 2.0,
            "{planner:?}: too short to have gone around"
        );
        assert!(r.planning_checks > 0 && r.iterations > 0);
    }
}

#[test]
fn same_seed_same_path_other_seed_other_path() {
    let (space, free) = wall();
    for planner in all_planners() {
        let run = |seed| {
            let mut check = FnValidity::new(free.clone());
            plan(
                &space,
                &mut check,
                &[1.0, 1.0],
                &[9.0, 1.0],
                &options(planner.clone(), seed),
            )
            .unwrap()
            .path
            .unwrap()
        };
        assert_eq!(run(7), run(7), "{planner:?} is not deterministic");
        assert_ne!(run(7), run(8), "{planner:?} ignores the seed");
    }
}

#[test]
fn the_budget_is_kept_when_there_is_no_path() {
    let (space, _) = wall();
    // The wall without its gap: no path.
    let closed = |q: &[f64]| !(4.0..=6.0).contains(&q[0]);
    for planner in all_planners() {
        let mut check = FnValidity::new(closed);
        let mut o = options(planner.clone(), 1);
        o.time = Duration::from_millis(100);
        let t = Instant::now();
        let r = plan(&space, &mut check, &[1.0, 1.0], &[9.0, 1.0], &o).unwrap();
        assert!(!r.solved, "{planner:?} solved the impossible");
        assert!(
            t.elapsed() < Duration::from_millis(600),
            "{planner:?} overran: {:?}",
            t.elapsed()
        );
    }
}

#[test]
fn invalid_end_points_are_errors_that_say_which() {
    let (space, free) = wall();
    let mut check = FnValidity::new(free);
    let o = options(PlannerKind::parse("rrt-connect").unwrap(), 0);
    match plan(&space, &mut check, &[5.0, 1.0], &[9.0, 1.0], &o) {
        Err(PlanError::InvalidEndpoint { which, .. }) => assert_eq!(which, "start"),
        other => panic!("{other:?}"),
    }
    match plan(&space, &mut check, &[1.0, 1.0], &[11.0, 1.0], &o) {
        Err(PlanError::InvalidEndpoint { which, .. }) => assert_eq!(which, "goal"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn optimisers_shorten_and_stay_valid() {
    let (space, free) = wall();
    for optimizer in [
        OptimizerKind::Simple,
        OptimizerKind::Shortcut,
        OptimizerKind::Advanced {
            length: 1.0,
            ratio: 0.1,
        },
    ] {
        let mut o = options(PlannerKind::parse("rrt-con-con").unwrap(), 4);
        o.optimizer = optimizer;
        let mut check = FnValidity::new(free.clone());
        let r = plan(&space, &mut check, &[1.0, 1.0], &[9.0, 1.0], &o).unwrap();
        assert!(r.length_after < r.length_before, "{optimizer:?}: {r:?}");
        let p = r.optimized.unwrap();
        let mut fine = FnValidity::new(free.clone());
        assert!(path_valid(
            &space,
            &mut fine,
            &p,
            &Verifier::sequential(0.005)
        ));
        // Around the wall through the gap: at least the distance via the gap's lower corners.
        let via = ((5.0f64 - 1.0).powi(2) + 6.0f64.powi(2)).sqrt() * 2.0;
        assert!(
            r.length_after >= via - 1.0,
            "{optimizer:?}: {}",
            r.length_after
        );
    }
}

#[test]
fn a_wrap_around_joint_is_crossed_the_short_way() {
    // One continuous joint; everything in |θ| < 2.5 is blocked, so 2.8 → −2.8 must cross ±π.
    let space = JointSpace::new(vec![("theta".into(), Topology::Circle)]).unwrap();
    let free = |q: &[f64]| rl_plan::space::wrap_angle(q[0]).abs() >= 2.5;
    for planner in all_planners() {
        let mut check = FnValidity::new(free);
        let r = plan(
            &space,
            &mut check,
            &[2.8],
            &[-2.8],
            &options(planner.clone(), 2),
        )
        .unwrap();
        assert!(r.solved, "{planner:?}");
        let p = r.path.unwrap();
        let mut fine = FnValidity::new(free);
        assert!(
            path_valid(&space, &mut fine, &p, &Verifier::sequential(0.005)),
            "{planner:?}"
        );
        assert!(
            p.length(&space) < 1.0,
            "{planner:?} went the long way: {}",
            p.length(&space)
        );
    }
}

/// Distance from `q` to the wall of [`wall`] (its two closed rectangles).
fn distance_to_wall(q: &[f64]) -> f64 {
    let rect = |y0: f64, y1: f64| {
        let dx = (4.0 - q[0]).max(q[0] - 6.0).max(0.0);
        let dy = (y0 - q[1]).max(q[1] - y1).max(0.0);
        dx.hypot(dy)
    };
    rect(0.0, 7.0).min(rect(8.5, 10.0))
}

#[test]
fn gaussian_samples_lie_near_obstacles_and_bridge_samples_in_the_gap() {
    use rl_plan::sampler::{Bridge, Gaussian, Sampler, Uniform};
    use rl_plan::{Budget, Rng};
    let (space, mut free) = wall();
    let sigma = 0.2;
    let budget = Budget::new(Duration::from_secs(5));
    let mut q = [0.0; 2];
    let n = 500;

    // Uniform: only about a third of the free samples lie within 6σ of the wall.
    let mut validity = FnValidity::new(free.clone());
    let mut rng = Rng::seed_from(1);
    let mut near = 0;
    for _ in 0..n {
        assert!(Uniform.generate_valid(&space, &mut validity, &mut rng, &budget, &mut q));
        assert!(free(&q));
        near += usize::from(distance_to_wall(&q) <= 6.0 * sigma);
    }
    assert!(near < n / 2, "uniform: {near} of {n} near the wall");

    // Gaussian: a valid point whose Gaussian neighbour (or origin) is in the wall.
    let mut gaussian = Gaussian::new(vec![sigma; 2]);
    let mut rng = Rng::seed_from(2);
    for _ in 0..n {
        assert!(gaussian.generate_valid(&space, &mut validity, &mut rng, &budget, &mut q));
        assert!(free(&q), "gaussian sample {q:?} is not free");
        let d = distance_to_wall(&q);
        assert!(
            d <= 6.0 * sigma,
            "gaussian sample {q:?} is {d} from the wall"
        );
    }

    // Bridge (every sample a bridge, σ sized to the 1.5 wide gap): both ends in the wall, the
    // midpoint free — so in the gap.
    let mut bridge = Bridge::new(vec![1.0; 2], 1.0);
    let mut rng = Rng::seed_from(3);
    for _ in 0..n {
        assert!(bridge.generate_valid(&space, &mut validity, &mut rng, &budget, &mut q));
        assert!(
            (4.0..=6.0).contains(&q[0]) && (7.0..=8.5).contains(&q[1]),
            "bridge sample {q:?} is not in the passage"
        );
    }
}

#[test]
fn rrt_con_con_adds_one_vertex_per_connect_as_rl_does() {
    // Through the gap with steps of 0.1: a connect crosses many steps. RL's RrtCon::connect adds
    // only its last valid step, so every iteration adds at most two vertices (one per tree);
    // a vertex per step would add dozens.
    let (space, free) = wall();
    for seed in 0..5 {
        let mut planner = PlannerKind::parse("rrt-con-con").unwrap();
        planner.rrt_settings_mut().unwrap().delta = 0.1;
        let mut check = FnValidity::new(free.clone());
        let r = plan(
            &space,
            &mut check,
            &[1.0, 1.0],
            &[9.0, 1.0],
            &options(planner, seed),
        )
        .unwrap();
        assert!(r.solved, "seed {seed}");
        assert!(
            r.iterations > 0,
            "seed {seed}: the straight motion is blocked"
        );
        assert!(
            r.vertices as u64 <= 2 + 2 * r.iterations,
            "seed {seed}: {} vertices after {} iterations",
            r.vertices,
            r.iterations
        );
        let p = r.path.as_ref().unwrap();
        let mut f = free.clone();
        assert!((0..p.len()).all(|i| f(p.point(i))), "seed {seed}");
        assert!(p.length(&space) > 10.0, "seed {seed}: through the wall");
    }
}
