//! Scene queries on shapes whose answers are known in closed form, and the broad phase against
//! brute force (every pair through the narrow phase) on cluttered random scenes.

mod support;

use glam::{DMat3, DVec3};
use rl_core::spatial::PlueckerTransform;
use rl_sg::{BodyId, CollisionFilter, Geometry, Model, ModelId, Scene, ShapeId};
use support::Rng;

fn at(x: f64, y: f64, z: f64) -> PlueckerTransform {
    PlueckerTransform::from_translation(DVec3::new(x, y, z))
}

/// Two models of one body with one shape each, the second's body at `pose`.
fn pair(a: Geometry, b: Geometry, pose: PlueckerTransform) -> (Scene, ModelId, ModelId) {
    let mut scene = Scene::new();
    let mut m = Model::new("a");
    m.add_body("a")
        .add_shape("a", a, PlueckerTransform::IDENTITY)
        .unwrap();
    let ia = scene.add_model(m).unwrap();
    let mut m = Model::new("b");
    m.add_body("b")
        .add_shape("b", b, PlueckerTransform::IDENTITY)
        .unwrap();
    let ib = scene.add_model(m).unwrap();
    scene
        .set_body_pose(
            BodyId {
                model: ib.0,
                body: 0,
            },
            &pose,
        )
        .unwrap();
    (scene, ia, ib)
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).length() <= tol
}

#[test]
fn sphere_sphere_distance_depth_and_witnesses() {
    let (s, a, b) = pair(
        Geometry::sphere(0.5).unwrap(),
        Geometry::sphere(0.25).unwrap(),
        at(2.0, 0.0, 0.0),
    );
    let d = s.model_distance(a, b).unwrap();
    assert!((d.distance - 1.25).abs() < 1e-12, "{d:?}");
    assert!(close(d.point_a, DVec3::new(0.5, 0.0, 0.0), 1e-12));
    assert!(close(d.point_b, DVec3::new(1.75, 0.0, 0.0), 1e-12));
    assert!(!s.is_colliding(&CollisionFilter::All));
    // Overlapping by 0.15: the distance is minus the depth, the points the deepest ones.
    let (s, a, b) = pair(
        Geometry::sphere(0.5).unwrap(),
        Geometry::sphere(0.25).unwrap(),
        at(0.0, 0.6, 0.0),
    );
    let d = s.model_distance(a, b).unwrap();
    assert!((d.distance + 0.15).abs() < 1e-12, "{d:?}");
    assert!(close(d.point_a, DVec3::new(0.0, 0.5, 0.0), 1e-12));
    assert!(close(d.point_b, DVec3::new(0.0, 0.35, 0.0), 1e-12));
    let c = s.collisions(&CollisionFilter::All);
    assert_eq!(c.len(), 1);
    assert_eq!(
        c[0].a,
        ShapeId {
            model: 0,
            body: 0,
            shape: 0
        }
    );
}

#[test]
fn boxes_rotated_and_the_depth_along_the_shallowest_axis() {
    // A unit box and a 45°-turned unit box whose corner is 0.1 m from the first's face.
    let r = DMat3::from_rotation_z(std::f64::consts::FRAC_PI_4);
    let h = 0.5 * 2f64.sqrt();
    let pose = PlueckerTransform::new(r, DVec3::new(0.5 + 0.1 + h, 0.0, 0.0));
    let (s, a, b) = pair(
        Geometry::cuboid(DVec3::ONE).unwrap(),
        Geometry::cuboid(DVec3::ONE).unwrap(),
        pose,
    );
    let d = s.model_distance(a, b).unwrap();
    assert!((d.distance - 0.1).abs() < 1e-9, "{d:?}");
    assert!(close(d.point_b, DVec3::new(0.6, 0.0, 0.0), 1e-9), "{d:?}");
    // Pushed 0.3 m into it: depth 0.2 along x.
    let pose = PlueckerTransform::new(r, DVec3::new(0.5 - 0.2 + h, 0.0, 0.0));
    let (s, a, b) = pair(
        Geometry::cuboid(DVec3::ONE).unwrap(),
        Geometry::cuboid(DVec3::ONE).unwrap(),
        pose,
    );
    let d = s.model_distance(a, b).unwrap();
    assert!((d.distance + 0.2).abs() < 1e-9, "{d:?}");
}

