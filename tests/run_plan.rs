//! `rl run --plan` end to end on MotionBenchMaker Panda problems against the in-process fake
//! H7, and the library path behind it (`rl::controller::planned`, `ControlRun::start_with`):
//! the run follows the planned path from the request's start to its goal, every position the
//! fake was sent is collision-free for the exact meshes (rl-sg, not the planner's spheres), and
//! problems that cannot be run fail before the servo goes on.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use rl::controller::planned::{PlannedMotion, PlannedMotionError, plan_motion};
use rl::controller::{ControlRun, RunError, RunOptions};
use rl::core::loader::LoadedModel;
use rl::drivers::fake::h7_controller::{FakeH7, FakeH7Config};
use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl::rt::StopFlag;
use rl_plan::PlanOptions;
use rl_plan::Validity;
use rl_plan::problem::Robot;
use rl_plan::problem::moveit::MotionRequest;

mod cli;
mod late;
use cli::{exit_by, rl_within as rl, watch_stderr};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/mbm")
        .join(p)
}

fn panda() -> PathBuf {
    data("panda/panda.urdf")
}

fn problem(name: &str) -> (PathBuf, PathBuf) {
    let dir = data("panda/problems").join(name);
    (dir.join("scene0001.yaml"), dir.join("request0001.yaml"))
}

/// Fraction of the speed limits the runs use: quick, with room below the limits for the
/// loop's timing on a busy machine.
const SPEED: &str = "0.6";

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("rl-run-plan-{}-{name}", std::process::id()))
}

/// One test at a time: a controller run is a SCHED_FIFO loop and a fake at real-time priority,
/// and anything else busy on two CPUs (another run, a planner loading meshes) takes their
/// cycles.
fn one_run_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static RUNS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    RUNS.lock().unwrap_or_else(|p| p.into_inner())
}

/// `rl run --model PANDA --plan --scene SCENE --request REQUEST`, then `extra`.
fn run_plan_args(scene: &Path, request: &Path, extra: &[&str]) -> Vec<OsString> {
    let mut args: Vec<OsString> = vec!["run".into(), "--model".into(), panda().into()];
    args.extend(["--plan".into(), "--scene".into(), scene.into()]);
    args.extend(["--request".into(), request.into()]);
    args.extend(extra.iter().map(OsString::from));
    args
}

