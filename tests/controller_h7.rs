//! The library's controller runtime on the Mitsubishi H7 driver against the fake controller on
//! its own 7.11 ms cycle, made to misbehave: the cases issue 12 found ending `result: ok` —
//! a model of another joint count, a joint the controller clamps, frozen replies, a frozen
//! controller, half the replies lost, a refused stop, a flood of foreign datagrams — now each
//! ends the run with a typed reason and the arm switched off.

use std::time::{Duration, Instant};

mod late;

use rl::controller::lateness::Culprit;
use rl::controller::{
    ControlRun, CycleRecord, Fault, PlanError, RunEnd, RunError, RunOptions, RunReport,
    Supervision, rv6sl,
};
use rl::core::loader::{self, LoadedModel};
use rl::drivers::fake::h7_controller::{FakeH7, FakeH7Config};
use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};

fn options() -> RunOptions {
    RunOptions {
        speed: 0.5,
        lock_memory: false,
        priority: 50,
        ..RunOptions::default()
    }
}

/// The fake for `loaded` (its limits and speeds, standing at home) with `tweak` applied.
fn fake(loaded: &LoadedModel<16>, tweak: impl FnOnce(&mut FakeH7Config)) -> FakeH7 {
    let mut config =
        FakeH7Config::for_model(&loaded.model, &loaded.home_or_neutral()).expect("fake config");
    // A real controller's cycle runs on its own CPU: the fake's, at a real-time priority above
    // the loop's, so the other test running beside this one does not shift its phase.
    config.on_thread_start = Some(rl::devices::fake_thread_realtime);
    tweak(&mut config);
    FakeH7::spawn(config).expect("fake H7")
}

fn h7(fake: &FakeH7) -> MitsubishiH7 {
    MitsubishiH7::new(MitsubishiH7Config::at(fake.udp_addr(), fake.r3_addr())).expect("device")
}

/// Runs to the end (bounded), calling `during` once after `after` of running.
fn run_with(
    loaded: LoadedModel<16>,
    fake: &FakeH7,
    options: RunOptions,
    after: Duration,
    during: impl FnOnce(&FakeH7),
) -> RunReport {
    let mut run = ControlRun::<_, 16, 8>::start(h7(fake), loaded, options).expect("starts");
    let started = Instant::now();
    let mut during = Some(during);
    while run.poll(Duration::from_millis(10)).is_some() {
        if started.elapsed() >= after {
            if let Some(f) = during.take() {
                f(fake);
            }
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "the run did not end"
        );
    }
    run.join()
}

fn fault(report: &RunReport) -> Fault {
    match report.end {
        Some(RunEnd::Fault(f)) => f,
        other => panic!("expected a fault, the run ended {other:?}\n{report}"),
    }
}

/// The servo went off, the program stopped, and (unless the controller was frozen when it
/// came, which drops it) the session ended with an end packet.
fn assert_switched_off(fake: &FakeH7, report: &RunReport, end_packet: bool) {
    let deadline = Instant::now() + Duration::from_secs(2);
    while end_packet && fake.status().ends == 0 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(5));
    }
    let s = fake.status();
    assert!(!s.servo_on, "servo still on\n{report}");
    assert!(!s.program_running, "program still running\n{report}");
    if end_packet {
        assert_eq!(s.ends, 1, "end packets\n{report}");
    }
}

fn rlmdl(name: &str) -> LoadedModel<16> {
    loader::load_file(format!(
        "{}/tests/data/rlmdl/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("RL model")
}

/// Runs `run` while it failed from the machine's lateness ([`late::failed_late`]: on a shared
/// VM the host holds a CPU for milliseconds); see [`late::while_late`]. A timing failure with
/// nobody late is returned to be checked, and fails its checks.
fn on_time(what: &str, run: impl Fn() -> (RunReport, FakeH7)) -> Option<(RunReport, FakeH7)> {
    late::while_late(what, run, |(report, _)| late::failed_late(report))
}

#[test]
fn a_clean_run_on_the_controller_cycle_ends_at_rest_with_the_servo_off() {
    let Some((report, fake)) = on_time("a clean run", || {
        let model = rv6sl().expect("model");
        let fake = fake(&model, |_| {});
        let report = run_with(
            model,
            &fake,
            options().duration(Duration::from_secs(2)),
            Duration::MAX,
            |_| {},
        );
        (report, fake)
    }) else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::CycleLimit), "{report}");
    assert_eq!(report.exit_code(), 0, "{report}");
    // The arm lags its command by the servo's two cycles: a tracking error, within the bound.
    assert!(report.tracking_error_max > 1e-4, "{report}");
    assert_switched_off(&fake, &report, true);
}

