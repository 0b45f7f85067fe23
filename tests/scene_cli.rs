//! `rl scene info | check | bench | dump` end to end: RL's Puma 560 among boxes, a URDF robot
//! among MotionBenchMaker obstacles; the JSON fields `check` promises; bad input exits with 2
//! and names the file and the reason.

mod cli;

use cli::{rl, rl_json, rl_within};
use serde_json::Value;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn path(rel: &str) -> String {
    format!("{ROOT}/{rel}")
}

fn puma(q: &str) -> Value {
    rl_json(&[
        "scene",
        "check",
        &path("tests/data/rlsg/unimation-puma560_boxes.convex.xml"),
        "--kinematics",
        &path("tests/data/rlmdl/unimation-puma560.xml"),
        "--q",
        q,
    ])
}

/// The fields of a distance object: two names, a number, two points.
fn check_distance(d: &Value) -> f64 {
    assert!(d["a"].is_string() && d["b"].is_string(), "{d}");
    let p: Vec<f64> = d["point_a"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let q: Vec<f64> = d["point_b"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!((p.len(), q.len()), (3, 3));
    let dist = d["distance"].as_f64().unwrap();
    let gap = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
    assert!((gap - dist.abs()).abs() < 1e-6, "{d}");
    dist
}

#[test]
fn check_reports_rls_puma_among_boxes() {
    // RL's rlCollisionTest configuration: link2 touches box3 (coal agrees, see rl-sg's coal.rs).
    let v = puma("0,0,0,0,0,0");
    assert_eq!(v["colliding"], true);
    let pairs = v["collisions"].as_array().unwrap();
    assert_eq!(pairs.len(), 1);
    assert_eq!(pairs[0], serde_json::json!(["link2", "boxes"]));
    let env = &v["environment_min_distance"];
    assert!(
        check_distance(env) < 0.0,
        "penetration is a negative distance: {env}"
    );
    assert_eq!(
        (env["a"].as_str(), env["b"].as_str()),
        (Some("link2"), Some("boxes"))
    );
    assert!(check_distance(&v["min_distance"]) <= check_distance(env));
    // Raised straight up the arm is clear of everything, its own links included.
    let v = puma("0,-1.5708,1.5708,0,0,0");
    assert_eq!(v["colliding"], false);
    assert!(v["collisions"].as_array().unwrap().is_empty());
    assert!(check_distance(&v["min_distance"]) > 0.0);
    assert!(check_distance(&v["environment_min_distance"]) > 0.05);
}

#[test]
fn check_a_urdf_robot_against_a_moveit_scene() {
    // A two-link arm in a file of its own, among the box_ur5 problem's obstacles.
    let dir = std::env::temp_dir().join(format!("rl-scene-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let urdf = dir.join("arm.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="arm">
  <link name="base"><collision><geometry><cylinder radius="0.1" length="0.2"/></geometry></collision></link>
  <link name="upper"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.6 0.08 0.08"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/><limit lower="-3.14" upper="3.14" effort="1" velocity="1"/></joint>
</robot>"#,
    )
    .unwrap();
    let env = path("tests/data/moveit/box_ur5_scene0001.yaml");
    let v = rl_json(&[
        "scene",
        "check",
        urdf.to_str().unwrap(),
        "--env",
        &env,
        "--q",
        "0",
    ]);
    for key in [
        "colliding",
        "collisions",
        "min_distance",
        "environment_min_distance",
    ] {
        assert!(v.get(key).is_some(), "no {key} in {v}");
    }
    let d = &v["environment_min_distance"];
    check_distance(d);
    assert_eq!(
        d["a"].as_str().map(|a| a == "base" || a == "upper"),
        Some(true),
        "{d}"
    );
    // The obstacle is named by its id in the scene file.
    let ids = std::fs::read_to_string(&env).unwrap();
    assert!(
        ids.contains(&format!("id: {}", d["b"].as_str().unwrap())),
        "{d}"
    );
    // base and upper are adjacent: no self pair is checked, and the JSON says so.
    assert_eq!(v["self_pairs_checked"], 0);
    assert!(v["self_min_distance"].is_null());
}

#[test]
fn info_lists_models_bodies_and_shapes() {
    let out = rl(&[
        "scene",
        "info",
        &path("tests/data/rlsg/unimation-puma560_boxes.convex.xml"),
    ]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("model      \"unimation-puma560\": 7 bodies, 7 shapes"),
        "{text}"
    );
    assert!(
        text.contains("model      \"boxes\": 1 bodies, 8 shapes"),
        "{text}"
    );
    let v = rl_json(&[
        "scene",
        "info",
        &path("tests/data/moveit/cage_panda_scene0001.yaml"),
        "--json",
    ]);
    let m = &v["models"][0];
    assert_eq!(m["name"], "cage_panda_scene0001");
    assert!(m["bodies"].as_array().unwrap().len() >= 5);
    let kinds: Vec<_> = m["bodies"][0]["shapes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["kind"].clone())
        .collect();
    assert!(
        kinds.iter().all(|k| k == "box" || k == "cylinder"),
        "{kinds:?}"
    );
}

#[test]
fn dump_and_bench_run_on_the_puma() {
    let v = rl_json(&[
        "scene",
        "dump",
        &path("tests/data/rlsg/unimation-puma560_boxes.convex.xml"),
        "--kinematics",
        &path("tests/data/rlmdl/unimation-puma560.xml"),
        "--random",
        "3",
    ]);
    assert_eq!(v["shapes"].as_array().unwrap().len(), 15);
    assert_eq!(v["configs"].as_array().unwrap().len(), 3);
    assert_eq!(v["configs"][0]["poses"][0].as_array().unwrap().len(), 7);
    assert_eq!(v["environment_pairs"].as_array().unwrap().len(), 6 * 8);
    let b = rl_json(&[
        "scene",
        "bench",
        &path("tests/data/rlsg/unimation-puma560_boxes.convex.xml"),
        "--kinematics",
        &path("tests/data/rlmdl/unimation-puma560.xml"),
        "--configs",
        "3",
        "--rounds",
        "1",
        "--json",
    ]);
    for k in [
        "update_ns",
        "self_collision_ns",
        "self_distance_ns",
        "environment_ns",
        "environment_distance_ns",
        "sphere_path_ns",
    ] {
        assert!(b[k].as_f64().is_some_and(|ns| ns > 0.0), "{k}: {b}");
    }
}

#[test]
fn bad_input_exits_2_naming_file_and_reason() {
    let out = rl(&["scene", "info", "/nonexistent/scene.yaml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/scene.yaml"));
    let scene = path("tests/data/rlsg/unimation-puma560_boxes.convex.xml");
    let kin = path("tests/data/rlmdl/unimation-puma560.xml");
    let out = rl(&[
        "scene",
        "check",
        &scene,
        "--kinematics",
        &kin,
        "--q",
        "0,0,0",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--q"));
    let out = rl(&[
        "scene",
        "check",
        &scene,
        "--kinematics",
        &kin,
        "--q",
        "0,0,nan,0,0,0",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let out = rl(&["scene", "check", &scene, "--q", "0,0,0,0,0,0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("kinematic model"));
    let out = rl(&["scene", "info", &path("tests/data/rlmdl/README.md")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unsupported format"));
}

#[test]
fn hostile_files_are_refused_at_once_naming_what_and_where() {
    // Issue 24: /dev/zero grew `rl model info` to 8.8 GB; a FIFO blocked it forever; 861 bytes
    // of VRML took `rl scene info` to a 6.17 GB allocation and `rl view --env` to 5.7 GB;
    // `--eds /dev/zero` read without end. Each is now an error within seconds.
    let limit = std::time::Duration::from_secs(60);
    let dir = std::env::temp_dir().join(format!("rl-hostile-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let refused = |args: &[&str], needles: &[&str]| {
        let out = rl_within(args, limit);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: {n:?} not in {err}");
        }
    };
    refused(
        &["model", "info", "/dev/zero"],
        &["/dev/zero", "character device"],
    );
    refused(
        &["fake-robot", "canopen", "--eds", "/dev/zero"],
        &["--eds", "character device"],
    );
    let fifo = dir.join("robot.urdf");
    if std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        refused(
            &["model", "info", fifo.to_str().unwrap()],
            &["robot.urdf", "FIFO"],
        );
    } else {
        println!("SKIPPED (FIFO case only): mkfifo is not available");
    }
    // Eight levels of ten USEs: 10^8 boxes from 861 bytes.
    let mut vrml = String::from("#VRML V2.0 utf8\nDEF a0 Shape { geometry Box { size 1 1 1 } }\n");
    for k in 1..=8 {
        let uses = vec![format!("USE a{}", k - 1); 10].join(" ");
        vrml.push_str(&format!("DEF a{k} Group {{ children [ {uses} ] }}\n"));
    }
    assert_eq!(vrml.len(), 861);
    let laughs = dir.join("laughs.wrl");
    std::fs::write(&laughs, &vrml).unwrap();
    let laughs = laughs.to_str().unwrap();
    let needles = [
        "laughs.wrl:2:8",
        "Group \"a1\" › Shape \"a0\"",
        "limit of 200000",
    ];
    refused(&["scene", "info", laughs], &needles);
    refused(
        &[
            "view",
            "--env",
            laughs,
            "--http",
            "127.0.0.1:0",
            "--no-coach",
        ],
        &needles,
    );
    let _ = std::fs::remove_dir_all(&dir);
}