/// `rl plan PANDA --scene SCENE --request REQUEST`, then `extra`.
fn plan_args(scene: &Path, request: &Path, extra: &[&str]) -> Vec<OsString> {
    let mut args: Vec<OsString> = vec!["plan".into(), panda().into()];
    args.extend([
        "--scene".into(),
        scene.into(),
        "--request".into(),
        request.into(),
    ]);
    args.extend(extra.iter().map(OsString::from));
    args
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// The request's start and goal, read independently of the binary (rl-plan's MoveIt reader).
fn start_and_goal(robot: &Robot, request: &Path) -> (Vec<f64>, Vec<f64>) {
    MotionRequest::load(request)
        .expect("request")
        .configurations(&robot.space)
        .expect("start and goal")
}

/// Commanded and measured joints per telemetry row, the row's time and state.
struct Telemetry {
    commanded: Vec<Vec<f64>>,
    measured: Vec<Vec<f64>>,
    time_s: Vec<f64>,
    running: Vec<bool>,
}

fn telemetry(path: &Path, joints: usize) -> Telemetry {
    let csv = std::fs::read_to_string(path).expect("telemetry written");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let cmd = header
        .iter()
        .position(|h| h.starts_with("cmd_"))
        .expect("cmd_ columns");
    let meas = header
        .iter()
        .position(|h| h.starts_with("meas_"))
        .expect("meas_ columns");
    assert_eq!(header[cmd], "cmd_panda_joint1");
    assert_eq!(header[1], "t_s");
    let (mut commanded, mut measured) = (Vec::new(), Vec::new());
    let (mut time_s, mut running) = (Vec::new(), Vec::new());
    let state = header
        .iter()
        .position(|h| *h == "state")
        .expect("state column");
    for line in lines {
        let v: Vec<f64> = line
            .split(',')
            .take(state)
            .map(|x| x.parse().expect("number"))
            .collect();
        commanded.push(v[cmd..cmd + joints].to_vec());
        measured.push(v[meas..meas + joints].to_vec());
        time_s.push(v[1]);
        running.push(line.split(',').nth(state) == Some("running"));
    }
    assert!(commanded.len() > 10, "{} rows", commanded.len());
    Telemetry {
        commanded,
        measured,
        time_s,
        running,
    }
}

/// Checks what a run on `problem` sent and measured: it started at the request's start, every
/// commanded position is free for the exact meshes, and the arm ended at the goal within
/// `tolerance` per joint.
fn check_motion(problem_name: &str, tel: &Telemetry, tolerance: &[f64]) {
    let robot = Robot::load_urdf(&panda(), None, None).expect("panda");
    let (scene, request) = problem(problem_name);
    let (start, goal) = start_and_goal(&robot, &request);
    let env = rl::sg::load::moveit::load_environment(&scene).expect("scene");
    let mut exact = robot.exact_checker(env).expect("exact checker");
    for k in 0..7 {
        // The wire and the CSV carry single precision.
        assert!(
            (tel.commanded[0][k] - start[k]).abs() < 1e-5,
            "joint {k} did not start at the request's start: {:?} vs {start:?}",
            tel.commanded[0]
        );
        let end = tel.measured.last().expect("rows")[k];
        assert!(
            (end - goal[k]).abs() <= tolerance[k],
            "joint {k} ended at {end}, the goal is {} (tolerance {})",
            goal[k],
            tolerance[k]
        );
    }
    let mut moved = 0.0f64;
    for (i, q) in tel.commanded.iter().enumerate() {
        assert!(
            exact.is_valid(q),
            "telemetry row {i}: the fake was sent {q:?}, in collision with the exact meshes"
        );
        moved = moved.max(q.iter().zip(&start).map(|(a, b)| (a - b).abs()).sum());
    }
    assert!(moved > 0.5, "the arm hardly moved: {moved} rad");
}

/// The commanded positions' differences over the run's equally spaced cycles: the first over
/// `T`, the second over `T²`, the third over `T³` are weighted averages of the trajectory's
/// velocity, acceleration and jerk (B-spline kernels of unit weight), so each is within the
/// limit its trajectory keeps: `speed` × the Panda's velocity limits, acceleration = velocity
/// / 0.5 s, jerk = acceleration / 0.15 s (`MotionLimits`), plus the retiming's margin (1e-3)
/// and the CSV's rounding (1e-7 rad, 1 µs: `slack`). Returns the largest ratio of each.
// Joint `k` of four rows at once reads as the differences are written.
#[allow(clippy::needless_range_loop)]
fn check_commanded_limits(tel: &Telemetry, speed: f64) -> [f64; 3] {
    let model = rl::core::loader::load_file::<16>(&panda())
        .expect("panda")
        .model;
    let mut worst = [0.0f64; 3];
    let rows = tel.commanded.len();
    for i in 3..rows {
        let t = &tel.time_s[i - 3..=i];
        let dt = t[1] - t[0];
        let even = (1..4).all(|k| ((t[k] - t[k - 1]) - dt).abs() <= 3e-6);
        if !(tel.running[i - 3..=i].iter().all(|r| *r) && even && dt > 1e-3) {
            continue;
        }
        let q = &tel.commanded[i - 3..=i];
        for k in 0..7 {
            let v = speed * model.limits(k).velocity;
            let limit = [v, v / 0.5, v / 0.5 / 0.15];
            let d = [
                (q[3][k] - q[2][k]) / dt,
                (q[3][k] - 2.0 * q[2][k] + q[1][k]) / dt.powi(2),
                (q[3][k] - 3.0 * q[2][k] + 3.0 * q[1][k] - q[0][k]) / dt.powi(3),
            ];
            for order in 0..3 {
                // Rounding: 1e-7 rad per position (2^order terms' weights sum to 2^order),
                // and 1 µs in each time (relative 2e-6/dt per power of dt).
                let slack = 2f64.powi(order as i32) * 1e-7 / dt.powi(order as i32 + 1)
                    + d[order].abs() * (order as f64 + 1.0) * 2e-6 / dt;
                let ratio = (d[order].abs() - slack).max(0.0) / limit[order];
                assert!(
                    ratio <= 1.0 + 1e-3,
                    "row {i}, joint {k}: derivative {} is {} over the limit {}",
                    order + 1,
                    d[order],
                    limit[order]
                );
                worst[order] = worst[order].max(ratio);
            }
        }
    }
    worst
}

#[test]
fn run_plan_follows_the_path_to_the_goal_and_says_so() {
    let _run = one_run_at_a_time();
    let Some((stdout, tel)) = run_problem("box_panda", &["--no-retime"], false, "box.csv") else {
        return;
    };
    assert!(stdout.contains("result: ok"), "{stdout}");
    // The blends' own timing: not retimed.
    assert!(stdout.contains("blended through"), "{stdout}");
    assert!(!stdout.contains("retimed"), "{stdout}");
    assert!(
        stdout.contains("trajectory (plan): planned path by RRT Extend Connect (seed 0)"),
        "the report says where the trajectory came from:\n{stdout}"
    );
    assert!(stdout.contains("end: completed"), "{stdout}");
    assert!(stdout.contains("plan: solved by"), "{stdout}");
    assert!(
        stdout.contains("fake H7 saw 1 end packet, servo off"),
        "{stdout}"
    );
    let bound = tracking_bound(&stdout);
    assert_eq!(bound.len(), 7, "{stdout}");
    let tel_rows = telemetry(&tel, 7);
    check_motion("box_panda", &tel_rows, &bound);
    let worst = check_commanded_limits(&tel_rows, SPEED.parse().unwrap());
    println!("box_panda blended: velocity, acceleration, jerk at most {worst:?} of the limits");
    std::fs::remove_file(&tel).ok();
}

/// `rl run --plan` on `problem_name` at [`SPEED`] with telemetry to the temporary file
/// `name` (and `--json` when `json`), then `extra`; it must succeed. Its stdout and the
/// telemetry file.
fn run_problem(
    problem_name: &str,
    extra: &[&str],
    json: bool,
    name: &str,
) -> Option<(String, PathBuf)> {
    let (scene, request) = problem(problem_name);
    let tel = temp(name);
    let telemetry = tel.display().to_string();
    let mut args = vec!["--speed", SPEED, "--no-mlock", "--telemetry", &telemetry];
    if json {
        args.push("--json");
    }
    args.extend_from_slice(extra);
    // A run the machine made late (the report's likely cause names the loop or the fake) goes
    // again, at most three times (then SKIPPED: the caller gets no output to check).
    let report = |out: &std::process::Output| {
        if json {
            serde_json::from_slice(&out.stdout)
                .ok()
                .and_then(|r: serde_json::Value| late::json_late(&r))
        } else {
            late::text_late(&text(&out.stdout))
        }
    };
    let out = late::while_late(
        problem_name,
        || {
            rl(
                &run_plan_args(&scene, &request, &args),
                Duration::from_secs(120),
            )
        },
        report,
    )?;
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(
        out.status.success(),
        "exit {:?}\nstdout:\n{stdout}\nstderr:\n{stderr}",
        out.status
    );
    Some((stdout, tel))
}

/// The bound a run supervised: its text report's row, in mrad, in rad.
fn tracking_bound(stdout: &str) -> Vec<f64> {
    stdout
        .lines()
        .find(|l| l.trim_start().starts_with("tracking bound mrad"))
        .expect("tracking bound row")
        .split_whitespace()
        .skip(3)
        .map(|x| x.parse::<f64>().expect("number") * 1e-3)
        .collect()
}

/// `rl run --plan` (blended and retimed with bounded jerk by default; `--no-retime` in the test
/// above, `--stop-at-waypoints` in the next) on box_panda, whose optimised path has interior
/// waypoints: the run completes at the goal, every commanded position is free for the exact
/// meshes and within the velocity, acceleration and jerk limits, and the report (text and JSON)
/// says how the path was executed, with the three durations.
#[test]
fn run_plan_blends_through_the_waypoints_by_default_and_says_so() {
    let _run = one_run_at_a_time();
    let Some((stdout, tel)) = run_problem("box_panda", &[], true, "blended.csv") else {
        return;
    };
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON report");
    assert_eq!(v["end"], "completed", "{v}");
    assert_eq!(v["limit_violations"], 0, "{v}");
    let plan = &v["plan"];
    // box_panda's blended path, retimed, is faster (3.44 s against 3.57 s at 60 %).
    assert_eq!(plan["execution"], "retimed", "{v}");
    let blend = &plan["blend"];
    let interior = blend["interior_waypoints"].as_u64().expect("count");
    assert_eq!(
        interior + 2,
        plan["waypoints"].as_array().unwrap().len() as u64,
        "{v}"
    );
    assert!(interior > 0, "box_panda's path has interior waypoints: {v}");
    assert_eq!(
        blend["blended"].as_u64().unwrap() + blend["stopped"].as_u64().unwrap(),
        interior
    );
    assert!(blend["collision_checks"].as_u64().unwrap() > 100, "{v}");
    let (duration, stop) = (
        plan["trajectory_duration_s"].as_f64().unwrap(),
        plan["stop_at_waypoints_duration_s"].as_f64().unwrap(),
    );
    let blended = plan["blended_duration_s"].as_f64().unwrap();
    println!(
        "box_panda: retimed {duration:.3} s, blended {blended:.3} s, stopping at every waypoint \
         {stop:.3} s"
    );
    assert_eq!(plan["retimed_duration_s"].as_f64(), Some(duration), "{v}");
    assert!(duration < blended, "{v}");
    if blend["blended"].as_u64().unwrap() > 0 {
        assert!(blended < stop, "{v}");
    }
    let description = v["trajectory"].as_str().expect("trajectory description");
    assert!(description.contains("blended through"), "{description}");
    assert!(
        description.contains(&format!("retimed with bounded jerk to {duration:.2} s")),
        "{description}"
    );
    // Certified on the meshes by conservative advancement, not only at samples.
    assert!(
        description.contains("certified on the exact geometry"),
        "{description}"
    );
    assert!(plan["certified"]["steps"].as_u64().unwrap() > 0, "{v}");
    assert!(
        plan["certified"]["min_distance"].as_f64().unwrap() > 0.0,
        "{v}"
    );
    assert!(
        description.contains("stopping at every waypoint: "),
        "{description}"
    );
    assert!((v["trajectory_time_s"].as_f64().unwrap() - duration).abs() < 0.01);
    let bound: Vec<f64> = v["tracking_error_rad"]["bound_per_joint"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let tel_rows = telemetry(&tel, 7);
    check_motion("box_panda", &tel_rows, &bound);
    let worst = check_commanded_limits(&tel_rows, SPEED.parse().unwrap());
    println!("box_panda retimed: velocity, acceleration, jerk at most {worst:?} of the limits");
    std::fs::remove_file(&tel).ok();
}

#[test]
fn run_plan_stop_at_waypoints_stops_at_each_and_says_so() {
    let _run = one_run_at_a_time();
    // The flag describes a planned motion: refused without --plan, before anything starts.
    let out = rl(&["run", "--stop-at-waypoints"], Duration::from_secs(30));
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("--stop-at-waypoints describes a planned motion: add --plan"),
        "{}",
        text(&out.stderr)
    );
    let Some((stdout, tel)) =
        run_problem("box_panda", &["--stop-at-waypoints"], false, "stops.csv")
    else {
        return;
    };
    assert!(stdout.contains("result: ok"), "{stdout}");
    assert!(stdout.contains("end: completed"), "{stdout}");
    let line = stdout
        .lines()
        .find(|l| l.contains("trajectory (plan): planned path by"))
        .unwrap_or_else(|| panic!("no trajectory line:\n{stdout}"));
    assert!(line.contains("stopping at every waypoint"), "{line}");
    assert!(line.contains("certified on the exact geometry"), "{line}");
    assert!(!stdout.contains("blended through"), "{stdout}");
    let bound = tracking_bound(&stdout);
    let tel_rows = telemetry(&tel, 7);
    check_motion("box_panda", &tel_rows, &bound);
    let worst = check_commanded_limits(&tel_rows, SPEED.parse().unwrap());
    println!("box_panda stopping: velocity, acceleration, jerk at most {worst:?} of the limits");
    std::fs::remove_file(&tel).ok();
}

#[test]
fn run_plan_json_has_the_plan_and_ends_at_its_goal() {
    let _run = one_run_at_a_time();
    let (_, request) = problem("bookshelf_thin_panda");
    let Some((stdout, tel)) = run_problem(
        "bookshelf_thin_panda",
        &["--seed", "2", "--plan-time", "2s"],
        true,
        "bookshelf.csv",
    ) else {
        return;
    };
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON report");
    assert_eq!(v["failed"], false, "{v}");
    assert_eq!(v["trajectory_source"], "plan", "{v}");
    assert_eq!(v["end"], "completed", "{v}");
    assert_eq!(v["limit_violations"], 0, "{v}");
    assert_eq!(v["fake_servo_on"], false, "{v}");
    let plan = &v["plan"];
    assert_eq!(plan["solved"], true, "{v}");
    assert_eq!(plan["seed"], 2, "{v}");
    let robot = Robot::load_urdf(&panda(), None, None).expect("panda");
    let (start, goal) = start_and_goal(&robot, &request);
    let numbers = |x: &serde_json::Value| -> Vec<f64> {
        x.as_array()
            .expect("array")
            .iter()
            .map(|n| n.as_f64().expect("number"))
            .collect()
    };
    assert_eq!(numbers(&plan["start"]), start);
    assert_eq!(numbers(&plan["goal"]), goal);
    let waypoints = plan["waypoints"].as_array().expect("waypoints");
    assert!(waypoints.len() >= 2);
    assert_eq!(numbers(waypoints.last().unwrap()), goal);
    // The whole trajectory ran: its duration is the plan's, and the run's.
    let duration = plan["trajectory_duration_s"].as_f64().unwrap();
    assert!((v["plan_duration_s"].as_f64().unwrap() - duration).abs() < 1e-9);
    assert!((v["trajectory_time_s"].as_f64().unwrap() - duration).abs() < 0.01);
    let bound = numbers(&v["tracking_error_rad"]["bound_per_joint"]);
    check_motion("bookshelf_thin_panda", &telemetry(&tel, 7), &bound);
    std::fs::remove_file(&tel).ok();
}

/// A MoveIt scene of one box `id` at `position` with edge lengths `dimensions` (m), written
/// to the temporary file `name`.
fn one_box_scene(name: &str, id: &str, position: [f64; 3], dimensions: [f64; 3]) -> PathBuf {
    let scene = temp(name);
    let ([x, y, z], [a, b, c]) = (position, dimensions);
    std::fs::write(
        &scene,
        format!(
            "world:\n  collision_objects:\n    - id: {id}\n      primitive_poses:\n        \
             - position: [{x:?}, {y:?}, {z:?}]\n          orientation: [0, 0, 0, 1]\n      \
             primitives:\n        - type: box\n          dimensions: [{a:?}, {b:?}, {c:?}]\n"
        ),
    )
    .unwrap();
    scene
}

#[test]
fn a_start_in_collision_fails_before_anything_starts() {
    let _run = one_run_at_a_time();
    // A block around the Panda's base: the request's start (and every configuration) collides.
    let scene = one_box_scene("block.yaml", "block", [0.0, 0.0, 0.3], [0.4, 0.4, 0.4]);
    let (_, request) = problem("box_panda");
    let out = rl(
        &run_plan_args(&scene, &request, &[]),
        Duration::from_secs(60),
    );
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("the start configuration is invalid: in collision"),
        "{stderr}"
    );
    // What touches, by name (the exact meshes' verdict).
    assert!(
        stderr.contains("touching: ") && stderr.contains("panda_link0") && stderr.contains("block"),
        "{stderr}"
    );
    assert!(stderr.contains("nothing was started"), "{stderr}");
    // No report: no device was opened, let alone switched on.
    assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
    std::fs::remove_file(&scene).ok();
}

