//! The blended execution of planned paths (`rl_plan::execute::blend`) on MotionBenchMaker Panda
//! problems, checked independently of how it was built: it starts and ends at rest at the
//! start and goal, its sampled velocity, acceleration and jerk stay within the limits, every
//! configuration sampled a tenth of the planner's resolution apart is free for the exact
//! meshes (rl-sg, parry), and it is shorter than stopping at every waypoint. An obstacle placed
//! where a blend leaves the path makes that blend shrink or stop, and the result is still free.
//!
//! Limits are checked twice: the exact derivatives (closed forms) within 1e-9 relative, and
//! central finite differences of sampled positions. A central difference of order `k` with
//! step `h` is an average of the `k`-th derivative over its stencil (a B-spline kernel), so it
//! obeys the same bound; its tolerance covers rounding only: `2^k · ε · max|q| / h^k`.

// Index loops over joints read as the math does (as in the crate).
#![allow(clippy::needless_range_loop)]

use std::path::PathBuf;
use std::time::Duration;

use rl_core::traj::{Piecewise, Segment, Trajectory};
use rl_plan::execute::{BlendOptions, Execution, ExecutionLimits, StopReason, WaypointOutcome};
use rl_plan::problem::{Robot, mbm};
use rl_plan::space::Topology;
use rl_plan::{JointSpace, Path, PlanOptions, Validity, plan};

const D: usize = 8;
/// Blended trajectories of up to 42 path segments.
const MAX: usize = 128;

fn data() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/mbm/panda"
    ))
}

fn panda() -> Robot {
    Robot::load_urdf(&data().join("panda.urdf"), None, None).unwrap()
}

fn options() -> PlanOptions {
    let mut o = PlanOptions {
        time: Duration::from_secs(5),
        optimize_time: Duration::from_secs(1),
        sampler: rl_plan::sampler::SamplerKind::Halton,
        ..Default::default()
    };
    let s = o.planner.rrt_settings_mut().unwrap();
    s.delta = 1.0;
    s.balance = true;
    o
}

/// The scene, start, goal and optimised path of a problem (planned with the hybrid checker,
/// as `rl run --plan` does).
fn planned(robot: &Robot, name: &str) -> (rl_sg::Model, Vec<f64>, Vec<f64>, Path) {
    let problems = mbm::find_problems(&data().join("problems")).unwrap();
    let p = problems
        .iter()
        .find(|p| p.name.starts_with(name))
        .unwrap_or_else(|| panic!("no problem {name}"));
    let (env, start, goal) = p.load(robot).unwrap();
    let mut hybrid = robot.hybrid_checker(&env).unwrap();
    let r = plan(&robot.space, &mut hybrid, &start, &goal, &options()).unwrap();
    assert!(r.solved, "{name}: not solved");
    (env, start, goal, r.optimized.unwrap())
}

fn limits(robot: &Robot) -> ExecutionLimits {
    ExecutionLimits::from_model(&robot.kinematics.model, 0.5).unwrap()
}