#[test]
fn cylinders_capsules_and_cones_lie_along_z() {
    let probe = |g: Geometry, origin: DVec3, dir: DVec3| -> f64 {
        let mut scene = Scene::new();
        let mut m = Model::new("m");
        m.add_body("b")
            .add_shape("s", g, PlueckerTransform::IDENTITY)
            .unwrap();
        scene.add_model(m).unwrap();
        scene
            .raycast(origin, dir, 100.0)
            .unwrap()
            .expect("a hit")
            .distance
    };
    let down = DVec3::NEG_Z;
    let cyl = || Geometry::cylinder(0.5, 2.0).unwrap();
    assert!((probe(cyl(), DVec3::new(0.0, 0.0, 5.0), down) - 4.0).abs() < 1e-9);
    assert!((probe(cyl(), DVec3::new(5.0, 0.0, 0.0), DVec3::NEG_X) - 4.5).abs() < 1e-9);
    let cap = || Geometry::capsule(0.5, 2.0).unwrap();
    assert!((probe(cap(), DVec3::new(0.0, 0.0, 5.0), down) - 3.5).abs() < 1e-9);
    // The cone's apex is at +length/2, its base disc (radius 0.5) at −length/2.
    let cone = || Geometry::cone(0.5, 2.0).unwrap();
    assert!((probe(cone(), DVec3::new(0.0, 0.0, 5.0), down) - 4.0).abs() < 1e-9);
    assert!((probe(cone(), DVec3::new(0.0, 0.0, -5.0), DVec3::Z) - 4.0).abs() < 1e-9);
    // Halfway up, the cone's radius is a quarter.
    assert!((probe(cone(), DVec3::new(5.0, 0.0, 0.0), DVec3::NEG_X) - 4.75).abs() < 1e-9);
    // A box's size is its edge lengths.
    let b = Geometry::cuboid(DVec3::new(1.0, 2.0, 3.0)).unwrap();
    assert!((probe(b, DVec3::new(0.0, 0.0, 5.0), down) - 3.5).abs() < 1e-9);
}

#[test]
fn half_spaces_bound_a_side() {
    let (s, a, b) = pair(
        Geometry::half_space(DVec3::Z, 0.0).unwrap(),
        Geometry::sphere(0.5).unwrap(),
        at(3.0, -2.0, 1.5),
    );
    let d = s.model_distance(a, b).unwrap();
    assert!((d.distance - 1.0).abs() < 1e-12, "{d:?}");
    assert!(close(d.point_b, DVec3::new(3.0, -2.0, 1.0), 1e-12));
    let (s, ..) = pair(
        Geometry::half_space(DVec3::Z, 2.0).unwrap(),
        Geometry::sphere(0.5).unwrap(),
        at(3.0, -2.0, 1.5),
    );
    assert!(s.is_colliding(&CollisionFilter::All));
}

#[test]
fn raycasts_report_the_first_shape_its_point_and_normal() {
    let mut scene = Scene::new();
    let mut m = Model::new("walls");
    for (i, x) in [3.0, 1.0, 2.0].into_iter().enumerate() {
        m.add_body(format!("wall{i}"))
            .add_shape(
                "w",
                Geometry::cuboid(DVec3::new(0.2, 4.0, 4.0)).unwrap(),
                at(x, 0.0, 0.0),
            )
            .unwrap();
    }
    let id = scene.add_model(m).unwrap();
    let hit = scene
        .raycast(DVec3::ZERO, DVec3::X * 3.0, 10.0)
        .unwrap()
        .unwrap();
    assert_eq!(
        hit.shape,
        ShapeId {
            model: id.0,
            body: 1,
            shape: 0
        }
    );
    assert!((hit.distance - 0.9).abs() < 1e-12, "{hit:?}");
    assert!(close(hit.point, DVec3::new(0.9, 0.0, 0.0), 1e-12));
    assert!(close(hit.normal, DVec3::NEG_X, 1e-12), "{hit:?}");
    assert!(scene.raycast(DVec3::ZERO, DVec3::X, 0.5).unwrap().is_none());
    assert!(
        scene
            .raycast(DVec3::ZERO, DVec3::NEG_X, 50.0)
            .unwrap()
            .is_none()
    );
    assert!(scene.raycast(DVec3::ZERO, DVec3::ZERO, 1.0).is_err());
    assert!(scene.raycast(DVec3::NAN, DVec3::X, 1.0).is_err());
}

