//! Hostile input (issue 24): small files that expand into huge scenes (a VRML `DEF`/`USE`
//! "billion laughs", the same fan-out through `Inline` files), paths that are not files (a
//! FIFO, `/dev/zero` behind a mesh's symbolic link), meshes above the size limit, attributes by
//! the hundred thousand, a planning scene of many objects. Each is refused with a typed error
//! that says what and where, in bounded memory and time; each limit can be raised by the
//! library's user ([`SceneLimits`]).

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use rl_sg::load::{self, MeshCache, SceneLimits, UrdfGeometryOptions, moveit, rlsg, urdf};
use rl_sg::{SgError, SgErrorKind};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rl-sg-hostile-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// `levels` levels of ten `USE`s of the level below, over one box: 10^levels boxes from the
/// last one (every level is a top-level node too, so the file holds 1 + 10 + … of them). Eight
/// levels (10^8 boxes) are 861 bytes.
fn laughs(levels: usize) -> String {
    let mut t = String::from("#VRML V2.0 utf8\nDEF a0 Shape { geometry Box { size 1 1 1 } }\n");
    for k in 1..=levels {
        let uses = vec![format!("USE a{}", k - 1); 10].join(" ");
        t.push_str(&format!("DEF a{k} Group {{ children [ {uses} ] }}\n"));
    }
    t
}

fn too_large(e: &SgError) -> (&'static str, u64) {
    match &*e.innermost().kind {
        SgErrorKind::TooLarge { what, limit } => (what, *limit),
        other => panic!("not a TooLarge error: {other:?} ({e})"),
    }
}

/// Runs `f` on a thread and fails if it has not returned within `limit` (a FIFO that blocks
/// the reader must fail the test, not hang it).
fn within<T: Send + 'static>(limit: Duration, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(limit)
        .unwrap_or_else(|_| panic!("still running after {limit:?}: the reader blocked"))
}

#[test]
fn a_def_use_billion_laughs_stops_at_the_shape_limit_naming_the_chain() {
    let d = dir("laughs");
    let text = laughs(8);
    assert!(text.len() < 901, "{} bytes", text.len());
    let p = write(&d, "laughs.wrl", &text);
    let start = Instant::now();
    let e = rlsg::load_vrml(&p).unwrap_err();
    let msg = e.to_string();
    assert_eq!(
        too_large(&e),
        (
            "number of shapes (after DEF/USE and Inline expansion)",
            SceneLimits::DEFAULT.max_shapes as u64
        ),
        "{msg}"
    );
    // The file, and the chain of nodes from its root to the shape that passed the limit.
    assert!(msg.starts_with(&format!("{}:2:", p.display())), "{msg}");
    assert!(
        msg.contains("file \"laughs.wrl\" › Group \"a6\" › Group \"a5\"")
            && msg.contains("Group \"a1\" › Shape \"a0\""),
        "{msg}"
    );
    println!("refused in {:?}: {msg}", start.elapsed());

    // The limits are the user's: three levels (1 111 boxes from the top-level nodes and their
    // uses) load by default, and not with a limit of 1 000 shapes.
    let small = write(&d, "small.wrl", &laughs(2));
    assert_eq!(
        rlsg::load_vrml(&small).unwrap().models()[0].shape_count(),
        111
    );
    let three = write(&d, "three.wrl", &laughs(3));
    assert_eq!(
        rlsg::load_vrml(&three).unwrap().models()[0].shape_count(),
        1111
    );
    let tight = SceneLimits {
        max_shapes: 1000,
        ..SceneLimits::DEFAULT
    };
    let e = rlsg::load_vrml_with(&three, &tight).unwrap_err();
    assert_eq!(too_large(&e).1, 1000, "{e}");
}

#[test]
fn a_search_for_a_missing_name_through_the_laughs_stops_at_the_visit_limit() {
    // RL's scene file names a model the VRML lacks: the search walks the whole expanded
    // graph, 10^8 nodes, unless bounded.
    let d = dir("search");
    write(&d, "laughs.wrl", &laughs(8));
    let p = write(
        &d,
        "scene.xml",
        "<rlsg><scene href=\"laughs.wrl\"><model name=\"nothere\"/></scene></rlsg>",
    );
    let e = rlsg::load_scene(&p).unwrap_err();
    let (what, limit) = too_large(&e);
    assert!(what.starts_with("number of node visits"), "{e}");
    assert_eq!(limit, SceneLimits::DEFAULT.max_visits);
    let msg = e.to_string();
    assert!(
        msg.contains("scene.xml") && msg.contains("laughs.wrl") && msg.contains("<model"),
        "{msg}"
    );
}

