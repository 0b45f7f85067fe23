//! Inverse kinematics: random reachable poses on a 6R (Puma 560 geometry), a 7R (KUKA iiwa
//! geometry), planar arms, a spherical wrist, a free-flying body and a two-armed tree; joint
//! limits, wraparound, unreachable goals, budgets, bad input, and a counting allocator that
//! proves solving allocates nothing.
//!
//! Targets are forward kinematics of random configurations (so they are reachable) and every
//! reported success is checked again here with an independent pose error.

use std::f64::consts::FRAC_PI_2;

use glam::{DMat3, DVec3};
use rl_core::algo::ik::{
    IkError, IkGoal, IkMethod, IkOptions, IkSolution, IkSolver, MAX_GOALS, SplitMix64,
};
use rl_core::algo::{forward_position, tool_pose};
use rl_core::joint::{Joint, Revolute, SixDof, Spherical};
use rl_core::model::{JointLimits, ROOT};
use rl_core::spatial::{PlueckerTransform, RigidBodyInertia};
use rl_core::{Data, Model, ModelBuilder};
use rl_testkit::{CountingAllocator, allocations};

// ---------------------------------------------------------------- counting allocator

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

// ---------------------------------------------------------------- models

fn link() -> RigidBodyInertia {
    RigidBodyInertia::from_com(1.0, DVec3::ZERO, DMat3::from_diagonal(DVec3::splat(0.01)))
}

/// Standard DH link transform `Tz(d) Tx(a) Rx(α)` (the joint rotation about z is the joint).
fn dh(d: f64, a: f64, alpha: f64) -> PlueckerTransform {
    PlueckerTransform::new(DMat3::from_rotation_x(alpha), DVec3::new(a, 0.0, d))
}

fn limits(lower_deg: f64, upper_deg: f64) -> JointLimits {
    JointLimits {
        lower: lower_deg.to_radians(),
        upper: upper_deg.to_radians(),
        ..JointLimits::UNLIMITED
    }
}

fn rz() -> Joint {
    Joint::Revolute(Revolute::new(DVec3::Z))
}

/// Adds joint `{prefix}j{k}` and link `{prefix}l{k}` below `parent`, the joint frame at
/// `placement`; returns the new body.
fn add_link<const N: usize>(
    b: &mut ModelBuilder<N>,
    parent: usize,
    joint: Joint,
    placement: PlueckerTransform,
    prefix: &str,
    k: usize,
) -> usize {
    b.add_body(
        parent,
        &format!("{prefix}j{k}"),
        joint,
        placement,
        &format!("{prefix}l{k}"),
        link(),
    )
    .unwrap()
}

/// Puma 560 standard DH table (Corke's `mdl_puma560`): `(d, a, α)` of each joint.
const PUMA_DH: [(f64, f64, f64); 6] = [
    (0.0, 0.0, FRAC_PI_2),
    (0.0, 0.4318, 0.0),
    (0.15005, 0.0203, -FRAC_PI_2),
    (0.4318, 0.0, FRAC_PI_2),
    (0.0, 0.0, -FRAC_PI_2),
    (0.0, 0.0, 0.0),
];

/// The Puma 560 ([`PUMA_DH`]) with its joint limits; the tool sits 0.1 m along the flange's z.
/// Returns the last body, so trees can hang several arms.
fn add_puma<const N: usize>(
    b: &mut ModelBuilder<N>,
    parent: usize,
    mount: PlueckerTransform,
    prefix: &str,
) -> usize {
    let lims = [
        (-160.0, 160.0),
        (-45.0, 225.0),
        (-225.0, 45.0),
        (-110.0, 170.0),
        (-100.0, 100.0),
        (-266.0, 266.0),
    ];
    let mut body = parent;
    let mut placement = mount;
    for (k, ((d, a, alpha), (lo, hi))) in PUMA_DH.iter().zip(lims).enumerate() {
        body = add_link(b, body, rz(), placement, prefix, k);
        b.set_limits(body, 0, limits(lo, hi)).unwrap();
        placement = dh(*d, *a, *alpha);
    }
    b.add_tool(
        &format!("{prefix}tool"),
        body,
        placement * dh(0.1, 0.0, 0.0),
    )
    .unwrap();
    body
}

fn puma() -> Model<8> {
    let mut b = ModelBuilder::<8>::new();
    add_puma(&mut b, ROOT, PlueckerTransform::IDENTITY, "");
    b.build()
}

