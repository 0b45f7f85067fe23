//! MoveIt planning-scene YAML: the MotionBenchMaker problems load into the obstacles they
//! describe; bad files say where and why.

mod support;

use glam::{DQuat, DVec3};
use rl_sg::load::moveit;
use rl_sg::{CollisionFilter, Geometry, Scene};
use support::repo;

#[test]
fn motionbenchmaker_scenes_load_with_ids_dimensions_and_poses() {
    let dir = repo().join("tests/data/moveit");
    let m = moveit::load_environment(&dir.join("bookshelf_small_panda_scene0006.yaml")).unwrap();
    assert_eq!(m.name(), "bookshelf_small_panda_scene0006");
    let ids: Vec<_> = m.bodies().iter().map(|b| b.name()).collect();
    assert_eq!(ids.len(), 7);
    assert_eq!(&ids[..4], ["Can1", "Can2", "Can3", "shelf_bottom"]);
    // Can1: a cylinder [height 0.14, radius 0.03] standing at its primitive pose.
    let can = &m.bodies()[0];
    let s = &can.shapes()[0];
    match s.geometry() {
        Geometry::Cylinder { radius, length } => assert_eq!((*radius, *length), (0.03, 0.14)),
        g => panic!("{g:?}"),
    }
    let x = s.world_pose();
    assert!(
        (x.translation - DVec3::new(0.9994961703805763, -0.4905523566982998, 0.06667428437711315))
            .length()
            < 1e-12
    );
    let q = DQuat::from_xyzw(0.0, 0.0, -0.2030123872432684, 0.9791761693514549).normalize();
    assert!(DQuat::from_mat3(&x.rotation).dot(q).abs() > 1.0 - 1e-12);
    // Its axis is vertical: the box around it is 0.14 tall.
    let (lo, hi) = s.world_aabb();
    assert!(((hi.z - lo.z) - 0.14).abs() < 1e-9);
    // Every scene shipped loads, and its obstacles are boxes and cylinders.
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.to_string_lossy().contains("_scene") {
            let m = moveit::load_environment(&p).unwrap_or_else(|e| panic!("{e}"));
            assert!(m.shape_count() >= 5, "{}", p.display());
            for b in m.bodies() {
                for s in b.shapes() {
                    assert!(
                        matches!(s.geometry().kind(), "box" | "cylinder"),
                        "{}",
                        s.geometry().kind()
                    );
                }
            }
        }
    }
}

#[test]
fn object_poses_compose_with_primitive_poses_and_meshes_load() {
    let text = r#"
world:
  collision_objects:
    - id: table
      pose: {position: {x: 1, y: 0, z: 0}, orientation: {x: 0, y: 0, z: 0.7071067811865476, w: 0.7071067811865476}}
      primitives:
        - {type: box, dimensions: [2, 1, 0.1]}
        - {type: sphere, dimensions: [0.1]}
      primitive_poses:
        - {position: [0, 0, 0.5], orientation: [0, 0, 0, 1]}
        - {position: [0.5, 0, 0], orientation: [0, 0, 0, 1]}
    - id: wedge
      meshes:
        - vertices: [{x: 0, y: 0, z: 0}, {x: 1, y: 0, z: 0}, {x: 0, y: 1, z: 0}, {x: 0, y: 0, z: 1}]
          triangles: [{vertex_indices: [0, 2, 1]}, {vertex_indices: [0, 1, 3]}, {vertex_indices: [0, 3, 2]}, {vertex_indices: [1, 2, 3]}]
      mesh_poses: [{position: [0, 3, 0]}]
"#;
    let m = moveit::environment_from_str(text, "cell").unwrap();
    let table = &m.bodies()[0];
    // The object is turned 90° about z: the box's long side lies along y, the sphere at (1, 0.5, 0).
    let (lo, hi) = table.shapes()[0].world_aabb();
    assert!(
        ((hi - lo) - DVec3::new(1.0, 2.0, 0.1)).length() < 1e-9,
        "{lo:?} {hi:?}"
    );
    let (lo, hi) = table.shapes()[1].world_aabb();
    assert!(((lo + hi) / 2.0 - DVec3::new(1.0, 0.5, 0.0)).length() < 1e-9);
    let wedge = &m.bodies()[1].shapes()[0];
    assert_eq!(wedge.geometry().kind(), "mesh");
    assert!((wedge.world_aabb().0 - DVec3::new(0.0, 3.0, 0.0)).length() < 1e-12);
    let mut s = Scene::new();
    s.add_model(m).unwrap();
    assert!(
        !s.is_colliding(&CollisionFilter::All),
        "one model, no self-collision"
    );
}

#[test]
fn bad_planning_scenes_say_where_and_why() {
    let cases = [
        (
            "world: {collision_objects: [{id: a, primitives: [{type: box, dimensions: [1, 1]}], primitive_poses: [{}]}]}",
            "wrong count",
            "\"a\"",
        ),
        (
            "world: {collision_objects: [{id: a, primitives: [{type: torus, dimensions: [1]}], primitive_poses: [{}]}]}",
            "torus",
            "\"a\"",
        ),
        (
            "world: {collision_objects: [{id: a, primitives: [{type: sphere, dimensions: [1]}]}]}",
            "primitive_poses",
            "\"a\"",
        ),
        (
            "world: {collision_objects: [{id: a, primitives: [{type: sphere, dimensions: [.nan]}], primitive_poses: [{}]}]}",
            "not finite",
            "",
        ),
        (
            "world: {collision_objects: [{id: a, pose: {position: {x: 0, y: .nan, z: 0}}, primitives: [{type: sphere, dimensions: [1]}], primitive_poses: [{}]}]}",
            "not finite",
            "",
        ),
        (
            "world: {collision_objects: [{id: a, primitives: [{type: sphere, dimensions: [1]}], primitive_poses: [{position: [.inf, 0, 0]}]}]}",
            "not finite",
            "",
        ),
        (
            "world: {collision_objects: [{id: a, primitives: [{type: sphere, dimensions: [1]}], primitive_poses: [{orientation: [0, 0, 0, 0]}]}]}",
            "zero quaternion",
            "",
        ),
        (
            "world: {collision_objects: [{id: a, primitives: [{type: sphere, dimensions: [x]}], primitive_poses: [{}]}]}",
            "not a number",
            "",
        ),
        (
            "world: {collision_objects: [{id: a}, {id: a}]}",
            "used twice",
            "",
        ),
        (
            "world: {collision_objects: [{id: a, planes: [{coef: [0, 0, 1, 0]}]}]}",
            "planes",
            "",
        ),
        (
            "world: {collision_objects: [{id: a, operation: 1}]}",
            "ADD",
            "",
        ),
        ("robot_state: {}", "missing field \"world\"", ""),
        ("world: [unclosed", "syntax", ""),
    ];
    for (text, why, element) in cases {
        let e = moveit::environment_from_str(text, "x").unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(why) && msg.contains(element), "{text}\n{msg}");
        assert!(e.position.is_some(), "{msg}");
    }
    let e = moveit::load_environment(std::path::Path::new("/nonexistent/scene.yaml")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/scene.yaml"), "{e}");
}
