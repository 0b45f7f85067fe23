//! The controller refuses what would hurt the robot, and every fault ends the run safely: the
//! library's `ControlRun` against a simulated robot that misbehaves on purpose (frozen, NaN or
//! jumping replies, a blocked joint, a clamped command, lost replies, a dropped connection),
//! and the checks made before the device is switched on (joint counts, the start pose, plans
//! too long or too coarse for the device, a stop request while planning).

mod common;
mod late;

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use common::sim::{Misbehaviour, SimRobot, SimStatus};
use rl::controller::supervise::FeedbackFault;
use rl::controller::{
    ControlRun, Fault, PlanError, RunEnd, RunError, RunOptions, RunReport, rv6sl,
};
use rl::core::loader::{self, LoadedModel, UrdfOptions};
use rl::drivers::State;
use rl::rt::{StopFlag, StopLevel};

const PERIOD: Duration = Duration::from_millis(2);

fn model() -> LoadedModel<16> {
    rv6sl().expect("embedded model")
}

fn limits(m: &LoadedModel<16>) -> (Vec<f64>, Vec<f64>) {
    let dof = m.model.dof();
    (
        (0..dof).map(|k| m.model.limits(k).lower).collect(),
        (0..dof).map(|k| m.model.limits(k).upper).collect(),
    )
}

/// A simulated RV-6SL standing at `start`, two cycles of lag.
fn robot(start: &[f64]) -> SimRobot {
    let (lower, upper) = limits(&model());
    SimRobot::new(start, &lower, &upper, PERIOD, 2)
}

fn options() -> RunOptions {
    RunOptions {
        speed: 0.5,
        lock_memory: false,
        priority: 50,
        ..RunOptions::default()
    }
}

/// Runs the robot `make` builds to the end (bounded): the report and what the robot saw.
/// Run again, from a new robot, while the run failed from the machine's lateness (the host
/// held the loop's CPU for milliseconds on a shared VM: [`late::failed_late`]); `None` after
/// three such runs (SKIPPED, printed). A run that failed with nobody late is returned to its
/// checks; the faults these runs expect are not timing failures (the tests that expect one
/// use [`run_once`]), so nothing is loosened.
fn run(
    what: &str,
    make: impl Fn() -> SimRobot,
    options: RunOptions,
) -> Option<(RunReport, Arc<Mutex<SimStatus>>)> {
    on_time(what, || run_once(make(), options.clone()))
}

/// Runs `robot` to the end (bounded), once: the report and what the robot saw. For the tests
/// that expect a timing fault (lost replies): a late machine cannot make one pass.
fn run_once(robot: SimRobot, options: RunOptions) -> (RunReport, Arc<Mutex<SimStatus>>) {
    let status = robot.status();
    let mut run = ControlRun::<_, 16, 8>::start(robot, model(), options).expect("starts");
    let deadline = Instant::now() + Duration::from_secs(60);
    while run.poll(Duration::from_millis(20)).is_some() {
        assert!(Instant::now() < deadline, "the run did not end within 60 s");
    }
    (run.join(), status)
}

/// `attempt` (a whole run) again while it failed from the machine's lateness; see [`run`].
fn on_time<T>(what: &str, attempt: impl FnMut() -> (RunReport, T)) -> Option<(RunReport, T)> {
    late::while_late(what, attempt, |(report, _)| late::failed_late(report))
}

fn fault(report: &RunReport) -> Fault {
    match report.end {
        Some(RunEnd::Fault(f)) => f,
        other => panic!("expected a fault, the run ended {other:?}\n{report}"),
    }
}

#[test]
fn a_clean_run_completes_and_switches_the_robot_off() {
    let Some((report, status)) = run(
        "a clean run",
        || robot(&[0.0; 6]),
        options().duration(Duration::from_secs(1)),
    ) else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::CycleLimit), "{report}");
    assert_eq!(report.exit_code(), 0, "{report}");
    assert!(report.shutdown.stopped);
    let st = status.lock().expect("status");
    assert_eq!(st.stopped_from, Some(State::Running));
    assert!(!st.powered);
    assert!(st.steps > 400, "{} steps", st.steps);
}

