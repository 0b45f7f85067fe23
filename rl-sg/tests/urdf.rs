//! URDF geometry: every robot of example-robot-data that rl-core's dynamics load must load here
//! too, with its meshes (STL, OBJ, COLLADA); small files exercise primitives, errors and SRDF.

mod support;

use std::path::PathBuf;

use glam::DVec3;
use rl_core::loader::{self, MimicJoints, UrdfOptions};
use rl_sg::load::MeshCache;
use rl_sg::load::srdf;
use rl_sg::load::urdf::{self, GeometryKind, MeshMode, UrdfGeometryOptions};
use rl_sg::{CollisionFilter, Geometry, Scene, SgErrorKind};

/// Visual geometry that cannot load, and why: meshes in formats no URDF tool reads (Ogre's
/// `.mesh`) at absolute paths of the authors' machines.
const VISUAL_FAILURES: &[(&str, &str)] = &[(
    "romeo_description/urdf/romeo_laas_small.urdf",
    "file not found",
)];

#[test]
fn every_robot_the_dynamics_load_loads_with_its_meshes() {
    let data = match support::robot_data_with_meshes() {
        Ok(d) => d,
        Err(e) => {
            println!("SKIPPED: example-robot-data with meshes is not available: {e}");
            return;
        }
    };
    let robots = data.join("robots");
    let files = support::files_ending(&robots, ".urdf");
    assert!(files.len() >= 60, "only {} URDFs", files.len());
    const BIG: usize = 128;
    let mut cache = MeshCache::new();
    let (mut robots_loaded, mut not_dynamics, mut shapes, mut triangles) = (0, 0, 0usize, 0usize);
    let mut total_non_manifold = 0;
    let mut kinds = std::collections::BTreeMap::<String, usize>::new();
    for f in &files {
        let rel = f
            .strip_prefix(&robots)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let mut core = UrdfOptions::default();
        if loader::load_file_with::<BIG>(f, &core).is_err() {
            core.mimic = MimicJoints::Independent;
        }
        if let Err(e) = loader::load_file_with::<BIG>(f, &core) {
            println!("not a dynamics model, skipped: {rel}: {e}");
            not_dynamics += 1;
            continue;
        }
        let opt = UrdfGeometryOptions::default();
        let robot = urdf::load_robot::<BIG>(f, &opt, &core, &mut cache)
            .unwrap_or_else(|e| panic!("{rel}: collision geometry does not load: {e}"));
        let m = &robot.model;
        let n_shapes = m.shape_count();
        let meshes: Vec<_> = m
            .bodies()
            .iter()
            .flat_map(|b| b.shapes())
            .filter_map(|s| match s.geometry() {
                Geometry::Mesh(mesh) => Some(mesh.triangles().len()),
                _ => None,
            })
            .collect();
        let non_manifold = m
            .bodies()
            .iter()
            .flat_map(|b| b.shapes())
            .filter(
                |s| matches!(s.geometry(), Geometry::Mesh(mesh) if mesh.non_manifold_edges().0 > 0),
            )
            .count();
        total_non_manifold += non_manifold;
        for b in m.bodies() {
            for s in b.shapes() {
                *kinds.entry(s.geometry().kind().to_string()).or_default() += 1;
                if let Some(src) = s.source() {
                    assert!(src.exists(), "{rel}: {}", src.display());
                }
            }
        }
        println!(
            "loads  {rel}: {} links, {n_shapes} collision shapes, {} meshes ({} triangles, {non_manifold} non-manifold), {} self pairs{}",
            m.bodies().len(),
            meshes.len(),
            meshes.iter().sum::<usize>(),
            m.self_collision_pairs().len(),
            if m.warnings().is_empty() {
                String::new()
            } else {
                format!(", {} notes", m.warnings().len())
            }
        );
        // Every link that has a frame in the kinematics follows it.
        let link = m.kinematics().expect("linked");
        for (i, b) in m.bodies().iter().enumerate() {
            if robot.kinematics.frame(b.name()).is_some() {
                assert!(link.frame(i).is_some(), "{rel}: {}", b.name());
            }
        }
        // A scene can be queried: self-collision at the neutral configuration terminates.
        let mut scene = Scene::new();
        let id = scene.add_model(robot.model.clone()).unwrap();
        let mut data = Box::new(rl_core::Data::<BIG>::new());
        let q = robot.kinematics.home_or_neutral();
        scene
            .set_configuration(id, &robot.kinematics.model, &mut data, &q)
            .unwrap();
        let _ = scene.collisions(&CollisionFilter::SelfCollision(id));
        // Visual geometry too.
        let vis = UrdfGeometryOptions {
            kind: GeometryKind::Visual,
            ..UrdfGeometryOptions::default()
        };
        match (
            urdf::load_geometry(f, &vis, &mut cache),
            VISUAL_FAILURES.iter().find(|(p, _)| *p == rel),
        ) {
            (Ok(v), None) => {
                shapes += v.shape_count();
            }
            (Err(e), Some((_, why))) => {
                assert!(e.to_string().contains(why), "{rel}: {e}");
                println!("        visual geometry refused as expected: {e}");
            }
            (Ok(_), Some(_)) => {
                panic!("{rel}: visual geometry loads now; take it off VISUAL_FAILURES")
            }
            (Err(e), None) => panic!("{rel}: visual geometry does not load: {e}"),
        }
        shapes += n_shapes;
        triangles += meshes.iter().sum::<usize>();
        robots_loaded += 1;
    }
    println!(
        "{robots_loaded} robots load with their meshes ({} mesh files read, {shapes} shapes, {triangles} collision triangles, {total_non_manifold} non-manifold collision meshes; kinds {kinds:?}); {not_dynamics} files are no dynamics model",
        cache.len()
    );
    assert!(robots_loaded >= 55, "{robots_loaded}");
    for k in ["mesh", "box", "cylinder", "sphere"] {
        assert!(
            kinds.get(k).copied().unwrap_or(0) > 0,
            "no {k} among the collision shapes"
        );
    }
}