/// `out`, of `rl run --plan`, found no path: exit code 1, says so and that nothing was started,
/// and prints no report.
fn no_path_and_nothing_started(out: &Output) {
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("no collision-free path found") && stderr.contains("nothing was started"),
        "{stderr}"
    );
    assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
}

/// A request with no solution: every joint but the first pinned by `--limits` (the space is
/// one-dimensional), and a post in the way of the arm as joint 1 turns from 0 to 1.5 rad
/// (start and goal are free: the post stands between them).
fn unsolvable() -> (PathBuf, PathBuf, &'static str) {
    let scene = one_box_scene("post.yaml", "post", [0.22, 0.20, 0.45], [0.08, 0.08, 0.5]);
    let request = temp("turn.yaml");
    let mut text = String::from(
        "group_name: panda_arm\nstart_state:\n  joint_state:\n    name: [panda_joint1, \
         panda_joint2, panda_joint3, panda_joint4, panda_joint5, panda_joint6, panda_joint7]\n    \
         position: [0, -0.785, 0, -2.356, 0, 1.571, 0.785]\ngoal_constraints:\n  - joint_constraints:\n",
    );
    for (k, q) in [1.5, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
        .iter()
        .enumerate()
    {
        text += &format!(
            "      - joint_name: panda_joint{}\n        position: {q}\n",
            k + 1
        );
    }
    std::fs::write(&request, text).unwrap();
    let pinned = "panda_joint2=-0.785:-0.785,panda_joint3=0:0,panda_joint4=-2.356:-2.356,\
                  panda_joint5=0:0,panda_joint6=1.571:1.571,panda_joint7=0.785:0.785";
    (scene, request, pinned)
}

#[test]
fn an_unsolvable_request_fails_before_anything_starts() {
    let _run = one_run_at_a_time();
    let (scene, request, pinned) = unsolvable();
    let out = rl(
        &run_plan_args(
            &scene,
            &request,
            &["--limits", pinned, "--plan-time", "300ms"],
        ),
        Duration::from_secs(60),
    );
    no_path_and_nothing_started(&out);
    std::fs::remove_file(&scene).ok();
    std::fs::remove_file(&request).ok();
}

/// Ctrl-C while `rl run --plan` plans (a search that cannot succeed, with a two-minute budget)
/// ends the planning at once: exit code 130, nothing started, no report.
#[test]
fn ctrl_c_while_planning_stops_before_anything_starts() {
    let _run = one_run_at_a_time();
    let (scene, request, pinned) = unsolvable();
    let mut child = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(run_plan_args(
            &scene,
            &request,
            &["--limits", pinned, "--plan-time", "120s"],
        ))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn rl");
    let (rx, reader) = watch_stderr(&mut child, "planning a collision-free path");
    rx.recv_timeout(Duration::from_secs(60))
        .expect("the planning line within 60 s");
    std::thread::sleep(Duration::from_millis(300));
    let deadline = Instant::now() + Duration::from_secs(20);
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(child.id() as i32),
        nix::sys::signal::Signal::SIGINT,
    )
    .expect("SIGINT");
    let status = exit_by(&mut child, deadline).expect("rl went on planning for 20 s after SIGINT");
    let stderr = reader.join().expect("stderr");
    let mut stdout = String::new();
    std::io::Read::read_to_string(&mut child.stdout.take().expect("stdout"), &mut stdout)
        .expect("stdout");
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("stopped on request before the motion started"),
        "{stderr}"
    );
    assert!(stdout.is_empty(), "no run, no report: {stdout}");
    std::fs::remove_file(&scene).ok();
    std::fs::remove_file(&request).ok();
}