#[test]
fn a_model_with_another_joint_count_is_refused_before_anything_moves() {
    let (lower, upper) = limits(&model());
    let mut lo7 = lower.clone();
    let mut up7 = upper.clone();
    lo7.push(-1.0);
    up7.push(1.0);
    let sim = SimRobot::new(&[0.0; 7], &lo7, &up7, PERIOD, 2);
    let status = sim.status();
    let e = match ControlRun::<_, 16, 8>::start(sim, model(), options()) {
        Err(e) => e,
        Ok(_) => panic!("a 6-joint model on a 7-axis robot must be refused"),
    };
    assert!(
        matches!(
            e,
            RunError::Plan(PlanError::DeviceJoints {
                model: 6,
                device: 7
            })
        ),
        "{e:?}"
    );
    let text = e.to_string();
    assert!(
        text.contains("6 joints") && text.contains("7 axes"),
        "{text}"
    );
    let st = status.lock().expect("status");
    assert_eq!((st.steps, st.powered), (0, false), "nothing moved");
}

#[test]
fn the_start_pose_tolerates_the_device_resolution_and_nothing_more() {
    let (_, upper) = limits(&model());
    let mut start = [0.0; 6];
    start[1] = upper[1] + 0.5e-7;
    let on_time = run(
        "a start within the resolution",
        || robot(&start).resolution(1e-7),
        options().duration(Duration::from_millis(200)),
    );
    if let Some((report, _)) = on_time {
        assert_eq!(report.exit_code(), 0, "{report}");
    }

    start[1] = upper[1] + 2e-7;
    let sim = robot(&start).resolution(1e-7);
    let status = sim.status();
    let e = ControlRun::<_, 16, 8>::start(sim, model(), options())
        .err()
        .expect("refused");
    assert!(
        matches!(&e, RunError::Plan(PlanError::OutsideLimits { what, .. }) if what == "start"),
        "{e:?}"
    );
    assert!(!status.lock().expect("status").powered);
}

#[test]
fn a_blocked_joint_is_a_tracking_fault_that_brings_the_arm_to_rest() {
    let Some((report, status)) = run(
        "a blocked joint",
        || robot(&[0.0; 6]).misbehave(Misbehaviour::Block(1), 40),
        options(),
    ) else {
        return;
    };
    let f = fault(&report);
    assert!(matches!(f, Fault::TrackingError { joint: 1, .. }), "{f:?}");
    assert!(!f.stops_at_once());
    assert_eq!(report.exit_code(), 1);
    assert!(
        report
            .failure
            .as_deref()
            .is_some_and(|w| w.contains("joint1")),
        "{report}"
    );
    let st = status.lock().expect("status");
    assert_eq!(st.stopped_from, Some(State::Running));
    assert!(!st.powered);
    // The plan ran at half speed; coming to rest never steps beyond the speed limit.
    let m = model();
    for k in 0..6 {
        let bound = m.model.limits(k).velocity * PERIOD.as_secs_f64();
        assert!(st.largest_step[k] <= bound * (1.0 + 1e-6), "joint {k}");
    }
    // It ended well before the plan did.
    assert!(
        report.trajectory_time_s < report.plan_duration_s / 2.0,
        "{report}"
    );
}

#[test]
fn a_frozen_reply_is_a_fault() {
    let Some((report, _)) = run(
        "a frozen reply",
        || robot(&[0.0; 6]).misbehave(Misbehaviour::Freeze, 60),
        options(),
    ) else {
        return;
    };
    assert!(
        matches!(fault(&report), Fault::Frozen { cycles: 10 }),
        "{report}"
    );
    // Caught ten replies after the freeze (at 0.12 s), then brought to rest (at most 2 s).
    assert!(report.trajectory_time_s < 2.2, "{report}");
    assert_eq!(report.exit_code(), 1);
}

#[test]
fn not_a_number_and_impossible_jumps_are_faults() {
    let not_a_number = run(
        "not a number",
        || robot(&[0.0; 6]).misbehave(Misbehaviour::NotANumber, 30),
        options(),
    );
    let jump = run(
        "an impossible jump",
        || robot(&[0.0; 6]).misbehave(Misbehaviour::Jump(0.5), 30),
        options(),
    );
    if let Some((report, _)) = not_a_number {
        assert!(
            matches!(
                fault(&report),
                Fault::Feedback {
                    joint: 0,
                    fault: FeedbackFault::NotFinite,
                    ..
                }
            ),
            "{report}"
        );
    }
    if let Some((report, _)) = jump {
        assert!(
            matches!(
                fault(&report),
                Fault::Feedback {
                    joint: 0,
                    fault: FeedbackFault::Jump { .. },
                    ..
                }
            ),
            "{report}"
        );
    }
}