#[test]
fn self_collision_respects_the_allowed_set_and_the_flag() {
    let mut scene = Scene::new();
    let mut m = Model::new("arm");
    for i in 0..3 {
        m.add_body(format!("l{i}"))
            .add_shape(
                "s",
                Geometry::cuboid(DVec3::new(1.2, 0.2, 0.2)).unwrap(),
                at(i as f64, 0.0, 0.0),
            )
            .unwrap();
    }
    m.set_self_collision(true);
    let id = scene.add_model(m).unwrap();
    // Neighbours overlap by 0.2 m: two pairs collide.
    let bodies = scene.colliding_bodies(&CollisionFilter::SelfCollision(id));
    assert_eq!(bodies.len(), 2, "{bodies:?}");
    scene
        .model_mut(id)
        .unwrap()
        .allowed_collisions_mut()
        .allow(0, 1);
    let bodies = scene.colliding_bodies(&CollisionFilter::All);
    assert_eq!(
        bodies,
        vec![(BodyId { model: 0, body: 1 }, BodyId { model: 0, body: 2 })]
    );
    let d = scene.self_distance(id).unwrap();
    assert!((d.distance + 0.2).abs() < 1e-9, "{d:?}");
    scene.model_mut(id).unwrap().set_self_collision(false);
    assert!(!scene.is_colliding(&CollisionFilter::All));
    // Asked for explicitly, self-collision is checked even with the flag off.
    assert!(scene.is_colliding(&CollisionFilter::SelfCollision(id)));
}

#[test]
fn bad_values_are_refused_with_the_reason() {
    for (g, why) in [
        (Geometry::sphere(-1.0), "positive"),
        (Geometry::sphere(f64::NAN), "not finite"),
        (Geometry::cuboid(DVec3::new(1.0, 0.0, 1.0)), "positive"),
        (Geometry::cylinder(1.0, f64::INFINITY), "not finite"),
        (Geometry::half_space(DVec3::ZERO, 1.0), "zero"),
        (
            Geometry::convex_hull(&[DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X + DVec3::Y]),
            "plane",
        ),
    ] {
        let e = g.unwrap_err().to_string();
        assert!(e.contains(why), "{e}");
    }
    let mut m = Model::new("m");
    let nan = PlueckerTransform::from_translation(DVec3::new(0.0, f64::NAN, 0.0));
    let e = m
        .add_body("b")
        .add_shape("s", Geometry::sphere(1.0).unwrap(), nan)
        .unwrap_err();
    assert!(e.to_string().contains("not finite"), "{e}");
    let skew = PlueckerTransform::new(DMat3::from_diagonal(DVec3::new(1.0, 2.0, 1.0)), DVec3::ZERO);
    let e = m
        .add_body("c")
        .add_shape("s", Geometry::sphere(1.0).unwrap(), skew)
        .unwrap_err();
    assert!(e.to_string().contains("not a rotation"), "{e}");
    let mut scene = Scene::new();
    scene.add_model(Model::new("x")).unwrap();
    assert!(scene.add_model(Model::new("x")).is_err());
}

/// A robot-like model of `n` bodies of two capsules among `k` random obstacles.
fn cluttered(seed: u64, n: usize, k: usize) -> Scene {
    let mut r = Rng::new(seed);
    let mut scene = Scene::new();
    let mut robot = Model::new("robot");
    for i in 0..n {
        let b = robot.add_body(format!("link{i}"));
        for j in 0..2 {
            let local = PlueckerTransform::new(DMat3::from_quat(r.quat()), r.vec3(0.1));
            let g = if j == 0 {
                Geometry::capsule(r.range(0.03, 0.08), r.range(0.1, 0.3)).unwrap()
            } else {
                Geometry::cuboid(DVec3::new(
                    r.range(0.05, 0.2),
                    r.range(0.05, 0.2),
                    r.range(0.05, 0.2),
                ))
                .unwrap()
            };
            b.add_shape(format!("s{j}"), g, local).unwrap();
        }
    }
    robot.set_self_collision(true);
    let rid = scene.add_model(robot).unwrap();
    let mut env = Model::new("env");
    for i in 0..k {
        let g = match i % 4 {
            0 => Geometry::sphere(r.range(0.02, 0.1)).unwrap(),
            1 => Geometry::cuboid(DVec3::new(
                r.range(0.02, 0.2),
                r.range(0.02, 0.2),
                r.range(0.02, 0.2),
            ))
            .unwrap(),
            2 => Geometry::cylinder(r.range(0.02, 0.08), r.range(0.05, 0.3)).unwrap(),
            _ => Geometry::cone(r.range(0.02, 0.08), r.range(0.05, 0.3)).unwrap(),
        };
        env.add_body(format!("obstacle{i}"))
            .add_shape("o", g, r.pose(1.0))
            .unwrap();
    }
    scene.add_model(env).unwrap();
    for i in 0..n {
        scene
            .set_body_pose(
                BodyId {
                    model: rid.0,
                    body: i,
                },
                &r.pose(0.8),
            )
            .unwrap();
    }
    scene
}

