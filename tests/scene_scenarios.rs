//! RL's planning scenarios (rlplan XML) as rlPlanDemo shows them: `rl view SCENARIO.xml` draws
//! the robot where the planner checks it (the scenario's `<world>` placement, RL's visual
//! meshes on the same body frames), at its start, with start and goal ghosts; `rl scene check
//! SCENARIO.xml --q start` checks the start as the planner does; `rl plan` solves the RV-6SL
//! and TX60L scenarios (whose scenes are RL's 2014 visual and convex meshes).
//!
//! The reference for the poses is rl-plan's own checker ([`Scenario::build`], RL's
//! `<world>` semantics tested in rl-plan), not the viewer's code: the test compares two
//! independent paths through the files (planner: the convex scene; viewer: the visual one).

mod cli;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::time::Duration;

use cli::{rl_json, rl_within};
use rl_plan::problem::rlplan::Scenario;
use serde_json::Value;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn data(rel: &str) -> String {
    format!("{ROOT}/tests/data/{rel}")
}

const SCENARIOS: [&str; 3] = [
    "rlplan/unimation-puma560_boxes_rrtConCon.xml",
    "rlplan/mitsubishi-rv6sl_boxes_rrtConCon.xml",
    "rlplan/staeubli-tx60l_wall_rrtConCon.xml",
];

fn get_json(addr: &str, path: &str) -> Value {
    let mut s = TcpStream::connect(addr).expect("connect to rl view");
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut out = Vec::new();
    s.read_to_end(&mut out).unwrap();
    let end = out.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    serde_json::from_slice(&out[end + 4..]).unwrap()
}

/// The robot's body poses the planner's checker computes at `q`, as [x,y,z,qx,qy,qz,qw].
fn planner_poses(sc: &Scenario, q: &[f64]) -> Vec<[f64; 7]> {
    let (_, mut checker) = sc.build().unwrap();
    checker.place(q);
    let robot = checker.robot();
    checker.scene().models()[robot.0]
        .bodies()
        .iter()
        .map(|b| rl_view::scene_json::pose7(b.pose()))
        .collect()
}

/// Largest difference between two lists of poses: metres, and the rotation angle between the
/// quaternions (sign-free).
fn worst(a: &[[f64; 7]], b: &Value) -> (f64, f64) {
    let b: Vec<Vec<f64>> = serde_json::from_value(b.clone()).unwrap();
    assert_eq!(a.len(), b.len());
    let mut dp: f64 = 0.0;
    let mut da: f64 = 0.0;
    for (x, y) in a.iter().zip(&b) {
        let d = ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt();
        let dot = (x[3] * y[3] + x[4] * y[4] + x[5] * y[5] + x[6] * y[6])
            .abs()
            .min(1.0);
        dp = dp.max(d);
        da = da.max(2.0 * dot.acos());
    }
    (dp, da)
}