#[test]
fn models_of_another_joint_count_are_refused_before_the_servo_goes_on() {
    // A 6-axis controller; RL's 2-joint planar arm and 7-joint iiwa.
    let six = rv6sl().expect("model");
    for (name, joints) in [("planar2.xml", 2), ("kuka-lbr-iiwa-7-r800.xml", 7)] {
        let fake = fake(&six, |c| c.initial_rad[2] = 1.2);
        let e = ControlRun::<_, 16, 8>::start(h7(&fake), rlmdl(name), options())
            .err()
            .expect("refused");
        assert!(
            matches!(e, RunError::Plan(PlanError::DeviceJoints { model, device: 6 }) if model == joints),
            "{name}: {e:?}"
        );
        let s = fake.status();
        assert!(!s.servo_on && s.moves == 0, "{name}: nothing may move");
        assert!(
            !s.r3_log.iter().any(|c| c == "SRVON"),
            "{name}: {:?}",
            s.r3_log
        );
    }
}

#[test]
fn a_joint_the_controller_clamps_ends_the_run() {
    let model = rv6sl().expect("model");
    // The controller's own limit of joint 0 is tighter than the model's.
    let fake = fake(&model, |c| c.upper_rad[0] = 0.1);
    let mut w = vec![0.0; 6];
    w[0] = 0.6;
    let report = run_with(
        model,
        &fake,
        RunOptions {
            waypoints: Some(vec![w]),
            ..options()
        },
        Duration::MAX,
        |_| {},
    );
    let f = fault(&report);
    assert!(
        matches!(
            f,
            Fault::DeviceLimit { joint: 0 } | Fault::TrackingError { joint: 0, .. }
        ),
        "{f:?}"
    );
    assert!(fake.status().limit_hits >= 1);
    assert_eq!(report.exit_code(), 1);
    // The JSON's `end` names the joint as the model does (not `#0`).
    let json = report.to_json();
    let end = json["end"].as_str().expect("an end");
    assert!(end.contains("joint joint0 "), "{end}");
    assert_eq!(json["fault_joint"], "joint0", "{json}");
    assert_switched_off(&fake, &report, true);
}

#[test]
fn frozen_replies_end_the_run() {
    let model = rv6sl().expect("model");
    let fake = fake(&model, |_| {});
    let report = run_with(model, &fake, options(), Duration::from_millis(500), |f| {
        f.set_fault(Some(rl::drivers::fake::h7_controller::FaultPlan {
            every: 1,
            fault: rl::drivers::fake::h7_controller::Fault::Replay,
        }))
    });
    let f = fault(&report);
    assert!(f.stops_at_once(), "{f:?}");
    assert!(report.link.corrupt >= 3, "{report}");
    assert!(report.wall_time_s < 3.0, "{report}");
    fake.set_fault(None);
    assert_switched_off(&fake, &report, true);
}

#[test]
fn a_frozen_controller_ends_the_run_and_is_still_switched_off() {
    let model = rv6sl().expect("model");
    let fake = fake(&model, |_| {});
    let report = run_with(model, &fake, options(), Duration::from_millis(500), |f| {
        f.freeze_for(Duration::from_millis(600))
    });
    // A freeze of 84 cycles: a short loss first (brought to rest), then a dead link that
    // stops the run at once.
    let f = fault(&report);
    assert!(
        matches!(f, Fault::ConsecutiveLost { .. } | Fault::LinkLost { .. }),
        "{report}"
    );
    assert!(f.stops_at_once(), "{report}");
    // The stop waited out the freeze (its R3 requests are answered after the thaw): program
    // stopped, servo off; the end packet came while frozen and was dropped, as a hung
    // controller would.
    assert!(report.shutdown.stopped, "{report}");
    assert_switched_off(&fake, &report, false);
}