/// Largest speed any trajectory within `limits` can have in the (unweighted) joint metric.
fn speed_bound(limits: &ExecutionLimits) -> f64 {
    limits.velocity.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Checks starts, ends, limits (exact and finite differences) of `tr` through `waypoints`.
fn check_limits(
    name: &str,
    tr: &Piecewise<Segment<D>, MAX>,
    waypoints: &[Vec<f64>],
    limits: &ExecutionLimits,
) {
    let n = limits.velocity.len();
    let (first, last) = (&waypoints[0], waypoints.last().unwrap());
    let t_end = tr.duration();
    for (t, at) in [(0.0, first), (t_end, last)] {
        let s = tr.sample(t);
        for k in 0..n {
            assert!(
                (s.position[k] - at[k]).abs() < 1e-9,
                "{name}: joint {k} at t={t}"
            );
            assert!(
                s.velocity[k].abs() < 1e-9,
                "{name}: joint {k} moving at t={t}"
            );
            assert!(
                s.acceleration[k].abs() < 1e-9,
                "{name}: joint {k} accelerating at t={t}"
            );
        }
    }
    // Exact derivatives every millisecond.
    let step = 1e-3;
    let count = (t_end / step).ceil() as usize;
    let mut peak = [[0.0f64; D]; 3];
    for i in 0..=count {
        let s = tr.sample((i as f64 * step).min(t_end));
        for k in 0..n {
            for (o, (x, lim)) in [
                (s.velocity[k], &limits.velocity),
                (s.acceleration[k], &limits.acceleration),
                (s.jerk[k], &limits.jerk),
            ]
            .into_iter()
            .enumerate()
            {
                assert!(
                    x.abs() <= lim[k] * (1.0 + 1e-9),
                    "{name}: derivative {} of joint {k} is {x} at t={} (limit {})",
                    o + 1,
                    i as f64 * step,
                    lim[k]
                );
                peak[o][k] = peak[o][k].max(x.abs() / lim[k]);
            }
        }
    }
    // Finite differences of positions (h = 2 ms), bounded by the same limits up to rounding.
    let h = 2e-3;
    let q = |t: f64| tr.position(t);
    let max_q = waypoints
        .iter()
        .flatten()
        .fold(0.0f64, |m, x| m.max(x.abs()))
        + 1.0;
    let eps = f64::EPSILON * max_q;
    let steps = (t_end / h).ceil() as usize;
    for i in 0..=steps {
        let t = i as f64 * h;
        let (m2, m1, p0, p1, p2) = (q(t - 2.0 * h), q(t - h), q(t), q(t + h), q(t + 2.0 * h));
        for k in 0..n {
            let v = (p1[k] - m1[k]) / (2.0 * h);
            let a = (p1[k] - 2.0 * p0[k] + m1[k]) / (h * h);
            let j = (p2[k] - 2.0 * p1[k] + 2.0 * m1[k] - m2[k]) / (2.0 * h * h * h);
            assert!(
                v.abs() <= limits.velocity[k] + 2.0 * eps / h,
                "{name}: FD v {k} t={t}"
            );
            assert!(
                a.abs() <= limits.acceleration[k] + 4.0 * eps / (h * h),
                "{name}: FD a {k} t={t}"
            );
            assert!(
                j.abs() <= limits.jerk[k] + 8.0 * eps / (h * h * h),
                "{name}: FD j {k} t={t}"
            );
        }
    }
    println!(
        "{name}: peak fraction of the limits over the joints: velocity {:.3}, acceleration \
         {:.3}, jerk {:.3}",
        peak[0].iter().fold(0.0f64, |a, b| a.max(*b)),
        peak[1].iter().fold(0.0f64, |a, b| a.max(*b)),
        peak[2].iter().fold(0.0f64, |a, b| a.max(*b)),
    );
}

/// Every configuration of `tr` sampled at most `step` apart (measured) passes `validity`;
/// returns the number of samples.
fn all_valid(
    space: &JointSpace,
    validity: &mut dyn Validity,
    tr: &Piecewise<Segment<D>, MAX>,
    speed: f64,
    step: f64,
) -> Result<usize, (f64, Vec<f64>)> {
    let n = space.nq();
    let count = (tr.duration() * speed / step).ceil() as usize + 1;
    let mut prev: Option<Vec<f64>> = None;
    for i in 0..=count {
        let t = tr.duration() * i as f64 / count as f64;
        let q = tr.position(t)[..n].to_vec();
        if let Some(p) = &prev {
            assert!(
                space.distance(p, &q) <= step * (1.0 + 1e-9),
                "samples too far apart"
            );
        }
        if !validity.is_valid(&q) {
            return Err((t, q));
        }
        prev = Some(q);
    }
    Ok(count + 1)
}

#[test]
fn blended_panda_paths_stay_within_limits_and_free_and_beat_stopping() {
    let robot = panda();
    let limits = limits(&robot);
    let delta = options().verifier.delta;
    let step = delta / 10.0;
    let mut blended_somewhere = false;
    for name in [
        "box_panda",
        "table_pick_panda",
        "bookshelf_small_panda",
        "bookshelf_tall_panda",
        "cage_panda",
    ] {
        let BlendedProblem {
            env,
            start,
            goal,
            path,
            ex,
            b,
        } = blended_problem(&robot, name, &limits, delta);
        // No circle joints on the Panda: the unwrapped waypoints (sums of differences) are the
        // request's, to rounding.
        let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        assert!(close(&ex.waypoints()[0], &start) && close(ex.waypoints().last().unwrap(), &goal));
        let stop = ex.trajectory::<D, 64>().unwrap();
        let tr = &b.trajectory;
        println!(
            "{name}: {} waypoints; blended {:.3} s, stop at every waypoint {:.3} s; {}",
            path.len(),
            tr.duration(),
            stop.duration(),
            b.report
        );
        assert!((b.report.stop_duration_s - stop.duration()).abs() < 1e-9);
        assert!((b.report.duration_s - tr.duration()).abs() < 1e-12);
        assert_eq!(b.report.waypoints.len(), path.len() - 2);
        check_limits(name, tr, ex.waypoints(), &limits);
        tr.check_continuity(2, 1e-9)
            .unwrap_or_else(|d| panic!("{name}: {d:?}"));
        // An independent check with a fresh exact checker at a tenth of the resolution.
        let mut fresh = robot.exact_checker(env).unwrap();
        let samples = all_valid(&robot.space, &mut fresh, tr, speed_bound(&limits), step)
            .unwrap_or_else(|(t, q)| panic!("{name}: in collision at t={t}: {q:?}"));
        println!("{name}: {samples} samples {step} apart free for the exact meshes");
        if b.report.blended() > 0 {
            blended_somewhere = true;
            assert!(
                tr.duration() < stop.duration(),
                "{name}: blending was not faster"
            );
        } else {
            assert!(tr.duration() <= stop.duration() + 1e-9);
        }
    }
    assert!(blended_somewhere, "no path had a waypoint to blend through");
}

/// The configuration of `tr` farthest from the path's straight segments, with the nearest
/// point on them and the interior waypoint (index into the report's list) it is nearest to.
fn farthest_from_path(
    tr: &Piecewise<Segment<D>, MAX>,
    waypoints: &[Vec<f64>],
) -> (Vec<f64>, Vec<f64>, usize) {
    let n = waypoints[0].len();
    let mut best = (0.0, vec![], vec![], 0);
    let count = 4000;
    for i in 0..=count {
        let q = tr.position(tr.duration() * i as f64 / count as f64)[..n].to_vec();
        let mut nearest = (f64::INFINITY, vec![]);
        for w in waypoints.windows(2) {
            let d: Vec<f64> = (0..n).map(|k| w[1][k] - w[0][k]).collect();
            let dd: f64 = d.iter().map(|x| x * x).sum();
            let lam = ((0..n).map(|k| (q[k] - w[0][k]) * d[k]).sum::<f64>() / dd).clamp(0.0, 1.0);
            let p: Vec<f64> = (0..n).map(|k| w[0][k] + lam * d[k]).collect();
            let dist = (0..n).map(|k| (q[k] - p[k]).powi(2)).sum::<f64>().sqrt();
            if dist < nearest.0 {
                nearest = (dist, p);
            }
        }
        if nearest.0 > best.0 {
            let j = (1..waypoints.len() - 1)
                .min_by(|&a, &b| {
                    let da: f64 = (0..n).map(|k| (q[k] - waypoints[a][k]).powi(2)).sum();
                    let db: f64 = (0..n).map(|k| (q[k] - waypoints[b][k]).powi(2)).sum();
                    da.total_cmp(&db)
                })
                .unwrap();
            best = (nearest.0, q, nearest.1, j - 1);
        }
    }
    (best.1, best.2, best.3)
}

/// The exact meshes, and a ball obstacle in configuration space (all joints) around a point
/// where a blend leaves the path.
struct MeshesAndBall<V> {
    exact: V,
    centre: Vec<f64>,
    radius: f64,
}

impl<V: Validity> Validity for MeshesAndBall<V> {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        let d: f64 = q
            .iter()
            .zip(&self.centre)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        d > self.radius && self.exact.is_valid(q)
    }
    fn checks(&self) -> u64 {
        self.exact.checks()
    }
    fn free_checks(&self) -> u64 {
        self.exact.free_checks()
    }
}