/// KUKA LBR iiwa 14 geometry: axes z, y, z, -y, z, y, z; link lengths 0.36, 0.42, 0.4, 0.126.
fn iiwa() -> Model<8> {
    let mut b = ModelBuilder::<8>::new();
    let axes = [
        DVec3::Z,
        DVec3::Y,
        DVec3::Z,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::Y,
        DVec3::Z,
    ];
    let offsets = [0.1575, 0.2025, 0.2045, 0.2155, 0.1845, 0.2155, 0.081];
    let lims = [170.0, 120.0, 170.0, 120.0, 170.0, 120.0, 175.0];
    let mut body = ROOT;
    for k in 0..7 {
        let placement = PlueckerTransform::from_translation(DVec3::new(0.0, 0.0, offsets[k]));
        let joint = Joint::Revolute(Revolute::new(axes[k]));
        body = add_link(&mut b, body, joint, placement, "", k);
        b.set_limits(body, 0, limits(-lims[k], lims[k])).unwrap();
    }
    b.add_tool(
        "flange",
        body,
        PlueckerTransform::from_translation(DVec3::new(0.0, 0.0, 0.045)),
    )
    .unwrap();
    b.build()
}

/// A planar arm in the xy plane (joints about z) with the given link lengths; joint 0 may
/// wrap around.
fn planar(lengths: &[f64], wrap_first: bool) -> Model<4> {
    let mut b = ModelBuilder::<4>::new();
    let mut body = ROOT;
    let mut placement = PlueckerTransform::IDENTITY;
    for (k, l) in lengths.iter().enumerate() {
        body = add_link(&mut b, body, rz(), placement, "", k);
        if k == 0 && wrap_first {
            b.set_limits(
                body,
                0,
                JointLimits {
                    wraparound: true,
                    ..JointLimits::UNLIMITED
                },
            )
            .unwrap();
        }
        placement = PlueckerTransform::from_translation(DVec3::new(*l, 0.0, 0.0));
    }
    b.add_tool("tip", body, placement).unwrap();
    b.build()
}

/// A torso joint carrying two Puma arms (13 DOF, two tools).
fn two_arms() -> Model<16> {
    let mut b = ModelBuilder::<16>::new();
    let torso = b
        .add_body(
            ROOT,
            "torso",
            rz(),
            PlueckerTransform::IDENTITY,
            "torso",
            link(),
        )
        .unwrap();
    b.set_limits(torso, 0, limits(-90.0, 90.0)).unwrap();
    for (prefix, y) in [("left_", 0.3), ("right_", -0.3)] {
        let mount = PlueckerTransform::from_translation(DVec3::new(0.0, y, 0.5));
        add_puma(&mut b, torso, mount, prefix);
    }
    b.build()
}

/// The Puma's first three joints with a spherical (ball) wrist: a quaternion joint.
fn ball_wrist() -> Model<8> {
    let mut b = ModelBuilder::<8>::new();
    let mut body = ROOT;
    let mut placement = PlueckerTransform::IDENTITY;
    for (k, (d, a, alpha)) in PUMA_DH[..3].iter().enumerate() {
        body = add_link(&mut b, body, rz(), placement, "", k);
        placement = dh(*d, *a, *alpha);
    }
    let wrist = b
        .add_body(
            body,
            "wrist",
            Joint::Spherical(Spherical),
            placement * dh(0.4318, 0.0, 0.0),
            "hand",
            link(),
        )
        .unwrap();
    b.add_tool("tool", wrist, dh(0.15, 0.05, 0.0)).unwrap();
    b.build()
}

// ---------------------------------------------------------------- helpers

fn random_q<const N: usize>(model: &Model<N>, rng: &mut SplitMix64) -> Vec<f64> {
    let mut q = vec![0.0; model.nq()];
    model.random_configuration(&mut q, || rng.next_f64());
    q
}

fn fk_tool<const N: usize>(model: &Model<N>, q: &[f64], tool: usize) -> PlueckerTransform {
    let mut data = Data::<N>::new();
    forward_position(model, &mut data, q).unwrap();
    tool_pose(model, &data, tool).unwrap()
}

/// Position error (m) and rotation angle (rad) between two poses, computed independently of
/// the solver (angle from the trace).
fn pose_distance(a: &PlueckerTransform, b: &PlueckerTransform) -> (f64, f64) {
    let r = a.rotation.transpose() * b.rotation;
    let c = ((r.x_axis.x + r.y_axis.y + r.z_axis.z - 1.0) / 2.0).clamp(-1.0, 1.0);
    // acos loses precision near 0; use the skew part for small angles.
    let s = DVec3::new(
        r.y_axis.z - r.z_axis.y,
        r.z_axis.x - r.x_axis.z,
        r.x_axis.y - r.y_axis.x,
    )
    .length()
        / 2.0;
    ((a.translation - b.translation).length(), s.atan2(c))
}

fn within_limits<const N: usize>(model: &Model<N>, q: &[f64]) -> bool {
    (0..model.dof()).all(|k| model.limits(k).contains(q[k]))
}

#[derive(Default, Debug)]
struct Stats {
    tries: usize,
    solved: usize,
    iterations: usize,
    restarts: usize,
}

