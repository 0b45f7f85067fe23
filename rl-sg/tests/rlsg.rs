//! RL's scene files: every shipped `.wrl` and rlsg file loads, into the models, bodies and
//! shapes RL's own loader makes of them; RL's two collision tests (the two tori, the Puma 560
//! among boxes) reproduced; the VRML reader never panics on arbitrary bytes.

mod support;

use std::path::{Path, PathBuf};

use glam::DVec3;
use rl_sg::load::rlsg;
use rl_sg::load::vrml::VrmlScene;
use rl_sg::{CollisionFilter, Geometry, ModelId, Scene};
use support::{Rng, repo, rlsg_data};

fn files(ext: &str) -> Vec<PathBuf> {
    support::files_ending(&rlsg_data(), ext)
}

fn shapes(s: &Scene) -> usize {
    s.models().iter().map(|m| m.shape_count()).sum()
}

#[test]
fn every_shipped_wrl_loads() {
    let all = files(".wrl");
    assert!(all.len() >= 17, "{}", all.len());
    for f in &all {
        let s = rlsg::load_vrml(f).unwrap_or_else(|e| panic!("{e}"));
        println!(
            "{}: {} shapes",
            f.strip_prefix(rlsg_data()).unwrap().display(),
            shapes(&s)
        );
        assert!(
            shapes(&s) > 0 || f.ends_with("box-6d-300505_maze.wrl"),
            "{}",
            f.display()
        );
    }
}

#[test]
fn every_shipped_rlsg_file_loads_as_rl_reads_it() {
    let names = |s: &Scene| -> Vec<(String, Vec<(String, usize)>)> {
        s.models()
            .iter()
            .map(|m| {
                (
                    m.name().to_string(),
                    m.bodies()
                        .iter()
                        .map(|b| (b.name().to_string(), b.shapes().len()))
                        .collect(),
                )
            })
            .collect()
    };
    let load = |f: &str| rlsg::load_scene(&rlsg_data().join(f)).unwrap_or_else(|e| panic!("{e}"));
    for f in files(".xml") {
        load(f.file_name().unwrap().to_str().unwrap());
    }
    let s = load("unimation-puma560_boxes.convex.xml");
    let links: Vec<_> = (0..7).map(|i| (format!("link{i}"), 1)).collect();
    // The boxes model's body "" is the inlined file's root group: all eight boxes.
    assert_eq!(
        names(&s),
        vec![
            ("unimation-puma560".into(), links.clone()),
            ("boxes".into(), vec![(String::new(), 8)])
        ]
    );
    // Body frames are the VRML transforms down to the body's node (RL's zero configuration).
    let link2 = &s.models()[0].bodies()[2];
    assert!((link2.pose().translation - DVec3::new(0.4318, 0.1291, 0.6604)).length() < 1e-12);
    // A shape's pose is relative to its body: link1's mesh turned by π about x inside it.
    let sh = &s.models()[0].bodies()[1].shapes()[0];
    assert!(
        (sh.local_pose().rotation.y_axis.y + 1.0).abs() < 1e-6,
        "{:?}",
        sh.local_pose()
    );
    // Model "" is the file's root group (planar2): bodies below it by name.
    let p = load("planar2.xml");
    assert_eq!(names(&p)[0].0, "");
    assert_eq!(
        names(&p)[0].1,
        vec![
            ("link0".into(), 1),
            ("link1".into(), 2),
            ("link2".into(), 2)
        ]
    );
    // A VRML cylinder is along y: turned onto our z, it lies along the file's y (planar2's
    // joint cylinders are turned by 90° about x: along the world's z).
    let cyl = &p.models()[0].bodies()[1].shapes()[1];
    assert!(matches!(cyl.geometry(), Geometry::Cylinder { .. }));
    let (lo, hi) = cyl.world_aabb();
    assert!(
        ((hi - lo) - DVec3::new(0.2, 0.2, 0.16)).length() < 1e-6,
        "{lo:?} {hi:?}"
    );
    let m = load("box-6d-300505_maze.xml");
    assert_eq!(m.models()[1].bodies()[0].shapes().len(), 25);
    assert_eq!(m.models()[0].bodies()[6].shapes().len(), 1);
}

#[test]
fn two_interlocked_tori_do_not_collide_but_their_hulls_do() {
    // RL's rlSceneCollisionTest on twotori.xml expects isColliding() == false.
    let s = rlsg::load_scene(&rlsg_data().join("twotori.xml")).unwrap();
    assert!(!s.is_colliding(&CollisionFilter::All));
    let d = s.model_distance(ModelId(0), ModelId(1)).unwrap();
    assert!(d.distance > 0.0, "{d:?}");
    // The same tori as convex hulls overlap: the test can fail.
    let mut hulls = Scene::new();
    for m in s.models() {
        let mut h = rl_sg::Model::new(m.name());
        let b = &m.bodies()[0];
        let sh = &b.shapes()[0];
        let Geometry::Mesh(mesh) = sh.geometry() else {
            panic!("a torus is a mesh")
        };
        h.add_body("")
            .add_shape(
                "hull",
                Geometry::convex_hull(mesh.vertices()).unwrap(),
                *sh.local_pose(),
            )
            .unwrap();
        let id = hulls.add_model(h).unwrap();
        hulls
            .set_body_pose(
                rl_sg::BodyId {
                    model: id.0,
                    body: 0,
                },
                b.pose(),
            )
            .unwrap();
    }
    assert!(hulls.is_colliding(&CollisionFilter::All));
}

