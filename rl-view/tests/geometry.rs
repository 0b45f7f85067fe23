//! Answers from rl-core and rl-sg in the state: inverse kinematics toward a dragged target,
//! collisions with obstacles and the robot–environment distance; and paths to play back.

mod support;

use rl_core::algo::{forward_position, tool_pose};
use rl_core::loader::{self, UrdfOptions};
use rl_view::Viewer;
use serde_json::json;
use support::*;

/// Runs `f` on a thread with room for kinematic models in unoptimised builds.
fn big_stack<R: Send + 'static>(f: impl FnOnce() -> R + Send + 'static) -> R {
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(f)
        .unwrap()
        .join()
        .unwrap()
}

/// The world pose `[x y z qx qy qz qw]` of ur5's `tool0` at `q`, by rl-core directly.
fn ur5_tool0(q: [f64; 6]) -> Vec<f64> {
    big_stack(move || {
        let k = loader::load_file_with::<32>(ur5(), &UrdfOptions::default()).unwrap();
        let mut data = Box::new(rl_core::Data::<32>::new());
        forward_position(&k.model, &mut data, &q).unwrap();
        let tool = k.model.tool_index("tool0").unwrap();
        let x = tool_pose(&k.model, &data, tool).unwrap();
        let r = x.quaternion();
        vec![
            x.translation.x,
            x.translation.y,
            x.translation.z,
            r.x,
            r.y,
            r.z,
            r.w,
        ]
    })
}

#[test]
fn ik_reaches_a_pose_computed_by_forward_kinematics_and_reports_failures() {
    let v = start(vec![ur5()]);
    let (mut page, _) = Page::connect(v.http_addr());
    let known = [0.3, -1.2, 1.4, -0.5, 0.8, 0.2];
    let target = ur5_tool0(known);
    page.send(json!({"type": "ik", "model": 0, "target": target}));
    let s = page.wait_state(|s| !s["ik"].is_null());
    let ik = &s["ik"];
    assert_eq!(ik["ok"], true, "{ik}");
    assert!(ik["position_error"].as_f64().unwrap() < 1e-5, "{ik}");
    assert!(ik["iterations"].as_u64().unwrap() > 0);
    assert_eq!(s["models"][0]["source"], "ik");
    // The solution puts the tool there (whichever of the arm's solutions it found).
    let q: [f64; 6] = floats(&s["models"][0]["q"]).try_into().unwrap();
    let reached = ur5_tool0(q);
    for k in 0..3 {
        assert!(
            (reached[k] - target[k]).abs() < 1e-5,
            "{reached:?} vs {target:?}"
        );
    }
    let q_before = s["models"][0]["q"].clone();

    // Beyond the arm's reach (about 0.85 m): a failure with a reason, and the model stays.
    page.send(json!({"type": "ik", "model": 0, "target": [3.0, 0.0, 0.5, 0.0, 0.0, 0.0, 1.0]}));
    let s = page.wait_state(|s| s["ik"]["ok"] == false);
    let ik = &s["ik"];
    assert!(
        ik["reason"].as_str().unwrap().contains("not reached"),
        "{ik}"
    );
    assert!(ik["position_error"].as_f64().unwrap() > 1.0, "{ik}");
    assert_eq!(s["models"][0]["q"], q_before, "a failed IK moves nothing");

    // A target that is not a pose.
    page.send(json!({"type": "ik", "model": 0, "target": [0.3, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0]}));
    let s = page.wait_state(|s| {
        s["ik"]["reason"]
            .as_str()
            .is_some_and(|r| r.contains("quaternion"))
    });
    assert_eq!(s["ik"]["ok"], false);
}

