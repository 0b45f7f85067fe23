//! Certified edges (conservative advancement, `SceneValidity::certify_edge`): an edge is
//! certified only if it keeps clear of everything, which dense sampling confirms; an edge that
//! passes between an edge verifier's samples through a thin obstacle is caught.

use std::path::PathBuf;
use std::time::Duration;

use glam::DVec3;
use rl_core::spatial::PlueckerTransform;
use rl_plan::problem::{Robot, mbm};
use rl_plan::scene::{CertifyOptions, SceneValidity, Uncertified};
use rl_plan::verifier::Verifier;
use rl_plan::{PlanOptions, Validity, plan};
use rl_sg::CollisionFilter;
use rl_sg::Geometry;

fn data() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/mbm"))
}

/// The smallest distance of any checked pair at `q` (self pairs and the environment).
fn clearance(checker: &mut SceneValidity, q: &[f64]) -> f64 {
    assert!(checker.place(q));
    let robot = checker.robot();
    let scene = checker.scene();
    [
        CollisionFilter::SelfCollision(robot),
        CollisionFilter::Against(robot),
    ]
    .iter()
    .filter_map(|f| scene.min_distance(f))
    .map(|d| d.distance)
    .fold(f64::INFINITY, f64::min)
}

/// The edge `a`–`b` is certified, and 2 001 samples along it agree: each keeps at least half
/// the margin, and none is closer than the certificate's closest distance.
fn certified_and_clear_densely(
    exact: &mut SceneValidity,
    space: &rl_plan::space::JointSpace,
    a: &[f64],
    b: &[f64],
    options: &CertifyOptions,
) {
    let cert = exact
        .certify_edge(a, b, options)
        .unwrap()
        .expect("clear of the plate");
    let mut q = vec![0.0; space.nq()];
    let dense = (0..=2_000)
        .map(|k| {
            space.interpolate(a, b, k as f64 / 2_000.0, &mut q);
            clearance(exact, &q)
        })
        .fold(f64::INFINITY, f64::min);
    println!(
        "certified in {} steps, dense clearance {dense:.4} m",
        cert.steps
    );
    assert!(dense >= options.margin / 2.0, "{dense}");
    assert!(cert.min_distance >= dense - 1e-12);
}

/// A one-joint arm about z: a 1 m × 1 cm × 1 cm bar along x from the axis.
const BAR_URDF: &str = r#"<robot name="bar">
  <link name="base"/>
  <link name="bar">
    <collision><origin xyz="0.5 0 0"/><geometry><box size="1 0.01 0.01"/></geometry></collision>
  </link>
  <joint name="j" type="revolute">
    <parent link="base"/><child link="bar"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
</robot>"#;

/// A 1 mm plate, 0.6 to 0.9 m out from the z axis and 20 cm tall, in the vertical plane
/// through the axis at `angle` (rad) from x.
fn plate_at(angle: f64) -> rl_sg::Model {
    let (c, s) = (angle.cos(), angle.sin());
    let mut env = rl_sg::Model::new("plate");
    env.add_body("plate")
        .add_shape(
            "plate",
            Geometry::cuboid(DVec3::new(0.3, 0.001, 0.1)).unwrap(),
            PlueckerTransform::new(
                glam::DMat3::from_rotation_z(angle),
                DVec3::new(0.75 * c, 0.75 * s, 0.0),
            ),
        )
        .unwrap();
    env
}

