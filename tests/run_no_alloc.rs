//! The controller's steady-state cycle allocates nothing: read, trajectory, RNEA, command,
//! device step against the fake H7, telemetry queue and progress mailbox, counted by a global
//! allocator that counts only on the thread under test (the fake runs its own threads). With
//! the viewer attached (`rl run --view`), the loop's hand-over of measured and commanded
//! positions to the viewer's lock-free mailbox allocates nothing either (the viewer's threads
//! are its own).

mod common;

use rl::controller::{Controller, CycleRecord, rv6sl};
use rl::drivers::Device;
use rl::drivers::mitsubishi_h7::MitsubishiH7;
use rl::rt::exchange::{mailbox, queue};
use rl_testkit::CountingAllocator;

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// Allocations made by `f` on this thread.
fn allocations(f: impl FnOnce()) -> u64 {
    rl_testkit::allocations(f).0
}

/// One test at a time: each steps a device against a fake that runs threads of its own (one at
/// 1 kHz), and side by side on two cores their fakes miss replies (a clean-clone CI run: one H7
/// step timed out while the Franka test ran beside it).
fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static ONE: std::sync::Mutex<()> = std::sync::Mutex::new(());
    ONE.lock().unwrap_or_else(|p| p.into_inner())
}

/// Runs `cycle` `cycles` times, counting allocations, each cycle `k` first waiting (yielding
/// its CPU, without allocating) until another thread has counted `min(k / per_send, sends)`
/// sends in `sent`: the inputs arrive across the cycles however the machine schedules the two
/// threads. The allocations, and whether a cycle said the run finished.
fn cycles_in_lockstep(
    cycles: u32,
    sent: &std::sync::atomic::AtomicU32,
    per_send: u32,
    sends: u32,
    mut cycle: impl FnMut() -> bool,
) -> (u64, bool) {
    let mut finished = false;
    let counted = allocations(|| {
        for k in 0..cycles {
            while sent.load(std::sync::atomic::Ordering::Acquire) < (k / per_send).min(sends) {
                std::thread::yield_now();
            }
            finished |= cycle();
        }
    });
    (counted, finished)
}

#[test]
fn steady_state_control_cycle_allocates_nothing() {
    let _one = one_at_a_time();
    // The counter sees allocations (so a zero below means something).
    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);

    let dof = rv6sl().expect("embedded model").model.dof();
    let fake = common::immediate_fake(dof);
    let mut control = Box::new(common::demo_controller(&fake));
    let (mut telemetry, mut sink) = queue::<CycleRecord>(1024);
    let (mut progress, _reader) = mailbox((0u64, 0.0f64));

    let mut cycle = |control: &mut Controller<MitsubishiH7>| {
        let out = control.cycle();
        let _ = telemetry.try_send(out.record);
        progress.publish((out.record.cycle, control.tracking().max_error()));
        out.finished
    };
    // Warm-up: first cycles, lazily initialised statics, the socket's first receives.
    for _ in 0..50 {
        assert!(!cycle(&mut control));
    }
    while sink.try_recv().is_some() {}
    let mut finished = false;
    let counted = allocations(|| {
        for _ in 0..400 {
            finished |= cycle(&mut control);
        }
    });
    assert!(!finished, "the plan is longer than 450 cycles");
    assert_eq!(counted, 0, "allocations in 400 steady-state control cycles");
    assert_eq!(control.failed_steps(), 0);
    assert!(control.tracking().max_error() > 0.0, "the arm moved");

    let mut robot = control.into_robot();
    robot.stop().expect("stop");
    robot.close().expect("close");
}