/// An obstacle at the widest point of a blended corner of a Panda path (a ball in joint space
/// of half its distance to the path, so the path itself stays free): that blend must shrink
/// or stop, and the result must still be free for the exact meshes and the ball. (A ball in
/// the workspace, on a link's surface where the blend's widest point moves it, was tried on
/// box, cage and bookshelf_small: the links leave their straight-segment positions by 4.5 cm
/// at most there, and the straight motion itself swept every such ball.)
#[test]
fn an_obstacle_at_a_blended_corner_shrinks_or_stops_the_blend() {
    let robot = panda();
    let limits = limits(&robot);
    let delta = options().verifier.delta;
    let step = delta / 10.0;
    let (env, _, _, path) = planned(&robot, "box_panda");
    assert!(path.len() >= 3, "box_panda's path has a corner");
    let ex = Execution::new(&robot.space, &path, limits.clone()).unwrap();
    let opts = BlendOptions::for_resolution(delta);
    let mut exact = robot.exact_checker(env.clone()).unwrap();
    let free = ex
        .blended::<D, MAX>(&robot.space, &mut exact, &opts)
        .unwrap();
    let (q_out, q_on, corner) = farthest_from_path(&free.trajectory, ex.waypoints());
    assert_eq!(
        free.report.waypoints[corner],
        WaypointOutcome::Blended { shrinks: 0 }
    );
    let off = robot.space.distance(&q_out, &q_on);
    println!("box_panda: the blend at interior waypoint {corner} leaves the path by {off:.4} rad");
    let blocked = || MeshesAndBall {
        exact: robot.exact_checker(env.clone()).unwrap(),
        centre: q_out.clone(),
        radius: 0.5 * off,
    };
    // Every configuration of `tr` a tenth of the resolution apart is free of the meshes and
    // the ball.
    let free_of_ball = |tr: &Piecewise<Segment<D>, MAX>| {
        all_valid(&robot.space, &mut blocked(), tr, speed_bound(&limits), step)
    };
    // The path itself (stopping at every waypoint) is free of the ball.
    let stop = ex.stop_at_waypoints::<D, MAX>().unwrap();
    free_of_ball(&stop)
        .unwrap_or_else(|(t, q)| panic!("the path touches the ball at t={t}: {q:?}"));

    let b = ex
        .blended::<D, MAX>(&robot.space, &mut blocked(), &opts)
        .unwrap();
    println!("box_panda with the ball: {}", b.report);
    assert_ne!(
        b.report.waypoints[corner],
        WaypointOutcome::Blended { shrinks: 0 },
        "the blend at the ball was kept whole"
    );
    check_limits("box_panda, ball", &b.trajectory, ex.waypoints(), &limits);
    free_of_ball(&b.trajectory).unwrap_or_else(|(t, q)| panic!("in collision at t={t}: {q:?}"));
    assert!(b.report.duration_s <= b.report.stop_duration_s);

    // No shrinks allowed: the trajectory stops there, and is still free.
    let none = BlendOptions { shrinks: 0, ..opts };
    let b = ex
        .blended::<D, MAX>(&robot.space, &mut blocked(), &none)
        .unwrap();
    println!("box_panda with the ball, no shrinking: {}", b.report);
    assert_eq!(
        b.report.waypoints[corner],
        WaypointOutcome::Stopped(StopReason::Collision)
    );
    check_limits("box_panda, stopped", &b.trajectory, ex.waypoints(), &limits);
    free_of_ball(&b.trajectory).unwrap_or_else(|(t, q)| panic!("in collision at t={t}: {q:?}"));
}