/// Every shape pair of different models, and of different bodies of the robot.
fn all_pairs(scene: &Scene) -> Vec<(ShapeId, ShapeId)> {
    let mut ids = Vec::new();
    for (m, model) in scene.models().iter().enumerate() {
        for (b, body) in model.bodies().iter().enumerate() {
            for s in 0..body.shapes().len() {
                ids.push(ShapeId {
                    model: m,
                    body: b,
                    shape: s,
                });
            }
        }
    }
    let mut out = Vec::new();
    for (i, a) in ids.iter().enumerate() {
        for b in &ids[i + 1..] {
            let same_body = a.model == b.model && a.body == b.body;
            let env_self = a.model == 1 && b.model == 1;
            if !same_body && !env_self {
                out.push((*a, *b));
            }
        }
    }
    out
}

#[test]
fn the_broad_phase_finds_exactly_what_brute_force_finds() {
    for seed in 0..6 {
        let scene = cluttered(seed, 8, 300);
        let pairs = all_pairs(&scene);
        let mut brute = Vec::new();
        let mut min = f64::INFINITY;
        for &(a, b) in &pairs {
            let d = scene.shape_distance(a, b).unwrap();
            if d.distance <= 0.0 {
                brute.push((a, b));
            }
            min = min.min(d.distance);
        }
        let found: Vec<_> = scene
            .collisions(&CollisionFilter::All)
            .into_iter()
            .map(|p| (p.a, p.b))
            .collect();
        brute.sort();
        assert_eq!(found, brute, "seed {seed}");
        assert!(
            !found.is_empty(),
            "seed {seed}: a clutter this dense has contacts"
        );
        let d = scene.min_distance(&CollisionFilter::All).unwrap();
        assert!(
            (d.distance - min).abs() < 1e-9,
            "seed {seed}: {} vs {min}",
            d.distance
        );
        assert_eq!(scene.is_colliding(&CollisionFilter::All), !brute.is_empty());
        // The broad phase hands only a small share of the pairs to the narrow phase.
        let candidates = scene.broad_phase_pairs(&CollisionFilter::All).len();
        assert_eq!(
            scene.pairs_checked(&CollisionFilter::All).len(),
            pairs.len()
        );
        assert!(
            candidates * 20 < pairs.len(),
            "seed {seed}: {candidates} of {} pairs",
            pairs.len()
        );
    }
}

#[test]
fn distance_between_models_matches_brute_force_when_apart() {
    for seed in 10..16 {
        let mut scene = cluttered(seed, 6, 200);
        // Lift the robot clear of the clutter: distances positive, the tree must prune well.
        for i in 0..6 {
            let id = BodyId { model: 0, body: i };
            let mut x = *scene.body(id).unwrap().pose();
            x.translation.z += 3.0;
            scene.set_body_pose(id, &x).unwrap();
        }
        let pairs: Vec<_> = all_pairs(&scene)
            .into_iter()
            .filter(|(a, b)| a.model != b.model)
            .collect();
        let (mut best, mut arg) = (f64::INFINITY, None);
        for &(a, b) in &pairs {
            let d = scene.shape_distance(a, b).unwrap();
            if d.distance < best {
                best = d.distance;
                arg = Some(d);
            }
        }
        let d = scene.model_distance(ModelId(0), ModelId(1)).unwrap();
        let arg = arg.unwrap();
        assert!(
            (d.distance - best).abs() < 1e-9,
            "seed {seed}: {d:?} vs {arg:?}"
        );
        assert!(d.distance > 0.0);
        assert!(((d.point_a - d.point_b).length() - d.distance).abs() < 1e-9);
        // Body against body: the closest of their shape pairs, named by shape, both ways round.
        for (ra, ob) in [(0, 0), (2, 7), (5, 31)] {
            let (a, b) = (BodyId { model: 0, body: ra }, BodyId { model: 1, body: ob });
            let (best, arg) = pairs
                .iter()
                .filter(|(x, y)| (x.model, x.body, y.model, y.body) == (0, ra, 1, ob))
                .map(|&(x, y)| scene.shape_distance(x, y).unwrap())
                .fold((f64::INFINITY, None), |(m, arg), d| {
                    if d.distance < m {
                        (d.distance, Some(d))
                    } else {
                        (m, arg)
                    }
                });
            let arg = arg.unwrap();
            let d = scene.body_distance(a, b).unwrap();
            assert!((d.distance - best).abs() < 1e-12, "{d:?} vs {arg:?}");
            assert_eq!((d.a, d.b), (arg.a, arg.b));
            let back = scene.body_distance(b, a).unwrap();
            assert_eq!((back.a, back.b), (arg.b, arg.a));
            assert!((back.point_a - d.point_b).length() < 1e-9);
        }
    }
}