impl Stats {
    fn rate(&self) -> f64 {
        self.solved as f64 / self.tries as f64
    }
    fn mean_iterations(&self) -> f64 {
        self.iterations as f64 / self.solved.max(1) as f64
    }
    fn report(&self, what: &str) {
        eprintln!(
            "{what}: solved {}/{} ({:.0} %), mean iterations {:.1}, restarts {} in total",
            self.solved,
            self.tries,
            100.0 * self.rate(),
            self.mean_iterations(),
            self.restarts
        );
    }
    /// Reports, then checks that at least `min_rate` of the tries were solved.
    fn expect(&self, what: &str, min_rate: f64) {
        self.report(what);
        assert!(self.rate() >= min_rate, "{what}: {self:?}");
    }
}

/// One try on random reachable poses: the poses of tools `0..tools` at a random configuration
/// as goals, solved from another random configuration. A success is checked here, independently
/// of the solver (the poses' errors, `√Σ (dp² + da²)` in m and rad, below the solver's epsilon;
/// `q` within the limits) and counted in `stats`. Returns the solution and that error, or the
/// solver's error; `what` names the case in failure messages.
fn try_random_poses<const N: usize>(
    model: &Model<N>,
    solver: &mut IkSolver<N>,
    data: &mut Data<N>,
    rng: &mut SplitMix64,
    tools: usize,
    stats: &mut Stats,
    what: &str,
) -> Result<(IkSolution, f64), IkError> {
    let q_target = random_q(model, rng);
    let targets: Vec<PlueckerTransform> =
        (0..tools).map(|t| fk_tool(model, &q_target, t)).collect();
    let goals: Vec<IkGoal> = (0..tools).map(|t| IkGoal::pose(t, targets[t])).collect();
    let start = random_q(model, rng);
    let mut q = vec![0.0; model.nq()];
    stats.tries += 1;
    let s = solver.solve(model, data, &goals, &start, &mut q)?;
    let error = (0..tools)
        .map(|t| {
            let (dp, da) = pose_distance(&fk_tool(model, &q, t), &targets[t]);
            dp * dp + da * da
        })
        .sum::<f64>()
        .sqrt();
    assert!(
        error < solver.options.epsilon,
        "{what}: claimed {s:?}, actual pose error {error:e}"
    );
    assert!(
        within_limits(model, &q),
        "{what}: solution outside the limits: {q:?}"
    );
    stats.solved += 1;
    stats.iterations += s.iterations;
    stats.restarts += s.restarts;
    Ok((s, error))
}

/// Solves `count` random reachable pose goals for `model`'s tool 0, starting each from
/// another random configuration, and checks every success independently.
fn reach_random_poses<const N: usize>(
    model: &Model<N>,
    options: IkOptions,
    count: usize,
    seed: u64,
) -> Stats {
    let mut rng = SplitMix64::new(seed);
    let mut solver = IkSolver::<N>::new(options);
    let mut data = Data::<N>::new();
    let mut stats = Stats::default();
    for _ in 0..count {
        let what = "tool 0";
        match try_random_poses(model, &mut solver, &mut data, &mut rng, 1, &mut stats, what) {
            Ok((s, error)) => assert!((error - s.residual).abs() < 1e-9),
            Err(IkError::NotConverged { residual, .. }) => {
                assert!(residual >= options.epsilon && residual.is_finite());
            }
            Err(e) => panic!("unexpected error {e}"),
        }
    }
    stats
}

fn dls() -> IkOptions {
    IkOptions::default()
}

fn svd() -> IkOptions {
    IkOptions {
        method: IkMethod::PseudoInverse { threshold: 1e-3 },
        ..IkOptions::default()
    }
}

// ---------------------------------------------------------------- reaching poses

#[test]
fn puma_reaches_random_poses_with_dls() {
    let stats = reach_random_poses(&puma(), dls(), 100, 1);
    stats.expect("puma 6R, DLS λ=1e-3", 0.95);
}

#[test]
fn puma_reaches_random_poses_with_the_pseudo_inverse() {
    let stats = reach_random_poses(&puma(), svd(), 100, 2);
    stats.expect("puma 6R, SVD σ₀=1e-3", 0.95);
}

#[test]
fn iiwa_reaches_random_poses_with_dls() {
    let stats = reach_random_poses(&iiwa(), dls(), 100, 3);
    stats.expect("iiwa 7R, DLS λ=1e-3", 0.95);
}

#[test]
fn iiwa_reaches_random_poses_with_the_pseudo_inverse() {
    let stats = reach_random_poses(&iiwa(), svd(), 100, 4);
    stats.expect("iiwa 7R, SVD σ₀=1e-3", 0.95);
}

/// RL's "dls" is undamped (`λ = 0`, the right pseudo-inverse through `J Jᵀ`); it still
/// works away from exact singularities, where a failed Cholesky just restarts the attempt.
#[test]
fn undamped_dls_as_rl_has_it() {
    let options = IkOptions {
        method: IkMethod::Dls { lambda: 0.0 },
        ..IkOptions::default()
    };
    let stats = reach_random_poses(&iiwa(), options, 30, 13);
    stats.expect("iiwa 7R, DLS λ=0 (RL's dls)", 0.9);
}