/// A fake H7 held up for seven of its cycles (as other real-time work on the machine would
/// starve it) loses the loop's replies; the report says the fake was late, not the link: the
/// likely cause names it, from its own lateness against its cycle.
#[test]
fn a_starved_fake_is_named_as_the_likely_cause_of_lost_replies() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    const HELD: Duration = Duration::from_millis(50);
    let model = rv6sl().expect("model");
    let (body, placement) = (model.model.body_count() - 1, Default::default());
    let fk = rl::drivers::fake::h7_controller::ForwardKinematics::from_model(
        model.model.clone(),
        body,
        placement,
    );
    // The loop itself held up as long by the machine (a VM's host holds real-time threads for
    // milliseconds) makes the cause "both": such a run goes again, at most three times.
    let Some(report) = late::while_late(
        "the starved fake",
        || {
            let starve = Arc::new(AtomicBool::new(false));
            let held = starve.clone();
            let fk = fk.clone();
            let fake = fake(&model, |c| {
                // The pose feedback the driver asks for goes through here, in the fake's cycle.
                c.kinematics = Some(rl::drivers::fake::h7_controller::ForwardKinematics::new(
                    move |q| {
                        if held.swap(false, Ordering::Relaxed) {
                            std::thread::sleep(HELD);
                        }
                        fk.pose(q)
                    },
                ));
            });
            let mut report = run_with(
                model.clone(),
                &fake,
                options(),
                Duration::from_millis(300),
                |_| starve.store(true, Ordering::Relaxed),
            );
            // What `rl run` does with its in-process fake after the run.
            let fake = rl::devices::InProcessFake::H7(fake);
            let seen = fake.after_run(report.shutdown.stopped);
            report.peer_lateness = seen.lateness;
            report
        },
        |report| {
            matches!(
                report.lateness().culprit(),
                Culprit::Loop | Culprit::LoopAndPeer
            )
            .then(|| report.lateness().summary())
        },
    ) else {
        return;
    };
    // Replies lost in a row: a short loss, a dead link, or the device's own bound on failed
    // steps (a timeout), whichever a loaded machine reaches first.
    assert!(
        matches!(
            fault(&report),
            Fault::LinkInterrupted { .. } | Fault::ConsecutiveLost { .. } | Fault::LinkLost { .. }
        ),
        "{report}"
    );
    let peer = report.peer_lateness.as_ref().expect("set above");
    assert!(peer.max >= HELD, "{peer:?}");
    assert!(peer.late.is_some_and(|n| n >= 1), "{peer:?}");
    let cause = report
        .likely_cause()
        .expect("a timing failure has a likely cause");
    assert!(
        cause.starts_with("the fake H7 ran up to"),
        "{cause}\n{report}"
    );
    let text = report.to_string();
    assert!(text.contains(&format!("likely cause: {cause}")), "{text}");
    assert!(text.contains("lateness: loop woke up to"), "{text}");
    assert_eq!(report.to_json()["lateness"]["culprit"], "peer", "{text}");
    println!("{text}");
}

#[test]
fn half_the_replies_lost_ends_the_run_early() {
    let model = rv6sl().expect("model");
    let fake = fake(&model, |_| {});
    let report = run_with(model, &fake, options(), Duration::from_millis(300), |f| {
        f.set_drop_fraction(0.5)
    });
    assert!(matches!(fault(&report), Fault::LossRate { .. }), "{report}");
    assert!(report.wall_time_s < report.plan_duration_s, "{report}");
    fake.set_drop_fraction(0.0);
    assert_switched_off(&fake, &report, true);
}

#[test]
fn a_refused_stop_fails_the_run_and_says_why() {
    // The rejection comes after the start (whose first R3 command is a STOP); a run that
    // failed before it from the machine's lateness never met it and is run again.
    let Some((report, _fake)) = on_time("a refused stop", || {
        let model = rv6sl().expect("model");
        let fake = fake(&model, |_| {});
        let report = run_with(
            model,
            &fake,
            options().duration(Duration::from_millis(500)),
            Duration::from_millis(100),
            |f| f.set_r3_rejection(Some("STOP")),
        );
        (report, fake)
    }) else {
        return;
    };
    assert!(!report.shutdown.stopped, "{report}");
    assert_eq!(report.exit_code(), 1);
    let json = report.to_json();
    assert_eq!(json["device_stopped"], false);
    let why = json["device_stop_error"].as_str().expect("a reason");
    assert!(why.contains("4100") || why.contains("STOP"), "{why}");
}

#[test]
fn foreign_datagrams_are_counted_after_the_device_is_closed() {
    let model = rv6sl().expect("model");
    let fake = fake(&model, |_| {});
    let report = run_with(
        model,
        &fake,
        options().duration(Duration::from_millis(800)),
        Duration::from_millis(200),
        |f| {
            f.flood_foreign(500).expect("flood");
        },
    );
    assert!(report.link.rejected >= 100, "{report}");
    assert_eq!(report.to_json()["rejected_packets"], report.link.rejected);
}