#[test]
fn raycasts_match_brute_force() {
    let scene = cluttered(42, 4, 150);
    let mut r = Rng::new(7);
    for _ in 0..200 {
        let o = r.vec3(1.5);
        let dir = r.vec3(1.0);
        let hit = scene.raycast(o, dir, 10.0).unwrap();
        let mut best: Option<(f64, ShapeId)> = None;
        for (m, model) in scene.models().iter().enumerate() {
            for (b, body) in model.bodies().iter().enumerate() {
                for s in 0..body.shapes().len() {
                    let id = ShapeId {
                        model: m,
                        body: b,
                        shape: s,
                    };
                    let mut one = Scene::new();
                    let mut mm = Model::new("x");
                    let sh = scene.shape(id).unwrap();
                    mm.add_body("b")
                        .add_shape("s", sh.geometry().clone(), sh.world_pose())
                        .unwrap();
                    one.add_model(mm).unwrap();
                    if let Some(h) = one.raycast(o, dir, 10.0).unwrap() {
                        if best.is_none_or(|(d, _)| h.distance < d) {
                            best = Some((h.distance, id));
                        }
                    }
                }
            }
        }
        match (hit, best) {
            (None, None) => {}
            (Some(h), Some((d, id))) => {
                assert!((h.distance - d).abs() < 1e-9, "{h:?} vs {d} {id:?}");
            }
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn mesh_mesh_distance_matches_parrys_own_on_rls_meshes() {
    // Our tree descent against parry's triangle-by-triangle distance, on the Puma's meshes and
    // the tori, at random poses (apart and penetrating).
    let scenes = ["unimation-puma560.convex.xml", "twotori.xml"];
    let mut meshes = Vec::new();
    for f in scenes {
        let s = rl_sg::load::rlsg::load_scene(&support::rlsg_data().join(f)).unwrap();
        for m in s.models() {
            for b in m.bodies() {
                for sh in b.shapes() {
                    meshes.push(sh.geometry().clone());
                }
            }
        }
    }
    let mut r = Rng::new(77);
    let mut apart = 0;
    for k in 0..200 {
        let a = meshes[k % meshes.len()].clone();
        let b = meshes[(k * 7 + 3) % meshes.len()].clone();
        let (s, ia, ib) = pair(a, b, r.pose(0.5));
        let d = s.model_distance(ia, ib).unwrap();
        let (sa, sb) = (s.shape(d.a).unwrap(), s.shape(d.b).unwrap());
        let reference = parry3d_f64::query::distance(
            &to_parry(&sa.world_pose()),
            &*parry_shape(sa.geometry()),
            &to_parry(&sb.world_pose()),
            &*parry_shape(sb.geometry()),
        )
        .unwrap()
        .distance;
        if reference > 0.0 {
            apart += 1;
            assert!(
                (d.distance - reference).abs() < 1e-9,
                "{k}: {} vs parry {reference}",
                d.distance
            );
            assert!(((d.point_a - d.point_b).length() - d.distance).abs() < 1e-9);
        } else {
            assert!(
                d.distance <= 0.0,
                "{k}: {} but parry says they touch",
                d.distance
            );
        }
    }
    assert!(apart > 50, "{apart}");
}

fn to_parry(x: &PlueckerTransform) -> parry3d_f64::math::Pose {
    parry3d_f64::math::Pose::from_parts(x.translation, glam::DQuat::from_mat3(&x.rotation))
}

fn parry_shape(g: &Geometry) -> parry3d_f64::shape::SharedShape {
    match g {
        Geometry::Mesh(m) => {
            parry3d_f64::shape::SharedShape::trimesh(m.vertices().to_vec(), m.triangles().to_vec())
                .unwrap()
        }
        g => panic!("not a mesh: {g:?}"),
    }
}