/// The transpose method converges linearly, so it gets the easy case: position-only goals
/// on a planar 3R arm, with 2000 iterations per attempt.
#[test]
fn planar_arm_reaches_random_positions_with_the_transpose() {
    let model = planar(&[1.0, 0.8, 0.5], false);
    let options = IkOptions {
        method: IkMethod::Transpose,
        iterations_per_attempt: 2_000,
        max_iterations: 20_000,
        ..IkOptions::default()
    };
    let mut rng = SplitMix64::new(5);
    let mut solver = IkSolver::<4>::new(options);
    let mut data = Data::<4>::new();
    let mut stats = Stats::default();
    for _ in 0..30 {
        let target = fk_tool(&model, &random_q(&model, &mut rng), 0).translation;
        let start = random_q(&model, &mut rng);
        let mut q = vec![0.0; 3];
        stats.tries += 1;
        if let Ok(s) = solver.solve(
            &model,
            &mut data,
            &[IkGoal::position(0, target)],
            &start,
            &mut q,
        ) {
            assert!((fk_tool(&model, &q, 0).translation - target).length() < 1e-6);
            stats.solved += 1;
            stats.iterations += s.iterations;
        }
    }
    stats.expect("planar 3R position-only, transpose", 0.9);
}

/// All three methods on the same position-only goals of a planar 3R arm (redundant for a
/// 2-D position, and the z row of the error is identically zero: a rank-deficient J Jᵀ).
#[test]
fn position_only_goals_with_every_method() {
    let model = planar(&[1.0, 0.8, 0.5], false);
    for (name, options) in [
        ("DLS", dls()),
        ("SVD", svd()),
        (
            "transpose",
            IkOptions {
                method: IkMethod::Transpose,
                iterations_per_attempt: 2_000,
                ..dls()
            },
        ),
    ] {
        let mut rng = SplitMix64::new(6);
        let mut solver = IkSolver::<4>::new(options);
        let mut data = Data::<4>::new();
        for _ in 0..10 {
            let target = fk_tool(&model, &random_q(&model, &mut rng), 0).translation;
            let mut q = vec![0.0; 3];
            let s = solver
                .solve(
                    &model,
                    &mut data,
                    &[IkGoal::position(0, target)],
                    &[0.1, 0.2, 0.3],
                    &mut q,
                )
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(
                (fk_tool(&model, &q, 0).translation - target).length() < 1e-6,
                "{name}"
            );
            assert!(s.residual < 1e-6);
        }
    }
}

/// The Jacobian transpose on full 6-D pose goals of the Puma, to a looser 1e-4, with 5000
/// iterations per attempt: slow but it gets there.
#[test]
fn puma_transpose_reaches_poses_to_a_looser_tolerance() {
    let options = IkOptions {
        method: IkMethod::Transpose,
        epsilon: 1e-4,
        iterations_per_attempt: 5_000,
        max_iterations: 50_000,
        ..IkOptions::default()
    };
    let stats = reach_random_poses(&puma(), options, 10, 7);
    stats.expect("puma 6R pose to 1e-4, transpose", 0.8);
}

// ---------------------------------------------------------------- trees and joint types

#[test]
fn two_tools_on_a_branched_tree() {
    let model = two_arms();
    assert_eq!(model.tools().len(), 2);
    let mut rng = SplitMix64::new(8);
    let mut data = Data::<16>::new();
    for (name, options) in [("DLS", dls()), ("SVD", svd())] {
        let mut solver = IkSolver::<16>::new(options);
        let mut stats = Stats::default();
        for _ in 0..20 {
            // Failures are counted, not checked: the rate is.
            let _ = try_random_poses(
                &model,
                &mut solver,
                &mut data,
                &mut rng,
                2,
                &mut stats,
                name,
            );
        }
        stats.expect(
            &format!("two arms on a torso (13 DOF, 2 pose goals), {name}"),
            0.9,
        );
    }
}

#[test]
fn spherical_wrist_keeps_a_unit_quaternion() {
    let model = ball_wrist();
    assert_eq!((model.nq(), model.dof()), (7, 6));
    let mut rng = SplitMix64::new(9);
    let mut solver = IkSolver::<8>::new(dls());
    let mut data = Data::<8>::new();
    for _ in 0..20 {
        let target = fk_tool(&model, &random_q(&model, &mut rng), 0);
        let start = random_q(&model, &mut rng);
        let mut q = vec![0.0; 7];
        solver
            .solve(
                &model,
                &mut data,
                &[IkGoal::pose(0, target)],
                &start,
                &mut q,
            )
            .unwrap();
        let (dp, da) = pose_distance(&fk_tool(&model, &q, 0), &target);
        assert!(dp.hypot(da) < 1e-6);
        let norm = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-12, "quaternion norm {norm}");
    }
}

