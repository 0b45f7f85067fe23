//! Against coal (PyPI `coal`, the collision library Pinocchio uses, not written here): the same
//! shapes at the same poses must give the same collision answer on every case and the same
//! distances to 1e-6 m. Fixtures and the script that made them: `rl-sg/tests/data/coal/`,
//! `scripts/gen-coal-fixtures`.

mod support;

use std::path::Path;

use glam::{DQuat, DVec3};
use rl_core::loader::{MimicJoints, UrdfOptions};
use rl_core::spatial::PlueckerTransform;
use rl_sg::load::{RobotSetup, UrdfGeometryOptions, load_mesh};
use rl_sg::{BodyId, CollisionFilter, Geometry, Model, ModelId, Scene, ShapeId, TriangleMesh};
use serde_json::Value;
use support::repo;

const TOL: f64 = 1e-6;

fn fixture(name: &str) -> Value {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/coal")
        .join(name);
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    assert_eq!(v["format"], "rl-rs coal fixture 1", "{}", p.display());
    v
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

fn vec3(v: &Value) -> DVec3 {
    DVec3::new(f(&v[0]), f(&v[1]), f(&v[2]))
}

fn pose(v: &Value) -> PlueckerTransform {
    let q = DQuat::from_xyzw(f(&v[3]), f(&v[4]), f(&v[5]), f(&v[6])).normalize();
    PlueckerTransform::from_quat_translation(q, vec3(v))
}

fn points(v: &Value) -> Vec<DVec3> {
    v.as_array().unwrap().iter().map(vec3).collect()
}

fn geometry(s: &Value) -> Geometry {
    let r = || f(&s["radius"]);
    let l = || f(&s["length"]);
    match s["kind"].as_str().unwrap() {
        "box" => Geometry::cuboid(vec3(&s["size"])).unwrap(),
        "sphere" => Geometry::sphere(r()).unwrap(),
        "cylinder" => Geometry::cylinder(r(), l()).unwrap(),
        "capsule" => Geometry::capsule(r(), l()).unwrap(),
        "cone" => Geometry::cone(r(), l()).unwrap(),
        "convex" => Geometry::convex_hull(&points(&s["points"])).unwrap(),
        "halfspace" => Geometry::half_space(vec3(&s["normal"]), f(&s["offset"])).unwrap(),
        "mesh" => {
            let t = s["triangles"]
                .as_array()
                .unwrap()
                .iter()
                .map(|t| [0, 1, 2].map(|k| t[k].as_u64().unwrap() as u32))
                .collect();
            Geometry::mesh(TriangleMesh::new(points(&s["vertices"]), t).unwrap().0)
        }
        k => panic!("{k}"),
    }
}

/// Two one-shape models at the given poses.
fn pair(a: Geometry, pa: PlueckerTransform, b: Geometry, pb: PlueckerTransform) -> Scene {
    let mut s = Scene::new();
    for (name, g, x) in [("a", a, pa), ("b", b, pb)] {
        let mut m = Model::new(name);
        m.add_body(name)
            .add_shape(name, g, PlueckerTransform::IDENTITY)
            .unwrap();
        let id = s.add_model(m).unwrap();
        s.set_body_pose(
            BodyId {
                model: id.0,
                body: 0,
            },
            &x,
        )
        .unwrap();
    }
    s
}

const A: ShapeId = ShapeId {
    model: 0,
    body: 0,
    shape: 0,
};
const B: ShapeId = ShapeId {
    model: 1,
    body: 0,
    shape: 0,
};

/// Whether moving shape b of `s` by `depth` (+0.1 µm) from its deepest point toward a's
/// separates the pair: `depth` is then a separating translation, and the true penetration
/// depth (the shortest one) is at most `depth`.
fn separates(
    a: &Geometry,
    pa: PlueckerTransform,
    b: &Geometry,
    pb: PlueckerTransform,
    d: &rl_sg::Distance,
) -> bool {
    let dir = (d.point_a - d.point_b).normalize();
    let mut moved = pb;
    moved.translation += dir * (-d.distance + 1e-7);
    let s = pair(a.clone(), pa, b.clone(), moved);
    s.shape_distance(A, B).is_some_and(|m| m.distance > 0.0)
        && s.shapes_collide(A, B) == Some(false)
}

#[test]
fn primitives_and_convex_hulls_agree_with_coal() {
    let fx = fixture("primitives.json");
    let cases = fx["cases"].as_array().unwrap();
    assert!(cases.len() >= 300);
    let (mut worst, mut colliding, mut shallower, mut coal_failed) = (0.0f64, 0, 0, 0);
    for (k, c) in cases.iter().enumerate() {
        let (ga, gb, pa, pb) = (
            geometry(&c["a"]),
            geometry(&c["b"]),
            pose(&c["pose_a"]),
            pose(&c["pose_b"]),
        );
        let s = pair(ga.clone(), pa, gb.clone(), pb);
        let kinds = format!("{}–{}", c["a"]["kind"], c["b"]["kind"]);
        let coal_hit = c["collide"].as_bool().unwrap();
        assert_eq!(
            s.shapes_collide(A, B),
            Some(coal_hit),
            "case {k} ({kinds}): collision differs"
        );
        let d = s.shape_distance(A, B).unwrap();
        let coal_d = f(&c["distance"]);
        assert!(
            ((d.point_a - d.point_b).length() - d.distance.abs()).abs() <= TOL,
            "case {k}"
        );
        colliding += usize::from(coal_hit);
        let err = (d.distance - coal_d).abs();
        if err <= TOL {
            worst = worst.max(err);
            continue;
        }
        // Only penetration depths may differ, and only where coal's EPA is provably not the
        // shortest separating translation: ours is shorter, and it does separate.
        assert!(
            coal_hit && d.distance < 0.0,
            "case {k} ({kinds}): distance {} vs coal {coal_d}",
            d.distance
        );
        assert!(
            separates(&ga, pa, &gb, pb, &d),
            "case {k} ({kinds}): our depth {} does not separate",
            d.distance
        );
        if coal_d.abs() > 1e100 {
            coal_failed += 1; // coal's EPA gave up (−DBL_MAX)
        } else {
            assert!(
                coal_d < d.distance - TOL,
                "case {k} ({kinds}): coal's depth {coal_d} is shallower than ours {}",
                d.distance
            );
            shallower += 1;
        }
    }
    println!(
        "{} cases ({colliding} colliding): collision agrees on all; distance agrees within {worst:.1e} m on {}; \
         on {shallower} coal's EPA depth is deeper than a separating translation we found, on {coal_failed} it failed",
        cases.len(),
        cases.len() - shallower - coal_failed
    );
    assert!(colliding > 100 && colliding < cases.len() - 100);
    assert!(
        shallower + coal_failed <= cases.len() / 50,
        "{shallower} + {coal_failed}"
    );
}

#[test]
fn half_spaces_agree_with_coal() {
    let fx = fixture("halfspaces.json");
    let cases = fx["cases"].as_array().unwrap();
    assert!(cases.len() >= 100);
    let (mut worst, mut colliding) = (0.0f64, 0);
    for (k, c) in cases.iter().enumerate() {
        let s = pair(
            geometry(&c["a"]),
            pose(&c["pose_a"]),
            geometry(&c["b"]),
            pose(&c["pose_b"]),
        );
        let kind = &c["b"]["kind"];
        let coal_hit = c["collide"].as_bool().unwrap();
        assert_eq!(
            s.shapes_collide(A, B),
            Some(coal_hit),
            "case {k} (half-space–{kind}): collision differs"
        );
        colliding += usize::from(coal_hit);
        // Signed distance (penetration depth when overlapping) and both witness points: for a
        // half-space the deepest point and its projection on the plane are unique except on
        // flat faces parallel to the plane, where only the distance is compared.
        let d = s.shape_distance(A, B).unwrap();
        let err = (d.distance - f(&c["distance"])).abs();
        assert!(
            err <= TOL,
            "case {k} (half-space–{kind}): distance {} vs coal {}",
            d.distance,
            c["distance"]
        );
        worst = worst.max(err);
        let gap = (d.point_a - d.point_b).length();
        assert!((gap - d.distance.abs()).abs() <= TOL, "case {k}: {d:?}");
        if matches!(kind.as_str(), Some("sphere" | "capsule")) {
            assert!(
                (d.point_b - vec3(&c["point_b"])).length() <= TOL,
                "case {k} (half-space–{kind}): witness on b {:?} vs coal {}",
                d.point_b,
                c["point_b"]
            );
        }
    }
    println!(
        "{} cases ({colliding} colliding): collision agrees on all, distance within {worst:.1e} m",
        cases.len()
    );
    assert!(colliding > 20 && colliding < cases.len() - 20);
}

#[test]
fn non_convex_meshes_agree_with_coal() {
    let fx = fixture("meshes.json");
    let library: Vec<Geometry> = fx["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .map(geometry)
        .collect();
    let cases = fx["cases"].as_array().unwrap();
    let (mut worst, mut apart) = (0.0f64, 0);
    for (k, c) in cases.iter().enumerate() {
        let a = library[c["a"].as_u64().unwrap() as usize].clone();
        let b = match c.get("b") {
            Some(i) => library[i.as_u64().unwrap() as usize].clone(),
            None => geometry(&c["b_shape"]),
        };
        let s = pair(a, pose(&c["pose_a"]), b, pose(&c["pose_b"]));
        let coal_hit = c["collide"].as_bool().unwrap();
        assert_eq!(
            s.shapes_collide(A, B),
            Some(coal_hit),
            "case {k}: collision differs"
        );
        if !coal_hit {
            let d = s.shape_distance(A, B).unwrap();
            let err = (d.distance - f(&c["distance"])).abs();
            assert!(
                err <= TOL,
                "case {k}: distance {} vs coal {}",
                d.distance,
                c["distance"]
            );
            worst = worst.max(err);
            apart += 1;
        }
    }
    println!(
        "{} cases: collision agrees on all, {apart} distances within {worst:.1e} m",
        cases.len()
    );
    assert!(apart > 30 && apart < cases.len() - 30);
}

/// Checks a scene fixture (per configuration, per pair checked) against `rs` after placing
/// the robot at each configuration.
fn check_scene(fx: &Value, rs: &mut rl_sg::load::RobotScene<64>) -> (usize, usize, f64) {
    let ids: Vec<ShapeId> = {
        let mut v = Vec::new();
        for (m, model) in rs.scene.models().iter().enumerate() {
            for (b, body) in model.bodies().iter().enumerate() {
                for s in 0..body.shapes().len() {
                    v.push(ShapeId {
                        model: m,
                        body: b,
                        shape: s,
                    });
                }
            }
        }
        v
    };
    assert_eq!(
        ids.len(),
        fx["shapes"].as_array().unwrap().len(),
        "the scene has the fixture's shapes"
    );
    let index_pairs = |f: CollisionFilter| -> Vec<[usize; 2]> {
        rs.scene
            .pairs_checked(&f)
            .iter()
            .map(|(a, b)| {
                [
                    ids.iter().position(|x| x == a).unwrap(),
                    ids.iter().position(|x| x == b).unwrap(),
                ]
            })
            .collect()
    };
    let as_pairs = |v: &Value| -> Vec<[usize; 2]> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|p| {
                [
                    p[0].as_u64().unwrap() as usize,
                    p[1].as_u64().unwrap() as usize,
                ]
            })
            .collect()
    };
    let pairs: Vec<[usize; 2]> = {
        let (s, e) = (
            as_pairs(&fx["self_pairs"]),
            as_pairs(&fx["environment_pairs"]),
        );
        assert_eq!(
            index_pairs(CollisionFilter::SelfCollision(rs.robot)),
            s,
            "self pairs differ"
        );
        assert_eq!(
            index_pairs(CollisionFilter::Against(rs.robot)),
            e,
            "environment pairs differ"
        );
        s.into_iter().chain(e).collect()
    };
    let mut data = Box::new(rl_core::Data::<64>::new());
    let (mut hits, mut measured, mut worst) = (0, 0, 0.0f64);
    for (ci, c) in fx["configs"].as_array().unwrap().iter().enumerate() {
        let q: Vec<f64> = c["q"].as_array().unwrap().iter().map(f).collect();
        rs.scene
            .set_configuration(rs.robot, &rs.kinematics.model, &mut data, &q)
            .unwrap();
        for (r, [i, j]) in c["results"].as_array().unwrap().iter().zip(&pairs) {
            let (a, b) = (ids[*i], ids[*j]);
            let names = format!(
                "{} – {}",
                rs.scene.body_name(a.body_id()),
                rs.scene.body_name(b.body_id())
            );
            let coal_hit = r["collide"].as_bool().unwrap();
            if r.get("near").is_some_and(|n| n.as_bool() == Some(true)) {
                continue; // within 1e-5 m of touching: a matter of tolerance
            }
            assert_eq!(
                rs.scene.shapes_collide(a, b),
                Some(coal_hit),
                "config {ci} {q:?}: {names}"
            );
            hits += usize::from(coal_hit);
            if let Some(cd) = r.get("distance") {
                let d = rs.scene.shape_distance(a, b).unwrap().distance;
                let err = (d - f(cd)).abs();
                assert!(
                    err <= TOL,
                    "config {ci}: {names}: distance {d} vs coal {cd}"
                );
                worst = worst.max(err);
                measured += 1;
            }
        }
    }
    (hits, measured, worst)
}