/// The Puma 560 of RL's rlCollisionTest, linked to its kinematic model.
fn puma() -> (Scene, rl_core::loader::LoadedModel<8>) {
    let rlmdl = repo().join("tests/data/rlmdl/unimation-puma560.xml");
    let loaded = rl_core::loader::load_file::<8>(&rlmdl).unwrap();
    let mut s = rlsg::load_scene(&rlsg_data().join("unimation-puma560_boxes.convex.xml")).unwrap();
    rlsg::link_rlmdl(s.model_mut(ModelId(0)).unwrap(), &rlmdl, &loaded).unwrap();
    (s, loaded)
}

#[test]
fn the_puma_follows_its_kinematics_and_keeps_rls_ignore_lists() {
    let (mut s, loaded) = puma();
    let m = &s.models()[0];
    // `<ignore/>` on body0: the base is not checked against the boxes; body0–body1 allowed.
    assert!(!m.bodies()[0].collision_enabled());
    assert!(m.allowed_collisions().is_allowed(0, 1) && m.allowed_collisions().is_allowed(5, 6));
    let mut data = Box::new(rl_core::Data::<8>::new());
    // At q = 0 the kinematic body frames equal the VRML ones (RL's contract).
    let before: Vec<_> = m.bodies().iter().map(|b| *b.pose()).collect();
    s.set_configuration(ModelId(0), &loaded.model, &mut data, &[0.0; 6])
        .unwrap();
    for (b, x) in s.models()[0].bodies().iter().zip(&before) {
        assert!(
            (b.pose().translation - x.translation).length() < 1e-4,
            "{}: {:?} vs {:?}",
            b.name(),
            b.pose(),
            x
        );
        let e = (b.pose().rotation - x.rotation).abs().to_cols_array();
        assert!(e.iter().all(|v| *v < 1e-5), "{}", b.name());
    }
    // RL's test prints the answer at q = 0 (the coal fixture in coal.rs checks it).
    let hits = s.colliding_bodies(&CollisionFilter::Against(ModelId(0)));
    let d = s.model_distance(ModelId(0), ModelId(1)).unwrap();
    println!(
        "q = 0: {:?}, min distance {:.4} m between {} and {}",
        hits.iter()
            .map(|(a, b)| (s.body_name(*a), s.body_name(*b)))
            .collect::<Vec<_>>(),
        d.distance,
        s.body_name(d.a.body_id()),
        s.body_name(d.b.body_id())
    );
    // Raised straight up (q2 = −90°) the arm is clear of every box.
    let up = std::f64::consts::FRAC_PI_2;
    s.set_configuration(
        ModelId(0),
        &loaded.model,
        &mut data,
        &[0.0, -up, up, 0.0, 0.0, 0.0],
    )
    .unwrap();
    let d = s.model_distance(ModelId(0), ModelId(1)).unwrap();
    assert!(d.distance > 0.05, "{d:?}");
    assert!(!s.is_colliding(&CollisionFilter::All));
}