#[test]
fn free_flying_body_reaches_a_pose() {
    let mut b = ModelBuilder::<6>::new();
    let body = b
        .add_body(
            ROOT,
            "free",
            Joint::SixDof(SixDof),
            PlueckerTransform::IDENTITY,
            "box",
            link(),
        )
        .unwrap();
    b.add_tool(
        "corner",
        body,
        PlueckerTransform::from_translation(DVec3::new(0.2, 0.1, 0.0)),
    )
    .unwrap();
    let model = b.build();
    let target = PlueckerTransform::new(
        DMat3::from_euler(glam::EulerRot::ZYX, 2.0, -0.7, 2.5),
        DVec3::new(0.3, -0.4, 0.8),
    );
    let mut q = [0.0; 7];
    let start = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
    let s = IkSolver::<6>::new(dls())
        .solve(
            &model,
            &mut Data::new(),
            &[IkGoal::pose(0, target)],
            &start,
            &mut q,
        )
        .unwrap();
    let (dp, da) = pose_distance(&fk_tool(&model, &q, 0), &target);
    assert!(dp.hypot(da) < 1e-6 && s.restarts == 0, "{s:?}");
}

// ---------------------------------------------------------------- limits

#[test]
fn solutions_respect_tight_limits() {
    // The iiwa with every joint limited to ±60°: targets from configurations inside.
    let mut b = ModelBuilder::<8>::new();
    let base = iiwa();
    let mut body = ROOT;
    for i in 0..7 {
        body = b
            .add_body(
                body,
                model_name(&base, i),
                *base.joint(i),
                *base.placement(i),
                "l",
                link(),
            )
            .unwrap();
        b.set_limits(body, 0, limits(-60.0, 60.0)).unwrap();
    }
    b.add_tool("flange", body, base.tools()[0].placement)
        .unwrap();
    let model = b.build();
    let stats = reach_random_poses(&model, dls(), 40, 10);
    stats.expect("iiwa with ±60° limits, DLS", 0.9);
}

fn model_name<const N: usize>(m: &Model<N>, i: usize) -> &str {
    m.joint_name(i)
}

#[test]
fn a_goal_only_reachable_outside_the_limits_fails_inside_them() {
    // 2R planar arm with the elbow limited to [0°, 30°]; the target needs a 90° elbow.
    let mut b = ModelBuilder::<4>::new();
    let j0 = b
        .add_body(ROOT, "j0", rz(), PlueckerTransform::IDENTITY, "l0", link())
        .unwrap();
    let placement = PlueckerTransform::from_translation(DVec3::X);
    let j1 = b.add_body(j0, "j1", rz(), placement, "l1", link()).unwrap();
    b.set_limits(j1, 0, limits(0.0, 30.0)).unwrap();
    b.add_tool("tip", j1, placement).unwrap();
    let model = b.build();
    let target = fk_tool(&model, &[0.0, std::f64::consts::FRAC_PI_2], 0).translation;
    let options = IkOptions {
        max_iterations: 1_000,
        ..dls()
    };
    let mut q = [0.0; 2];
    let err = IkSolver::<4>::new(options)
        .solve(
            &model,
            &mut Data::new(),
            &[IkGoal::position(0, target)],
            &[0.0, 0.0],
            &mut q,
        )
        .unwrap_err();
    let IkError::NotConverged {
        residual,
        iterations,
        ..
    } = err
    else {
        panic!("{err:?}")
    };
    assert_eq!(iterations, 1_000);
    assert!(within_limits(&model, &q), "{q:?}");
    // The closest reachable point has the elbow at its 30° limit: |target| = √2 against a
    // reach of 2 cos 15°, so the residual is at least their difference.
    let best_possible = 2.0 * 15f64.to_radians().cos() - 2f64.sqrt();
    assert!(residual >= best_possible - 1e-9, "{residual}");
    assert!((fk_tool(&model, &q, 0).translation - target).length() - residual < 1e-12);
    // and it gets close to that best
    assert!(
        residual < best_possible + 1e-3,
        "{residual} vs {best_possible}"
    );
}

#[test]
fn wraparound_joints_stay_wrapped() {
    let model = planar(&[1.0, 0.8, 0.5], true);
    // Start near +π, target near −π: the base joint crosses the seam.
    let target = fk_tool(&model, &[-3.0, 0.4, 0.3], 0);
    let mut q = [0.0; 3];
    IkSolver::<4>::new(dls())
        .solve(
            &model,
            &mut Data::new(),
            &[IkGoal::pose(0, target)],
            &[3.0, 0.3, 0.2],
            &mut q,
        )
        .unwrap();
    assert!(
        (-std::f64::consts::PI..std::f64::consts::PI).contains(&q[0]),
        "{q:?}"
    );
    let (dp, da) = pose_distance(&fk_tool(&model, &q, 0), &target);
    assert!(dp.hypot(da) < 1e-6);
}

