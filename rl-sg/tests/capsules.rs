//! The control-rate path: fitted capsules contain their bodies (sampled surface points), its
//! distances never exceed the exact ones, and the kernel and the scene update allocate nothing.

mod support;

use glam::{DMat3, DVec3};
use rl_core::spatial::PlueckerTransform;
use rl_sg::capsule::{Capsule, CapsuleModel};
use rl_sg::fit::{FitOptions, fit_body, fit_capsule_model};
use rl_sg::{Body, Geometry, Model};
use rl_testkit::{CountingAllocator, allocations};
use support::{Rng, rlsg_data};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// A point on the surface of `g` (its own frame), uniformly enough to find a gap.
fn surface_point(g: &Geometry, r: &mut Rng) -> DVec3 {
    let disc = |r: &mut Rng, radius: f64| {
        let (a, s) = (
            r.range(0.0, std::f64::consts::TAU),
            radius * r.uniform().sqrt(),
        );
        DVec3::new(s * a.cos(), s * a.sin(), 0.0)
    };
    let ring = |r: &mut Rng, radius: f64| {
        let a = r.range(0.0, std::f64::consts::TAU);
        DVec3::new(radius * a.cos(), radius * a.sin(), 0.0)
    };
    let dir = |r: &mut Rng| loop {
        let v = r.vec3(1.0);
        if v.length() > 0.1 && v.length() < 1.0 {
            break v.normalize();
        }
    };
    match g {
        Geometry::Box { size } => {
            let h = *size / 2.0;
            let mut p = DVec3::new(r.range(-h.x, h.x), r.range(-h.y, h.y), r.range(-h.z, h.z));
            let axis = (r.uniform() * 3.0) as usize;
            let sign = if r.uniform() < 0.5 { -1.0 } else { 1.0 };
            p[axis] = sign * h[axis];
            p
        }
        Geometry::Sphere { radius } => dir(r) * *radius,
        Geometry::Cylinder { radius, length } => match (r.uniform() * 3.0) as usize {
            0 => ring(r, *radius) + DVec3::Z * r.range(-length / 2.0, length / 2.0),
            1 => disc(r, *radius) + DVec3::Z * (length / 2.0),
            _ => disc(r, *radius) - DVec3::Z * (length / 2.0),
        },
        Geometry::Capsule { radius, length } => {
            if r.uniform() < 0.5 {
                ring(r, *radius) + DVec3::Z * r.range(-length / 2.0, length / 2.0)
            } else {
                let d = dir(r);
                d * *radius + DVec3::Z * (length / 2.0).copysign(d.z)
            }
        }
        Geometry::Cone { radius, length } => {
            if r.uniform() < 0.5 {
                disc(r, *radius) - DVec3::Z * (length / 2.0)
            } else {
                let t = r.uniform();
                ring(r, radius * (1.0 - t)) + DVec3::Z * (-length / 2.0 + t * length)
            }
        }
        Geometry::Convex(m) | Geometry::Mesh(m) => {
            let k = (r.uniform() * m.triangles().len() as f64) as usize;
            let [a, b, c] = m.triangle(k.min(m.triangles().len() - 1));
            let (mut u, mut v) = (r.uniform(), r.uniform());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            a + (b - a) * u + (c - a) * v
        }
        Geometry::HalfSpace { .. } => unreachable!("no surface samples of a half-space"),
    }
}

/// Checks that `capsules` (body frame) contain `samples` points of every shape of `body`, and
/// every mesh vertex; returns the largest excess (≤ 0: inside).
fn worst_excess(body: &Body, capsules: &[Capsule], samples: usize, r: &mut Rng) -> f64 {
    let mut worst = f64::NEG_INFINITY;
    let mut check = |p: DVec3| {
        let d = capsules
            .iter()
            .map(|c| c.signed_distance_to_point(p))
            .fold(f64::INFINITY, f64::min);
        worst = worst.max(d);
    };
    for s in body.shapes() {
        let x = s.local_pose();
        for _ in 0..samples {
            let p = surface_point(s.geometry(), r);
            check(x.rotation * p + x.translation);
        }
        if let Geometry::Mesh(m) | Geometry::Convex(m) = s.geometry() {
            for &v in m.vertices() {
                check(x.rotation * v + x.translation);
            }
        }
    }
    worst
}