const TWO_LINKS: &str = r#"<robot name="two">
  <link name="base"><collision><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  <link name="arm">
    <collision name="upper"><origin xyz="0.25 0 0" rpy="0 1.5707963267948966 0"/><geometry><cylinder radius="0.04" length="0.5"/></geometry></collision>
    <collision><origin xyz="0.5 0 0"/><geometry><sphere radius="0.06"/></geometry></collision>
    <visual><geometry><capsule radius="0.05" length="0.5"/></geometry></visual>
  </link>
  <link name="tip"/>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="f" type="fixed"><parent link="arm"/><child link="tip"/><origin xyz="0.5 0 0"/></joint>
</robot>"#;

fn write_tmp(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rl-sg-urdf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn primitives_poses_adjacency_and_kinematics() {
    let p = write_tmp("two.urdf", TWO_LINKS);
    let mut cache = MeshCache::new();
    let r = urdf::load_robot::<8>(
        &p,
        &UrdfGeometryOptions::default(),
        &UrdfOptions::default(),
        &mut cache,
    )
    .unwrap();
    let m = &r.model;
    assert_eq!(
        m.bodies().iter().map(|b| b.name()).collect::<Vec<_>>(),
        ["base", "arm", "tip"]
    );
    assert_eq!(m.bodies()[1].shapes().len(), 2);
    assert_eq!(m.bodies()[1].shapes()[0].name(), "upper");
    assert_eq!(m.bodies()[1].shapes()[1].name(), "arm/collision/1");
    // base–arm adjacent, arm–tip adjacent (and rigidly merged): nothing left to check.
    assert!(m.allowed_collisions().is_allowed(0, 1) && m.allowed_collisions().is_allowed(1, 2));
    assert!(m.self_collision_pairs().is_empty());
    let mut scene = Scene::new();
    let id = scene.add_model(r.model.clone()).unwrap();
    let mut data = Box::new(rl_core::Data::<8>::new());
    scene
        .set_configuration(
            id,
            &r.kinematics.model,
            &mut data,
            &[std::f64::consts::FRAC_PI_2],
        )
        .unwrap();
    // The arm turned 90° about z: its sphere is at (0, 0.5, 0.2).
    let s = &scene.models()[0].bodies()[1].shapes()[1];
    let (lo, hi) = s.world_aabb();
    assert!(
        ((lo + hi) / 2.0 - DVec3::new(0.0, 0.5, 0.2)).length() < 1e-9,
        "{lo:?} {hi:?}"
    );
    // The tip link follows through its fixed joint.
    assert!(
        (scene.models()[0].bodies()[2].pose().translation - DVec3::new(0.0, 0.5, 0.2)).length()
            < 1e-9
    );
    // Visual geometry.
    let vis = UrdfGeometryOptions {
        kind: GeometryKind::Visual,
        ..Default::default()
    };
    let v = urdf::load_geometry(&p, &vis, &mut cache).unwrap();
    assert_eq!(v.bodies()[1].shapes()[0].geometry().kind(), "capsule");
}

#[test]
fn srdf_replaces_the_default_allowed_set() {
    let p = write_tmp("srdf.urdf", TWO_LINKS);
    let mut cache = MeshCache::new();
    let mut m = urdf::load_geometry(&p, &UrdfGeometryOptions::default(), &mut cache).unwrap();
    let report = srdf::apply_str(
        r#"<robot name="two"><disable_collisions link1="base" link2="tip" reason="Never"/>
           <disable_collisions link1="base" link2="ghost" reason="Never"/></robot>"#,
        &mut m,
    )
    .unwrap();
    assert_eq!(report.disabled, 1);
    assert_eq!(report.unknown_links, vec!["ghost".to_string()]);
    assert!(m.warnings().iter().any(|w| w.contains("ghost")));
    // Only base–tip is allowed now: base–arm is checked again.
    // (tip has no shapes: no pair with it is checked.)
    assert_eq!(m.self_collision_pairs(), &[(0, 1)]);
    let e = srdf::apply_str(
        "<robot><disable_collisions link1=\"base\"/></robot>",
        &mut m,
    )
    .unwrap_err();
    assert!(e.to_string().contains("link2"), "{e}");
    let e = srdf::apply_str("<rlsg/>", &mut m).unwrap_err();
    assert!(
        matches!(*e.kind, SgErrorKind::UnsupportedFormat { .. })
            && e.to_string().contains("<rlsg>: not an SRDF <robot>"),
        "{e}"
    );
}

#[test]
fn bad_urdf_geometry_names_file_element_and_reason() {
    let cases = [
        (
            r#"<robot name="r"><link name="l"><collision><geometry><mesh filename="missing.stl"/></geometry></collision></link></robot>"#,
            "file not found",
            "link \"l\"",
        ),
        (
            r#"<robot name="r"><link name="l"><collision><geometry><mesh filename="x.ply"/></geometry></collision></link></robot>"#,
            "",
            "link \"l\"",
        ),
        (
            r#"<robot name="r"><link name="l"><collision><geometry><sphere radius="nan"/></geometry></collision></link></robot>"#,
            "not finite",
            "<sphere>",
        ),
        (
            r#"<robot name="r"><link name="l"><collision><geometry><box size="1 1"/></geometry></collision></link></robot>"#,
            "too few",
            "<box>",
        ),
        (
            r#"<robot name="r"><link name="l"><collision><origin xyz="0 0 x"/><geometry><sphere radius="1"/></geometry></collision></link></robot>"#,
            "not a number",
            "<origin>",
        ),
        (
            r#"<robot name="r"><link name="l"><collision><geometry><torus/></geometry></collision></link></robot>"#,
            "unsupported",
            "<torus>",
        ),
        (
            r#"<robot name="r"><link name="l"><collision></collision></link></robot>"#,
            "missing <geometry>",
            "<collision>",
        ),
        (
            r#"<robot name="r"><link name="l"/><link name="l"/></robot>"#,
            "used twice",
            "<link",
        ),
        (r#"<robot name="r"><link name="l">"#, "syntax", ""),
        (r#"<rlmdl/>"#, "<rlmdl>: not a URDF <robot>", "<rlmdl>"),
    ];
    for (text, why, element) in cases {
        let p = write_tmp("bad.urdf", text);
        let e = urdf::load_geometry(&p, &UrdfGeometryOptions::default(), &mut MeshCache::new())
            .unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(&*p.to_string_lossy()), "{msg}");
        assert!(msg.contains(why), "{text}\n{msg}");
        assert!(msg.contains(element), "{text}\n{msg}");
        assert!(e.position.is_some(), "{msg}");
    }
    // A mesh in a format we do not read.
    let bad = write_tmp("x.ply", "ply\n");
    let p = write_tmp(
        "ply.urdf",
        &format!(
            r#"<robot name="r"><link name="l"><collision><geometry><mesh filename="{}"/></geometry></collision></link></robot>"#,
            bad.display()
        ),
    );
    let e = urdf::load_geometry(&p, &UrdfGeometryOptions::default(), &mut MeshCache::new())
        .unwrap_err();
    assert!(
        matches!(*e.innermost().kind, SgErrorKind::UnsupportedFormat { .. }),
        "{e}"
    );
}

#[test]
fn meshes_scale_and_convex_hulls() {
    // An ASCII STL tetrahedron.
    let stl = "solid t\nfacet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\nvertex 1 0 0\nendloop\nendfacet\n\
               facet normal 0 -1 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 0 1\nendloop\nendfacet\n\
               facet normal -1 0 0\nouter loop\nvertex 0 0 0\nvertex 0 0 1\nvertex 0 1 0\nendloop\nendfacet\n\
               facet normal 1 1 1\nouter loop\nvertex 1 0 0\nvertex 0 1 0\nvertex 0 0 1\nendloop\nendfacet\nendsolid t\n";
    let mesh = write_tmp("tetra.stl", stl);
    let urdf_text = format!(
        r#"<robot name="r"><link name="l"><collision><geometry><mesh filename="{}" scale="2 2 2"/></geometry></collision></link></robot>"#,
        mesh.file_name().unwrap().to_string_lossy()
    );
    let p = write_tmp("mesh.urdf", &urdf_text);
    let mut cache = MeshCache::new();
    for mode in [MeshMode::Mesh, MeshMode::ConvexHull] {
        let opt = UrdfGeometryOptions {
            mesh: mode,
            ..Default::default()
        };
        let m = urdf::load_geometry(&p, &opt, &mut cache).unwrap();
        let s = &m.bodies()[0].shapes()[0];
        assert_eq!(
            s.geometry().kind(),
            if mode == MeshMode::Mesh {
                "mesh"
            } else {
                "convex"
            }
        );
        let (lo, hi) = s.world_aabb();
        assert!(
            (hi - DVec3::splat(2.0)).length() < 1e-6 && lo.length() < 1e-6,
            "{lo:?} {hi:?}"
        );
        assert_eq!(s.source(), Some(mesh.as_path()));
    }
}

#[test]
fn non_manifold_and_sliver_meshes_load_with_a_note_or_are_refused_when_strict() {
    // Three triangles on the edge (0,0,0)–(1,0,0), and one without area.
    let facet = |a: &str, b: &str, c: &str| {
        format!(
            "facet normal 0 0 0\nouter loop\nvertex {a}\nvertex {b}\nvertex {c}\nendloop\nendfacet\n"
        )
    };
    let stl = format!(
        "solid fan\n{}{}{}{}endsolid fan\n",
        facet("0 0 0", "1 0 0", "0 1 0"),
        facet("0 0 0", "1 0 0", "0 0 1"),
        facet("0 0 0", "1 0 0", "0 -1 0"),
        facet("0 0 0", "1 0 0", "2 0 0")
    );
    write_tmp("fan.stl", &stl);
    let p = write_tmp(
        "fan.urdf",
        r#"<robot name="r"><link name="l"><collision><geometry><mesh filename="fan.stl"/></geometry></collision></link></robot>"#,
    );
    let m =
        urdf::load_geometry(&p, &UrdfGeometryOptions::default(), &mut MeshCache::new()).unwrap();
    let notes = m.warnings().join("\n");
    assert!(
        notes.contains("1 edges are shared by more than two triangles"),
        "{notes}"
    );
    assert!(notes.contains("1 of 4 triangles have no area"), "{notes}");
    let strict = UrdfGeometryOptions {
        strict_meshes: true,
        ..Default::default()
    };
    let e = urdf::load_geometry(&p, &strict, &mut MeshCache::new()).unwrap_err();
    assert!(
        e.to_string().contains("fan.stl") && e.to_string().contains("link \"l\""),
        "{e}"
    );
    assert!(
        matches!(*e.innermost().kind, SgErrorKind::DegenerateMesh { .. }),
        "{e}"
    );
    // Without the sliver, the strict check names the non-manifold edge.
    let stl = format!(
        "solid fan\n{}{}{}endsolid fan\n",
        facet("0 0 0", "1 0 0", "0 1 0"),
        facet("0 0 0", "1 0 0", "0 0 1"),
        facet("0 0 0", "1 0 0", "0 -1 0")
    );
    write_tmp("fan.stl", &stl);
    let e = urdf::load_geometry(&p, &strict, &mut MeshCache::new()).unwrap_err();
    assert!(
        matches!(
            *e.innermost().kind,
            SgErrorKind::NonManifoldMesh { edges: 1, .. }
        ),
        "{e}"
    );
}
