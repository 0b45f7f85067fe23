//! End to end on loopback: the library controller drives six fake CiA 402 drives over
//! cannelloni UDP at 2 ms for 5,000 cycles (10 s) in the real-time loop: enable → CSP motion
//! along the default tour → disable, with no lost TPDO, and the fake drives where the
//! controller put them.

use std::ops::ControlFlow;
use std::time::Duration;

use rl::controller::{Controller, MotionLimits, Plan, RunEnd, default_waypoints, rv6sl};
use rl::drivers::canopen::{Cia402, Cia402Config};
use rl::drivers::cia402::{AxisUnits, PowerState};
use rl::drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config};
use rl::drivers::transport::can::CanAddress;
use rl::drivers::{Device, JointPositionSensor, LinkStatisticsSensor};
use rl_rt::{CyclicLoop, OverrunPolicy, Policy, RtThreadBuilder};

const PERIOD: Duration = Duration::from_millis(2);
const CYCLES: u64 = 5000;

/// Runs the session in a SCHED_FIFO thread where the process may (as root in CI), so the fake
/// drives' thread, spawned from it, inherits the policy: two real-time threads on loopback, as
/// a controller and its drives would be, whatever else the machine runs. Otherwise it runs with
/// the normal policy and says so.
///
/// The premise is a machine that keeps a 2 ms loop: a session that failed while the loop itself
/// overran or woke more than half a period late (its SYNC then goes out so late that the
/// drives' answers cross into the next cycle), or while the fake drives' thread woke more than
/// half a period late (held up on a
/// shared VM, which no code of ours can prevent and real drives with their own CPUs never see),
/// is not a verdict on the master and is tried again, up to three times; if the machine never
/// kept the loop, the test says SKIPPED with the measurements. A session whose loop kept every
/// deadline must meet every assertion.
#[test]
fn six_fake_drives_at_2_ms_for_5000_cycles_without_a_lost_tpdo() {
    let mut measured = Vec::new();
    for attempt in 1..=3 {
        // The controller (model, data, plan) lives on this thread's stack: a large one.
        let rt = RtThreadBuilder::new("canopen-e2e")
            .policy(Policy::Fifo)
            .priority(80)
            .stack_size(64 << 20);
        let outcome = match rt.spawn(session) {
            Ok(t) => t.join().unwrap_or_else(|e| std::panic::resume_unwind(e)),
            Err(e) => {
                println!("note: no SCHED_FIFO ({e}); running with the normal policy");
                session()
            }
        };
        match outcome {
            Session::Passed => return,
            Session::MachineLate(why) => {
                println!("attempt {attempt}: the loop did not keep 2 ms: {why}");
                measured.push(why);
            }
        }
    }
    println!(
        "SKIPPED: this machine did not keep a 2 ms real-time loop in three sessions ({})",
        measured.join("; ")
    );
}

/// How a session ended.
enum Session {
    /// Every assertion held.
    Passed,
    /// The loop overran: the machine, not the code, missed the cycle.
    MachineLate(String),
}

