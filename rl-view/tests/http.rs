//! The HTTP side: the embedded page, `/api/scene` for a URDF and an RL XML model, the fixed
//! table of model files (a mesh is served, anything else is refused).

mod support;

use std::io::{Read, Write};
use std::net::TcpStream;

use support::*;

#[test]
fn index_and_scene_of_ur5() {
    let v = start(vec![ur5()]);
    let addr = v.http_addr();
    assert_ne!(addr.port(), 0, "the actual port is reported");
    let (status, body) = get(addr, "/");
    assert_eq!(status, 200);
    let page = String::from_utf8_lossy(&body);
    assert!(
        page.contains("<html") || page.contains("<!doctype"),
        "{page}"
    );
    // Every embedded file is served under /dist/.
    for name in rl_view::http::embedded_names() {
        let (status, body) = get(addr, &format!("/dist/{name}"));
        assert_eq!(status, 200, "/dist/{name}");
        assert_eq!(body, rl_view::http::embedded(name).unwrap());
    }
    assert_eq!(get(addr, "/dist/no-such-file.js").0, 404);

    let scene = get_json(addr, "/api/scene");
    assert_eq!(scene["version"], 1);
    let m = &scene["models"][0];
    assert_eq!(m["index"], 0);
    assert_eq!(m["urdf"], "/files/0/robot.urdf");
    let joints: Vec<&str> = m["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        &joints[..6],
        [
            "shoulder_pan_joint",
            "shoulder_lift_joint",
            "elbow_joint",
            "wrist_1_joint",
            "wrist_2_joint",
            "wrist_3_joint"
        ]
    );
    assert_eq!(m["joints"][0]["kind"], "revolute");
    assert_eq!(m["joints"][0]["unit"], "rad");
    assert!(m["joints"][0]["max"].as_f64().unwrap() > 3.0);
    assert_eq!(m["tool"], "tool0");
    let bodies = m["bodies"].as_array().unwrap();
    let names: Vec<&str> = bodies.iter().map(|b| b["name"].as_str().unwrap()).collect();
    assert!(names.contains(&"base_link") && names.contains(&"wrist_3_link"));
    // The visual .dae files are not in the data set: the collision meshes stand in, served
    // from the file table.
    let upper = bodies
        .iter()
        .find(|b| b["name"] == "upper_arm_link")
        .unwrap();
    let shape = &upper["shapes"][0];
    assert_eq!(shape["kind"], "mesh");
    assert_eq!(shape["format"], "stl");
    assert_eq!(shape["pose"].as_array().unwrap().len(), 7);
    let url = shape["url"].as_str().unwrap();
    assert!(url.starts_with("/files/0/"), "{url}");
    let (status, mesh) = get(addr, url);
    assert_eq!(status, 200);
    let on_disk =
        std::fs::read(repo().join("tests/data/mbm/ur5/meshes/ur5/collision/upperarm.stl")).unwrap();
    assert_eq!(mesh, on_disk, "the mesh is served as it is on disk");

    // The URDF is served with its mesh references rewritten into the table.
    let (status, urdf) = get(addr, "/files/0/robot.urdf");
    assert_eq!(status, 200);
    let urdf = String::from_utf8(urdf).unwrap();
    assert!(!urdf.contains("package://"), "package URIs rewritten");
    assert!(urdf.contains(url), "the URDF names the served mesh");
    let doc = roxmltree::Document::parse(&urdf).expect("still XML");
    for mesh in doc.descendants().filter(|n| n.has_tag_name("mesh")) {
        let f = mesh.attribute("filename").unwrap();
        assert!(f.starts_with("/files/0/"), "{f}");
        assert_eq!(get(addr, f).0, 200, "{f} is served");
    }
    assert!(
        scene["models"][0]["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("visual mesh"))
    );
}

#[test]
fn files_outside_the_table_are_refused() {
    let v = start(vec![ur5()]);
    let addr = v.http_addr();
    for p in [
        "/files/0/../ur5.urdf",
        "/files/0/%2e%2e/ur5.urdf",
        "/files/1/robot.urdf",
        "/files/0/0/../../../../../etc/passwd",
        "/files//etc/passwd",
        "/files/0/99/base.stl",
        "/files/0/ur5.srdf",
        "/etc/passwd",
        "/../Cargo.toml",
    ] {
        assert_eq!(get(addr, p).0, 404, "{p}");
    }
    // Not GET, and not HTTP at all.
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(WAIT)).unwrap();
    s.write_all(b"POST /api/scene HTTP/1.1\r\nHost: x\r\n\r\n")
        .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    assert!(out.starts_with("HTTP/1.1 405"), "{out}");
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(WAIT)).unwrap();
    s.write_all(b"\x01\x02 garbage\r\n\r\n").unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    assert!(out.starts_with("HTTP/1.1 400"), "{out}");
    // The server is still there.
    assert_eq!(get(addr, "/api/scene").0, 200);
}