#[test]
fn no_path_within_the_budget_fails_before_anything_starts() {
    let _run = one_run_at_a_time();
    // The straight motion collides (the planner must search), and a microsecond is not enough.
    let (scene, request) = problem("box_panda");
    let out = rl(
        &run_plan_args(&scene, &request, &["--plan-time", "1us"]),
        Duration::from_secs(60),
    );
    no_path_and_nothing_started(&out);
}

#[test]
fn plan_flags_are_checked_before_anything_starts() {
    let _run = one_run_at_a_time();
    let (scene, request) = problem("box_panda");
    let (s, r) = (scene.to_str().unwrap(), request.to_str().unwrap());
    let strings = |args: &[&str]| args.iter().map(OsString::from).collect::<Vec<_>>();
    for (args, says) in [
        (
            strings(&["run", "--scene", s]),
            "--scene describes a planned motion: add --plan",
        ),
        (
            strings(&["run", "--plan", "--scene", s]),
            "--plan needs --scene",
        ),
        (
            strings(&["run", "--plan", "--scene", s, "--request", r]),
            "--plan needs --model",
        ),
        (
            run_plan_args(&scene, &request, &["--planner", "astar"]),
            "unknown planner \"astar\"",
        ),
    ] {
        let out = rl(&args, Duration::from_secs(30));
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    }
}