#[test]
fn a_limit_the_device_reports_is_a_fault() {
    let m = model();
    let (lower, mut upper) = limits(&m);
    // The robot's own limit for joint 0 is tighter than the model's: it clamps there.
    upper[0] = 0.2;
    let mut waypoint = vec![0.0; 6];
    waypoint[0] = 0.5;
    let Some((report, _)) = run(
        "a limit the device reports",
        || SimRobot::new(&[0.0; 6], &lower, &upper, PERIOD, 2),
        RunOptions {
            waypoints: Some(vec![waypoint]),
            ..options()
        },
    ) else {
        return;
    };
    assert!(
        matches!(fault(&report), Fault::DeviceLimit { joint: 0 }),
        "{report}"
    );
}

#[test]
fn a_lost_connection_stops_at_once_and_still_switches_off() {
    let Some((report, status)) = run(
        "a lost connection",
        || robot(&[0.0; 6]).misbehave(Misbehaviour::Disconnect, 50),
        options(),
    ) else {
        return;
    };
    let f = fault(&report);
    assert!(matches!(f, Fault::LinkLost { .. }), "{f:?}");
    assert!(f.stops_at_once());
    let st = status.lock().expect("status");
    // The device faulted on the lost connection; stop still ran, from the faulted state.
    assert_eq!(st.stopped_from, Some(State::Faulted));
    assert!(!st.powered);
    assert!(report.shutdown.fault_before_stop.is_some(), "{report}");
}

#[test]
fn a_silent_peer_ends_the_run_after_a_few_cycles() {
    let (report, status) = run_once(
        robot(&[0.0; 6]).misbehave(Misbehaviour::Silent, 50),
        options(),
    );
    // Three lost: a short loss, the arm brought to rest; ten: a dead link, stopped at once.
    let f = fault(&report);
    assert!(
        matches!(
            f,
            Fault::ConsecutiveLost {
                count: 10,
                bound: 10
            } | Fault::LinkLost { .. }
        ),
        "{report}"
    );
    assert!(f.stops_at_once());
    let st = status.lock().expect("status");
    assert!(st.steps < 60, "ended after {} steps", st.steps);
    assert!(!st.powered);
}

#[test]
fn a_lossy_link_ends_the_run_with_the_loss_rate() {
    // Every other reply lost: 50 % over the 100-cycle window.
    let (report, _) = run_once(
        robot(&[0.0; 6]).misbehave(Misbehaviour::LoseEvery(2), 20),
        options(),
    );
    let f = fault(&report);
    assert!(matches!(f, Fault::LossRate { .. }), "{f:?}");
    assert!(!f.stops_at_once());
    assert!(report.wall_time_s < 5.0, "{report}");
}

#[test]
fn stop_requests_come_to_rest_then_stop_at_once() {
    // `now`: the second request (stop at once); otherwise the first (come to rest).
    let stopped = |now: bool| {
        let stop = StopFlag::new();
        let mut run =
            ControlRun::<_, 16, 8>::start(robot(&[0.0; 6]), model(), options().stop_flag(&stop))
                .expect("starts");
        std::thread::sleep(Duration::from_millis(300));
        if now {
            stop.request(StopLevel::Now);
        } else {
            stop.request_stop();
        }
        while run.poll(Duration::from_millis(20)).is_some() {}
        (run.join(), ())
    };
    if let Some((report, ())) = on_time("a stop request", || stopped(false)) {
        assert_eq!(report.end, Some(RunEnd::Stopped), "{report}");
        assert_eq!(report.exit_code(), 130);
    }
    if let Some((report, ())) = on_time("a stop-now request", || stopped(true)) {
        assert_eq!(report.end, Some(RunEnd::Aborted), "{report}");
    }
}

#[test]
fn a_stop_request_while_planning_cancels_before_the_device_starts() {
    let stop = StopFlag::new();
    stop.request_stop();
    let sim = robot(&[0.0; 6]);
    let status = sim.status();
    let e = ControlRun::<_, 16, 8>::start(sim, model(), options().stop_flag(&stop))
        .err()
        .expect("cancelled");
    assert!(matches!(e, RunError::Cancelled), "{e:?}");
    assert_eq!(e.exit_code(), 130);
    assert!(!status.lock().expect("status").powered);
}

/// A two-joint URDF with the given speed limit.
fn planar(speed: &str) -> LoadedModel<16> {
    let urdf = format!(
        r#"<robot name="slow">
  <link name="base"/>
  <link name="a"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><origin xyz="0.5 0 0"/><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="100" velocity="{speed}"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="100" velocity="{speed}"/></joint>
</robot>"#
    );
    loader::load_str(&urdf, &UrdfOptions::default()).expect("planar model")
}