#[test]
fn scene_of_an_rl_xml_model() {
    let v = start(vec![puma()]);
    let scene = get_json(v.http_addr(), "/api/scene");
    let m = &scene["models"][0];
    assert!(m["urdf"].is_null(), "RL models have no URDF");
    assert_eq!(m["joints"].as_array().unwrap().len(), 6);
    let bodies = m["bodies"].as_array().unwrap();
    // A base plus one body per rl-core body, drawn from their link geometry.
    assert_eq!(bodies.len(), 7);
    let kinds: Vec<&str> = bodies
        .iter()
        .flat_map(|b| b["shapes"].as_array().unwrap())
        .map(|s| s["kind"].as_str().unwrap())
        .collect();
    assert!(
        kinds.contains(&"sphere") && kinds.contains(&"capsule"),
        "{kinds:?}"
    );
    assert!(m["tool"].is_string());
    let state = get_json(v.http_addr(), "/api/state");
    assert_eq!(
        bodies.len(),
        state["models"][0]["bodies"].as_array().unwrap().len()
    );
    assert_eq!(state["models"][0]["source"], "init");
    // The skeleton's spheres and capsules touch at every joint: it is not checked against
    // itself, so alone it never collides.
    assert_eq!(state["colliding"], serde_json::json!([]));
    let mut coach = Coach::connect(v.coach_addr().unwrap());
    coach.send("2 0 0.5 -0.7 0.9 0.4 -0.6 0.8\n6 0\n");
    assert_eq!(coach.read_line(), "6 0 0.5 -0.7 0.9 0.4 -0.6 0.8");
    let state = get_json(v.http_addr(), "/api/state");
    assert_eq!(state["models"][0]["source"], "coach");
    assert_eq!(state["colliding"], serde_json::json!([]));
}

#[test]
fn obstacles_from_a_moveit_scene() {
    let mut o = options(vec![ur5()]);
    o.load.env = Some(repo().join("tests/data/moveit/box_ur5_scene0001.yaml"));
    let v = rl_view::Viewer::start(&o).unwrap();
    let scene = get_json(v.http_addr(), "/api/scene");
    let env = scene["env"]["bodies"].as_array().unwrap();
    let names: Vec<&str> = env.iter().map(|b| b["name"].as_str().unwrap()).collect();
    assert!(
        names.contains(&"Can1") && names.contains(&"side_back"),
        "{names:?}"
    );
    let can = env.iter().find(|b| b["name"] == "Can1").unwrap();
    assert_eq!(can["shapes"][0]["kind"], "cylinder");
    let state = get_json(v.http_addr(), "/api/state");
    let d = &state["distance"];
    assert!(d["value"].is_f64(), "{d}");
    assert_eq!(d["model"], 0);
    assert!(d["obstacle"].is_string());
}