#[test]
fn rls_puma_among_boxes_agrees_with_coal() {
    let fx = fixture("puma_boxes.json");
    let setup = RobotSetup {
        model: repo().join("tests/data/rlsg/unimation-puma560_boxes.convex.xml"),
        kinematics: Some(repo().join("tests/data/rlmdl/unimation-puma560.xml")),
        ..RobotSetup::default()
    };
    let mut rs = setup.load::<64>().unwrap();
    let (hits, measured, worst) = check_scene(&fx["scene"], &mut rs);
    println!(
        "Puma 560 among boxes: {hits} colliding pairs, {measured} distances within {worst:.1e} m"
    );
    assert!(hits > 0 && measured > 100);
    // RL's rlCollisionTest at q = 0: link2 touches box3 (coal says so too: the first config).
    let first = &fx["scene"]["configs"][0];
    assert!(
        first["results"]
            .as_array()
            .unwrap()
            .iter()
            .any(|r| r["collide"] == true)
    );
}

#[test]
fn ur5_and_panda_among_motionbenchmaker_obstacles_agree_with_coal() {
    let data = match support::robot_data_with_meshes() {
        Ok(d) => d,
        Err(e) => {
            println!("SKIPPED: example-robot-data with meshes is not available: {e}");
            return;
        }
    };
    let fx = fixture("robots.json");
    for r in fx["robots"].as_array().unwrap() {
        let mimic = r["args"]
            .as_array()
            .unwrap()
            .iter()
            .any(|a| a == "--mimic-independent");
        let setup = RobotSetup {
            model: data.join(r["urdf"].as_str().unwrap()),
            srdf: Some(data.join(r["srdf"].as_str().unwrap())),
            environment: Some(repo().join(r["env"].as_str().unwrap())),
            urdf: UrdfOptions {
                mimic: if mimic {
                    MimicJoints::Independent
                } else {
                    MimicJoints::Reject
                },
                ..UrdfOptions::default()
            },
            geometry: UrdfGeometryOptions::default(),
            ..RobotSetup::default()
        };
        let mut rs = setup.load::<64>().unwrap();
        let (hits, measured, worst) = check_scene(r, &mut rs);
        println!(
            "{}: {hits} colliding pairs, {measured} distances within {worst:.1e} m",
            r["name"]
        );
        assert!(hits > 0 && measured > 100, "{hits} {measured}");
    }
}