#[test]
fn bad_vrml_and_rlsg_name_file_element_and_reason() {
    let dir = std::env::temp_dir().join(format!("rl-sg-vrml-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let w = |name: &str, text: &str| -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let cases: &[(&str, &str, &str)] = &[
        (
            "#VRML V2.0 utf8\nShape { geometry Text { string \"x\" } }",
            "unsupported",
            "Text",
        ),
        (
            "#VRML V2.0 utf8\nShape { geometry IndexedFaceSet { coord Coordinate { point [0 0 0, 1 0 0, 0 1 0] } coordIndex [0 1 7 -1] } }",
            "coordIndex",
            "IndexedFaceSet",
        ),
        (
            "#VRML V2.0 utf8\nShape { geometry Box { size 1 -1 1 } }",
            "positive",
            "Box",
        ),
        (
            "#VRML V2.0 utf8\nInline { url \"nowhere.wrl\" }",
            "file not found",
            "Inline",
        ),
        (
            "#VRML V2.0 utf8\nTransform { scale 1 2 1 rotation 0 0 1 0.5 children Shape { geometry Sphere {} } }",
            "scaling a sphere",
            "Sphere",
        ),
        (
            "#VRML V2.0 utf8\nShape { geometry Box { size 1 1 1 }",
            "end of file",
            "",
        ),
        ("not vrml at all", "VRML97", ""),
    ];
    for (text, why, element) in cases {
        let p = w("bad.wrl", text);
        let e = rlsg::load_vrml(&p).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains(why) && msg.contains(element) && msg.contains("bad.wrl"),
            "{text}\n{msg}"
        );
        assert!(e.innermost().position.is_some(), "{msg}");
    }
    // An inline that fails names both files.
    w(
        "inner.wrl",
        "#VRML V2.0 utf8\nShape { geometry Cone { height 0 } }",
    );
    let p = w(
        "outer.wrl",
        "#VRML V2.0 utf8\nGroup { children [ Inline { url \"inner.wrl\" } ] }",
    );
    let msg = rlsg::load_vrml(&p).unwrap_err().to_string();
    assert!(
        msg.contains("outer.wrl") && msg.contains("inner.wrl") && msg.contains("cone length"),
        "{msg}"
    );
    // An inline cycle is refused, not followed forever.
    let p = w("self.wrl", "#VRML V2.0 utf8\nInline { url \"self.wrl\" }");
    assert!(
        rlsg::load_vrml(&p)
            .unwrap_err()
            .to_string()
            .contains("cycle")
    );
    // rlsg naming a model or body the VRML lacks.
    w(
        "two.wrl",
        "#VRML V2.0 utf8\nDEF a Transform { children [ DEF b Shape { geometry Sphere {} } ] }",
    );
    let p = w(
        "x.xml",
        "<rlsg><scene href=\"two.wrl\"><model name=\"a\"><body name=\"c\"/></model></scene></rlsg>",
    );
    let msg = rlsg::load_scene(&p).unwrap_err().to_string();
    assert!(msg.contains("x.xml") && msg.contains("\"c\""), "{msg}");
    let p = w(
        "y.xml",
        "<rlsg><scene href=\"two.wrl\"><model name=\"z\"/></scene></rlsg>",
    );
    assert!(
        rlsg::load_scene(&p)
            .unwrap_err()
            .to_string()
            .contains("\"z\"")
    );
    let p = w("z.xml", "<rlsg><scene/></rlsg>");
    assert!(
        rlsg::load_scene(&p)
            .unwrap_err()
            .to_string()
            .contains("href")
    );
}

fn no_panic(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let path = Path::new("/nonexistent/fuzz.wrl");
    let r = std::panic::catch_unwind(|| VrmlScene::from_str(&text, path).map(|s| s.to_model("f")));
    assert!(r.is_ok(), "the VRML reader panicked on {text:?}");
}

#[test]
fn arbitrary_bytes_never_panic_the_vrml_reader() {
    let mut r = Rng::new(99);
    // Random bytes, random tokens, and mutations of real files.
    let alphabet: &[&str] = &[
        "#VRML V2.0 utf8\n",
        "Transform",
        "Shape",
        "Box",
        "Sphere",
        "Cylinder",
        "Cone",
        "IndexedFaceSet",
        "Coordinate",
        "Inline",
        "Group",
        "Switch",
        "LOD",
        "DEF",
        "USE",
        "NULL",
        "TRUE",
        "FALSE",
        "ROUTE",
        "TO",
        ".",
        "{",
        "}",
        "[",
        "]",
        "children",
        "geometry",
        "coord",
        "point",
        "coordIndex",
        "size",
        "radius",
        "height",
        "translation",
        "rotation",
        "scale",
        "url",
        "\"a.wrl\"",
        "-1",
        "0",
        "1",
        "2.5",
        "-0.5",
        "1e309",
        "nan",
        "0x1F",
        ",",
        "#c\n",
        " ",
        "\n",
        "a",
        "convex",
        "ccw",
        "whichChoice",
        "choice",
        "level",
        "PROTO",
        "IS",
        "\"",
    ];
    let mut seeds: Vec<Vec<u8>> = files(".wrl")
        .iter()
        .map(|f| std::fs::read(f).unwrap())
        .collect();
    seeds.truncate(6);
    for i in 0..3000 {
        let bytes: Vec<u8> = match i % 3 {
            0 => (0..r.range(0.0, 400.0) as usize)
                .map(|_| (r.next_u64() & 0xff) as u8)
                .collect(),
            1 => {
                let mut s = String::from("#VRML V2.0 utf8\n");
                for _ in 0..r.range(0.0, 200.0) as usize {
                    s.push_str(alphabet[(r.uniform() * alphabet.len() as f64) as usize]);
                    s.push(' ');
                }
                s.into_bytes()
            }
            _ => {
                let mut b = seeds[i % seeds.len()].clone();
                for _ in 0..1 + (r.uniform() * 8.0) as usize {
                    let k = (r.uniform() * b.len() as f64) as usize;
                    match r.next_u64() % 3 {
                        0 => {
                            let at = k.min(b.len() - 1);
                            b[at] = (r.next_u64() & 0xff) as u8;
                        }
                        1 => b.truncate(k),
                        _ => {
                            let chunk: Vec<u8> = b[k..(k + 40).min(b.len())].to_vec();
                            b.splice(k..k, chunk);
                        }
                    }
                    if b.is_empty() {
                        break;
                    }
                }
                b
            }
        };
        no_panic(&bytes);
    }
    // Deep nesting is refused, not a stack overflow.
    let deep = format!(
        "#VRML V2.0 utf8\n{}",
        "Transform { children [ ".repeat(100_000)
    );
    no_panic(deep.as_bytes());
}