#[test]
fn rl_view_draws_a_scenario_where_the_planner_checks_it() {
    for rel in SCENARIOS {
        let file = data(rel);
        let sc = Scenario::load(std::path::Path::new(&file)).unwrap();
        let mut child = Command::new(env!("CARGO_BIN_EXE_rl"))
            .args(["view", &file, "--http", "127.0.0.1:0", "--no-coach"])
            .args(["--duration", "120"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
        let first = lines.next().expect("a line").expect("text");
        let addr = first
            .strip_prefix("rl view: open http://")
            .and_then(|u| u.strip_suffix('/'))
            .unwrap_or_else(|| panic!("{first}"))
            .to_string();
        std::thread::spawn(move || lines.for_each(drop));
        let scene = get_json(&addr, "/api/scene");
        let state = get_json(&addr, "/api/state");
        let _ = child.kill();
        let _ = child.wait();
        let m = &scene["models"][0];
        // The viewer's model: RL's visual scene (rlPlanDemo's <viewer><model>).
        let viewer = sc
            .viewer
            .as_ref()
            .expect("RL's scenarios have a viewer model");
        assert_ne!(viewer.scene, sc.scene, "{rel}");
        assert_eq!(m["initial_source"], "start", "{rel}");
        let q0: Vec<f64> = serde_json::from_value(state["models"][0]["q"].clone()).unwrap();
        assert_eq!(
            q0, sc.start,
            "{rel}: the robot starts at the scenario's start"
        );
        let start = planner_poses(&sc, &sc.start);
        let goal = planner_poses(&sc, &sc.goal);
        let drawn = worst(&start, &state["models"][0]["bodies"]);
        let ghost_start = worst(&start, &scene["plan"]["start"]["bodies"]);
        let ghost_goal = worst(&goal, &scene["plan"]["goal"]["bodies"]);
        println!(
            "{rel}: drawn vs planner at the start {:.1e} m / {:.1e} rad; start ghost {:.1e} m; \
             goal ghost {:.1e} m / {:.1e} rad",
            drawn.0, drawn.1, ghost_start.0, ghost_goal.0, ghost_goal.1
        );
        // Same files, same frames: what is left is the convex and visual files' printed
        // rotations (RL wrote both robot files; they agree to 1e-9 m, see rl-sg's hull tests).
        for (what, (dp, da)) in [
            ("drawn", drawn),
            ("start ghost", ghost_start),
            ("goal ghost", ghost_goal),
        ] {
            assert!(dp < 1e-6 && da < 1e-5, "{rel}: {what} {dp} m {da} rad");
        }
        assert_eq!(scene["plan"]["goal"]["q"], serde_json::json!(sc.goal));
    }
}

#[test]
fn scene_check_applies_the_scenarios_world() {
    // The Puma's scenario turns its kinematic world by 90° about z: its valid start is clear
    // of the boxes there; the same q without the rotation lays the arm into them.
    let puma = data("rlplan/unimation-puma560_boxes_rrtConCon.xml");
    let v = rl_json(&["scene", "check", &puma, "--q", "start"]);
    assert_eq!(v["colliding"], false, "{v}");
    let v = rl_json(&["scene", "check", &puma, "--q", "goal"]);
    assert_eq!(v["colliding"], false, "{v}");
    let sc = Scenario::load(std::path::Path::new(&puma)).unwrap();
    let q: Vec<String> = sc.start.iter().map(|x| x.to_string()).collect();
    let unplaced = rl_json(&[
        "scene",
        "check",
        &sc.scene.display().to_string(),
        "--kinematics",
        &sc.kinematics.display().to_string(),
        "--q",
        &q.join(","),
    ]);
    assert_eq!(unplaced["colliding"], true, "{unplaced}");
    // The same placement given by hand (--place, RL's Rz·Ry·Rx in degrees) is clear again.
    let placed = rl_json(&[
        "scene",
        "check",
        &sc.scene.display().to_string(),
        "--kinematics",
        &sc.kinematics.display().to_string(),
        "--place",
        "0,0,0,0,0,90",
        "--q",
        &q.join(","),
    ]);
    assert_eq!(placed["colliding"], false, "{placed}");
    // The TX60L stands 0.625 m before its wall: at its start it is clear.
    let tx = data("rlplan/staeubli-tx60l_wall_rrtConCon.xml");
    let v = rl_json(&["scene", "check", &tx, "--q", "start"]);
    assert_eq!(v["colliding"], false, "{v}");
}

#[test]
fn rl_plan_solves_the_rv6sl_and_tx60l_scenarios() {
    // One seed each, 20 s at most (here: 0.2 s and 1.6 s of planning, loaded machine).
    for rel in [
        "rlplan/mitsubishi-rv6sl_boxes_rrtConCon.xml",
        "rlplan/staeubli-tx60l_wall_rrtConCon.xml",
    ] {
        let out = rl_within(
            &["plan", &data(rel), "--plan-time", "20s", "--seed", "0"],
            Duration::from_secs(120),
        );
        assert!(
            out.status.success(),
            "{rel}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["solved"], true, "{rel}: {v}");
        assert!(v["waypoints_after"].as_u64().unwrap() >= 2, "{rel}: {v}");
    }
}

#[test]
fn every_rl_example_model_and_scenario_loads() {
    // RL's example files (byte for byte from RL's repository; rl-sg's tests load the rlsg
    // and VRML ones): every kinematic model loads (but RL's one XSLT stylesheet), every
    // planning scenario loads and builds (kinematics, scene, the robot linked and placed).
    let mut n = 0;
    for dir in ["rlmdl", "rlkin"] {
        for e in std::fs::read_dir(data(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_none_or(|x| x != "xml") {
                continue;
            }
            let r = rl_core::loader::load_file::<64>(&p);
            if p.ends_with("planar2.param.xml") {
                // An XSLT stylesheet that makes planar2 with a parameter (RL applies it with
                // libxslt): not read yet, refused with a clear reason.
                let e = r.map(|_| ()).unwrap_err().to_string();
                assert!(e.contains("planar2.param.xml") && e.contains("XSLT"), "{e}");
                continue;
            }
            r.unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            n += 1;
        }
    }
    let mut scenarios = 0;
    for e in std::fs::read_dir(data("rlplan")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "xml") {
            let sc = Scenario::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            sc.build()
                .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            scenarios += 1;
        }
    }
    println!("{n} kinematic models, {scenarios} scenarios");
    assert!(n >= 14 && scenarios == 10, "{n} {scenarios}");
}