#[test]
fn our_mesh_loader_reads_what_assimp_reads() {
    let data = match support::robot_data_with_meshes() {
        Ok(d) => d,
        Err(e) => {
            println!("SKIPPED: example-robot-data with meshes is not available: {e}");
            return;
        }
    };
    let fx = fixture("mesh_files.json");
    for m in fx["files"].as_array().unwrap() {
        let file = m["file"].as_str().unwrap();
        let (mesh, stats) = load_mesh(&data.join(file)).unwrap();
        let scale = vec3(&m["scale"]);
        let (lo, hi) = mesh
            .vertices()
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), v| {
                (l.min(*v * scale), h.max(*v * scale))
            });
        // Both read f32 coordinates: the boxes agree to float precision.
        assert!(
            (lo - vec3(&m["min"])).abs().max_element() < 1e-6,
            "{file}: {lo:?} vs {}",
            m["min"]
        );
        assert!(
            (hi - vec3(&m["max"])).abs().max_element() < 1e-6,
            "{file}: {hi:?} vs {}",
            m["max"]
        );
        // assimp drops degenerate triangles too; the counts agree up to ours dropped.
        let coal_tris = m["triangles"].as_u64().unwrap() as usize;
        assert!(
            mesh.triangles().len() == coal_tris || stats.triangles_in == coal_tris,
            "{file}: {} triangles ({} read) vs coal {coal_tris}",
            mesh.triangles().len(),
            stats.triangles_in
        );
    }
    let _ = ModelId(0);
}
