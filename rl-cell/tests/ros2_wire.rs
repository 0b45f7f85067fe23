//! ROS 2 sees what ROS 2 would send: RIHS01 type hashes equal to those ROS 2 Jazzy reports
//! and to PyPI rosbags' (ROS2_JAZZY), CDR bytes equal to rosbags' serializer, for every message
//! a cell exchanges.

mod support;

use std::io::Write;
use std::process::{Command, Stdio};

use rl_cell::ros2::msg::{
    self, Header, JointState, JointTrajectory, JointTrajectoryPoint, Message, PointStamped,
    PoseStamped, Text, Time,
};
use rl_cell::ros2::type_hash::TypeDescription;

/// Hashes recorded from ROS 2 itself, not computed here: `sensor_msgs/msg/JointState` as
/// `ros2 topic info --verbose /joint_states` prints it on a ROS 2 system, `std_msgs/msg/String`
/// from rmw_zenoh's design document, and `trajectory_msgs/msg/JointTrajectory`,
/// `std_msgs/msg/Header` and `builtin_interfaces/msg/Time` from the type description files a ROS
/// 2 installation ships (`share/<package>/msg/<Type>.json`, `type_hashes[0]`; rosbags gives
/// the same for Jazzy, Kilted and Lyrical).
#[test]
fn type_hashes_equal_ros2_jazzys() {
    assert_eq!(
        msg::JOINT_STATE.rihs01(),
        "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e"
    );
    assert_eq!(
        msg::STRING.rihs01(),
        "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
    );
    assert_eq!(
        msg::JOINT_TRAJECTORY.rihs01(),
        "RIHS01_179b33eba59d676f6d967ac71fe35e7ca2f64b2f3928f4a018cec115e213796e"
    );
    assert_eq!(
        msg::HEADER.rihs01(),
        "RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01"
    );
    assert_eq!(
        msg::TIME.rihs01(),
        "RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197"
    );
}

/// A JointState as rosbags 0.11 serializes it (recorded; the live comparison below covers the
/// rest): stamp 1 s 2 ns, frame "base", joints j1 j2 at 0.5 and -1.0, no velocity or effort.
#[test]
fn joint_state_bytes_equal_a_recorded_rosbags_vector() {
    let js = JointState {
        header: Header {
            stamp: Time { sec: 1, nanosec: 2 },
            frame_id: "base".into(),
        },
        name: vec!["j1".into(), "j2".into()],
        position: vec![0.5, -1.0],
        velocity: vec![],
        effort: vec![],
    };
    let mut buf = Vec::new();
    js.encode(&mut buf);
    let hex: String = buf.iter().map(|b| format!("{b:02x}")).collect();
    assert_eq!(
        hex,
        "00010000010000000200000005000000626173650000000002000000030000006a310000030000006a32\
         00000200000000000000000000000000e03f000000000000f0bf0000000000000000"
    );
}

fn header_json(h: &Header) -> serde_json::Value {
    serde_json::json!({"stamp": {"sec": h.stamp.sec, "nanosec": h.stamp.nanosec}, "frame_id": h.frame_id})
}

