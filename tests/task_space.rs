//! The task-space law (`rl::controller::task_space::CartesianImpedance`) on the fake FR3 in
//! torque mode at its 1 kHz (FCI on loopback; the fake integrates the arm's dynamics from the
//! same URDF with rl-core's ABA and adds gravity itself, as the robot does): a streamed tool
//! pose is reached and held at the start orientation, a figure-eight is followed, and the
//! robot never raises a reflex — in particular not its torque-rate reflex (1 N·m per ms),
//! which the law's rate limit keeps.

mod common;
mod late;

use std::time::{Duration, Instant};

use rl::controller::task_space::{CartesianImpedance, DEFAULT_TORQUE_RATE, TaskInput, TaskMotion};
use rl::controller::{ControlRun, RunEnd, RunOptions, RunReport};
use rl::core::loader::{LoadedModel, UrdfOptions, load_urdf_str};
use rl::core::spatial::PlueckerTransform;
use rl::core::{Data, Model, algo};
use rl::drivers::fake::franka_controller::{FakeFranka, fr3_shaped_urdf};
use rl::drivers::franka::FrankaArm;

fn options(duration: Duration) -> RunOptions {
    RunOptions {
        lock_memory: false,
        priority: 50,
        telemetry: false,
        ..RunOptions::default()
    }
    .duration(duration)
}

fn one_run_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static RUNS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    RUNS.lock().unwrap_or_else(|p| p.into_inner())
}

fn model(urdf: &str) -> LoadedModel<16> {
    load_urdf_str::<16>(urdf, &UrdfOptions::default()).expect("model")
}

/// The tool's pose at `q`.
fn tool_at(m: &Model<16>, q: &[f64]) -> PlueckerTransform {
    let mut d = Box::new(Data::<16>::new());
    algo::forward_position(m, &mut d, q).expect("fk");
    algo::tool_pose(m, &d, 0).expect("tool")
}

use common::fake_franka_in_torque_mode as fake_and_arm;

/// The lateness rule for these runs (`common::franka_run_late`), except that a reflex is
/// never the machine's doing: the law steps its torques from the robot's last applied command,
/// so commands lost while the machine was late raise none.
fn failed_late(r: &RunReport, fake: &FakeFranka) -> Option<String> {
    if fake.status().raised.is_empty() {
        common::franka_run_late(r, fake)
    } else {
        None
    }
}

/// franky-sim's FR3 (its MuJoCo model's joint armature, kg·m²).
const FR3_ARMATURE: &str = "0.195,0.195,0.195,0.195,0.074,0.074,0.074";

fn run_to_end<L>(mut run: ControlRun<FrankaArm, 16, 8, L>) -> RunReport
where
    L: rl::controller::ControlLaw<16, 8> + 'static,
{
    let deadline = Instant::now() + Duration::from_secs(60);
    while run.poll(Duration::from_millis(10)).is_some() {
        assert!(Instant::now() < deadline, "the run did not end within 60 s");
    }
    run.join()
}

fn law_json(report: &RunReport) -> serde_json::Value {
    report.law.clone().expect("the law's summary")
}

fn assert_no_reflex(fake: &FakeFranka) {
    let status = fake.status();
    assert!(
        status.raised.is_empty(),
        "the robot raised {:?}",
        status.raised
    );
}

/// Torque changes at most the law's rate (half the robot's 1 N·m per ms, so that a lost
/// command leaves the next within the robot's limit).
fn assert_rate(law: &serde_json::Value) {
    let rate = law["torque_rate_max"].as_f64().expect("rate");
    assert!(rate <= DEFAULT_TORQUE_RATE * (1.0 + 1e-9), "{law}");
}