#[test]
fn inline_fan_out_reads_each_file_once_and_stops_at_the_shape_limit() {
    // Seven files of about 280 bytes, each inlining the next ten times: 10^6 boxes.
    let d = dir("inline");
    let files = |n: usize| {
        for k in 0..n {
            let body = if k == n - 1 {
                "Shape { geometry Box { size 1 1 1 } }".to_string()
            } else {
                format!(
                    "Group {{ children [ {}] }}",
                    format!("Inline {{ url \"f{}.wrl\" }} ", k + 1).repeat(10)
                )
            };
            write(
                &d,
                &format!("f{k}.wrl"),
                &format!("#VRML V2.0 utf8\n{body}\n"),
            );
        }
        d.join("f0.wrl")
    };
    let top = files(7);
    assert!(std::fs::metadata(&top).unwrap().len() < 300);
    let e = rlsg::load_vrml(&top).unwrap_err();
    let msg = e.to_string();
    assert_eq!(
        too_large(&e).1,
        SceneLimits::DEFAULT.max_shapes as u64,
        "{msg}"
    );
    // The chain crosses every file, down to the shape in the last one.
    assert!(
        msg.contains("file \"f0.wrl\" › Group › Inline › file \"f1.wrl\"")
            && msg.contains("file \"f6.wrl\" › Shape"),
        "{msg}"
    );
    // Four levels load: 1 000 boxes from four files, each read once (not 1 + 10 + 100 + 1000).
    for k in 0..7 {
        std::fs::remove_file(d.join(format!("f{k}.wrl"))).unwrap();
    }
    let top = files(4);
    let v = load::vrml::VrmlScene::load(&top).unwrap();
    assert_eq!(v.file_count(), 4);
    assert_eq!(v.to_model("m").unwrap().shape_count(), 1000);
    // The number of files one scene reads is bounded too.
    let few = SceneLimits {
        max_files: 3,
        ..SceneLimits::DEFAULT
    };
    let e = load::vrml::VrmlScene::load_with(&top, &few).unwrap_err();
    assert_eq!(too_large(&e).1, 3, "{e}");
}

#[test]
fn mesh_vertices_and_triangles_are_counted_for_every_use() {
    // One IndexedFaceSet of 200 triangles used 100 times: 20 000 triangles.
    let mut points = String::new();
    let mut index = String::new();
    for k in 0..200 {
        let x = k as f64;
        points.push_str(&format!("{x} 0 0, {x} 1 0, {x} 0 1, "));
        index.push_str(&format!("{} {} {} -1 ", 3 * k, 3 * k + 1, 3 * k + 2));
    }
    let text = format!(
        "#VRML V2.0 utf8\nSwitch {{ whichChoice -1 choice [ DEF m Shape {{ geometry \
         IndexedFaceSet {{ coord Coordinate {{ point [ {points} ] }} coordIndex [ {index} ] }} }} \
         DEF g Group {{ children [ {} ] }} ] }}\nGroup {{ children [ {} ] }}\n",
        "USE m ".repeat(10),
        "USE g ".repeat(10)
    );
    let d = dir("mesh");
    let p = write(&d, "mesh.wrl", &text);
    let s = rlsg::load_vrml(&p).unwrap();
    assert_eq!(s.models()[0].shape_count(), 100);
    for (limits, what) in [
        (
            SceneLimits {
                max_triangles: 19_999,
                ..SceneLimits::DEFAULT
            },
            "triangles",
        ),
        (
            SceneLimits {
                max_vertices: 59_999,
                ..SceneLimits::DEFAULT
            },
            "vertices",
        ),
    ] {
        let e = rlsg::load_vrml_with(&p, &limits).unwrap_err();
        assert!(too_large(&e).0.contains(what), "{e}");
        assert!(e.to_string().contains("Group \"g\" › Shape \"m\""), "{e}");
    }
}