/// Library: box_panda's request planned as `rl run --plan` plans it (the hybrid checker, default
/// options, half the speed limits), stopped by `stop`; with the request's start and the model
/// as the controller loads it.
fn plan_box(
    stop: Option<&StopFlag>,
) -> (
    Result<PlannedMotion<8>, PlannedMotionError>,
    Vec<f64>,
    LoadedModel<16>,
) {
    let robot = Robot::load_urdf(&panda(), None, None).expect("panda");
    let (scene, request) = problem("box_panda");
    let (start, goal) = start_and_goal(&robot, &request);
    let env = rl::sg::load::moveit::load_environment(&scene).expect("scene");
    let mut checker = robot.hybrid_checker(&env).expect("checker");
    let loaded = rl::core::loader::load_file::<16>(panda()).expect("model");
    let planned = plan_motion::<16, 8>(
        &loaded.model,
        &robot.space,
        &mut checker,
        &start,
        &goal,
        &PlanOptions::default(),
        0.5,
        stop,
    );
    (planned, start, loaded)
}

/// Library: a robot that does not stand at the trajectory's start is refused before the device
/// is started (the check `rl run --plan` makes for a real robot).
#[test]
fn a_robot_away_from_the_start_is_refused_before_servo_on() {
    let _run = one_run_at_a_time();
    let (planned, start, loaded) = plan_box(None);
    let planned = planned.expect("planned");
    assert!(planned.result.solved);
    assert_eq!(planned.waypoints.first().unwrap(), &start);
    // The fake stands 0.2 rad away from the start on joint 1.
    let mut away = start.clone();
    away[0] += 0.2;
    let fake = FakeH7::spawn(FakeH7Config {
        on_thread_start: Some(rl::devices::fake_thread_realtime),
        ..FakeH7Config::for_model(&loaded.model, &away).expect("config")
    })
    .expect("fake");
    let h7 =
        MitsubishiH7::new(MitsubishiH7Config::at(fake.udp_addr(), fake.r3_addr())).expect("device");
    let options = RunOptions {
        lock_memory: false,
        priority: 50,
        ..RunOptions::default()
    };
    let e = ControlRun::<_, 16, 8>::start_with(h7, loaded, options, planned.motion)
        .err()
        .expect("refused");
    match &e {
        RunError::NotAtStart {
            joint,
            start: s,
            measured,
            ..
        } => {
            assert_eq!(joint, "panda_joint1");
            assert!((s - start[0]).abs() < 1e-12);
            // The H7 carries positions at about 1.5e-5 rad.
            assert!((measured - away[0]).abs() < 1e-4, "{e}");
        }
        e => panic!("expected NotAtStart, got {e}"),
    }
    assert!(e.to_string().contains("where the trajectory starts"), "{e}");
    let status = fake.status();
    assert!(!status.servo_on, "the servo went on");
    assert_eq!(status.moves, 0, "the fake was sent motion");
}