#[cfg(feature = "view")]
#[test]
fn steady_state_control_cycle_with_the_viewer_attached_allocates_nothing() {
    let _one = one_at_a_time();
    use rl::controller::{RV6SL_XML, ViewHook};

    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);

    let dof = rv6sl().expect("embedded model").model.dof();
    let view = ViewHook::start(
        rl_view::ModelSource::Text {
            name: "RV-6SL".into(),
            text: RV6SL_XML.into(),
        },
        "127.0.0.1:0".parse().unwrap(),
    )
    .expect("viewer starts");
    let mut shown = view.attach(dof).expect("the viewer's model is the run's");
    assert!(
        view.attach(dof + 1).is_err(),
        "a model of other joints is refused"
    );
    let fake = common::immediate_fake(dof);
    let mut control = Box::new(common::demo_controller(&fake));
    let (mut telemetry, mut sink) = queue::<CycleRecord>(1024);

    // What the real-time loop of `ControlRun` does each cycle with a view attached.
    let mut cycle = |control: &mut Controller<MitsubishiH7>| {
        let out = control.cycle();
        let _ = telemetry.try_send(out.record);
        shown.show(&out.record);
        out.finished
    };
    for _ in 0..50 {
        assert!(!cycle(&mut control));
    }
    while sink.try_recv().is_some() {}
    let mut finished = false;
    let counted = allocations(|| {
        for _ in 0..400 {
            finished |= cycle(&mut control);
        }
    });
    assert!(!finished, "the plan is longer than 450 cycles");
    assert_eq!(
        counted, 0,
        "allocations in 400 control cycles publishing to the viewer"
    );
    assert_eq!(shown.published(), 450);
    assert_eq!(shown.refused(), 0);
    // The viewer took the newest frame: the controller's last measured and commanded q.
    let end = std::time::Instant::now() + std::time::Duration::from_secs(10);
    let last = control.tracking().last_error().to_vec();
    loop {
        let state = view.viewer().state();
        let m = &state["models"][0];
        let q: Vec<f64> = serde_json::from_value(m["q"].clone()).unwrap();
        let c: Option<Vec<f64>> = serde_json::from_value(m["q_cmd"].clone()).unwrap();
        if let Some(c) = c {
            let e: Vec<f64> = c.iter().zip(&q).map(|(c, q)| c - q).collect();
            if e.iter().zip(&last).all(|(a, b)| (a - b).abs() < 1e-12) {
                assert_eq!(m["source"], "live");
                break;
            }
        }
        assert!(
            std::time::Instant::now() < end,
            "the viewer shows {m}, the last error is {last:?}"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }

    let mut robot = control.into_robot();
    robot.stop().expect("stop");
    robot.close().expect("close");
}

