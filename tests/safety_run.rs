//! The controller's safety chain in a run (`RunOptions::safety`, rl-drivers' `SafetyChain` over
//! fake embedded-hal pins), against the fake H7: an open e-stop refuses the run before anything
//! moves; an e-stop opened while the arm moves ends the run at once in stop category 0 (the
//! brake output drops in that cycle) or brings the arm to rest first in category 1 (the brake
//! output drops when the drives are off); the watchdog toggles every cycle while the loop runs
//! and holds after it; closing the e-stop again restarts nothing — only a new run, which arms
//! the chain again, moves.

mod common;
mod late;

use std::convert::Infallible;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
use rl::controller::safety::SafetyHandle;
use rl::controller::{
    ControlRun, CycleRecord, Fault, RunEnd, RunError, RunOptions, RunReport, rv6sl,
};
use rl::drivers::fake::h7_controller::FakeH7;
use rl::drivers::safety::{ChainState, SafetyChain, SafetyConfig, StopCategory, StopReason};

/// An input line another thread sets (a switch).
#[derive(Clone)]
struct Switch(Arc<AtomicBool>);

impl ErrorType for Switch {
    type Error = Infallible;
}

impl InputPin for Switch {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(self.0.load(Ordering::Acquire))
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(!self.0.load(Ordering::Acquire))
    }
}

/// An output line whose level and changes another thread reads (a relay).
#[derive(Clone, Default)]
struct Relay {
    high: Arc<AtomicBool>,
    changes: Arc<AtomicU64>,
}

impl Relay {
    fn set(&mut self, high: bool) {
        if self.high.swap(high, Ordering::AcqRel) != high {
            self.changes.fetch_add(1, Ordering::AcqRel);
        }
    }
    fn is_high(&self) -> bool {
        self.high.load(Ordering::Acquire)
    }
    fn changes(&self) -> u64 {
        self.changes.load(Ordering::Acquire)
    }
}

impl ErrorType for Relay {
    type Error = Infallible;
}

impl OutputPin for Relay {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.set(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.set(true);
        Ok(())
    }
}

/// The pins of one chain: the e-stop (closed = high), the watchdog and the brake.
struct Pins {
    estop: Arc<AtomicBool>,
    watchdog: Relay,
    brake: Relay,
}

fn chain(category: StopCategory) -> (SafetyHandle, Pins) {
    let estop = Arc::new(AtomicBool::new(true));
    let (watchdog, brake) = (Relay::default(), Relay::default());
    let config = SafetyConfig {
        category,
        ..SafetyConfig::default()
    };
    let chain =
        SafetyChain::new(config, Switch(estop.clone()), watchdog.clone()).with_brake(brake.clone());
    (
        SafetyHandle::new(chain),
        Pins {
            estop,
            watchdog,
            brake,
        },
    )
}

/// One run at a time (each is a SCHED_FIFO loop and an in-process fake).
fn one_run_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static RUNS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    RUNS.lock().unwrap_or_else(|p| p.into_inner())
}

fn options(handle: &SafetyHandle) -> RunOptions {
    RunOptions {
        lock_memory: false,
        priority: 60,
        telemetry: true,
        safety: Some(handle.clone()),
        ..RunOptions::default()
    }
    .duration(Duration::from_secs(20))
}

/// A tour on a fake H7; `open_after`: the e-stop opens that long after the loop started.
fn run(
    handle: &SafetyHandle,
    pins: &Pins,
    open_after: Option<Duration>,
) -> Result<Outcome, RunError> {
    let (fake, robot) = common::realtime_fake_h7();
    let mut run = ControlRun::<_, 16, 8>::start(robot, rv6sl().expect("model"), options(handle))?;
    let started = Instant::now();
    let mut rows = Vec::new();
    let mut brake_seen = Vec::new();
    while run.poll(Duration::from_millis(5)).is_some() {
        run.drain_telemetry(|r| rows.push(*r));
        brake_seen.push(pins.brake.is_high());
        if open_after.is_some_and(|t| started.elapsed() >= t) {
            pins.estop.store(false, Ordering::Release);
        }
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "the run did not end"
        );
    }
    let report = run.join_with(|r| rows.push(*r));
    Ok((report, rows, fake, brake_seen))
}

#[test]
fn an_open_estop_refuses_the_run_before_anything_moves() {
    let _one = one_run_at_a_time();
    let (handle, pins) = chain(StopCategory::Zero);
    pins.estop.store(false, Ordering::Release);
    let (fake, robot) = common::realtime_fake_h7();
    let e = ControlRun::<_, 16, 8>::start(robot, rv6sl().expect("model"), options(&handle))
        .err()
        .expect("refused");
    assert!(matches!(e, RunError::Safety(_)), "{e}");
    assert!(e.to_string().contains("e-stop"), "{e}");
    assert!(e.to_string().contains("nothing was started"), "{e}");
    assert_eq!(fake.status().moves, 0, "the device was never commanded");
    assert!(!pins.brake.is_high(), "the brake output never energised");
    // The chain went back to its handle, latched.
    let state = handle.with(|c| c.state()).expect("the chain is back");
    assert_ne!(state, ChainState::Ready);
}