/// A disc in a plane of two joints, just inside a right-angle corner of the path: the path
/// passes it, a blend cutting the corner does not.
struct Disc {
    centre: [f64; 2],
    radius: f64,
    checks: u64,
}

impl Validity for Disc {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        (q[0] - self.centre[0]).hypot(q[1] - self.centre[1]) > self.radius
    }
    fn checks(&self) -> u64 {
        self.checks
    }
    fn free_checks(&self) -> u64 {
        0
    }
}

#[test]
fn a_corner_blocked_in_configuration_space_is_shrunk_then_stopped_at() {
    let interval = Topology::Interval {
        lower: -2.0,
        upper: 2.0,
    };
    let space = JointSpace::new(vec![("a".into(), interval), ("b".into(), interval)]).unwrap();
    let path = Path::from_points(
        2,
        &[
            vec![0.0, 0.0],
            vec![1.0, 0.0],
            vec![1.0, 1.0],
            vec![0.0, 1.0],
        ],
    );
    let limits = ExecutionLimits {
        velocity: vec![1.0, 1.0],
        acceleration: vec![2.0, 2.0],
        jerk: vec![13.0, 13.0],
    };
    let ex = Execution::new(&space, &path, limits.clone()).unwrap();
    let opts = BlendOptions::for_resolution(0.01);
    // Free: both corners blended, faster than stopping.
    let mut free = Disc {
        centre: [5.0, 5.0],
        radius: 0.1,
        checks: 0,
    };
    let b = ex.blended::<D, MAX>(&space, &mut free, &opts).unwrap();
    assert_eq!(b.report.blended(), 2, "{}", b.report);
    assert!(
        b.report.duration_s < b.report.stop_duration_s,
        "{}",
        b.report
    );
    check_limits("square", &b.trajectory, ex.waypoints(), &limits);
    // A disc inside the first corner, 0.005 from both segments, where the full blend passes.
    let disc = || Disc {
        centre: [0.9, 0.1],
        radius: 0.095,
        checks: 0,
    };
    let mut blocked = disc();
    let b = ex.blended::<D, MAX>(&space, &mut blocked, &opts).unwrap();
    println!("disc in the corner: {}", b.report);
    assert_ne!(
        b.report.waypoints[0],
        WaypointOutcome::Blended { shrinks: 0 }
    );
    assert_eq!(
        b.report.waypoints[1],
        WaypointOutcome::Blended { shrinks: 0 }
    );
    check_limits("square, disc", &b.trajectory, ex.waypoints(), &limits);
    let mut check = disc();
    all_valid(&space, &mut check, &b.trajectory, 2f64.sqrt(), 0.001)
        .unwrap_or_else(|(t, q)| panic!("in the disc at t={t}: {q:?}"));
    // No shrinking allowed: it stops there, and still avoids the disc.
    let none = BlendOptions { shrinks: 0, ..opts };
    let b = ex.blended::<D, MAX>(&space, &mut disc(), &none).unwrap();
    assert_eq!(
        b.report.waypoints,
        vec![
            WaypointOutcome::Stopped(StopReason::Collision),
            WaypointOutcome::Blended { shrinks: 0 }
        ]
    );
    assert!(
        b.report.duration_s < b.report.stop_duration_s,
        "{}",
        b.report
    );
    all_valid(&space, &mut disc(), &b.trajectory, 2f64.sqrt(), 0.001)
        .unwrap_or_else(|(t, q)| panic!("in the disc at t={t}: {q:?}"));
    check_limits("square, stopped", &b.trajectory, ex.waypoints(), &limits);
}