#[test]
fn a_fifo_and_dev_zero_are_refused_unread() {
    let d = dir("special");
    // A FIFO named as a scene: opening it for reading would wait for a writer forever.
    let fifo = d.join("scene.wrl");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        println!("SKIPPED: mkfifo is not available");
        return;
    }
    let f = fifo.clone();
    let e = within(Duration::from_secs(20), move || {
        load::load_scene_file(&f, &UrdfGeometryOptions::default(), &mut MeshCache::new())
            .unwrap_err()
    });
    assert!(
        matches!(
            &*e.kind,
            SgErrorKind::File(rl_core::loader::ReadErrorKind::NotRegular { file_type })
                if file_type.contains("FIFO")
        ),
        "{e}"
    );
    assert!(e.to_string().contains("scene.wrl"), "{e}");

    // A URDF whose mesh is a symbolic link to /dev/zero (a file that never ends).
    std::os::unix::fs::symlink("/dev/zero", d.join("zero.stl")).unwrap();
    let u = write(
        &d,
        "r.urdf",
        "<robot name=\"r\"><link name=\"a\"><collision><geometry><mesh filename=\"zero.stl\"/>\
         </geometry></collision></link></robot>",
    );
    let e = within(Duration::from_secs(20), move || {
        urdf::load_geometry(&u, &UrdfGeometryOptions::default(), &mut MeshCache::new()).unwrap_err()
    });
    let msg = e.to_string();
    assert!(
        matches!(
            &*e.innermost().kind,
            SgErrorKind::File(rl_core::loader::ReadErrorKind::NotRegular { .. })
        ),
        "{msg}"
    );
    assert!(
        msg.contains("r.urdf") && msg.contains("zero.stl") && msg.contains("character device"),
        "{msg}"
    );

    // Meshes have the file limit too (they had none).
    let stl = d.join("big.stl");
    let mut bytes = vec![0u8; 84];
    bytes[80..84].copy_from_slice(&20u32.to_le_bytes());
    bytes.extend(std::iter::repeat_n(0u8, 20 * 50));
    std::fs::write(&stl, &bytes).unwrap();
    let mut cache = MeshCache::with_limits(SceneLimits {
        max_file_bytes: 1000,
        ..SceneLimits::DEFAULT
    });
    let e = cache.get(&stl).unwrap_err();
    assert!(
        matches!(
            &*e.kind,
            SgErrorKind::File(rl_core::loader::ReadErrorKind::TooLarge { limit: 1000 })
        ),
        "{e}"
    );
}

#[test]
fn an_element_with_100k_attributes_is_refused_before_it_is_parsed() {
    // roxmltree compares each new attribute with the element's earlier ones: 22 s for these
    // 1.1 MB. The check before parsing refuses them in one pass.
    let attributes: String = (0..100_000).map(|k| format!(" a{k}=\"\"")).collect();
    let text = format!("<robot name=\"r\">\n  <link name=\"a\"{attributes}/>\n</robot>\n");
    let d = dir("attrs");
    let p = write(&d, "attrs.urdf", &text);
    let e = urdf::load_geometry(&p, &UrdfGeometryOptions::default(), &mut MeshCache::new())
        .unwrap_err();
    assert_eq!(
        too_large(&e),
        ("number of attributes of one element", 256),
        "{e}"
    );
    assert_eq!(e.position, Some((2, 3)), "{e}");
    assert!(e.to_string().contains("<link>"), "{e}");
}

/// A planning scene of `n` objects with nothing but their ids.
fn objects(n: usize) -> String {
    let mut t = String::from("world:\n  collision_objects:\n");
    for k in 0..n {
        t.push_str(&format!("    - id: o{k}\n"));
    }
    t
}

#[test]
fn a_planning_scene_of_many_objects_loads_in_linear_time() {
    // Each id was looked up in a list of the bodies before it: 100 000 objects took 50 s. A
    // scaling check, not a timed one: 4× the objects may take at most 10× the time (linear is
    // 4×; the list made it 40× here). Sizes alternate and the best of five counts for each, so
    // a busy moment spoils neither side alone.
    let texts = [objects(10_000), objects(40_000)];
    let mut best = [Duration::MAX; 2];
    for _ in 0..5 {
        for (k, text) in texts.iter().enumerate() {
            let t = Instant::now();
            let m = moveit::environment_from_str(text, "env").unwrap();
            best[k] = best[k].min(t.elapsed());
            assert_eq!(m.bodies().len(), [10_000, 40_000][k]);
        }
    }
    let ratio = best[1].as_secs_f64() / best[0].as_secs_f64();
    println!(
        "10 000 objects {:?}, 40 000 objects {:?}: ratio {ratio:.1}",
        best[0], best[1]
    );
    assert!(ratio < 10.0, "4× the objects took {ratio:.1}× the time");
    // Duplicate ids are still found, with the object named.
    let e = moveit::environment_from_str(
        "world:\n  collision_objects:\n    - id: a\n    - id: b\n    - id: a\n",
        "env",
    )
    .unwrap_err();
    assert!(
        matches!(&*e.kind, SgErrorKind::DuplicateName { name } if name == "a"),
        "{e}"
    );
    assert!(e.to_string().contains("collision object #2"), "{e}");
}