#[test]
fn obstacles_from_an_rl_scene_around_an_rl_model() {
    let mut o = options(vec![puma()]);
    o.load.env = Some(repo().join("tests/data/rlsg/scene.xml"));
    let v = rl_view::Viewer::start(&o).unwrap();
    let scene = get_json(v.http_addr(), "/api/scene");
    let env = scene["env"]["bodies"].as_array().unwrap();
    assert_eq!(env.len(), 2);
    assert_eq!(env[0]["name"], "body1");
    assert_eq!(env[0]["shapes"][0]["kind"], "box");
    assert_eq!(
        env[0]["shapes"][0]["size"],
        serde_json::json!([1.5, 1.5, 1.5])
    );
    let p = floats(&env[0]["pose"]);
    assert!((p[0] + 1.0).abs() < 1e-12 && p[1].abs() < 1e-12, "{p:?}");
    let state = get_json(v.http_addr(), "/api/state");
    let d = &state["distance"];
    assert!(d["obstacle"] == "body1" || d["obstacle"] == "body2", "{d}");
    assert!(d["value"].is_f64());
}

/// RL's `rlCoachMdl scene.xml model.xml`: the robot drawn with the scene's own geometry (VRML
/// faces, inline), the scene's other models as obstacles, Coach lines moving it.
#[test]
fn an_rl_scene_with_the_kinematics_of_its_robot() {
    let mut o = options(vec![]);
    o.load.models = vec![rl_view::ModelSource::RlScene {
        scene: repo().join("tests/data/rlsg/unimation-puma560_boxes.convex.xml"),
        kinematics: vec![puma()],
    }];
    let v = rl_view::Viewer::start(&o).unwrap();
    let (mut page, hello) = Page::connect(v.http_addr());
    let m = &hello["scene"]["models"][0];
    assert_eq!(m["bodies"].as_array().unwrap().len(), 7);
    assert_eq!(m["joints"].as_array().unwrap().len(), 6);
    let link1 = &m["bodies"][1]["shapes"][0];
    assert_eq!(link1["kind"], "mesh");
    assert!(!link1["vertices"].as_array().unwrap().is_empty(), "{link1}");
    assert!(
        !hello["scene"]["env"]["bodies"]
            .as_array()
            .unwrap()
            .is_empty()
    );
    assert!(hello["state"]["distance"]["value"].is_f64());
    let before = bodies(&hello["state"], 0);
    let mut coach = Coach::connect(v.coach_addr().unwrap());
    coach.send("2 0 0.5 0.5 0.5 0.5 0.5 0.5\n");
    let s = page.wait_state(|s| s["models"][0]["source"] == "coach");
    assert!(max_diff(&before, &bodies(&s, 0)) > 0.05);

    // RL's rlCoachKin: the RV-6SL among boxes with its rlkin (Denavit–Hartenberg) kinematics.
    let mut o = options(vec![]);
    o.coach = None;
    o.load.models = vec![rl_view::ModelSource::RlScene {
        scene: repo().join("tests/data/rlsg/mitsubishi-rv6sl_boxes.convex.xml"),
        kinematics: vec![repo().join("tests/data/rlkin/mitsubishi-rv6sl.xml")],
    }];
    let v = rl_view::Viewer::start(&o).unwrap();
    let (_page, hello) = Page::connect(v.http_addr());
    let m = &hello["scene"]["models"][0];
    assert_eq!(m["joints"].as_array().unwrap().len(), 6, "{m}");
    assert_eq!(m["bodies"].as_array().unwrap().len(), 7, "{m}");
    assert!(hello["state"]["distance"]["value"].is_f64());
    drop(v);

    // A scene without its kinematics is refused with a hint.
    let mut o = options(vec![
        repo().join("tests/data/rlsg/unimation-puma560_boxes.convex.xml"),
    ]);
    o.coach = None;
    let e = rl_view::Viewer::start(&o).unwrap_err().to_string();
    assert!(e.contains("--kinematics"), "{e}");
}