#[test]
fn a_thin_plate_between_the_verifiers_samples_is_caught() {
    let dir = std::env::temp_dir().join(format!("rl-plan-certify-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let urdf = dir.join("bar.urdf");
    std::fs::write(&urdf, BAR_URDF).unwrap();
    let robot = Robot::load_urdf(&urdf, None, None).unwrap();
    // The edge from −0.5 to 0.5 rad; a 1/32 rad verifier checks it at −0.5 + k/32. A 1 mm plate
    // on the plane through the axis at half a sample past 0.25 rad, from 0.6 to 0.9 m out, lies
    // between two samples: the bar (±5 mm) covers ±0.0055/0.6 rad ≈ ±0.0092 rad of the plate at
    // its inner end, a sample spacing is 0.031 rad.
    let (a, b) = ([-0.5], [0.5]);
    let delta: f64 = 1.0 / 32.0;
    let angle = -0.5 + (24.0 + 0.5) * delta;
    let env = plate_at(angle);
    let mut exact = robot.exact_checker(env).unwrap();
    assert!(exact.is_valid(&a) && exact.is_valid(&b));
    // The sampled verifier sees nothing...
    let verifier = Verifier::sequential(delta);
    let mut scratch = Default::default();
    assert!(
        verifier.is_valid(&robot.space, &mut exact, (&a, &b), true, &mut scratch),
        "the plate was meant to lie between samples"
    );
    // ...but the bar passes through the plate: dense sampling finds the contact,
    let hits = (0..=10_000)
        .map(|k| -0.5 + k as f64 / 10_000.0)
        .filter(|&q| !exact.is_valid(&[q]))
        .count();
    assert!(hits > 0);
    // and the certifier says where.
    let options = CertifyOptions::default();
    match exact.certify_edge(&a, &b, &options).unwrap() {
        Err(Uncertified::TooClose {
            s,
            a: x,
            b: y,
            distance,
        }) => {
            println!("caught at s = {s:.4}: {x} – {y}, {distance:.2e} m");
            let q = -0.5 + s;
            assert!(q < angle, "before the plate's plane: {q} vs {angle}");
            assert!(angle - q < 0.05, "near it: {q} vs {angle}");
            assert!(distance < options.margin);
        }
        other => panic!("not caught: {other:?}"),
    }
    // The same edge stopped short of the plate is certified, and dense sampling agrees that
    // it keeps at least half the margin everywhere.
    let short = [angle - 0.05];
    certified_and_clear_densely(&mut exact, &robot.space, &a, &short, &options);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_path_tells_its_progress_edge_by_edge() {
    let dir = std::env::temp_dir().join(format!("rl-plan-certify-progress-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let urdf = dir.join("bar.urdf");
    std::fs::write(&urdf, BAR_URDF).unwrap();
    let robot = Robot::load_urdf(&urdf, None, None).unwrap();
    let mut exact = robot.exact_checker(plate_at(0.3)).unwrap();
    let path = rl_plan::Path::from_points(1, &[vec![-0.5], vec![-0.3], vec![-0.1], vec![0.1]]);
    let options = CertifyOptions::default();
    let mut seen = Vec::new();
    let c = exact
        .certify_path_with_progress(&path, &options, &mut |p| seen.push(*p))
        .unwrap();
    assert!(c.is_certified(), "{c:?}");
    // Told before the first edge and after each one, steps adding up to the certificate's.
    let done: Vec<_> = seen.iter().map(|p| (p.edges_done, p.edges)).collect();
    assert_eq!(done, [(0, 3), (1, 3), (2, 3), (3, 3)]);
    assert_eq!(seen.last().unwrap().steps, c.steps);
    assert!(seen.windows(2).all(|w| w[0].steps < w[1].steps));
    // The plain call gives the same certificate.
    assert_eq!(exact.certify_path(&path, &options).unwrap(), c);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A free-floating 1 m bar (URDF `floating` joint: translation and a quaternion), its body from
/// the joint's origin out along x.
const FLOATING_BAR_URDF: &str = r#"<robot name="floating_bar">
  <link name="world"/>
  <link name="bar">
    <collision><origin xyz="0.5 0 0"/><geometry><box size="1 0.01 0.01"/></geometry></collision>
  </link>
  <joint name="j" type="floating"><parent link="world"/><child link="bar"/></joint>
</robot>"#;

/// `[x, y, z, quaternion about z by φ]`.
fn floating(z: f64, phi: f64) -> [f64; 7] {
    [0.0, 0.0, z, 0.0, 0.0, (phi / 2.0).sin(), (phi / 2.0).cos()]
}

/// Rotations (slerp) and translations together: the floating bar turning about z by one rad
/// while rising 2 cm sweeps through a 1 mm plate; the certifier catches it just before the
/// plate's plane, and certifies the motion stopped short of it, which dense sampling confirms.
#[test]
fn a_floating_body_turning_through_a_thin_plate_is_caught() {
    let dir = std::env::temp_dir().join(format!("rl-plan-certify-rot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let urdf = dir.join("floating_bar.urdf");
    std::fs::write(&urdf, FLOATING_BAR_URDF).unwrap();
    let loaded = rl_sg::load::load_robot::<{ rl_plan::scene::MAX_BODIES }>(
        &urdf,
        &Default::default(),
        &Default::default(),
        &mut rl_sg::load::MeshCache::new(),
    )
    .unwrap();
    let bounds: Vec<(String, f64, f64)> = ["x", "y", "z"]
        .iter()
        .map(|a| (format!("j/{a}"), -1.0, 1.0))
        .collect();
    let model = loaded.kinematics.model;
    let space = rl_plan::space::JointSpace::from_model_with_bounds(&model, &bounds).unwrap();
    assert_eq!(space.nq(), 7);
    let angle: f64 = 0.26;
    let env = plate_at(angle);
    let mut scene = rl_sg::Scene::new();
    let robot = scene.add_model(loaded.model).unwrap();
    scene.add_model(env).unwrap();
    let mut exact = SceneValidity::new(scene, robot, model, space.clone()).unwrap();
    let (a, b) = (floating(0.0, -0.5), floating(0.02, 0.5));
    assert!(exact.is_valid(&a) && exact.is_valid(&b));
    // Along the edge the bar turns at a constant rate (slerp) while rising: at fraction t its
    // angle is −0.5 + t; it passes through the plate.
    let n = 10_000;
    let mut q = [0.0; 7];
    let hits = (0..=n)
        .filter(|&k| {
            space.interpolate(&a, &b, k as f64 / n as f64, &mut q);
            !exact.is_valid(&q)
        })
        .count();
    assert!(hits > 0);
    let options = CertifyOptions::default();
    match exact.certify_edge(&a, &b, &options).unwrap() {
        Err(Uncertified::TooClose { s, distance, .. }) => {
            println!("caught at s = {s:.4}, {distance:.2e} m");
            let phi = -0.5 + s;
            assert!(phi < angle, "before the plate's plane: {phi} vs {angle}");
            assert!(angle - phi < 0.05, "near it: {phi} vs {angle}");
            assert!(distance < options.margin);
        }
        other => panic!("not caught: {other:?}"),
    }
    let short = floating(0.01, angle - 0.05);
    certified_and_clear_densely(&mut exact, &space, &a, &short, &options);
    let _ = std::fs::remove_dir_all(&dir);
}

/// On a robot's MotionBenchMaker fixtures: every edge of every planned path is certified or
/// refused; the certified ones keep at least half the margin at every one of 200 dense samples
/// each, and a refused one is measured within the margin where the certifier says.
#[test]
fn panda_path_edges_certified_are_clear_everywhere() {
    certified_edges_are_clear_everywhere("panda");
}

/// Heavy (≈5 min on two loaded cores: the UR5's fine gripper meshes make each exact distance
/// milliseconds): `cargo test -p rl-plan --release --test certify -- --ignored`. Last run
/// 2026-12-02: 21 edges certified, 1 refused (bookshelf_tall 0001, within 0.9 mm), dense
/// samples agreeing.
#[test]
#[ignore = "heavy: about 5 minutes; run on demand (see the doc comment)"]
fn ur5_path_edges_certified_are_clear_everywhere() {
    certified_edges_are_clear_everywhere("ur5");
}

fn certified_edges_are_clear_everywhere(name: &str) {
    let robot =
        Robot::load_urdf(&data().join(name).join(format!("{name}.urdf")), None, None).unwrap();
    let problems = mbm::find_problems(&data().join(name).join("problems")).unwrap();
    // 15 s: the hybrid checker asks the meshes wherever its covering spheres touch (issue 29),
    // slower in the cage than when the file's spheres refused on their own.
    let mut opts = PlanOptions {
        time: Duration::from_secs(15),
        optimize_time: Duration::from_secs(1),
        ..Default::default()
    };
    opts.seed = 1;
    let options = CertifyOptions {
        margin: 1e-3,
        ..Default::default()
    };
    let (mut certified, mut refused) = (0, 0);
    for p in &problems {
        let (env, start, goal) = p.load(&robot).unwrap();
        let mut hybrid = robot.hybrid_checker(&env).unwrap();
        let r = plan(&robot.space, &mut hybrid, &start, &goal, &opts).unwrap();
        let path = r.optimized.expect("solved");
        // The whole path through the planner's own checker's exact geometry.
        let whole = hybrid
            .exact_checker()
            .expect("the hybrid checker has exact geometry")
            .certify_path(&path, &options)
            .unwrap();
        let mut exact = robot.exact_checker(env).unwrap();
        let n = robot.space.nq();
        let before = refused;
        for e in 0..path.len() - 1 {
            let (a, b) = (path.point(e), path.point(e + 1));
            match exact.certify_edge(a, b, &options).unwrap() {
                Ok(cert) => {
                    certified += 1;
                    let mut q = vec![0.0; n];
                    let mut lowest = f64::INFINITY;
                    for k in 0..=200 {
                        robot.space.interpolate(a, b, k as f64 / 200.0, &mut q);
                        lowest = lowest.min(clearance(&mut exact, &q));
                    }
                    assert!(
                        lowest >= options.margin / 2.0,
                        "{} edge {e}: certified ({} steps) but {lowest} m clear",
                        p.name,
                        cert.steps
                    );
                }
                Err(Uncertified::TooClose { s, distance, .. }) => {
                    refused += 1;
                    let mut q = vec![0.0; n];
                    robot.space.interpolate(a, b, s, &mut q);
                    let measured = clearance(&mut exact, &q);
                    println!("{} edge {e}: within {distance:.2e} m at s = {s:.3}", p.name);
                    assert!(measured < options.margin, "{measured}");
                }
                Err(other) => panic!("{} edge {e}: {other}", p.name),
            }
        }
        assert_eq!(whole.edges, path.len() - 1);
        assert_eq!(whole.is_certified(), refused == before, "{whole:?}");
    }
    println!("{name}: {certified} edges certified, {refused} refused");
    assert!(certified > 0);
}