/// A law of one's own (position targets streamed in, a speed-limited step toward the newest
/// one, RNEA feed-forward in the model's workspace) with its input channel: the controller's
/// cycle around it — inputs taken, the law run, its command checked and sent, the device
/// stepped — allocates nothing, while another thread sends targets.
#[test]
fn steady_state_cycle_with_a_users_law_and_streamed_targets_allocates_nothing() {
    let _one = one_at_a_time();
    use rl::controller::Target;
    use rl::controller::law::{BrakeReason, Command, Context, ControlLaw, LawStatus, Start};

    /// Steps toward the newest target by at most `step` per cycle.
    struct Toward {
        step: f64,
        at: [f64; 8],
    }
    impl ControlLaw<16, 8> for Toward {
        type Input = [f64; 3];
        fn start(&mut self, start: &Start<'_, 16, 8>) -> Result<(), rl::controller::LawError> {
            self.at[..start.position.len()].copy_from_slice(start.position);
            Ok(())
        }
        fn cycle(
            &mut self,
            cx: &mut Context<'_, 16, 8, [f64; 3]>,
            out: &mut Command<8>,
        ) -> LawStatus {
            if let Some(Target::Position { position, .. }) = cx.inputs.target() {
                for (at, p) in self.at.iter_mut().zip(position).take(cx.dof) {
                    *at += (p - *at).clamp(-self.step, self.step);
                }
            }
            let zero = [0.0; 8];
            if let Ok(tau) = rl::core::algo::rnea(
                cx.model,
                cx.data,
                &self.at[..cx.dof],
                &zero[..cx.dof],
                &zero[..cx.dof],
            ) {
                out.torque[..cx.dof].copy_from_slice(tau);
            }
            out.position = self.at;
            LawStatus::Running
        }
        fn brake(&mut self, _: BrakeReason) {}
    }

    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);

    let fake = common::immediate_fake(6);
    let law = Toward {
        step: 1e-4,
        at: [0.0; 8],
    };
    let common::LawOnH7 {
        mut control,
        tx,
        start,
        ..
    } = common::law_on_h7(&fake, law, 64);
    let mut goal = start.clone();
    goal[0] += 0.2;
    tx.send_position(&goal).expect("target");
    for _ in 0..50 {
        assert!(!control.cycle().finished);
    }
    // The sender counts what it has sent; each cycle waits (yielding its CPU, without allocating) for
    // the sends its place in the run is owed, so that targets and inputs arrive across the
    // cycles however the machine schedules the two threads (a loaded machine once ran all 400
    // cycles before the sender's second target).
    let sent = std::sync::Arc::new(std::sync::atomic::AtomicU32::new(0));
    let sent_by = sent.clone();
    let sender = std::thread::spawn(move || {
        for i in 0..200 {
            let mut g = goal.clone();
            g[1] += 1e-4 * f64::from(i);
            let _ = tx.send_position(&g);
            let _ = tx.send([0.1, 0.2, 0.3]);
            sent_by.store(i + 1, std::sync::atomic::Ordering::Release);
            std::thread::sleep(std::time::Duration::from_micros(200));
        }
    });
    let (counted, finished) = cycles_in_lockstep(400, &sent, 2, 200, || control.cycle().finished);
    sender.join().expect("sender");
    assert!(!finished);
    assert_eq!(
        counted, 0,
        "allocations in 400 cycles of a user's law taking inputs"
    );
    let report = control.input_report().expect("inputs");
    assert!(report.targets > 1 && report.others > 0, "{report:?}");
    assert_eq!(control.failed_steps(), 0);
    assert!(control.tracking().max_error() > 0.0, "the arm moved");
    let mut robot = control.into_robot();
    robot.stop().expect("stop");
    robot.close().expect("close");
}

/// Following a planned path blended through its waypoints (lines and sextic blends mixed with
/// jerk-limited moves, `PlanTrajectory::Blended`): the trajectory is built before the loop,
/// and evaluating it in the loop allocates nothing.
#[cfg(feature = "plan")]
#[test]
fn steady_state_cycle_following_a_blended_path_allocates_nothing() {
    follow_planned_path(false);
}

/// The same path retimed with bounded jerk (`PlanTrajectory::Retimed`, what `rl run --plan`
/// follows by default): each cycle finds the path's own time by bisection and Newton steps on
/// its arc length, without allocating.
#[cfg(feature = "plan")]
#[test]
fn steady_state_cycle_following_a_retimed_path_allocates_nothing() {
    follow_planned_path(true);
}

#[cfg(feature = "plan")]
fn follow_planned_path(retime: bool) {
    let _one = one_at_a_time();
    use rl::controller::{MotionLimits, Plan, PlanBudget};

    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);

    let model = rv6sl().expect("embedded model").model;
    let dof = model.dof();
    let fake = common::immediate_fake(dof);
    let (robot, start) = common::started_h7_standing(&fake, dof);
    let limits = MotionLimits::<8>::from_model(&model, 0.25).expect("limits");
    let trajectory = common::tour_as_planned_path(&model, &start, &limits, retime);
    let plan =
        Plan::from_trajectory(&model, trajectory, &limits, &PlanBudget::default()).expect("plan");
    let mut control =
        Box::new(Controller::new(robot, model, plan, common::PERIOD).expect("controller"));
    for _ in 0..50 {
        assert!(!control.cycle().finished);
    }
    let mut finished = false;
    let counted = allocations(|| {
        for _ in 0..400 {
            finished |= control.cycle().finished;
        }
    });
    assert!(!finished, "the plan is longer than 450 cycles");
    assert_eq!(
        counted, 0,
        "allocations in 400 cycles following a planned path (retimed: {retime})"
    );
    assert_eq!(control.failed_steps(), 0);
    assert!(control.tracking().max_error() > 0.0, "the arm moved");
    let mut robot = control.into_robot();
    robot.stop().expect("stop");
    robot.close().expect("close");
}