/// The problems the retiming tests run.
const RETIMED: [&str; 5] = [
    "box_panda",
    "table_pick_panda",
    "bookshelf_small_panda",
    "bookshelf_tall_panda",
    "cage_panda",
];

/// A problem planned and its path blended (checked with the exact meshes).
struct BlendedProblem {
    /// The problem's scene.
    env: rl_sg::Model,
    start: Vec<f64>,
    goal: Vec<f64>,
    path: Path,
    /// The path's execution.
    ex: Execution,
    /// Its blended trajectory.
    b: rl_plan::execute::Blended<D, MAX>,
}

fn blended_problem(
    robot: &Robot,
    name: &str,
    limits: &ExecutionLimits,
    delta: f64,
) -> BlendedProblem {
    let (env, start, goal, path) = planned(robot, name);
    let ex = Execution::new(&robot.space, &path, limits.clone()).unwrap();
    let mut exact = robot.exact_checker(env.clone()).unwrap();
    let b = ex
        .blended::<D, MAX>(
            &robot.space,
            &mut exact,
            &BlendOptions::for_resolution(delta),
        )
        .unwrap();
    BlendedProblem {
        env,
        start,
        goal,
        path,
        ex,
        b,
    }
}

/// TOPP-RA on the geometry the blended trajectory follows: the least time any timing of it can
/// take within the velocity and acceleration limits (jerk unbounded), so at most the blended
/// duration; on a path of one segment (a straight line) the closed-form optimum, the limits'
/// trapezoid along the line. Prints how far the blends are from it (a jerk-limited timing of
/// the same geometry cannot reach it: on one segment rl-core's time-optimal jerk-limited move
/// takes 6 % longer with these limits).
#[test]
fn time_optimal_retiming_bounds_the_blended_durations() {
    let robot = panda();
    let limits = limits(&robot);
    let delta = options().verifier.delta;
    let n = limits.velocity.len();
    let mut single = 0;
    for name in RETIMED {
        let BlendedProblem { path, ex, b, .. } = blended_problem(&robot, name, &limits, delta);
        let tr = &*b.trajectory;
        let coarse = rl_plan::execute::time_optimal(tr, &limits, 2000).unwrap();
        let fine = rl_plan::execute::time_optimal(tr, &limits, 8000).unwrap();
        // Second order in the grid step: four times the stages, a sixteenth of the error.
        assert!(
            (coarse.duration() - fine.duration()).abs() < 2e-3 * fine.duration(),
            "{name}: {} s on 2000 stages, {} s on 8000",
            coarse.duration(),
            fine.duration()
        );
        assert!(
            fine.duration() <= tr.duration() * (1.0 + 1e-4),
            "{name}: TOPP-RA {} s, blended {} s",
            fine.duration(),
            tr.duration()
        );
        // The same configurations: the path's own, at its own times.
        let (q, _, _) = fine.sample::<D>(0.5 * fine.duration());
        let (s, _, _) = fine.timing().eval(0.5 * fine.duration());
        assert_eq!(q, tr.position(s));
        if ex.waypoints().len() == 2 {
            // A straight line: path speed and acceleration bounded by the joint that moves
            // most for its limits; the trapezoid (or triangle) of those bounds on length 1.
            let (a0, a1) = (&ex.waypoints()[0], &ex.waypoints()[1]);
            let v = (0..n)
                .map(|k| limits.velocity[k] / (a1[k] - a0[k]).abs())
                .fold(f64::INFINITY, f64::min);
            let a = (0..n)
                .map(|k| limits.acceleration[k] / (a1[k] - a0[k]).abs())
                .fold(f64::INFINITY, f64::min);
            let want = if v * v / a <= 1.0 {
                1.0 / v + v / a
            } else {
                2.0 / a.sqrt()
            };
            // The grid is uniform in the path's own time, singular where it is at rest
            // (q' ∝ τ² after a jerk-limited start): the first and last stages' error is
            // O(Δ^1.5), so finer grids approach the closed form more slowly than the interior's
            // second order. 2e-4 relative on 8000 stages, 5.5e-4 on 2000.
            let (e_coarse, e_fine) = (
                (coarse.duration() - want) / want,
                (fine.duration() - want) / want,
            );
            assert!(
                e_fine.abs() < 1e-3 && e_fine.abs() < e_coarse.abs(),
                "{name}: TOPP-RA {} s (2000 stages {} s), the line's trapezoid {want} s",
                fine.duration(),
                coarse.duration()
            );
            single += 1;
        }
        println!(
            "{name}: {} waypoints, {} blended; blended {:.3} s, time-optimal (v, a) on the same \
             geometry {:.3} s: ratio {:.3}",
            path.len(),
            b.report.blended(),
            tr.duration(),
            fine.duration(),
            tr.duration() / fine.duration()
        );
    }
    assert!(
        single >= 1,
        "no path of one segment to check the closed form on"
    );
}