/// One loss test at a time: what they assert about the loss must not be the machine's.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Runs with telemetry; `lose` replies dropped in a row after 0.5 s. The report and the
/// records from the fault on.
fn run_losing(lose: u32, supervision: Supervision) -> (RunReport, Vec<CycleRecord<8>>, FakeH7) {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let model = rv6sl().expect("model");
    let fake = fake(&model, |_| {});
    let options = RunOptions {
        supervision,
        ..options().duration(Duration::from_secs(3)).telemetry(true)
    };
    let mut run = ControlRun::<_, 16, 8>::start(h7(&fake), model, options).expect("starts");
    let started = Instant::now();
    let mut records = Vec::new();
    let mut dropped = false;
    while run.poll(Duration::from_millis(10)).is_some() {
        run.drain_telemetry(|r| records.push(*r));
        if !dropped && started.elapsed() >= Duration::from_millis(500) {
            fake.drop_next(lose);
            dropped = true;
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "the run did not end"
        );
    }
    let report = run.join_with(|r| records.push(*r));
    (report, records, fake)
}

/// Largest commanded speed of any joint between two records, rad/s.
fn speed(a: &CycleRecord<8>, b: &CycleRecord<8>) -> f64 {
    let dt = 7.11e-3;
    (0..6)
        .map(|k| (b.commanded[k] - a.commanded[k]).abs() / dt)
        .fold(0.0, f64::max)
}

#[test]
fn a_short_loss_brings_the_arm_to_rest_along_its_path() {
    let (report, records, fake) = run_losing(5, Supervision::default());
    let f = fault(&report);
    assert_eq!(f, Fault::LinkInterrupted { count: 3, bound: 3 }, "{report}");
    assert!(!f.stops_at_once());
    assert!(report.to_string().contains("brought to rest"), "{report}");
    // The five dropped (a loaded machine may lose more, counted too).
    assert!(report.link.lost >= 5, "{report}");
    // After the loss the commands went on along the path and slowed to rest: the last
    // commanded step is (almost) nothing, and it took the halt's ramp (≥ 0.1 s), not a cycle.
    let last = records.len() - 1;
    assert!(
        speed(&records[last - 1], &records[last]) < 1e-3,
        "still moving at the end"
    );
    let moving = records
        .windows(2)
        .rposition(|w| speed(&w[0], &w[1]) > 0.05)
        .expect("the arm moved");
    let lost_at = records
        .iter()
        .position(|r| r.time_s >= 0.49)
        .expect("the loss came during the run");
    assert!(
        moving > lost_at + 14,
        "the arm came to rest over {} cycles after the loss",
        moving.saturating_sub(lost_at)
    );
    // It never stepped beyond what the speed limits allow: the controller clamped nothing.
    let s = fake.status();
    assert_eq!((s.speed_clamps, s.limit_hits), (0, 0), "{s:?}");
    assert_switched_off(&fake, &report, true);
}

#[test]
fn a_dead_link_still_stops_at_once() {
    let (report, records, fake) = run_losing(1000, Supervision::default());
    let f = fault(&report);
    assert!(f.stops_at_once(), "{report}");
    assert!(
        matches!(
            f,
            Fault::ConsecutiveLost { count: 10, .. } | Fault::LinkLost { .. }
        ),
        "{report}"
    );
    // Ten lost replies after the loss began, not a halt's ramp.
    let lost_at = records
        .iter()
        .position(|r| r.time_s >= 0.49)
        .expect("the loss came during the run");
    assert!(
        records.len() - lost_at <= 16,
        "{} cycles after the loss began",
        records.len() - lost_at
    );
    fake.drop_next(0);
    assert_switched_off(&fake, &report, false);
}

#[test]
fn the_loss_bounds_are_the_callers() {
    // Eight lost in a row allowed: a loss of five is ridden through, the run completes.
    let supervision = Supervision {
        rest_after_lost: 8,
        max_consecutive_lost: 12,
        ..Supervision::default()
    };
    let (report, _, fake) = run_losing(5, supervision);
    assert_eq!(report.end, Some(RunEnd::CycleLimit), "{report}");
    assert!(report.link.lost >= 5, "{report}");
    assert_switched_off(&fake, &report, true);
}