/// A body of every primitive kind, at odd poses.
fn primitives_body() -> Model {
    let mut r = Rng::new(3);
    let mut m = Model::new("primitives");
    let b = m.add_body("all");
    for g in [
        Geometry::cuboid(DVec3::new(0.3, 0.1, 0.05)).unwrap(),
        Geometry::sphere(0.07).unwrap(),
        Geometry::cylinder(0.04, 0.3).unwrap(),
        Geometry::capsule(0.03, 0.2).unwrap(),
        Geometry::cone(0.05, 0.12).unwrap(),
        Geometry::convex_hull(&(0..20).map(|_| r.vec3(0.1)).collect::<Vec<_>>()).unwrap(),
    ] {
        let pose = PlueckerTransform::new(DMat3::from_quat(r.quat()), r.vec3(0.3));
        b.add_shape("s", g, pose).unwrap();
    }
    m
}

#[test]
fn fitted_capsules_contain_every_sampled_surface_point() {
    let mut models = vec![primitives_body()];
    for f in ["twotori.xml", "unimation-puma560.convex.xml", "planar3.xml"] {
        let s = rl_sg::load::rlsg::load_scene(&rlsg_data().join(f)).unwrap();
        models.extend(s.models().iter().cloned());
    }
    let mut r = Rng::new(11);
    let mut checked = 0;
    for m in &models {
        for b in m.bodies() {
            for options in [
                FitOptions::default(),
                FitOptions {
                    per_body: 1,
                    ..FitOptions::default()
                },
                FitOptions {
                    per_body: 4,
                    ..FitOptions::default()
                },
                FitOptions {
                    spheres: true,
                    per_body: 3,
                    ..FitOptions::default()
                },
            ] {
                let caps = fit_body(b, &options).unwrap();
                if b.shapes().is_empty() {
                    assert!(caps.is_empty());
                    continue;
                }
                assert!(!caps.is_empty() && caps.len() <= options.per_body);
                let e = worst_excess(b, &caps, 2000, &mut r);
                assert!(
                    e <= 1e-12,
                    "{}/{}: a surface point {e} m outside ({options:?})",
                    m.name(),
                    b.name()
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 40, "{checked}");
}

#[test]
fn a_fit_that_shrinks_is_caught() {
    // The check above can fail: a capsule 1 mm too thin leaves points outside.
    let m = primitives_body();
    let b = &m.bodies()[0];
    let mut caps = fit_body(b, &FitOptions::default()).unwrap();
    for c in &mut caps {
        c.radius -= 1e-3;
    }
    assert!(worst_excess(b, &caps, 2000, &mut Rng::new(5)) > 0.0);
}

#[test]
fn capsule_distances_never_exceed_the_exact_ones() {
    let scene =
        rl_sg::load::rlsg::load_scene(&rlsg_data().join("unimation-puma560.convex.xml")).unwrap();
    let robot = &scene.models()[0];
    let fitted = fit_capsule_model::<32>(robot, &FitOptions::default()).unwrap();
    let mut caps = fitted.capsules.clone();
    caps.update_world_only();
    let mut r = Rng::new(21);
    let mut tightest = f64::INFINITY;
    for _ in 0..300 {
        let c = DVec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(0.0, 1.6));
        let radius = r.range(0.01, 0.1);
        let kernel = caps.min_distance(&[Capsule::sphere(c, radius)]).unwrap();
        // The exact distance from the meshes.
        let mut s = scene.clone();
        let mut ball = Model::new("ball");
        ball.add_body("ball")
            .add_shape(
                "b",
                Geometry::sphere(radius).unwrap(),
                PlueckerTransform::from_translation(c),
            )
            .unwrap();
        let ib = s.add_model(ball).unwrap();
        let exact = s.model_distance(rl_sg::ModelId(0), ib).unwrap();
        assert!(
            kernel.distance <= exact.distance + 1e-9,
            "capsules {} > exact {} at {c:?}",
            kernel.distance,
            exact.distance
        );
        tightest = tightest.min(exact.distance - kernel.distance);
        // The kernel's closest point on the robot and the sphere's are consistent.
        assert!(
            ((kernel.point - kernel.other_point).length() - kernel.distance.abs()).abs() < 1e-9
        );
    }
    assert!(tightest >= -1e-9);
}

#[test]
fn the_kernel_and_the_scene_update_allocate_nothing() {
    // The Puma 560 linked to its RL kinematics, as a controller would hold it.
    let data_dir = rlsg_data();
    let rlmdl = support::repo().join("tests/data/rlmdl/unimation-puma560.xml");
    let loaded = rl_core::loader::load_file::<8>(&rlmdl).unwrap();
    let mut scene =
        rl_sg::load::rlsg::load_scene(&data_dir.join("unimation-puma560_boxes.convex.xml"))
            .unwrap();
    let id = rl_sg::ModelId(0);
    rl_sg::load::rlsg::link_rlmdl(scene.model_mut(id).unwrap(), &rlmdl, &loaded).unwrap();
    let fitted = fit_capsule_model::<32>(&scene.models()[0], &FitOptions::default()).unwrap();
    let mut caps: Box<CapsuleModel<32>> = Box::new(fitted.capsules.clone());
    let mut data = Box::new(rl_core::Data::<8>::new());
    let mut r = Rng::new(1);
    let qs: Vec<Vec<f64>> = (0..50)
        .map(|_| (0..6).map(|_| r.range(-3.0, 3.0)).collect())
        .collect();
    let obstacles: Vec<Capsule> = (0..10).map(|_| Capsule::sphere(r.vec3(1.0), 0.1)).collect();
    let pairs = fitted.self_pairs.clone();
    let mut per = [0.0; 32];
    let mut sink = 0.0;
    // Warm up (first use of lazily built tables happens outside the loop).
    scene
        .set_configuration(id, &loaded.model, &mut data, &qs[0])
        .unwrap();
    let (n, ()) = allocations(|| {
        for q in &qs {
            rl_core::algo::forward_position(&loaded.model, &mut data, q).unwrap();
            caps.update(&data);
            sink += caps.min_distance(&obstacles).map_or(0.0, |d| d.distance);
            sink += caps.min_self_distance(&pairs).map_or(0.0, |d| d.distance);
            sink += f64::from(u8::from(caps.any_closer_than(&obstacles, 0.05)));
            caps.distances_per_capsule(&obstacles, &mut per);
            scene.update(id, &data).unwrap();
            scene
                .set_configuration(id, &loaded.model, &mut data, q)
                .unwrap();
        }
    });
    assert_eq!(n, 0, "the control-rate path allocated {n} times");
    assert!(sink.is_finite());
    // And the scene really moved with the kinematics.
    let q = &qs[qs.len() - 1];
    rl_core::algo::forward_position(&loaded.model, &mut data, q).unwrap();
    let (k, x) = scene.models()[0].kinematics().unwrap().frame(3).unwrap();
    let expect = *data.world_pose(k) * x;
    let got = scene.models()[0].bodies()[3].pose();
    assert!((got.translation - expect.translation).length() < 1e-12);
    // A NaN configuration is refused before it reaches the scene.
    let nan = [f64::NAN; 6];
    assert!(
        scene
            .set_configuration(id, &loaded.model, &mut data, &nan)
            .is_err()
    );
}

/// A model without collision geometry gets a capsule along every link of its skeleton: every
/// joint's origin and the tool's lie on a capsule's axis, wherever the arm is.
#[test]
fn a_skeleton_covers_every_joint_origin_and_the_tool() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../rl-core/tests/data/urdf/kuka_lbr_iiwa.urdf"
    );
    let m = rl_core::loader::load_file::<16>(path)
        .unwrap_or_else(|e| panic!("{e}"))
        .model;
    let mut caps = CapsuleModel::<32>::skeleton(&m, 0.06).unwrap();
    // One per child joint and per tool (a chain: one per body).
    assert_eq!(caps.len(), m.body_count());
    let mut d = rl_core::Data::<16>::new();
    let mut r = Rng::new(3);
    for _ in 0..20 {
        let q: Vec<f64> = (0..m.dof()).map(|_| r.range(-2.0, 2.0)).collect();
        rl_core::algo::forward_position(&m, &mut d, &q).unwrap();
        caps.update(&d);
        let tool = rl_core::algo::tool_pose(&m, &d, 0).unwrap().translation;
        let points = (0..m.body_count())
            .map(|b| d.world_pose(b).translation)
            .chain([tool]);
        for p in points {
            let on_axis = (0..caps.len())
                .filter_map(|i| caps.world_capsule(i))
                .map(|c| c.signed_distance_to_point(p) + c.radius)
                .fold(f64::INFINITY, f64::min);
            assert!(on_axis.abs() < 1e-12, "{p}: {on_axis}");
        }
    }
    assert!(CapsuleModel::<3>::skeleton(&m, 0.06).is_err());
}