/// `rl run --follow`'s law: targets taken from the input channel every few cycles, each a
/// recalculation of the online trajectory generator from the state commanded last, and then
/// the stop along its braking profile — allocation-free from the first cycle to rest.
#[test]
fn following_streamed_targets_and_braking_allocates_nothing() {
    let _one = one_at_a_time();
    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);

    let dof = rv6sl().expect("embedded model").model.dof();
    let fake = common::immediate_fake(dof);
    let common::LawOnH7 {
        mut control,
        tx,
        start,
        ..
    } = common::law_on_h7(&fake, rl::controller::TargetFollower::<8>::new(), 64);
    let home = start.clone();
    let target = move |i: u32| {
        let mut g = home.clone();
        g[0] += 0.05 * f64::from(i % 5);
        g[1] -= 0.03 * f64::from(i % 3);
        g
    };
    tx.send_position(&target(1)).expect("target");
    for _ in 0..50 {
        assert!(!control.cycle().finished);
    }
    // A target every four cycles from another thread (sending is the sender's work, not the
    // loop's), in lockstep: target i is sent once the loop has reached cycle 4i, and that cycle
    // waits for it, so each is taken (a loaded machine that held the loop while two were sent
    // left one unseen: the exchange keeps the latest).
    use std::sync::atomic::{AtomicU32, Ordering};
    let sent = std::sync::Arc::new(AtomicU32::new(0));
    let reached = std::sync::Arc::new(AtomicU32::new(0));
    let (sent_by, reached_by) = (sent.clone(), reached.clone());
    let sender = std::thread::spawn(move || {
        for i in 0..100u32 {
            while reached_by.load(Ordering::Acquire) < i {
                std::thread::yield_now();
            }
            let _ = tx.send_position(&target(i + 2));
            sent_by.store(i + 1, Ordering::Release);
        }
    });
    let mut finished = false;
    let counted = allocations(|| {
        for k in 0..400u32 {
            if k % 4 == 0 {
                reached.store(k / 4, Ordering::Release);
                while sent.load(Ordering::Acquire) < k / 4 + 1 {
                    std::thread::yield_now();
                }
            }
            finished |= control.cycle().finished;
        }
        control.request_halt();
        for _ in 0..2000 {
            if control.cycle().finished {
                finished = true;
                break;
            }
        }
    });
    sender.join().expect("sender");
    assert!(finished, "the stop brought the arm to rest");
    assert_eq!(
        counted, 0,
        "allocations in 400 cycles following targets and the stop"
    );
    assert_eq!(control.end(), Some(rl::controller::RunEnd::Stopped));
    // The first target and the hundred sent in lockstep, every one taken.
    assert_eq!(
        control.law().counts().targets,
        101,
        "{:?}",
        control.law().counts()
    );
    assert_eq!(control.failed_steps(), 0);
    let mut robot = control.into_robot();
    robot.stop().expect("stop");
    robot.close().expect("close");
}

/// The safety chain's check in every cycle (pins read, watchdog toggled, brake written, one
/// virtual call) allocates nothing.
#[test]
fn the_safety_chains_check_in_the_cycle_allocates_nothing() {
    let _one = one_at_a_time();
    use rl::drivers::safety::{Level, NoPin, SafetyChain, SafetyConfig};

    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);
    let dof = rv6sl().expect("embedded model").model.dof();
    let fake = common::immediate_fake(dof);
    let mut control = Box::new(common::demo_controller(&fake));
    // Pins that read low: a chain closed at low.
    let mut config = SafetyConfig::default();
    config.estop.closed_level = Level::Low;
    control.attach_safety(Box::new(
        SafetyChain::new(config, NoPin, NoPin).with_brake(NoPin),
    ));
    control
        .arm_safety()
        .expect("armed: the e-stop reads closed");
    for _ in 0..50 {
        assert!(!control.cycle().finished);
    }
    let mut finished = false;
    let counted = allocations(|| {
        for _ in 0..400 {
            finished |= control.cycle().finished;
        }
    });
    assert!(!finished);
    assert_eq!(
        counted, 0,
        "allocations in 400 cycles with the safety chain"
    );
    assert!(control.fault().is_none(), "{:?}", control.fault());
    let chain = control.detach_safety().expect("the chain");
    assert!(chain.counters().cycles >= 450, "{:?}", chain.counters());
    let mut robot = control.into_robot();
    robot.stop().expect("stop");
    robot.close().expect("close");
}