#[test]
fn a_box_on_the_arm_collides_and_the_distance_follows_the_arm() {
    // Where ur5's wrist_3_link is at the start (q = 0).
    let v = start(vec![ur5()]);
    let scene = get_json(v.http_addr(), "/api/scene");
    let state = get_json(v.http_addr(), "/api/state");
    drop(v);
    let names: Vec<&str> = scene["models"][0]["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["name"].as_str().unwrap())
        .collect();
    let wrist = names.iter().position(|n| *n == "wrist_3_link").unwrap();
    let p = &bodies(&state, 0)[wrist];
    let yaml = format!(
        "name: test\nworld:\n  collision_objects:\n    - id: obstacle\n      primitives:\n        \
         - type: box\n          dimensions: [0.1, 0.1, 0.1]\n      primitive_poses:\n        \
         - position: [{}, {}, {}]\n          orientation: [0, 0, 0, 1]\n",
        p[0], p[1], p[2]
    );
    let env = temp_file("box.yaml", &yaml);
    let mut o = options(vec![ur5()]);
    o.load.env = Some(env);
    let v = Viewer::start(&o).unwrap();
    let (mut page, hello) = Page::connect(v.http_addr());
    let s = &hello["state"];
    let colliding = s["colliding"].as_array().unwrap();
    assert!(
        colliding.contains(&json!([0, "wrist_3_link"])),
        "{colliding:?}"
    );
    assert!(
        s["distance"]["value"].as_f64().unwrap() <= 0.0,
        "{}",
        s["distance"]
    );
    assert_eq!(s["distance"]["obstacle"], "obstacle");
    assert_eq!(hello["scene"]["env"]["bodies"][0]["name"], "obstacle");

    // Turned away from the box: nothing touches it, the distance is positive and its points
    // lie on the robot and on the box.
    page.send(json!({"type": "set_q", "model": 0, "q": [1.6, 0.0, 0.0, 0.0, 0.0, 0.0]}));
    let s = page.wait_state(|s| s["models"][0]["q"][0] == 1.6);
    let colliding = s["colliding"].as_array().unwrap();
    assert!(
        !colliding.contains(&json!([0, "wrist_3_link"])),
        "{colliding:?}"
    );
    let d = &s["distance"];
    let value = d["value"].as_f64().unwrap();
    assert!(value > 0.1, "{d}");
    let (a, b) = (floats(&d["a"]), floats(&d["b"]));
    let gap = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
    assert!((gap - value).abs() < 1e-6, "{d}");
    assert!(
        (b[0] - p[0]).abs() <= 0.05 + 1e-9 && (b[1] - p[1]).abs() <= 0.05 + 1e-9,
        "{d}"
    );
}

#[test]
fn a_planned_path_is_in_the_scene() {
    let out = temp_file(
        "path.csv",
        "shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint\n\
         0,0,0,0,0,0\n0.1,0.2,0.3,0.4,0.5,0.6\n",
    );
    let mut o = options(vec![ur5()]);
    o.load.path = Some(out);
    let v = Viewer::start(&o).unwrap();
    let scene = get_json(v.http_addr(), "/api/scene");
    assert_eq!(scene["path"]["model"], 0);
    // No times in the file: timed at the joints' speed limits (every ur5 joint of this URDF:
    // 0.5 rad/s), the slowest joint sets the segment: wrist_3 moves 0.6 rad, 1.2 s.
    assert_eq!(scene["path"]["t"], json!([0.0, 0.6 / 0.5]));
    assert_eq!(scene["path"]["timing"]["from"], "speed_limits");
    assert_eq!(scene["path"]["timing"]["assumed_for"], json!([]));
    assert_eq!(scene["path"]["q"][1], json!([0.1, 0.2, 0.3, 0.4, 0.5, 0.6]));
    drop(v);

    // `rl plan --trajectory`: t, positions, velocities, accelerations.
    let names = [
        "shoulder_pan_joint",
        "shoulder_lift_joint",
        "elbow_joint",
        "wrist_1_joint",
        "wrist_2_joint",
        "wrist_3_joint",
    ];
    let mut header = vec!["t".to_string()];
    for suffix in ["", "/v", "/a"] {
        header.extend(names.iter().map(|n| format!("{n}{suffix}")));
    }
    let mut text = header.join(",") + "\n";
    for (t, x) in [(0.0, 0.0), (0.01, 0.5)] {
        let row: Vec<String> = std::iter::once(t)
            .chain(std::iter::repeat_n(x, 18))
            .map(|v| v.to_string())
            .collect();
        text += &(row.join(",") + "\n");
    }
    let mut o = options(vec![ur5()]);
    o.load.path = Some(temp_file("traj.csv", &text));
    let v = Viewer::start(&o).unwrap();
    let scene = get_json(v.http_addr(), "/api/scene");
    assert_eq!(scene["path"]["t"], json!([0.0, 0.01]));
    assert_eq!(scene["path"]["q"][1], json!(vec![0.5; 6]));
    drop(v);

    // A bad file says where.
    let mut o = options(vec![ur5()]);
    o.load.path = Some(temp_file(
        "bad.csv",
        &format!("{}\n0,0,0,0,0,x\n", names.join(",")),
    ));
    let e = Viewer::start(&o).unwrap_err().to_string();
    assert!(
        e.contains("bad.csv:2") && e.contains("not a finite number"),
        "{e}"
    );
}

#[test]
fn ur5_folded_into_itself_reports_its_colliding_links() {
    let mut o = options(vec![ur5()]);
    o.load.srdf = Some(repo().join("tests/data/mbm/ur5/ur5.srdf"));
    let v = Viewer::start(&o).unwrap();
    let (mut page, hello) = Page::connect(v.http_addr());
    assert_eq!(
        hello["state"]["colliding"],
        json!([]),
        "stretched out: nothing"
    );
    assert!(
        hello["state"]["distance"].is_null(),
        "no obstacles, no distance"
    );
    // The elbow folded back: the forearm and wrist reach the shoulder (as `rl scene check`).
    page.send(json!({"type": "set_q", "model": 0, "q": [0.0, -1.57, 3.0, 0.0, 0.0, 0.0]}));
    let s = page.wait_state(|s| s["models"][0]["q"][2] == 3.0);
    let colliding = s["colliding"].as_array().unwrap();
    for link in [
        "shoulder_link",
        "forearm_link",
        "wrist_1_link",
        "upper_arm_link",
    ] {
        assert!(
            colliding.contains(&json!([0, link])),
            "{link}: {colliding:?}"
        );
    }
    assert!(
        !colliding.contains(&json!([0, "base_link"])),
        "{colliding:?}"
    );
    page.send(json!({"type": "set_q", "model": 0, "q": vec![0.0; 6]}));
    page.wait_state(|s| s["models"][0]["q"][2] == 0.0 && s["colliding"] == json!([]));
}