#[test]
fn cdr_and_hashes_equal_rosbags() {
    let Some(python) = support::python() else {
        println!("SKIPPED: no Python with rosbags (scripts/test makes target/cell-venv)");
        return;
    };
    let types: Vec<&TypeDescription> = vec![
        &msg::JOINT_STATE,
        &msg::JOINT_TRAJECTORY,
        &msg::JOINT_TRAJECTORY_POINT,
        &msg::POSE_STAMPED,
        &msg::POINT_STAMPED,
        &msg::STRING,
        &msg::HEADER,
        &msg::TIME,
        &msg::DURATION,
        &msg::POSE,
        &msg::POINT,
        &msg::QUATERNION,
    ];
    // Messages with odd lengths and empty sequences in every position, to exercise alignment.
    let h = Header {
        stamp: Time {
            sec: 1_700_000_123,
            nanosec: 987_654_321,
        },
        frame_id: "world".into(),
    };
    let js = JointState {
        header: Header {
            frame_id: String::new(),
            ..h.clone()
        },
        name: (1..=7).map(|k| format!("panda_joint{k}")).collect(),
        position: vec![0.1, -0.2, 0.3, -1.5, 0.0, 1.8, 0.785],
        velocity: vec![0.01; 7],
        effort: vec![],
    };
    let js_empty = JointState {
        header: h.clone(),
        name: vec!["a".into()],
        position: vec![],
        velocity: vec![1.0],
        effort: vec![-2.5],
    };
    let jt = JointTrajectory {
        header: h.clone(),
        joint_names: vec!["joint_1".into(), "j2".into(), "joint_three".into()],
        points: vec![
            JointTrajectoryPoint {
                positions: vec![0.5, 0.25, -0.125],
                velocities: vec![],
                accelerations: vec![],
                effort: vec![],
                time_from_start: Time {
                    sec: 0,
                    nanosec: 50_000_000,
                },
            },
            JointTrajectoryPoint {
                positions: vec![],
                velocities: vec![0.1, 0.2, 0.3],
                accelerations: vec![0.0; 3],
                effort: vec![1.0],
                time_from_start: Time { sec: 2, nanosec: 1 },
            },
        ],
    };
    let pose = PoseStamped {
        header: Header {
            frame_id: "w".into(),
            ..h.clone()
        },
        position: [0.4, -0.1, 0.9],
        orientation: [0.0, 0.0, 0.38268343236508984, 0.9238795325112867],
    };
    let point = PointStamped {
        header: h.clone(),
        point: [1.0, 2.0, 3.0],
    };
    let text = Text {
        data: "{\"state\": \"running\"}".into(),
    };
    let point_json = |p: &JointTrajectoryPoint| {
        serde_json::json!({"positions": p.positions, "velocities": p.velocities,
            "accelerations": p.accelerations, "effort": p.effort,
            "time_from_start": {"sec": p.time_from_start.sec, "nanosec": p.time_from_start.nanosec}})
    };
    let js_json = |j: &JointState| {
        serde_json::json!({"header": header_json(&j.header), "name": j.name,
            "position": j.position, "velocity": j.velocity, "effort": j.effort})
    };
    let xyz = |p: &[f64]| serde_json::json!({"x": p[0], "y": p[1], "z": p[2]});
    let messages = serde_json::json!([
        {"type": "sensor_msgs/msg/JointState", "msg": js_json(&js)},
        {"type": "sensor_msgs/msg/JointState", "msg": js_json(&js_empty)},
        {"type": "trajectory_msgs/msg/JointTrajectory", "msg": {"header": header_json(&jt.header),
            "joint_names": jt.joint_names, "points": jt.points.iter().map(point_json).collect::<Vec<_>>()}},
        {"type": "geometry_msgs/msg/PoseStamped", "msg": {"header": header_json(&pose.header),
            "pose": {"position": xyz(&pose.position), "orientation": {"x": pose.orientation[0],
            "y": pose.orientation[1], "z": pose.orientation[2], "w": pose.orientation[3]}}}},
        {"type": "geometry_msgs/msg/PointStamped", "msg": {"header": header_json(&point.header),
            "point": xyz(&point.point)}},
        {"type": "std_msgs/msg/String", "msg": {"data": text.data}},
    ]);
    let request = serde_json::json!({
        "hashes": types.iter().map(|t| t.name).collect::<Vec<_>>(),
        "messages": messages,
    });
    let mut child = Command::new(&python)
        .arg(support::peer_script("ros2_ref.py"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("python runs");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(request.to_string().as_bytes())
        .expect("request written");
    let out = child.wait_with_output().expect("python ends");
    assert!(out.status.success(), "ros2_ref.py failed");
    let reply: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    for t in &types {
        assert_eq!(
            reply["hashes"][t.name].as_str(),
            Some(t.rihs01().as_str()),
            "RIHS01 of {}",
            t.name
        );
    }
    let mut ours = Vec::new();
    let mut buf = Vec::new();
    js.encode(&mut buf);
    ours.push(buf.clone());
    js_empty.encode(&mut buf);
    ours.push(buf.clone());
    jt.encode(&mut buf);
    ours.push(buf.clone());
    pose.encode(&mut buf);
    ours.push(buf.clone());
    point.encode(&mut buf);
    ours.push(buf.clone());
    text.encode(&mut buf);
    ours.push(buf.clone());
    let theirs = reply["cdr"].as_array().expect("cdr list");
    assert_eq!(theirs.len(), ours.len());
    for (k, (a, b)) in ours.iter().zip(theirs).enumerate() {
        let hex: String = a.iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(
            Some(hex.as_str()),
            b.as_str(),
            "message {k}: {}",
            messages[k]["type"]
        );
    }
    // And rosbags' bytes decode to the same messages here.
    let unhex = |s: &str| -> Vec<u8> {
        (0..s.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&s[i..i + 2], 16).expect("hex"))
            .collect()
    };
    let get = |k: usize| unhex(theirs[k].as_str().expect("hex"));
    assert_eq!(JointState::decode(&get(0)), Ok(js));
    assert_eq!(JointState::decode(&get(1)), Ok(js_empty));
    assert_eq!(JointTrajectory::decode(&get(2)), Ok(jt));
    assert_eq!(PoseStamped::decode(&get(3)), Ok(pose));
    assert_eq!(PointStamped::decode(&get(4)), Ok(point));
    assert_eq!(Text::decode(&get(5)), Ok(text));
}