#[test]
fn a_streamed_tool_pose_is_reached_and_held_at_the_start_orientation() {
    let urdf = fr3_shaped_urdf();
    let m = model(&urdf);
    let attempt = || {
        let _one = one_run_at_a_time();
        let (fake, arm) = fake_and_arm(&urdf);
        let start_q = fake.status().q;
        let start = tool_at(&m.model, &start_q);
        let goal = PlueckerTransform::new(
            start.rotation,
            start.translation + glam::DVec3::new(0.0, 0.08, -0.05),
        );
        // The Franka device says it adds gravity: the law leaves it out by itself.
        let law = CartesianImpedance::<16, 8>::new(0, TaskMotion::Streamed);
        let mut run = ControlRun::start_law(arm, m.clone(), options(Duration::from_secs(3)), law)
            .expect("starts");
        // The pose comes while the arm is held, 0.3 s into the run (as a tracker's would).
        while run
            .poll(Duration::from_millis(5))
            .is_some_and(|p| p.time_s < 0.3)
        {}
        // A run that already ended (the machine made it late: the rule below judges) takes no
        // pose; the checks count the poses taken.
        let _ = run.inputs().send(TaskInput::Pose(goal));
        let report = run_to_end(run);
        (report, (fake, start, goal))
    };
    let Some((report, (fake, start, goal))) = late::while_late(
        "a streamed pose on the fake FR3",
        attempt,
        |(r, (fake, _, _))| failed_late(r, fake),
    ) else {
        return;
    };
    println!("{report}");
    assert!(matches!(report.end, Some(RunEnd::CycleLimit)), "{report}");
    assert_eq!(report.exit_code(), 0, "{report}");
    assert_no_reflex(&fake);
    let law = law_json(&report);
    assert_eq!(law["poses"], 1, "{law}");
    assert_eq!(law["failed_cycles"], 0, "{law}");
    assert_rate(&law);
    // The goal 9.4 cm away was approached through the law's filter, whose velocity and
    // acceleration the task feeds forward: the tool followed its target within a millimetre.
    let max = law["task_error_max_m"].as_f64().expect("max");
    println!("streamed pose: the tool trailed its target by {max} m at most");
    assert!(max < 1e-3, "{law}");
    // At rest there, at the start orientation (the robot's own state, through the model's FK).
    let status = fake.status();
    let end = tool_at(&m.model, &status.q);
    let off = (end.translation - goal.translation).length();
    assert!(off < 1e-3, "the tool ended {off} m from its target");
    let turn = glam::DQuat::from_mat3(&(end.rotation * start.rotation.transpose()));
    let angle = turn.to_axis_angle().1;
    let angle = angle.min(2.0 * std::f64::consts::PI - angle);
    assert!(angle < 2e-3, "the tool turned {angle} rad");
    assert!(status.dq.iter().all(|v| v.abs() < 1e-2), "{:?}", status.dq);
}

#[test]
fn the_tool_follows_a_figure_eight_at_constant_orientation() {
    let urdf = fr3_shaped_urdf();
    let m = model(&urdf);
    let attempt = || {
        let _one = one_run_at_a_time();
        let (fake, arm) = fake_and_arm(&urdf);
        let law = CartesianImpedance::<16, 8>::new(
            0,
            TaskMotion::FigureEight {
                size_m: 0.2,
                period_s: 2.0,
            },
        )
        .gravity_by_device(true);
        let run = ControlRun::start_law(arm, m.clone(), options(Duration::from_secs(5)), law)
            .expect("starts");
        (run_to_end(run), fake)
    };
    let Some((report, fake)) =
        late::while_late("a figure-eight on the fake FR3", attempt, |(r, fake)| {
            failed_late(r, fake)
        })
    else {
        return;
    };
    println!("{report}");
    assert_eq!(report.exit_code(), 0, "{report}");
    assert_no_reflex(&fake);
    let law = law_json(&report);
    assert_eq!(law["failed_cycles"], 0, "{law}");
    assert_rate(&law);
    let max = law["task_error_max_m"].as_f64().expect("max");
    let rms = law["task_error_rms_m"].as_f64().expect("rms");
    let ori = law["orientation_error_max_rad"]
        .as_f64()
        .expect("orientation");
    println!("figure-eight: task error max {max} m, rms {rms} m, orientation {ori} rad");
    assert!(max < 1e-3 && rms < 5e-4 && ori < 5e-3, "{law}");
}

