//! Inputs from a peer not written here: a Python publisher on PyPI eclipse-zenoh 1.10.2 and
//! rosbags streams targets (`trajectory_msgs/JointTrajectory`), obstacles
//! (`geometry_msgs/PoseStamped`, `PointStamped`) and a stop request to a cell, each with
//! rmw_zenoh's attachment; the cell hands on exactly the valid ones, typed and in the model's
//! joint order, and refuses the stale, repeated, unattached and out-of-limit ones, counted by
//! reason. Also: a Python subscriber sees the cell's joint states and its liveliness tokens
//! come and go.

mod support;

use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use rl_cell::ros2::msg::{JOINT_STATE, JOINT_TRAJECTORY, POINT_STAMPED, POSE_STAMPED, STRING};
use rl_cell::ros2::names::topic_key;
use rl_cell::{Arrival, Cell, CellConfig, FnInbound, JointLimits, Obstacle, Sample, Target};
use rl_rt::{StopFlag, StopLevel};

type Seen = Arc<Mutex<Vec<(String, Arrival)>>>;

fn joints() -> JointLimits {
    JointLimits {
        names: vec!["j0".into(), "j1".into(), "j2".into()],
        lower: vec![-1.0; 3],
        upper: vec![1.0; 3],
        speed: vec![0.5; 3],
    }
}

fn header() -> serde_json::Value {
    serde_json::json!({"stamp": {"sec": 0, "nanosec": 0}, "frame_id": "world"})
}

fn point(positions: &[f64], velocities: &[f64]) -> serde_json::Value {
    serde_json::json!({"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
        "joint_names": ["j2", "j0", "j1"],
        "points": [{"positions": positions, "velocities": velocities, "accelerations": [],
            "effort": [], "time_from_start": {"sec": 0, "nanosec": 0}}]})
}