// ---------------------------------------------------------------- failures and budgets

#[test]
fn unreachable_goal_reports_the_best_residual() {
    let model = puma();
    let target = PlueckerTransform::from_translation(DVec3::new(3.0, 0.0, 0.0));
    for options in [dls(), svd()] {
        // Stall detection off, so every attempt runs its full 100 iterations.
        let options = IkOptions {
            max_iterations: 2_000,
            stall_iterations: usize::MAX,
            ..options
        };
        let mut q = [0.0; 6];
        let err = IkSolver::<8>::new(options)
            .solve(
                &model,
                &mut Data::new(),
                &[IkGoal::pose(0, target)],
                &[0.0; 6],
                &mut q,
            )
            .unwrap_err();
        let IkError::NotConverged {
            residual,
            iterations,
            restarts,
        } = err
        else {
            panic!("{err:?}")
        };
        assert_eq!(iterations, 2_000);
        assert_eq!(restarts, 19, "one restart per 100 iterations");
        // The Puma reaches less than 1 m; the goal is 3 m out.
        assert!(
            residual > 2.0 && residual < 3.0 + std::f64::consts::PI,
            "{residual}"
        );
        // q_out holds the configuration with that residual.
        let (dp, da) = pose_distance(&fk_tool(&model, &q, 0), &target);
        assert!((dp.hypot(da) - residual).abs() < 1e-9);
        assert!(within_limits(&model, &q));
        assert!(
            err.to_string()
                .contains("no solution after 2000 iterations")
        );
    }
    // With the default stall detection the hopeless attempts end early: more restarts.
    let mut q = [0.0; 6];
    let err = IkSolver::<8>::new(IkOptions {
        max_iterations: 2_000,
        ..dls()
    })
    .solve(
        &model,
        &mut Data::new(),
        &[IkGoal::pose(0, target)],
        &[0.0; 6],
        &mut q,
    )
    .unwrap_err();
    assert!(
        matches!(err, IkError::NotConverged { restarts: 40.., .. }),
        "{err:?}"
    );
}