/// What a run makes: its report, telemetry, fake and the brake output seen while it ran.
type Outcome = (RunReport, Vec<CycleRecord<8>>, FakeH7, Vec<bool>);

/// A tour on a fresh chain of `category` whose e-stop opens 800 ms in. A run in which the
/// machine was late (a short loss brakes along the path before the e-stop, and the fault's
/// cycle is then the loss's) runs again with a fresh chain (`late::while_late`).
fn estop_run(category: StopCategory) -> Option<(SafetyHandle, Pins, Outcome)> {
    late::while_late(
        &format!("an e-stop in category {category:?}"),
        || {
            let (handle, pins) = chain(category);
            let outcome = run(&handle, &pins, Some(Duration::from_millis(800))).expect("starts");
            (handle, pins, outcome)
        },
        |(_, _, (report, ..))| late::any_shortfall(report),
    )
}

fn the_estop(report: &RunReport) -> (StopCategory, StopReason) {
    match report.end {
        Some(RunEnd::Fault(Fault::Safety { category, reason })) => (category, reason),
        other => panic!("the run ended by {other:?}:\n{report}"),
    }
}

#[test]
fn an_estop_opened_while_the_arm_moves_stops_it_at_once_in_category_0() {
    let _one = one_run_at_a_time();
    let Some((handle, pins, (report, rows, fake, brake_seen))) = estop_run(StopCategory::Zero)
    else {
        return;
    };
    let (category, reason) = the_estop(&report);
    assert_eq!(category, StopCategory::Zero);
    assert!(matches!(reason, StopReason::EStopOpen { .. }), "{reason}");
    assert_ne!(report.exit_code(), 0);
    assert!(report.shutdown.stopped, "{report}");
    // At once: no cycle after the fault's.
    let fault = report.fault_at.expect("fault cycle").cycle;
    assert!(rows.last().expect("rows").cycle <= fault + 1, "{report}");
    // The brake output was energised while the arm moved, and dropped.
    assert!(
        brake_seen.iter().any(|b| *b),
        "the brake output was never energised"
    );
    assert!(!pins.brake.is_high(), "the brake output dropped");
    // The watchdog toggled every cycle (the arming's cycles too), and holds now.
    let cycles = report.stats.cycles();
    let toggles = pins.watchdog.changes();
    assert!(
        toggles >= cycles,
        "{toggles} watchdog changes in {cycles} cycles"
    );
    std::thread::sleep(Duration::from_millis(50));
    assert_eq!(
        pins.watchdog.changes(),
        toggles,
        "the watchdog holds after the run"
    );
    let safety = report.safety.expect("the chain's report");
    assert_eq!(safety.counters.stops, 1);
    assert!(!safety.brake_energised);
    // Closing the e-stop restarts nothing: the chain stays latched until a new run arms it.
    pins.estop.store(true, Ordering::Release);
    std::thread::sleep(Duration::from_millis(100));
    let moves = fake.status().moves;
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(
        fake.status().moves,
        moves,
        "nothing moves after the e-stop closed"
    );
    assert_ne!(handle.with(|c| c.state()), Some(ChainState::Ready));
    // A new run arms the chain again (it reads closed) and moves.
    let (report, rows, _fake, _) = run(&handle, &pins, Some(Duration::from_millis(300)))
        .expect("a new run starts once the e-stop is closed");
    assert!(rows.len() > 10, "{report}");
    assert_eq!(the_estop(&report).0, StopCategory::Zero);
}

#[test]
fn an_estop_in_category_1_brings_the_arm_to_rest_before_the_brake_drops() {
    let _one = one_run_at_a_time();
    let Some((_handle, pins, (report, rows, _fake, _))) = estop_run(StopCategory::One) else {
        return;
    };
    let (category, reason) = the_estop(&report);
    assert_eq!(category, StopCategory::One);
    assert!(matches!(reason, StopReason::EStopOpen { .. }), "{reason}");
    assert!(report.shutdown.stopped, "{report}");
    // Brought to rest along its path after the fault: the run went on for the halt's cycles.
    let fault = report.fault_at.expect("fault cycle").cycle;
    let after = rows.iter().filter(|r| r.cycle > fault).count();
    assert!(
        after >= 10,
        "category 1 brings the arm to rest along its path ({after} cycles after the fault): \
         {report}"
    );
    // At rest at the end: the last step of the command is a hundredth of the step when the
    // e-stop opened (the halt's ramp ends at rest).
    let step = |i: usize| {
        (0..6)
            .map(|k| (rows[i].commanded[k] - rows[i - 1].commanded[k]).abs())
            .fold(0.0, f64::max)
    };
    let at_fault = rows
        .iter()
        .position(|r| r.cycle == fault)
        .expect("the fault's row");
    let (moving, last) = (step(at_fault), step(rows.len() - 1));
    assert!(
        last < 0.01 * moving,
        "still moving at the end: {last} rad per cycle against {moving} when the e-stop opened"
    );
    assert!(
        !pins.brake.is_high(),
        "the brake output dropped after the drives were off"
    );
    let safety = report.safety.expect("the chain's report");
    assert_eq!(safety.counters.stops, 1);
}
