//! Per-robot options of the viewer: where a robot stands (`--place`), the SRDF's named state it
//! starts at, a floating base, and a plan's ghosts and trail — read from the Scene JSON and the
//! state a page gets, against rl-core's forward kinematics directly.

mod support;

use glam::{DMat3, DVec3};
use rl_core::spatial::PlueckerTransform;
use rl_view::{RobotOptions, Viewer};
use serde_json::json;
use support::*;

#[test]
fn a_robot_starts_at_its_srdfs_named_state() {
    // ur5.srdf names "home" (shoulder_lift and wrist_1 at -1.57) for the manipulator.
    let mut o = options(vec![ur5()]);
    o.load.srdf = Some(repo().join("tests/data/mbm/ur5/ur5.srdf"));
    let v = Viewer::start(&o).unwrap();
    let scene = get_json(v.http_addr(), "/api/scene");
    let state = get_json(v.http_addr(), "/api/state");
    assert_eq!(scene["models"][0]["initial_source"], "srdf:home");
    assert_eq!(
        floats(&state["models"][0]["q"]),
        vec![0.0, -1.57, 0.0, -1.57, 0.0, 0.0]
    );
    drop(v);
    // Without the SRDF: the model's zero.
    let v = start(vec![ur5()]);
    let scene = get_json(v.http_addr(), "/api/scene");
    assert_eq!(scene["models"][0]["initial_source"], "neutral");
    // A state naming a joint with the wrong count of values is refused, naming it.
    let bad = temp_file(
        "bad.srdf",
        r#"<robot name="ur5"><group_state name="home" group="m">
           <joint name="elbow_joint" value="0 1"/></group_state></robot>"#,
    );
    let mut o = options(vec![ur5()]);
    o.load.robots = vec![RobotOptions {
        srdf: Some(bad),
        ..RobotOptions::default()
    }];
    let e = Viewer::start(&o).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("bad.srdf") && e.contains("elbow_joint"), "{e}");
}

#[test]
fn each_robot_stands_where_it_is_placed() {
    // Two ur5s: the second 1 m along y and turned 90° about z; its bodies are the first's
    // moved by that placement, at any q.
    let x = PlueckerTransform::new(
        DMat3::from_rotation_z(std::f64::consts::FRAC_PI_2),
        DVec3::new(0.0, 1.0, 0.0),
    );
    let mut o = options(vec![ur5(), ur5()]);
    o.load.robots = vec![
        RobotOptions::default(),
        RobotOptions {
            place: Some(x),
            ..RobotOptions::default()
        },
    ];
    let v = Viewer::start(&o).unwrap();
    let scene = get_json(v.http_addr(), "/api/scene");
    assert_eq!(
        floats(&scene["models"][1]["base"])[..3],
        [0.0, 1.0, 0.0],
        "{}",
        scene["models"][1]["base"]
    );
    let mut coach = Coach::connect(v.coach_addr().unwrap());
    let q = "0.3 -1.0 1.2 -0.5 0.7 0.1";
    coach.send(&format!("2 0 {q}\n2 1 {q}\n"));
    let (mut page, _) = Page::connect(v.http_addr());
    let s = page
        .wait_state(|s| s["models"][1]["source"] == "coach" && s["models"][0]["source"] == "coach");
    let a = bodies(&s, 0);
    let b = bodies(&s, 1);
    let mut worst: f64 = 0.0;
    for (p, w) in a.iter().zip(&b) {
        let moved = x.transform_point(DVec3::new(p[0], p[1], p[2]));
        worst = worst.max((moved - DVec3::new(w[0], w[1], w[2])).length());
    }
    assert!(worst < 1e-12, "robot 1 is robot 0 placed: {worst} m");
    // More placements than robots: refused.
    let mut o = options(vec![ur5()]);
    o.load.robots = vec![RobotOptions::default(), RobotOptions::default()];
    let e = Viewer::start(&o).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("2 robots given, 1 robots loaded"), "{e}");
}

#[test]
fn a_floating_base_adds_position_and_quaternion_coordinates() {
    let mut o = options(vec![ur5()]);
    o.load.floating_base = true;
    let v = Viewer::start(&o).unwrap();
    let scene = get_json(v.http_addr(), "/api/scene");
    let joints = scene["models"][0]["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 13);
    let kinds: Vec<_> = joints[..7].iter().map(|j| j["kind"].clone()).collect();
    assert_eq!(
        kinds,
        vec![
            json!("position"),
            json!("position"),
            json!("position"),
            json!("quaternion"),
            json!("quaternion"),
            json!("quaternion"),
            json!("quaternion")
        ]
    );
    // The base moved by Coach carries the arm: its first body is where q puts it.
    let mut coach = Coach::connect(v.coach_addr().unwrap());
    coach.send("2 0 0.5 -0.2 0.3 0 0 0 1 0 0 0 0 0 0\n");
    let (mut page, _) = Page::connect(v.http_addr());
    let s = page.wait_state(|s| s["models"][0]["source"] == "coach");
    let root = &bodies(&s, 0)[0];
    assert!(
        (root[0] - 0.5).abs() < 1e-12
            && (root[1] + 0.2).abs() < 1e-12
            && (root[2] - 0.3).abs() < 1e-12,
        "{root:?}"
    );
}

#[test]
fn a_plan_has_start_and_goal_ghosts_and_a_tool_trail() {
    // A start (given) and a goal: ghosts at rl-core's poses; with a path, the trail starts at
    // the tool at the path's first sample and ends at its last.
    let names = "shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint";
    let path = temp_file(
        "plan.csv",
        &format!("{names}\n0,-1,1,0,0,0\n0.5,-1,1,0,0,0\n0.5,-1.2,1.3,0.2,0,0\n"),
    );
    let mut o = options(vec![ur5()]);
    o.load.path = Some(path);
    let v = Viewer::start(&o).unwrap();
    let scene = get_json(v.http_addr(), "/api/scene");
    let plan = &scene["plan"];
    assert_eq!(plan["start"]["q"], json!([0.0, -1.0, 1.0, 0.0, 0.0, 0.0]));
    assert_eq!(plan["goal"]["q"], json!([0.5, -1.2, 1.3, 0.2, 0.0, 0.0]));
    let n = scene["models"][0]["bodies"].as_array().unwrap().len();
    assert_eq!(plan["start"]["bodies"].as_array().unwrap().len(), n);
    // The trail's ends are tool0 at the first and last samples (rl-core directly).
    let trail = plan["trail"].as_array().unwrap();
    let tool = |q: [f64; 6]| {
        let k = rl_core::loader::load_file_with::<32>(ur5(), &Default::default()).unwrap();
        let mut data = Box::new(rl_core::Data::<32>::new());
        rl_core::algo::forward_position(&k.model, &mut data, &q).unwrap();
        let t = k.model.tool_index("tool0").unwrap();
        rl_core::algo::tool_pose(&k.model, &data, t)
            .unwrap()
            .translation
    };
    let first = floats(&trail[0]);
    let last = floats(trail.last().unwrap());
    let a = tool([0.0, -1.0, 1.0, 0.0, 0.0, 0.0]);
    let b = tool([0.5, -1.2, 1.3, 0.2, 0.0, 0.0]);
    assert!((DVec3::new(first[0], first[1], first[2]) - a).length() < 1e-12);
    assert!((DVec3::new(last[0], last[1], last[2]) - b).length() < 1e-12);
    // Sampled at most 1° apart per joint: 0.5 rad is 29 steps, 0.3 rad 18: 1 + 29 + 18.
    assert_eq!(trail.len(), 48, "{}", trail.len());
}