/// The blended trajectory retimed with bounded jerk along its own configurations
/// (`execute::jerk_limited`): it starts and ends at rest at the start and goal, it keeps every
/// velocity, acceleration and jerk limit on 37 117 samples, its derivatives are those of its
/// positions (central differences), it never goes back along the path, on a single straight
/// segment it is rl-core's time-optimal jerk-limited move (to the 1e-3 margin asked), and it
/// is never faster than TOPP-RA's velocity-and-acceleration optimum. Prints the durations:
/// the retiming beats the blends where they keep one speed through many corners (cage).
#[test]
fn jerk_limited_retiming_keeps_the_limits_and_the_path() {
    let robot = panda();
    let limits = limits(&robot);
    let delta = options().verifier.delta;
    let n = limits.velocity.len();
    for name in RETIMED {
        let BlendedProblem {
            start, goal, ex, b, ..
        } = blended_problem(&robot, name, &limits, delta);
        let tr = &*b.trajectory;
        let topp = rl_plan::execute::time_optimal(tr, &limits, 4000).unwrap();
        let rests = rl_plan::execute::rests_of::<D, _, MAX>(tr, n);
        let j = rl_plan::execute::jerk_limited(tr, &rests, &limits, 1000, 1e-3).unwrap();
        let total = j.duration();
        // At rest at the start and the goal.
        for (t, q) in [(0.0, &start), (total, &goal)] {
            let [p, v, a, _] = j.sample::<D>(t);
            for k in 0..n {
                assert!((p[k] - q[k]).abs() < 1e-9, "{name}: joint {k} at {t}");
                assert!(
                    v[k].abs() < 1e-9 && a[k].abs() < 1e-6,
                    "{name}: moving at {t}"
                );
            }
        }
        // Every limit; the path's own time never decreases.
        let m = 37_117;
        let mut worst = [0.0f64; 3];
        let mut last = 0.0;
        for i in 0..=m {
            let t = total * i as f64 / m as f64;
            let [_, v, a, jj] = j.sample::<D>(t);
            for k in 0..n {
                worst[0] = worst[0].max(v[k].abs() / limits.velocity[k]);
                worst[1] = worst[1].max(a[k].abs() / limits.acceleration[k]);
                worst[2] = worst[2].max(jj[k].abs() / limits.jerk[k]);
            }
            let tau = j.path_time::<D>(t);
            assert!(tau >= last - 1e-12, "{name}: back along the path at {t}");
            last = tau;
        }
        assert!(
            worst.iter().all(|w| *w <= 1.0),
            "{name}: velocity, acceleration, jerk at {worst:?} of the limits"
        );
        // The derivatives are the positions': central differences, step h, agree to the
        // next derivative's bound times h² (velocity, acceleration); jerk steps where the
        // averaged s̈ bends, so there a difference of accelerations is checked at most
        // points.
        let h = 1e-5;
        let (mut jerk_ok, mut jerk_n) = (0, 0);
        for i in 1..400 {
            let t = total * i as f64 / 400.0;
            let [p0, v0, a0, _] = j.sample::<D>(t - h);
            let [_, v1, a1, j1] = j.sample::<D>(t);
            let [p2, v2, a2, _] = j.sample::<D>(t + h);
            for k in 0..n {
                let fv = (p2[k] - p0[k]) / (2.0 * h);
                let fa = (v2[k] - v0[k]) / (2.0 * h);
                let fj = (a2[k] - a0[k]) / (2.0 * h);
                assert!(
                    (fv - v1[k]).abs() <= 1e-6 * limits.velocity[k],
                    "{name}: joint {k} at {t}: velocity {} vs {fv}",
                    v1[k]
                );
                assert!(
                    (fa - a1[k]).abs() <= 1e-3 * limits.acceleration[k],
                    "{name}: joint {k} at {t}: acceleration {} vs {fa}",
                    a1[k]
                );
                jerk_n += 1;
                jerk_ok += usize::from((fj - j1[k]).abs() <= 1e-3 * limits.jerk[k]);
            }
        }
        assert!(
            jerk_ok * 100 >= jerk_n * 99,
            "{name}: jerk matches the accelerations' differences at {jerk_ok} of {jerk_n}"
        );
        assert!(
            total >= topp.duration() * (1.0 - 1e-3),
            "{name}: {total} s, below TOPP-RA's {} s",
            topp.duration()
        );
        if ex.waypoints().len() == 2 {
            assert!(
                total <= tr.duration() * (1.0 + 2e-3),
                "{name}: one straight segment in {total} s, rl-core's move {} s",
                tr.duration()
            );
        }
        println!(
            "{name}: blended {:.3} s, jerk-limited retiming {total:.3} s ({:.3} of blended), \
             TOPP-RA (v, a) {:.3} s: retiming/TOPP-RA {:.3}; limits reached {worst:.4?}; jerk \
             as the accelerations' differences at {jerk_ok} of {jerk_n} points",
            tr.duration(),
            total / tr.duration(),
            topp.duration(),
            total / topp.duration()
        );
    }
}