/// `rl run --device franka://… --law cartesian-impedance ARGS --json` against `rl fake-robot
/// franka --model` (the arm's dynamics integrated from the same URDF), as a user runs it: the
/// exit code, the JSON report and the fake's last status line; `None` when the machine made
/// every attempt late (SKIPPED by the rule). With `armature`, the fake's arm carries it
/// (`rl fake-robot franka --armature`) and so does the run's model (`rl run --armature`).
/// `beside` runs on a thread of its own while `rl run` does (a peer that talks to it).
fn cli_run(
    what: &str,
    args: &[&str],
    armature: Option<&str>,
    beside: Option<&(dyn Fn() + Sync)>,
) -> Option<(Option<i32>, serde_json::Value, String)> {
    let armature: Vec<&str> = armature.map_or(Vec::new(), |a| vec!["--armature", a]);
    let dir = std::env::temp_dir().join(format!("rl-task-space-{}-{what}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let urdf = dir.join("fr3.urdf");
    std::fs::write(&urdf, fr3_shaped_urdf()).expect("URDF written");
    let attempt = || {
        let _one = one_run_at_a_time();
        let mut fake = std::process::Command::new(env!("CARGO_BIN_EXE_rl"))
            .args([
                "fake-robot",
                "franka",
                "--port",
                "0",
                "--duration",
                "60",
                "--model",
            ])
            .arg(&urdf)
            .args(&armature)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("the fake starts");
        // The fake's lines (its address first, then its status every second) are read as
        // they come.
        let (lines_tx, lines) = std::sync::mpsc::channel::<String>();
        let stdout = fake.stdout.take().expect("stdout");
        let reader = std::thread::spawn(move || {
            for line in
                std::io::BufRead::lines(std::io::BufReader::new(stdout)).map_while(Result::ok)
            {
                let _ = lines_tx.send(line);
            }
        });
        let first = lines
            .recv_timeout(Duration::from_secs(10))
            .expect("the fake's first line");
        let addr = first
            .split(" on ")
            .nth(1)
            .and_then(|s| s.split(',').next())
            .unwrap_or_else(|| panic!("no address in {first:?}"))
            .to_owned();
        let out = std::thread::scope(|s| {
            if let Some(beside) = beside {
                s.spawn(beside);
            }
            std::process::Command::new(env!("CARGO_BIN_EXE_rl"))
                .args(["run", "--device", &format!("franka://{addr}"), "--model"])
                .arg(&urdf)
                .args(&armature)
                .args(["--law", "cartesian-impedance"])
                .args(args)
                .args(["--json", "--no-mlock"])
                .output()
                .expect("rl run")
        });
        // One more status line of the fake's (each second), then it is stopped.
        let mut status = lines.try_iter().last();
        if let Ok(line) = lines.recv_timeout(Duration::from_millis(1500)) {
            status = Some(line);
        }
        let _ = fake.kill();
        let _ = fake.wait();
        let _ = reader.join();
        let status = status.unwrap_or_default();
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
            panic!(
                "no JSON report ({e}): {}\n{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            )
        });
        (out.status.code(), report, status)
    };
    // The run's own rule (the loop late), and the fake's: a run that failed while the fake (a
    // process of its own, whose lateness the run cannot see) slipped or woke a quarter cycle
    // late, by its status line.
    let result = late::while_late(what, attempt, |(code, report, status)| {
        late::json_late(report).or_else(|| {
            let field = |key: &str| {
                status
                    .split_whitespace()
                    .find_map(|w| w.strip_prefix(key))
                    .and_then(|v| v.parse::<u64>().ok())
                    .unwrap_or(0)
            };
            (*code != Some(0) && (field("slips=") > 0 || field("max_lateness_us=") > 250))
                .then(|| format!("the fake was late: {status}"))
        })
    });
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// `rl run --device franka://… --law cartesian-impedance --task figure-eight` against the fake
/// FR3: the device is opened in torque mode, the tool follows the figure-eight, the robot
/// raises no reflex, and the JSON report carries the law's numbers. The fake's arm carries
/// franky-sim's joint armature (rotor inertia, which URDF cannot carry) and the run is told it
/// (`--armature`): without it in the law the orientation strays by about 0.13 rad.
#[test]
fn rl_run_with_the_cartesian_impedance_law_on_the_fake_franka() {
    let args = [
        "--task",
        "figure-eight",
        "--task-size",
        "0.1",
        "--task-period",
        "2s",
        "--duration",
        "4s",
    ];
    let Some((code, report, status)) = cli_run(
        "rl run --law cartesian-impedance",
        &args,
        Some(FR3_ARMATURE),
        None,
    ) else {
        return;
    };
    assert_eq!(code, Some(0), "{report}");
    assert_eq!(
        report["trajectory_source"], "cartesian-impedance",
        "{report}"
    );
    assert!(
        report["device"]
            .as_str()
            .is_some_and(|d| d.contains("joint torques")),
        "{report}"
    );
    // The fake's last status line: the robot raised no reflex.
    assert!(status.contains(" reflexes=0 "), "{status}");
    let law = &report["law"];
    assert_eq!(law["failed_cycles"], 0, "{law}");
    assert!(law["cycles"].as_u64() >= Some(3900), "{law}");
    assert_rate(law);
    let max = law["task_error_max_m"].as_f64().expect("max");
    assert!(max < 1e-3, "{law}");
    let ori = law["orientation_error_max_rad"]
        .as_f64()
        .expect("orientation");
    assert!(ori < 5e-3, "{law}");
    // The headline keys at the report's top.
    assert_eq!(report["result"], "ok", "{report}");
    assert_eq!(report["reflexes"], 0, "{report}");
    assert_eq!(report["task_error_max_m"], law["task_error_max_m"]);
    assert!(report["min_obstacle_distance_m"].is_null(), "{report}");
}

/// `rl run … --task figure-eight --obstacle moving-sphere`: a sphere comes at the tool while it
/// draws the figure; the arm keeps the margin from it with the orientation held, and the
/// report's top carries what the issue names.
#[test]
fn rl_run_avoids_a_moving_sphere_while_the_orientation_holds() {
    let args = [
        "--task",
        "figure-eight",
        "--task-size",
        "0.1",
        "--task-period",
        "2s",
        "--obstacle",
        "moving-sphere",
        "--obstacle-period",
        "3s",
        "--duration",
        "4s",
    ];
    let Some((code, report, status)) =
        cli_run("rl run --obstacle moving-sphere", &args, None, None)
    else {
        return;
    };
    assert_eq!(code, Some(0), "{report}");
    assert!(status.contains(" reflexes=0 "), "{status}");
    for key in [
        "result",
        "cycles",
        "reflexes",
        "task_error_max_m",
        "task_error_rms_m",
        "orientation_error_max_rad",
        "min_obstacle_distance_m",
        "torque_rate_max",
        "compute_us",
    ] {
        assert!(!report[key].is_null(), "no {key}: {report}");
    }
    assert_eq!(report["result"], "ok");
    assert_eq!(report["reflexes"], 0);
    let o = &report["law"]["obstacles"];
    println!("moving sphere: {o}");
    assert_eq!(report["law"]["priority"], "OrientationFirst", "{report}");
    let min = report["min_obstacle_distance_m"].as_f64().expect("min");
    let margin = o["margin_m"].as_f64().expect("margin");
    assert!(min >= margin, "{o}");
    assert!(o["repelling_cycles"].as_u64() > Some(100), "{o}");
    assert!(
        report["orientation_error_max_rad"].as_f64() < Some(5e-3),
        "{report}"
    );
    let c = &report["compute_us"];
    assert!(c["p50"].as_f64() <= c["p99"].as_f64(), "{c}");
    assert!(c["p99"].as_f64() <= c["max"].as_f64(), "{c}");
}

/// A hand (a sphere of 8 cm) that comes horizontally at the fake FR3's tool, from 60 cm out
/// to 12 cm of it, in 1.5 s: left there, it would overlap the tool's capsule. Its radius too.
fn a_hand_at_the_tool() -> (rl::controller::task_space::MovingSphere, f64) {
    use rl::controller::task_space::{MovingSphere, SKELETON_RADIUS};
    use rl::drivers::fake::franka_controller::READY;
    let m = model(&fr3_shaped_urdf());
    let p = tool_at(&m.model, &READY).translation;
    let u = glam::DVec3::new(p.x, p.y, 0.0).normalize();
    let radius = 0.08;
    let way = MovingSphere {
        radius,
        from: p + u * 0.6,
        to: p + u * 0.12,
        period_s: 3.0,
    };
    let untouched = (way.to - p).length() - radius - SKELETON_RADIUS;
    assert!(untouched < 0.0, "left alone it would overlap: {untouched}");
    (way, radius)
}

/// The hand's run ended with the law having taken `inputs` obstacles, never nearer than the
/// margin, repelling for over half a second, with the orientation held.
fn assert_kept_away(report: &serde_json::Value, inputs: usize) {
    let o = &report["law"]["obstacles"];
    assert_eq!(o["inputs"], inputs, "{o}");
    assert_eq!(o["margin_violations"], 0, "{o}");
    assert!(o["repelling_cycles"].as_u64() > Some(500), "{o}");
    let min = report["min_obstacle_distance_m"].as_f64().expect("min");
    assert!(min >= o["margin_m"].as_f64().expect("margin"), "{o}");
    assert!(
        report["orientation_error_max_rad"].as_f64() < Some(5e-3),
        "{report}"
    );
}

/// `rl run … --obstacle FILE`: a recorded tracker's file — a sphere coming at the tool over
/// 1.5 s (`at` every 50 ms, a tracker at 20 Hz, with its velocity) and staying where, left alone, it would overlap
/// the tool's capsule, a capsule put in and cleared, and one line the law's protocol does not
/// know — replayed into the running law in time. The arm keeps the margin with the orientation
/// held; every line is accounted for in the report (inputs sent and taken, the malformed one
/// with its place); the file's end leaves the run going to its duration.
#[test]
#[ignore = "the Franka link's start-up: in a rehearsal 13 of the first 100 steps found the next \
            state already waiting with the loop and the fake on time (a phase of the loop against \
            the robot's clock), which faults the run's loss-rate check; run with --ignored"]
fn rl_run_avoids_obstacles_replayed_from_a_file() {
    let (way, radius) = a_hand_at_the_tool();
    let mut lines = vec![
        "# a tracked hand, recorded: at SECONDS sphere SLOT x y z r velocity vx vy vz".to_owned(),
    ];
    let mut inputs = 0;
    for k in 0..=30 {
        let t = 0.05 * f64::from(k);
        let o = way.at(t);
        let v = if k == 30 {
            glam::DVec3::ZERO
        } else {
            o.velocity
        };
        let c = o.shape.a;
        lines.push(format!(
            "at {t:.2} sphere 0 {} {} {} {radius} velocity {} {} {}",
            c.x, c.y, c.z, v.x, v.y, v.z
        ));
        inputs += 1;
    }
    // A capsule far behind the base, put in and cleared; a line no protocol knows.
    lines.push("at 1.6 capsule 1, -1 -1 0, -1 1 0, 0.05".into());
    lines.push("at 1.7 cube 2 0 0 0".into());
    let cube_line = lines.len(); // counted from 1
    lines.push("at 2.0 clear 1".into());
    inputs += 2;
    let dir = std::env::temp_dir().join(format!("rl-obstacle-file-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("hand.obstacles");
    std::fs::write(&file, lines.join("\n") + "\n").expect("obstacle file");
    let args = [
        "--obstacle",
        file.to_str().expect("path"),
        "--duration",
        "3500ms",
    ];
    let Some((code, report, status)) = cli_run("rl run --obstacle FILE", &args, None, None) else {
        return;
    };
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(code, Some(0), "{report}");
    assert_eq!(report["result"], "ok", "{report}");
    assert!(status.contains(" reflexes=0 "), "{status}");
    let seen = &report["obstacles"];
    println!("obstacle file: {seen}\nlaw: {}", report["law"]["obstacles"]);
    assert_eq!(seen["lines"], lines.len(), "{seen}");
    assert_eq!(seen["inputs_sent"], inputs, "{seen}");
    assert_eq!(seen["malformed"], 1, "{seen}");
    assert!(
        seen["first_malformed"]
            .as_str()
            .is_some_and(|m| m.starts_with(&format!("line {cube_line}: unknown keyword 'cube'"))),
        "{seen}"
    );
    assert_eq!(seen["ended_by_eof"], true, "{seen}");
    assert_eq!(seen["rest_at_end"], false, "{seen}");
    // The file's end did not end the run: its duration did.
    assert_eq!(
        report["end"], "duration reached, brought to rest",
        "{report}"
    );
    assert_kept_away(&report, inputs);
}

/// `rl run … --obstacle zenoh`: a tracker not written here — a Python publisher (PyPI
/// eclipse-zenoh and rosbags' CDR, `geometry_msgs/PoseStamped` on the cell's
/// `obstacles/hand` topic, 50 Hz) — brings a hand at the tool and leaves it where, left alone,
/// it would overlap the tool's capsule. The cell turns each pose into a sphere of
/// `--obstacle-radius` moving at the velocity its stamps give; the arm keeps the margin with
/// the orientation held, and the cell's report counts every pose taken.
#[cfg(feature = "zenoh")]
#[test]
#[ignore = "the Franka link's start-up: in a rehearsal 13 of the first 100 steps found the next \
            state already waiting with the loop and the fake on time (a phase of the loop against \
            the robot's clock), which faults the run's loss-rate check; run with --ignored"]
fn rl_run_avoids_a_hand_a_zenoh_peer_publishes() {
    #[path = "../rl-cell/tests/support/mod.rs"]
    mod support;
    use rl_cell::ros2::msg::POSE_STAMPED;
    use rl_cell::ros2::names::topic_key;
    let Some(python) = support::python() else {
        println!(
            "SKIPPED: no Python with eclipse-zenoh and rosbags (scripts/test makes target/cell-venv)"
        );
        return;
    };
    let (way, _) = a_hand_at_the_tool();
    let key = topic_key(0, "/arm1/obstacles/hand", &POSE_STAMPED);
    let poses: Vec<serde_json::Value> = (0..=75)
        .map(|k| {
            let t = 0.02 * f64::from(k);
            let c = way.at(t).shape.a;
            // The tracker's own clock in the header: 20 ms apart.
            let ns = 1_000_000_000_000_u64 + 20_000_000 * k as u64;
            serde_json::json!({"key": key, "type": "geometry_msgs/msg/PoseStamped",
                "sequence": k + 1, "after_s": if k == 0 { 0.0 } else { 0.02 },
                "msg": {"header": {"stamp": {"sec": ns / 1_000_000_000,
                    "nanosec": ns % 1_000_000_000}, "frame_id": "world"},
                    "pose": {"position": {"x": c.x, "y": c.y, "z": c.z},
                        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}}})
        })
        .collect();
    let sent = poses.len();
    let dir = std::env::temp_dir().join(format!("rl-obstacle-zenoh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let plan = dir.join("plan.json");
    // The run opens the cell, then connects to the robot; the publisher (Python: 1–3 s to
    // start) connects to the cell, and the hand comes 0.5 s later, while the law runs.
    let plan_json = serde_json::json!({"settle_s": 0.5, "samples": poses, "linger_s": 0.2});
    std::fs::write(&plan, plan_json.to_string()).expect("plan");
    let port = support::free_port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    // Whether it published is judged by what the run took (below): a run the machine made
    // late may end before the publisher found it, and goes again.
    let publish = || {
        let out = support::publish(&python, &endpoint, &plan);
        println!("the publisher: {}", out.status);
    };
    let args = [
        "--obstacle",
        "zenoh",
        "--obstacle-radius",
        "0.08",
        "--zenoh-listen",
        &endpoint,
        "--zenoh-namespace",
        "/arm1",
        "--duration",
        "8s",
    ];
    let Some((code, report, status)) =
        cli_run("rl run --obstacle zenoh", &args, None, Some(&publish))
    else {
        return;
    };
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(code, Some(0), "{report}");
    assert!(status.contains(" reflexes=0 "), "{status}");
    let inbound = &report["zenoh"]["inbound"]["obstacles"];
    println!(
        "zenoh obstacles: {inbound}\nlaw: {}",
        report["law"]["obstacles"]
    );
    assert_eq!(inbound["accepted"], sent, "{inbound}");
    assert_kept_away(&report, sent);
}

/// The seed's tracked worker: a sphere streamed into the running law from another thread (as
/// a tracker would, 200 times a second, with its velocity) comes at the tool until, left where
/// it is, it would overlap the tool's capsule. With the orientation first, the position yields:
/// the arm keeps the margin from it — by the law's own distances and by the robot's joint
/// states sampled meanwhile — while the orientation holds, and the robot raises no reflex, not
/// even its torque-discontinuity one after twelve commands lost while the torques ramp.
#[test]
fn a_streamed_obstacle_is_kept_at_the_margin_while_the_orientation_holds() {
    use rl::controller::task_space::{MovingSphere, SKELETON_RADIUS};
    use rl::core::task::{ImpedanceGains, Priority};
    use rl::sg::capsule::{Capsule, CapsuleModel};
    let urdf = fr3_shaped_urdf();
    let m = model(&urdf);
    let gains = ImpedanceGains {
        priority: Priority::OrientationFirst,
        ..ImpedanceGains::default()
    };
    let margin = gains.repulsion.margin;
    let radius = 0.08;
    let attempt = || {
        let _one = one_run_at_a_time();
        let (fake, arm) = fake_and_arm(&urdf);
        let start = tool_at(&m.model, &fake.status().q);
        // From 60 cm out (horizontally, away from the base) to 12 cm of the tool, in 1.5 s.
        let p = start.translation;
        let u = glam::DVec3::new(p.x, p.y, 0.0).normalize();
        let way = MovingSphere {
            radius,
            from: p + u * 0.6,
            to: p + u * 0.12,
            period_s: 3.0,
        };
        let law = CartesianImpedance::<16, 8>::new(0, TaskMotion::Hold)
            .gains(gains)
            .avoid();
        // Twelve states lost on the way while the repulsion builds up (below): the link's
        // supervision is told to ride that out, as the robot does (it stops at 20).
        let mut opts = options(Duration::from_millis(3500));
        opts.supervision.rest_after_lost = 15;
        opts.supervision.max_consecutive_lost = 19;
        opts.supervision.max_loss_rate = 0.25;
        let mut run = ControlRun::start_law(arm, m.clone(), opts, law).expect("starts");
        // The tracker: the sphere's pose and velocity every 5 ms (it stops at its nearest),
        // and the robot's joints sampled meanwhile: the nearest the arm came, by our capsules
        // at the robot's own state.
        let mut caps = CapsuleModel::<64>::skeleton(&m.model, SKELETON_RADIUS).expect("skeleton");
        let mut d = Box::new(Data::<16>::new());
        let began = Instant::now();
        let mut nearest = f64::INFINITY;
        let mut sent = 0;
        let mut dropped = false;
        while run.poll(Duration::from_millis(5)).is_some() {
            let t = began.elapsed().as_secs_f64().min(1.5);
            // The robot gets no command for 12 ms while the law's torques change at their
            // rate limit: the next must step from the robot's last, not from the law's own.
            if t > 1.1 && !dropped {
                fake.drop_states(12);
                dropped = true;
            }
            let mut o = way.at(t);
            if t >= 1.5 {
                o.velocity = glam::DVec3::ZERO;
            }
            if run
                .inputs()
                .send(TaskInput::Obstacle {
                    slot: 0,
                    obstacle: Some(o),
                })
                .is_ok()
            {
                sent += 1;
            }
            algo::forward_position(&m.model, &mut d, &fake.status().q).expect("fk");
            caps.update(&d);
            let sphere = [Capsule::sphere(o.shape.a, radius)];
            if let Some(c) = caps.min_distance(&sphere) {
                nearest = nearest.min(c.distance);
            }
            assert!(
                began.elapsed() < Duration::from_secs(60),
                "the run did not end"
            );
        }
        let report = run.join();
        let end = tool_at(&m.model, &fake.status().q);
        (report, (fake, start, end, way.to, nearest, sent))
    };
    let Some((report, (fake, start, end, stop, nearest, sent))) = late::while_late(
        "a streamed obstacle on the fake FR3",
        attempt,
        |(r, (fake, ..))| failed_late(r, fake),
    ) else {
        return;
    };
    println!("{report}");
    assert_eq!(report.exit_code(), 0, "{report}");
    assert_no_reflex(&fake);
    let law = law_json(&report);
    assert_eq!(law["failed_cycles"], 0, "{law}");
    assert_rate(&law);
    let o = &law["obstacles"];
    println!("streamed obstacle: {o}; nearest at the robot's sampled states {nearest} m");
    // Left where it stopped, the sphere would overlap the tool's capsule.
    let untouched = (stop - start.translation).length() - radius - SKELETON_RADIUS;
    assert!(untouched < 0.0, "{untouched}");
    assert!(o["inputs"].as_u64() >= Some(100), "{o} ({sent} sent)");
    assert!(o["repelling_cycles"].as_u64() > Some(500), "{o}");
    assert_eq!(o["margin_violations"], 0, "{o}");
    let min = o["min_distance_m"].as_f64().expect("min distance");
    assert!(min >= margin, "{o}");
    // By the robot's own states (sampled between cycles, against the sphere as sent).
    assert!(nearest >= margin - 2e-3, "{nearest}");
    // The position yielded, the orientation held.
    let moved = (end.translation - start.translation).length();
    assert!(moved > 0.05, "the tool moved {moved} m");
    let ori = law["orientation_error_max_rad"]
        .as_f64()
        .expect("orientation");
    assert!(ori < 5e-3, "{law}");
    // The report's headline keys, at its top.
    let json = report.to_json();
    assert_eq!(json["result"], "ok");
    assert_eq!(json["reflexes"], 0);
    assert_eq!(json["min_obstacle_distance_m"], o["min_distance_m"]);
    assert!(json["compute_us"]["p99"].as_f64().is_some(), "{json}");
}

/// What the law refuses before anything moves: a figure-eight faster than it takes, gains that
/// are not gains, a torque-rate limit that is not one, a tool the model does not have.
#[test]
fn the_law_refuses_what_it_cannot_do_before_the_start() {
    use rl::controller::law::Start;
    use rl::controller::{ControlLaw, MotionLimits};
    let m = model(&fr3_shaped_urdf()).model;
    let q = [0.0, -0.7, 0.0, -2.3, 0.0, 1.6, 0.8];
    let limits = MotionLimits::<8>::from_model(&m, 0.25).expect("limits");
    let start = Start {
        position: &q,
        model: &m,
        limits: &limits,
        period_s: 1e-3,
        device_period_s: 1e-3,
        device_adds_gravity: true,
    };
    let refused = |mut law: CartesianImpedance<16, 8>| {
        ControlLaw::<16, 8>::start(&mut law, &start)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    let fast = CartesianImpedance::new(
        0,
        TaskMotion::FigureEight {
            size_m: 0.2,
            period_s: 0.2,
        },
    );
    assert!(refused(fast).contains("at most 1 m/s and 10 m/s²"));
    let bad = CartesianImpedance::new(0, TaskMotion::Hold).gains(rl::core::task::ImpedanceGains {
        damping_ratio: -1.0,
        ..Default::default()
    });
    assert_eq!(
        refused(bad),
        "the gain `damping_ratio` must be finite and ≥ 0"
    );
    let no_rate = CartesianImpedance::new(0, TaskMotion::Hold).torque_rate(f64::NAN);
    assert!(refused(no_rate).contains("torque-rate limit"));
    let no_tool = CartesianImpedance::new(5, TaskMotion::Hold);
    assert!(refused(no_tool).contains("no tool 5"));
    // And one it takes: 0.2 m every 4 s (0.16 m/s, 0.49 m/s²).
    let fine = CartesianImpedance::new(
        0,
        TaskMotion::FigureEight {
            size_m: 0.2,
            period_s: 4.0,
        },
    );
    assert_eq!(refused(fine), "");
}