/// The task-space law (`CartesianImpedance`: Jacobian, J̇q̇, CRBA and its factors, the clamped
/// operational inertia's eigen-decomposition, the nullspace, the rate limit) on a Franka arm in
/// torque mode against the fake FR3 with the arm's dynamics, streamed poses arriving from
/// another thread: 500 cycles, no allocation.
#[test]
fn the_task_space_law_on_a_franka_arm_allocates_nothing() {
    let _one = one_at_a_time();
    use rl::controller::law::Start;
    use rl::controller::task_space::{CartesianImpedance, TaskInput, TaskMotion};
    use rl::controller::{ControlLaw, MotionLimits, Supervision, input};
    use rl::core::loader::{UrdfOptions, load_urdf_str};
    use rl::drivers::fake::franka_controller::fr3_shaped_urdf;
    use rl::drivers::{CyclicDevice, JointPositionSensor};
    use std::time::Duration;

    let urdf = fr3_shaped_urdf();
    let (_fake, mut robot) = common::fake_franka_in_torque_mode(&urdf);
    robot.open().expect("open");
    robot.start().expect("start");
    robot.step().expect("first exchange");
    let model = load_urdf_str::<16>(&urdf, &UrdfOptions::default())
        .expect("model")
        .model;
    let mut start = vec![0.0; model.dof()];
    robot.joint_position(&mut start).expect("joints");
    let limits = MotionLimits::<8>::from_model(&model, 0.25).expect("limits");
    let period = Duration::from_millis(1);
    let mut law = CartesianImpedance::<16, 8>::new(0, TaskMotion::Streamed);
    ControlLaw::<16, 8>::start(
        &mut law,
        &Start {
            position: &start,
            model: &model,
            limits: &limits,
            period_s: 1e-3,
            device_period_s: 1e-3,
            device_adds_gravity: true,
        },
    )
    .expect("law starts");
    let (tx, rx) = input::channel::<16, 8, TaskInput>(&model, 64);
    let mut control = Box::new(
        Controller::with_law(
            robot,
            model.clone(),
            law,
            &start,
            &limits,
            period,
            &Supervision::default(),
        )
        .expect("controller"),
    );
    control.attach_inputs(rx);
    control.input_timeout(Duration::from_secs(60));
    for _ in 0..50 {
        assert!(!control.cycle().finished);
    }
    let mut d = Box::new(rl::core::Data::<16>::new());
    rl::core::algo::forward_position(&model, &mut d, &start).expect("fk");
    let home = rl::core::algo::tool_pose(&model, &d, 0).expect("tool");
    let sent = std::sync::Arc::new(std::sync::atomic::AtomicU32::new(0));
    let sent_by = sent.clone();
    let sender = std::thread::spawn(move || {
        for i in 0..100 {
            let mut pose = home;
            pose.translation.y += 1e-4 * f64::from(i);
            let _ = tx.send(TaskInput::Pose(pose));
            sent_by.store(i + 1, std::sync::atomic::Ordering::Release);
            std::thread::sleep(Duration::from_micros(500));
        }
    });
    let (counted, finished) = cycles_in_lockstep(500, &sent, 5, 100, || control.cycle().finished);
    sender.join().expect("sender");
    assert!(!finished);
    assert_eq!(
        counted, 0,
        "allocations in 500 cycles of the task-space law"
    );
    let stats = *control.law().stats();
    assert!(stats.poses >= 90 && stats.cycles == 550, "{stats:?}");
    assert_eq!(stats.failed_cycles, 0, "{stats:?}");
    let mut robot = control.into_robot();
    robot.stop().expect("stop");
    robot.close().expect("close");
}