fn session() -> Session {
    let model = rv6sl().expect("model").model;
    let nodes = [1, 2, 3, 4, 5, 6];
    let mut fc = FakeCia402Config::new(&nodes).unwrap();
    for (k, a) in fc.axes.iter_mut().enumerate() {
        let l = model.limits(k);
        a.lower = l.lower;
        a.upper = l.upper;
        if l.velocity.is_finite() && l.velocity > 0.0 {
            a.max_velocity = l.velocity;
        }
        a.initial = 0.1_f64.clamp(l.lower, l.upper);
        a.units = AxisUnits::GEARED_100;
    }
    let fake = FakeCia402::serve(
        fc,
        &CanAddress::parse("cannelloni+udp://127.0.0.1:0").unwrap(),
    )
    .unwrap();
    let bus =
        CanAddress::parse(&format!("cannelloni+udp://{}", fake.local_addr().unwrap())).unwrap();
    let mut config = Cia402Config::new(bus, &nodes);
    // The master reads the drives' units (the fakes' 100:1 gear carries the inverse-dynamics
    // torques: ±3 276 N·m in the torque offset).
    config.sdo_timeout = Duration::from_millis(200);
    let mut robot = Cia402::new(config).unwrap();
    robot.open().unwrap();
    // The arm's position comes from SDO at open: the plan is made before anything is enabled.
    let mut start = vec![0.0; 6];
    robot.joint_position(&mut start).unwrap();
    assert!(start.iter().all(|q| (q - 0.1).abs() < 1e-5), "{start:?}");
    let limits = MotionLimits::<8>::from_model(&model, 0.25).unwrap();
    // The tour twice (it ends where it starts): longer than the 5,000 cycles (10 s) at a
    // quarter of the speed limits, so the session ends at the cycle limit while moving.
    let tour = default_waypoints(&model, &start);
    let waypoints: Vec<_> = tour.iter().chain(&tour).cloned().collect();
    let plan = Plan::new(&model, &start, &waypoints, &limits).unwrap();
    robot.start().unwrap();
    let mut control = Controller::new(robot, model, plan, PERIOD).unwrap();
    control.limit_cycles(CYCLES);
    let looped = CyclicLoop::new(PERIOD)
        .unwrap()
        .overrun_policy(OverrunPolicy::Skip);
    let mut cycles = 0u64;
    let report = looped
        .run(|_| {
            cycles += 1;
            if control.cycle().finished {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .unwrap();
    // What the checks need is taken at once, and the drives are stopped at once: drives left
    // enabled without SYNC fault after two periods (as real ones do), so nothing else may come
    // between the loop's end and the stop.
    let stats = control.robot().link_statistics();
    let counters = control.robot().counters();
    let control_end = control.end();
    let failed_steps = control.failed_steps();
    let max_tracking = control.tracking().max_error();
    let mut q = [0.0; 6];
    let measured = control.robot().joint_position(&mut q);
    let at_end = fake.status();
    let mut robot = control.into_robot();
    let stopped = robot.stop();
    let closed = robot.close();
    // How late the fake's thread ran (its own deadlines, and frames taken after their kernel
    // receive time), read after the stop: a stall still going on when the loop ended shows only
    // once the fake's thread runs again.
    let fake_late = fake.status().max_lateness;
    println!(
        "{cycles} cycles, {} overruns, max wake-up latency {:?} ns, max step {:?} ns, fake drives' thread up to {:?} late; link {stats:?}; device {counters:?}; max tracking error {max_tracking:.2e} rad",
        report.stats.overruns,
        report.stats.wakeup.max_ns(),
        report.stats.step.max_ns(),
        fake_late,
    );
    // The fake drives share this machine's CPUs; real drives have their own. A session that
    // failed while the loop overran, woke more than half a period late, or while the fake was
    // held up for longer than the master waits for its TPDOs is the machine's, not a verdict on
    // the master.
    let loop_late = Duration::from_nanos(report.stats.wakeup.max_ns().unwrap_or(0));
    let clean =
        matches!(control_end, Some(RunEnd::CycleLimit)) && stats.lost == 0 && stats.late == 0;
    if !clean && (report.stats.overruns > 0 || loop_late > PERIOD / 2 || fake_late > PERIOD / 2) {
        return Session::MachineLate(format!(
            "{} overruns, max wake-up latency {:.2} ms, the fake drives' thread up to {:.2} ms \
             late, end {:?}, {} TPDOs lost",
            report.stats.overruns,
            report.stats.wakeup.max_ns().unwrap_or(0) as f64 * 1e-6,
            fake_late.as_secs_f64() * 1e3,
            control_end,
            stats.lost
        ));
    }
    assert!(
        matches!(control_end, Some(RunEnd::CycleLimit)),
        "{control_end:?}"
    );
    assert!(cycles >= CYCLES, "{cycles}");
    assert_eq!(stats.lost, 0, "lost TPDOs");
    assert_eq!((stats.late, stats.corrupt, stats.rejected), (0, 0, 0));
    assert_eq!(failed_steps, 0);
    assert_eq!(counters.commands_clamped, 0);
    assert_eq!(counters.syncs, counters.tpdos / 6 + counters.tpdos_lost);
    // The drives were where the controller's last measurement says.
    measured.unwrap();
    for (k, n) in at_end.nodes.iter().enumerate() {
        assert!(
            (n.position - q[k]).abs() < 1e-3,
            "joint {k}: drive {} vs measured {}",
            n.position,
            q[k]
        );
    }
    stopped.unwrap();
    closed.unwrap();
    fake.wait_for(Duration::from_secs(1), |s| {
        s.nodes
            .iter()
            .all(|n| n.power == PowerState::SwitchOnDisabled)
    })
    .unwrap();
    Session::Passed
}