#[test]
fn a_tiny_speed_limit_is_refused_quickly_before_the_device_starts() {
    let loaded = planar("1e-300");
    let sim = SimRobot::new(&[0.0; 2], &[-1.0; 2], &[1.0; 2], PERIOD, 2);
    let status = sim.status();
    let started = Instant::now();
    let e = ControlRun::<_, 16, 8>::start(sim, loaded, options())
        .err()
        .expect("refused");
    assert!(
        started.elapsed() < Duration::from_secs(5),
        "{:?}",
        started.elapsed()
    );
    assert!(
        matches!(e, RunError::Plan(PlanError::TooLong { .. })),
        "{e:?}"
    );
    assert!(e.to_string().contains("j1"), "{e}");
    assert!(!status.lock().expect("status").powered);
}

#[test]
fn a_control_period_too_coarse_for_the_device_is_refused() {
    let sim = robot(&[0.0; 6]);
    let status = sim.status();
    let e = ControlRun::<_, 16, 8>::start(
        sim,
        model(),
        RunOptions {
            period: Some(Duration::from_millis(500)),
            ..options()
        },
    )
    .err()
    .expect("refused");
    assert!(
        matches!(e, RunError::Plan(PlanError::StepTooLarge { .. })),
        "{e:?}"
    );
    assert!(!status.lock().expect("status").powered);
    let e = ControlRun::<_, 16, 8>::start(
        robot(&[0.0; 6]),
        model(),
        RunOptions {
            period: Some(Duration::from_micros(500)),
            ..options()
        },
    )
    .err()
    .expect("refused");
    assert!(matches!(e, RunError::Options(_)), "{e:?}");
}

#[test]
fn a_model_without_speed_limits_says_which_speed_it_assumes() {
    let loaded = planar("0");
    let sim = SimRobot::new(&[0.0; 2], &[-1.0; 2], &[1.0; 2], PERIOD, 2);
    let mut run =
        ControlRun::<_, 16, 8>::start(sim, loaded, options().duration(Duration::from_millis(200)))
            .expect("starts");
    while run.poll(Duration::from_millis(20)).is_some() {}
    let report = run.join();
    let (speed, joints) = report
        .assumed_speed
        .clone()
        .expect("assumed speed reported");
    assert_eq!(joints, ["j1", "j2"]);
    assert!(speed > 0.0);
    let text = report.to_string();
    assert_eq!(text.matches("assumed").count(), 1, "{text}");
    let json = report.to_json();
    assert_eq!(json["assumed_speed"]["joints"][1], "j2");
}

/// RL's mekabot (torso and two arms: 17 joints) does not fit the default 16 bodies and 8
/// joints; with a capacity the user chooses, the same runtime drives it.
#[test]
fn a_capacity_the_user_chooses_runs_rls_mekabot() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/rlmdl/mekabot-torso-rightarm-leftarm.xml"
    );
    let fits_default = loader::load_file_with::<16>(path, &UrdfOptions::default())
        .is_ok_and(|m| m.model.dof() <= 8);
    assert!(!fits_default, "the mekabot outgrows 16 bodies and 8 joints");
    let loaded = loader::load_file_with::<64>(path, &UrdfOptions::default()).expect("mekabot");
    let dof = loaded.model.dof();
    assert_eq!(dof, 17);
    let lower: Vec<f64> = (0..dof).map(|k| loaded.model.limits(k).lower).collect();
    let upper: Vec<f64> = (0..dof).map(|k| loaded.model.limits(k).upper).collect();
    let Some((report, status)) = on_time("the mekabot", || {
        let sim = SimRobot::new(&loaded.home_or_neutral(), &lower, &upper, PERIOD, 2);
        let status = sim.status();
        let options = options().duration(Duration::from_secs(1));
        let mut run = ControlRun::<_, 64, 32>::start(sim, loaded.clone(), options).expect("starts");
        let deadline = Instant::now() + Duration::from_secs(60);
        while run.poll(Duration::from_millis(20)).is_some() {
            assert!(Instant::now() < deadline, "the run did not end within 60 s");
        }
        (run.join(), status)
    }) else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::CycleLimit), "{report}");
    assert_eq!(report.exit_code(), 0, "{report}");
    assert_eq!(report.joints.len(), 17);
    let st = status.lock().expect("status");
    assert!(st.steps > 400, "{} steps", st.steps);
    assert!(!st.powered);
}