#[test]
fn restart_limit_ends_the_search() {
    let model = puma();
    let target = PlueckerTransform::from_translation(DVec3::new(3.0, 0.0, 0.0));
    let options = IkOptions {
        max_restarts: 3,
        stall_iterations: usize::MAX,
        ..dls()
    };
    let mut q = [0.0; 6];
    let err = IkSolver::<8>::new(options)
        .solve(
            &model,
            &mut Data::new(),
            &[IkGoal::pose(0, target)],
            &[0.0; 6],
            &mut q,
        )
        .unwrap_err();
    assert!(
        matches!(
            err,
            IkError::NotConverged {
                iterations: 400,
                restarts: 3,
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn time_budget_stops_the_search() {
    let model = puma();
    let target = PlueckerTransform::from_translation(DVec3::new(3.0, 0.0, 0.0));
    let options = IkOptions {
        max_iterations: usize::MAX,
        ..dls()
    };
    let mut solver = IkSolver::<8>::new(options);
    let mut q = [0.0; 6];
    // A fake clock that advances 1 ms per reading: the 50 ms budget is spent after 50
    // readings — deterministic, no real time involved.
    let mut t = 0.0;
    let mut clock = || {
        t += 1e-3;
        t
    };
    let goals = [IkGoal::pose(0, target)];
    let err = solver
        .solve_within(
            &model,
            &mut Data::new(),
            &goals,
            &[0.0; 6],
            &mut q,
            &mut clock,
            0.05,
        )
        .unwrap_err();
    let IkError::TimeBudget {
        iterations,
        residual,
        ..
    } = err
    else {
        panic!("{err:?}")
    };
    assert!((49..=51).contains(&iterations), "{iterations}");
    assert!(residual > 2.0);
    // and with a real clock
    let start = std::time::Instant::now();
    let mut real = || start.elapsed().as_secs_f64();
    let err = solver
        .solve_within(
            &model,
            &mut Data::new(),
            &goals,
            &[0.0; 6],
            &mut q,
            &mut real,
            0.01,
        )
        .unwrap_err();
    assert!(matches!(err, IkError::TimeBudget { .. }), "{err:?}");
    // A reachable goal within a generous budget succeeds.
    let reachable = fk_tool(&model, &[0.3, 0.2, -0.4, 0.5, 0.6, 0.7], 0);
    solver
        .solve_within(
            &model,
            &mut Data::new(),
            &[IkGoal::pose(0, reachable)],
            &[0.0; 6],
            &mut q,
            &mut real,
            60.0,
        )
        .unwrap();
}

#[test]
fn same_seed_same_answer() {
    let model = iiwa();
    let mut rng = SplitMix64::new(11);
    let target = fk_tool(&model, &random_q(&model, &mut rng), 0);
    // A start far from the target and a short attempt force restarts.
    let options = IkOptions {
        iterations_per_attempt: 30,
        ..dls()
    };
    let solve = |seed| {
        let mut q = [0.0; 7];
        let s = IkSolver::<8>::new(IkOptions { seed, ..options })
            .solve(
                &model,
                &mut Data::new(),
                &[IkGoal::pose(0, target)],
                &[0.0; 7],
                &mut q,
            )
            .map(|s| s.iterations);
        (s, q)
    };
    let (a, b) = (solve(1), solve(1));
    assert_eq!(a, b);
    let c = solve(2);
    assert!(a.0.is_ok() && c.0.is_ok());
}

#[test]
fn a_solved_start_needs_no_iteration_and_steps_are_bounded() {
    let model = puma();
    let start = [0.3, 0.2, -0.4, 0.5, 0.6, 0.7];
    let goal = [IkGoal::pose(0, fk_tool(&model, &start, 0))];
    let mut q = [0.0; 6];
    let s = IkSolver::<8>::default()
        .solve(&model, &mut Data::new(), &goal, &start, &mut q)
        .unwrap();
    assert_eq!((s.iterations, s.restarts), (0, 0));
    assert_eq!(q, start);
    // One iteration towards a far goal moves q by at most max_step (Euclidean).
    let far = [IkGoal::pose(
        0,
        fk_tool(&model, &[-1.0, 1.0, -1.0, 1.0, -1.0, 1.0], 0),
    )];
    let options = IkOptions {
        max_iterations: 1,
        max_step: 0.1,
        ..dls()
    };
    let err = IkSolver::<8>::new(options)
        .solve(&model, &mut Data::new(), &far, &start, &mut q)
        .unwrap_err();
    assert!(
        matches!(err, IkError::NotConverged { iterations: 1, .. }),
        "{err:?}"
    );
    // q_out is the best of the two configurations seen, so either the start or one step on.
    let moved = q
        .iter()
        .zip(start)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(moved <= 0.1 + 1e-12, "{moved}");
}

// ---------------------------------------------------------------- bad input

#[test]
fn bad_input_is_refused_with_a_typed_error() {
    let model = puma();
    let mut data = Data::<8>::new();
    let mut solver = IkSolver::<8>::default();
    let ok_goal = IkGoal::pose(0, fk_tool(&model, &[0.1; 6], 0));
    let mut q = [7.0; 6];
    let mut run = |solver: &mut IkSolver<8>, goals: &[IkGoal], q_init: &[f64], q: &mut [f64]| {
        solver
            .solve(&model, &mut data, goals, q_init, q)
            .unwrap_err()
    };
    assert_eq!(
        run(&mut solver, &[ok_goal], &[0.0; 5], &mut q),
        IkError::Dimension {
            argument: "q_init",
            expected: 6,
            got: 5
        }
    );
    assert_eq!(
        run(&mut solver, &[ok_goal], &[0.0; 6], &mut [0.0; 7]),
        IkError::Dimension {
            argument: "q_out",
            expected: 6,
            got: 7
        }
    );
    assert_eq!(
        run(
            &mut solver,
            &[ok_goal],
            &[0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0],
            &mut q
        ),
        IkError::NotFiniteStart { index: 1 }
    );
    assert_eq!(run(&mut solver, &[], &[0.0; 6], &mut q), IkError::NoGoals);
    assert_eq!(
        run(&mut solver, &[ok_goal; MAX_GOALS + 1], &[0.0; 6], &mut q),
        IkError::TooManyGoals { got: MAX_GOALS + 1 }
    );
    assert_eq!(
        run(
            &mut solver,
            &[ok_goal, IkGoal::pose(1, PlueckerTransform::IDENTITY)],
            &[0.0; 6],
            &mut q
        ),
        IkError::UnknownTool { goal: 1, tool: 1 }
    );
    let nan = IkGoal::position(0, DVec3::new(0.0, f64::NAN, 0.0));
    assert!(matches!(
        run(&mut solver, &[nan], &[0.0; 6], &mut q),
        IkError::InvalidGoal { goal: 0, .. }
    ));
    let mut squashed = PlueckerTransform::IDENTITY;
    squashed.rotation.z_axis = DVec3::new(0.0, 0.0, 0.5);
    let e = run(
        &mut solver,
        &[ok_goal, IkGoal::pose(0, squashed)],
        &[0.0; 6],
        &mut q,
    );
    assert_eq!(
        e,
        IkError::InvalidGoal {
            goal: 1,
            reason: "target rotation is not a rotation matrix"
        }
    );
    assert_eq!(
        e.to_string(),
        "goal 1: target rotation is not a rotation matrix"
    );
    for (options, name) in [
        (
            IkOptions {
                method: IkMethod::Dls { lambda: -1.0 },
                ..dls()
            },
            "lambda",
        ),
        (
            IkOptions {
                method: IkMethod::PseudoInverse { threshold: 0.0 },
                ..dls()
            },
            "threshold",
        ),
        (
            IkOptions {
                epsilon: 0.0,
                ..dls()
            },
            "epsilon",
        ),
        (
            IkOptions {
                epsilon: f64::NAN,
                ..dls()
            },
            "epsilon",
        ),
        (
            IkOptions {
                iterations_per_attempt: 0,
                ..dls()
            },
            "iterations_per_attempt",
        ),
        (
            IkOptions {
                stall_iterations: 0,
                ..dls()
            },
            "stall_iterations",
        ),
        (
            IkOptions {
                max_step: f64::NAN,
                ..dls()
            },
            "max_step",
        ),
    ] {
        solver.options = options;
        assert_eq!(
            run(&mut solver, &[ok_goal], &[0.0; 6], &mut q),
            IkError::InvalidOption { option: name }
        );
    }
    // Nothing was written on refusal.
    assert_eq!(q, [7.0; 6]);
    solver.options = dls();
    let mut clock = || 0.0;
    let e = solver
        .solve_within(
            &model,
            &mut data,
            &[ok_goal],
            &[0.0; 6],
            &mut q,
            &mut clock,
            f64::NAN,
        )
        .unwrap_err();
    assert_eq!(e, IkError::InvalidOption { option: "budget_s" });
}

// ---------------------------------------------------------------- allocation

#[test]
fn solving_allocates_nothing() {
    // The counter sees this thread's allocations (a check of the instrument itself).
    let (n, probe) = allocations(|| std::hint::black_box(vec![1u8; 16]));
    assert!(n > 0 && probe.len() == 16);
    let model = two_arms();
    let mut data = Data::<16>::new();
    let mut rng = SplitMix64::new(12);
    let q_target = random_q(&model, &mut rng);
    let goals = [
        IkGoal::pose(0, fk_tool(&model, &q_target, 0)),
        IkGoal::position(1, fk_tool(&model, &q_target, 1).translation),
    ];
    let unreachable = [IkGoal::pose(
        0,
        PlueckerTransform::from_translation(DVec3::splat(5.0)),
    )];
    let start = random_q(&model, &mut rng);
    let mut q = vec![0.0; model.nq()];
    let methods = [
        dls(),
        svd(),
        IkOptions {
            method: IkMethod::Transpose,
            max_iterations: 3_000,
            ..dls()
        },
    ];
    let mut solvers: Vec<IkSolver<16>> = methods.iter().map(|o| IkSolver::new(*o)).collect();
    let mut results: Vec<Result<IkSolution, IkError>> = Vec::with_capacity(8);
    let mut clock = || 0.0;
    let (n, ()) = allocations(|| {
        for solver in solvers.iter_mut() {
            results.push(solver.solve(&model, &mut data, &goals, &start, &mut q));
        }
        // The failure path with restarts and the timed variant.
        solvers[0].options.max_iterations = 500;
        results.push(solvers[0].solve(&model, &mut data, &unreachable, &start, &mut q));
        results.push(
            solvers[1].solve_within(&model, &mut data, &goals, &start, &mut q, &mut clock, 1.0),
        );
    });
    assert_eq!(n, 0, "IK allocated {n} times");
    assert!(results[0].is_ok() && results[1].is_ok(), "{results:?}");
    assert!(matches!(results[3], Err(IkError::NotConverged { .. })));
    assert!(results[4].is_ok());
}

// ---------------------------------------------------------------- RL's example models

/// Every model of RL's example corpus (`tests/data/rlmdl`): random reachable poses of all its
/// tools at once (up to `MAX_GOALS`) with DLS and SVD, checked independently.
#[cfg(feature = "std")]
#[test]
fn rl_example_models_reach_random_poses() {
    use rl_core::loader;
    const C: usize = 32;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/rlmdl");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        // RL's XSLT-parameterised form is refused by the loader (see loader_rlmdl.rs).
        .filter(|p| !p.to_string_lossy().ends_with(".param.xml"))
        .collect();
    files.sort();
    assert!(files.len() >= 12, "corpus not found in {}", dir.display());
    for (f, path) in files.iter().enumerate() {
        let model = loader::load_file::<C>(path).unwrap().model;
        let tools = model.tools().len().min(MAX_GOALS);
        assert!(tools > 0);
        for (method, options) in [("DLS", dls()), ("SVD", svd())] {
            let mut rng = SplitMix64::new(100 + f as u64);
            let mut solver = IkSolver::<C>::new(options);
            let mut data = Data::<C>::new();
            let mut stats = Stats::default();
            let what = path.display().to_string();
            for _ in 0..20 {
                // Failures are counted, not checked: the rate is.
                let _ = try_random_poses(
                    &model,
                    &mut solver,
                    &mut data,
                    &mut rng,
                    tools,
                    &mut stats,
                    &what,
                );
            }
            let name = path.file_name().unwrap().to_string_lossy();
            stats.expect(
                &format!("{name} ({} DOF, {tools} tools), {method}", model.dof()),
                0.9,
            );
        }
    }
}