/// Library: a raised stop flag cancels planning (Ctrl-C while `rl run --plan` plans).
#[test]
fn a_stop_request_cancels_planning() {
    let _run = one_run_at_a_time();
    let stop = StopFlag::new();
    stop.request_stop();
    let e = plan_box(Some(&stop)).0.expect_err("cancelled");
    assert_eq!(e, PlannedMotionError::Cancelled);
}

/// `--limits` overrides the model's joint limits for planning, in `rl plan` and `rl run --plan`:
/// the path stays within them, a goal outside them is refused, and an unknown joint is named.
#[test]
fn joint_limit_overrides_bound_the_path_and_name_unknown_joints() {
    let _run = one_run_at_a_time();
    let (scene, request) = problem("box_panda");
    let path = temp("limited-path.csv");
    // The request goes from panda_joint1 = 0 to 0.4534; the override keeps joint 1 within
    // [-0.1, 0.6] and joint 3 within [-0.3, 0.3] (the model allows ±2.9671 for both).
    let limits = "panda_joint1=-0.1:0.6,panda_joint3=-0.3:0.3";
    let out = rl(
        &plan_args(
            &scene,
            &request,
            &["--limits", limits, "--out", path.to_str().unwrap()],
        ),
        Duration::from_secs(60),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["solved"], true, "{v}");
    let csv = std::fs::read_to_string(&path).expect("path written");
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() >= 2);
    for row in &rows {
        assert!((-0.1..=0.6).contains(&row[0]), "{row:?}");
        assert!((-0.3..=0.3).contains(&row[2]), "{row:?}");
    }
    std::fs::remove_file(&path).ok();

    // A goal outside the override is refused, naming the joint.
    let out = rl(
        &plan_args(&scene, &request, &["--limits", "panda_joint1=-0.1:0.4"]),
        Duration::from_secs(60),
    );
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("goal configuration is invalid") && stderr.contains("panda_joint1"),
        "{stderr}"
    );

    // Unknown joints and malformed entries are usage errors, in both commands, before
    // anything starts.
    let unknown = ["--limits", "panda_joint9=0:1"];
    for args in [
        plan_args(&scene, &request, &unknown),
        run_plan_args(&scene, &request, &unknown),
    ] {
        let out = rl(&args, Duration::from_secs(60));
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("--limits: unknown joint \"panda_joint9\"")
                && stderr.contains("panda_joint7"),
            "{args:?}: {stderr}"
        );
        assert!(out.stdout.is_empty(), "{args:?}: nothing ran");
    }
    let out = rl(
        &run_plan_args(&scene, &request, &["--limits", "panda_joint1=1:0"]),
        Duration::from_secs(60),
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("MIN is above MAX"));
}