#[test]
fn a_python_publisher_streams_targets_obstacles_and_a_stop() {
    let Some(python) = support::python() else {
        println!(
            "SKIPPED: no Python with eclipse-zenoh and rosbags (scripts/test makes target/cell-venv)"
        );
        return;
    };
    let port = support::free_port();
    let seen: Seen = Arc::default();
    let (t_seen, o_seen) = (Arc::clone(&seen), Arc::clone(&seen));
    let inbound = FnInbound(
        move |t: &Target<4>, a: &Arrival| {
            t_seen.lock().expect("lock").push((format!("{t:?}"), *a));
            Ok(())
        },
        move |o: &Obstacle, a: &Arrival| {
            o_seen.lock().expect("lock").push((format!("{o:?}"), *a));
            Ok(())
        },
    );
    let stop = StopFlag::new();
    let config = CellConfig {
        listen: vec![format!("tcp/127.0.0.1:{port}")],
        namespace: "/arm".into(),
        ..CellConfig::default()
    };
    let cell: Cell<4> =
        Cell::open(config, joints(), Box::new(inbound), stop.clone()).expect("cell");
    let target_key = topic_key(0, "/arm/joint_trajectory", &JOINT_TRAJECTORY);
    let stop_key = topic_key(0, "/arm/stop", &STRING);
    let ball_key = topic_key(0, "/arm/obstacles/ball", &POSE_STAMPED);
    let hand_key = topic_key(0, "/arm/obstacles/hand", &POINT_STAMPED);
    let t = |seq: i64, msg: serde_json::Value| {
        serde_json::json!({"key": target_key, "type": "trajectory_msgs/msg/JointTrajectory",
            "msg": msg, "sequence": seq, "after_s": 0.05})
    };
    let pose = serde_json::json!({"header": header(), "pose": {
        "position": {"x": 0.5, "y": -0.25, "z": 0.75},
        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}});
    let far = serde_json::json!({"header": header(), "pose": {
        "position": {"x": 50.0, "y": 0.0, "z": 0.0},
        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}});
    let plan = serde_json::json!({"settle_s": 1.5, "samples": [
        t(1, point(&[0.3, 0.1, 0.2], &[])),                      // j2 j0 j1 -> [0.1, 0.2, 0.3]
        {"key": target_key, "type": "trajectory_msgs/msg/JointTrajectory",
            "msg": point(&[0.0, 0.0, 0.0], &[]), "sequence": 2, "age_s": 0.5},  // stale
        t(3, point(&[1.5, 0.0, 0.0], &[])),                      // j2 beyond its limit
        t(4, point(&[], &[0.05, -0.1, 0.0])),                    // a velocity target
        t(4, point(&[0.0, 0.0, 0.0], &[])),                      // sequence 4 again
        {"key": target_key, "type": "trajectory_msgs/msg/JointTrajectory",
            "msg": point(&[0.0, 0.0, 0.0], &[]), "sequence": 9, "attachment": false},
        t(6, point(&[0.0, 0.0, 0.0], &[0.0, 0.9, 0.0])),         // j0 too fast
        {"key": ball_key, "type": "geometry_msgs/msg/PoseStamped", "msg": pose, "sequence": 1},
        {"key": hand_key, "type": "geometry_msgs/msg/PointStamped", "gid": "22".repeat(16),
            "msg": {"header": header(), "point": {"x": 0.1, "y": 0.2, "z": 0.3}}, "sequence": 1},
        {"key": ball_key, "type": "geometry_msgs/msg/PoseStamped", "msg": far, "sequence": 2},
        {"key": stop_key, "type": "std_msgs/msg/String", "msg": {"data": "please"}, "sequence": 1},
        {"key": stop_key, "type": "std_msgs/msg/String", "msg": {"data": "rest"}, "sequence": 2},
    ]});
    let dir = std::env::temp_dir().join(format!("rl-cell-inbound-{port}"));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let plan_path = dir.join("plan.json");
    std::fs::write(&plan_path, plan.to_string()).expect("plan written");
    let out = support::publish(&python, &format!("tcp/127.0.0.1:{port}"), &plan_path);
    assert!(out.status.success(), "the publisher failed");
    std::thread::sleep(Duration::from_millis(300));

    let got = seen.lock().expect("lock").clone();
    let shown: Vec<&str> = got.iter().map(|(s, _)| s.as_str()).collect();
    assert_eq!(
        shown,
        [
            "Position { position: [0.1, 0.2, 0.3, 0.0], velocity: None }",
            "Velocity { velocity: [-0.1, 0.0, 0.05, 0.0] }",
            "Obstacle { id: 0, position: [0.5, -0.25, 0.75], orientation: [0.0, 0.0, 0.0, 1.0], stamp_ns: 0 }",
            "Obstacle { id: 1, position: [0.1, 0.2, 0.3], orientation: [0.0, 0.0, 0.0, 1.0], stamp_ns: 0 }",
        ]
    );
    for (_, a) in &got {
        assert!(
            (0..100_000_000).contains(&a.age_ns()),
            "arrived {} ns after publication",
            a.age_ns()
        );
    }
    assert_eq!(
        stop.level(),
        StopLevel::Rest,
        "the stop request was applied"
    );
    let counts = cell.inbound_counts();
    let refused = |c: &rl_cell::inbound::TopicCounts, kind: &str| {
        c.refused
            .iter()
            .find(|(k, _)| *k == kind)
            .map_or(0, |(_, n)| *n)
    };
    let t = &counts.targets;
    assert_eq!((t.received, t.accepted), (7, 2));
    assert_eq!(refused(t, "stale"), 1);
    assert_eq!(refused(t, "out_of_limits"), 2);
    assert_eq!(refused(t, "out_of_order"), 1);
    assert_eq!(refused(t, "no_attachment"), 1);
    assert_eq!(t.lost, 1, "sequence 5 never came");
    let o = &counts.obstacles;
    assert_eq!(
        (o.received, o.accepted, refused(o, "out_of_limits")),
        (3, 2, 1)
    );
    assert_eq!(counts.obstacle_names, ["ball", "hand"]);
    let s = &counts.stops;
    assert_eq!(
        (s.received, s.accepted, refused(s, "unsupported")),
        (2, 1, 1)
    );
    let report = cell.finish("{}".into(), "{}".into(), None);
    assert_eq!(report.inbound.targets.accepted, 2);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_python_subscriber_sees_joint_states_and_the_cell_come_and_go() {
    let Some(python) = support::python() else {
        println!(
            "SKIPPED: no Python with eclipse-zenoh and rosbags (scripts/test makes target/cell-venv)"
        );
        return;
    };
    let port = support::free_port();
    let dir = std::env::temp_dir().join(format!("rl-cell-sub-{port}"));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let out_path = dir.join("seen.jsonl");
    let key = topic_key(0, "/joint_states", &JOINT_STATE);
    let mut sub = Command::new(&python)
        .arg(support::peer_script("peer.py"))
        .args([
            "subscribe",
            "--listen",
            &format!("tcp/127.0.0.1:{port}"),
            "--key",
            &key,
        ])
        .arg("--out")
        .arg(&out_path)
        .args(["--duration", "30", "--idle", "1.5"])
        .stdout(Stdio::piped())
        .spawn()
        .expect("python runs");
    // Wait for "ready".
    let mut line = String::new();
    std::io::BufRead::read_line(
        &mut std::io::BufReader::new(sub.stdout.as_mut().expect("stdout")),
        &mut line,
    )
    .expect("ready line");
    assert_eq!(line.trim(), "ready");
    let config = CellConfig {
        connect: vec![format!("tcp/127.0.0.1:{port}")],
        period: Duration::from_millis(2),
        ..CellConfig::default()
    };
    let mut cell: Cell<2> = Cell::open(
        config,
        JointLimits::unlimited(vec!["a".into(), "b".into()]),
        Box::new(rl_cell::Refuse("no inputs")),
        StopFlag::new(),
    )
    .expect("cell");
    std::thread::sleep(Duration::from_millis(1500));
    let n = 500u64;
    for cycle in 0..n {
        let q = cycle as f64 * 1e-3;
        cell.forward(&Sample {
            cycle,
            commanded: [q, -q],
            measured: [q - 1e-4, -q],
            effort: [1.0, 2.0],
        });
        // At the loop's rate, as a drain hands records on (never faster than the loop).
        std::thread::sleep(Duration::from_millis(2));
    }
    std::thread::sleep(Duration::from_millis(500));
    let report = cell.finish("{\"state\":\"ended\"}".into(), "{}".into(), None);
    assert_eq!(report.outbound.dropped, 0);
    assert_eq!(report.outbound.joint_states, 2 * n);
    let status = sub.wait().expect("subscriber ends");
    assert!(status.success());
    let records = support::recorded(&out_path);
    let states: Vec<&serde_json::Value> =
        records.iter().filter(|r| r.get("seq").is_some()).collect();
    assert_eq!(states.len() as u64, n, "every sample, once");
    for (k, r) in states.iter().enumerate() {
        assert_eq!(r["seq"].as_i64(), Some(k as i64 + 1), "in order");
        let q = k as f64 * 1e-3;
        assert_eq!(
            r["position_bits"],
            serde_json::json!([(q - 1e-4).to_bits(), (-q).to_bits()])
        );
        assert_eq!(r["name"], serde_json::json!(["a", "b"]));
        assert_eq!(r["effort"], serde_json::json!([]), "no measured effort");
        if k > 0 {
            // 1e-3 per cycle of 2 ms.
            let v = f64::from_bits(r["velocity_bits"][0].as_u64().expect("velocity"));
            assert!((v - 0.5).abs() < 1e-9, "velocity {v}");
        }
    }
    // The stamps step by the period: handed on no earlier than the loop's grid, the first
    // sample's estimate of the grid's start stands.
    let stamp = |r: &serde_json::Value| {
        r["stamp"][0].as_i64().expect("sec") * 1_000_000_000 + r["stamp"][1].as_i64().expect("ns")
    };
    for w in states.windows(2) {
        assert_eq!(stamp(w[1]) - stamp(w[0]), 2_000_000, "{} {}", w[0], w[1]);
    }
    // The node's token came and went.
    let tokens: Vec<(&str, &str)> = records
        .iter()
        .filter_map(|r| Some((r.get("token")?.as_str()?, r.get("kind")?.as_str()?)))
        .filter(|(t, _)| t.contains(&format!("/{}/", report.zid)) && t.contains("/NN/"))
        .collect();
    assert_eq!(tokens.len(), 2, "{tokens:?}");
    assert!(
        tokens[0].1.contains("PUT") && tokens[1].1.contains("DELETE"),
        "{tokens:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
