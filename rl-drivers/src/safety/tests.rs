//! Unit tests of the chain over hand-written fake pins whose levels and failures the test sets
//! between cycles.

use std::cell::Cell;
use std::rc::Rc;
use std::vec::Vec;

use embedded_hal::digital::{ErrorKind, ErrorType, InputPin, OutputPin};

use super::*;

#[derive(Debug)]
struct PinError;

impl embedded_hal::digital::Error for PinError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// An input whose level and failure the test sets through shared cells.
#[derive(Clone, Default)]
struct FakeInput {
    high: Rc<Cell<bool>>,
    fail: Rc<Cell<bool>>,
}

impl ErrorType for FakeInput {
    type Error = PinError;
}

impl InputPin for FakeInput {
    fn is_high(&mut self) -> Result<bool, PinError> {
        if self.fail.get() {
            Err(PinError)
        } else {
            Ok(self.high.get())
        }
    }
    fn is_low(&mut self) -> Result<bool, PinError> {
        self.is_high().map(|h| !h)
    }
}

/// An output that records every level written.
#[derive(Clone, Default)]
struct FakeOutput {
    written: Rc<std::cell::RefCell<Vec<bool>>>,
    fail: Rc<Cell<bool>>,
}

impl FakeOutput {
    fn last(&self) -> Option<bool> {
        self.written.borrow().last().copied()
    }
    fn count(&self) -> usize {
        self.written.borrow().len()
    }
}

impl ErrorType for FakeOutput {
    type Error = PinError;
}

impl OutputPin for FakeOutput {
    fn set_low(&mut self) -> Result<(), PinError> {
        if self.fail.get() {
            return Err(PinError);
        }
        self.written.borrow_mut().push(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), PinError> {
        if self.fail.get() {
            return Err(PinError);
        }
        self.written.borrow_mut().push(true);
        Ok(())
    }
}

struct Rig {
    chain: SafetyChain<FakeInput, FakeOutput, FakeInput, FakeOutput>,
    estop: FakeInput,
    enable: FakeInput,
    watchdog: FakeOutput,
    brake: FakeOutput,
}

fn rig(config: SafetyConfig) -> Rig {
    let (estop, enable) = (FakeInput::default(), FakeInput::default());
    let (watchdog, brake) = (FakeOutput::default(), FakeOutput::default());
    estop.high.set(true);
    enable.high.set(true);
    let chain = SafetyChain::new(config, estop.clone(), watchdog.clone())
        .with_enable(enable.clone())
        .with_brake(brake.clone());
    Rig {
        chain,
        estop,
        enable,
        watchdog,
        brake,
    }
}

/// Powered up, closed long enough, reset, started, running with the drives on.
fn running(config: SafetyConfig) -> Rig {
    let mut r = rig(config);
    for _ in 0..config.estop.debounce.close_cycles {
        assert_eq!(r.chain.cycle(false), Verdict::Stopped);
    }
    r.chain.reset().unwrap();
    r.chain.may_start().unwrap();
    assert_eq!(r.chain.cycle(true), Verdict::Run);
    assert_eq!(r.brake.last(), Some(true));
    r
}

fn estop_id() -> PinId {
    PinId {
        role: PinRole::EStop,
        name: PinRole::EStop.default_name(),
    }
}

#[test]
fn powers_up_open_and_latched() {
    let mut r = rig(SafetyConfig::default());
    assert_eq!(r.chain.state(), ChainState::Open);
    assert_eq!(
        r.chain.may_start(),
        Err(StopReason::EStopOpen { pin: estop_id() })
    );
    for _ in 0..9 {
        assert_eq!(r.chain.cycle(true), Verdict::Stopped);
        assert_eq!(r.chain.state(), ChainState::Open);
        assert_eq!(
            r.brake.last(),
            Some(false),
            "no brake release before a reset"
        );
    }
    assert_eq!(r.chain.cycle(true), Verdict::Stopped);
    assert_eq!(r.chain.state(), ChainState::Latched);
    assert_eq!(r.chain.may_start(), Err(StopReason::Latched));
    r.chain.reset().unwrap();
    assert_eq!(r.chain.state(), ChainState::Ready);
    assert_eq!(r.chain.counters().stops, 0);
}

#[test]
fn category_0_stops_and_drops_the_brake_in_the_first_open_cycle() {
    let mut r = running(SafetyConfig::default());
    r.estop.high.set(false);
    assert_eq!(
        r.chain.cycle(true),
        Verdict::Stop {
            category: StopCategory::Zero,
            reason: StopReason::EStopOpen { pin: estop_id() }
        }
    );
    assert_eq!(r.brake.last(), Some(false));
    assert!(!r.chain.brake_energised());
    assert_eq!(r.chain.cycle(true), Verdict::Stopped);
    assert_eq!(r.brake.last(), Some(false));
    assert_eq!(r.chain.counters().stops, 1);
    assert_eq!(r.chain.state(), ChainState::Open);
}

#[test]
fn category_1_holds_the_brake_until_the_drives_are_off() {
    let config = SafetyConfig {
        category: StopCategory::One,
        max_cat1_cycles: 100,
        ..SafetyConfig::default()
    };
    let mut r = running(config);
    r.estop.high.set(false);
    assert!(matches!(
        r.chain.cycle(true),
        Verdict::Stop {
            category: StopCategory::One,
            ..
        }
    ));
    assert_eq!(r.brake.last(), Some(true), "controlled stop: still powered");
    for _ in 0..5 {
        assert_eq!(r.chain.cycle(true), Verdict::Stopped);
        assert_eq!(r.brake.last(), Some(true));
    }
    assert_eq!(r.chain.cycle(false), Verdict::Stopped);
    assert_eq!(r.brake.last(), Some(false));
    // Dropped for good: drives on again does not re-energise it.
    assert_eq!(r.chain.cycle(true), Verdict::Stopped);
    assert_eq!(r.brake.last(), Some(false));
}

#[test]
fn category_1_drops_the_brake_after_the_bound() {
    let config = SafetyConfig {
        category: StopCategory::One,
        max_cat1_cycles: 3,
        ..SafetyConfig::default()
    };
    let mut r = running(config);
    r.estop.high.set(false);
    let mut levels = Vec::new();
    for _ in 0..5 {
        r.chain.cycle(true);
        levels.push(r.brake.last().unwrap());
    }
    assert_eq!(levels, [true, true, true, false, false]);
}

#[test]
fn a_one_cycle_glitch_does_not_stop_with_two_open_cycles() {
    let mut config = SafetyConfig::default();
    config.estop.debounce.open_cycles = 2;
    let mut r = running(config);
    r.estop.high.set(false);
    assert_eq!(r.chain.cycle(true), Verdict::Run);
    r.estop.high.set(true);
    assert_eq!(r.chain.cycle(true), Verdict::Run);
    r.estop.high.set(false);
    assert_eq!(r.chain.cycle(true), Verdict::Run);
    assert!(matches!(r.chain.cycle(true), Verdict::Stop { .. }));
}

#[test]
fn releasing_the_enable_stops_and_closing_again_does_not_restart() {
    let mut r = running(SafetyConfig::default());
    r.enable.high.set(false);
    let pin = r.chain.pin_id(PinRole::Enable);
    assert_eq!(
        r.chain.cycle(true),
        Verdict::Stop {
            category: StopCategory::Zero,
            reason: StopReason::EnableReleased { pin }
        }
    );
    assert_eq!(r.chain.state(), ChainState::EnableReleased);
    assert_eq!(r.chain.reset(), Err(StopReason::EnableReleased { pin }));
    r.enable.high.set(true);
    for _ in 0..20 {
        assert_eq!(r.chain.cycle(true), Verdict::Stopped);
    }
    assert_eq!(r.chain.state(), ChainState::Latched);
    r.chain.reset().unwrap();
    assert_eq!(r.chain.cycle(true), Verdict::Run);
}

#[test]
fn reset_waits_for_close_cycles() {
    let mut r = running(SafetyConfig::default());
    r.estop.high.set(false);
    r.chain.cycle(true);
    r.estop.high.set(true);
    for _ in 0..9 {
        r.chain.cycle(false);
        assert_eq!(
            r.chain.reset(),
            Err(StopReason::EStopOpen { pin: estop_id() })
        );
    }
    r.chain.cycle(false);
    r.chain.reset().unwrap();
}

#[test]
fn may_start_samples_the_pins_fresh() {
    let mut r = running(SafetyConfig::default());
    // Open between cycles: the debounced state has not seen it yet, the fresh reading has.
    r.estop.high.set(false);
    assert_eq!(
        r.chain.may_start(),
        Err(StopReason::EStopOpen { pin: estop_id() })
    );
    assert!(r.chain.is_latched());
    assert_eq!(r.chain.counters().stops, 1);
    assert_eq!(r.chain.cycle(true), Verdict::Stopped);
}

#[test]
fn a_read_error_is_open_counted_and_a_fault() {
    let mut r = running(SafetyConfig::default());
    r.estop.fail.set(true);
    assert_eq!(
        r.chain.cycle(true),
        Verdict::Stop {
            category: StopCategory::Zero,
            reason: StopReason::PinReadError { pin: estop_id() }
        }
    );
    assert_eq!(r.brake.last(), Some(false));
    assert_eq!(r.chain.state(), ChainState::Fault);
    assert_eq!(r.chain.counters().read_errors, 1);
    assert_eq!(
        r.chain.reset(),
        Err(StopReason::EStopOpen { pin: estop_id() })
    );
    r.estop.fail.set(false);
    for _ in 0..10 {
        r.chain.cycle(false);
    }
    assert_eq!(r.chain.state(), ChainState::Fault);
    r.chain.reset().unwrap();
    assert_eq!(r.chain.state(), ChainState::Ready);
}

#[test]
fn a_watchdog_write_error_stops_in_category_0() {
    let config = SafetyConfig {
        category: StopCategory::One,
        ..SafetyConfig::default()
    };
    let mut r = running(config);
    r.watchdog.fail.set(true);
    let pin = r.chain.pin_id(PinRole::Watchdog);
    assert_eq!(
        r.chain.cycle(true),
        Verdict::Stop {
            category: StopCategory::Zero,
            reason: StopReason::PinWriteError { pin }
        }
    );
    assert_eq!(r.brake.last(), Some(false));
    assert_eq!(r.chain.counters().write_errors, 1);
    assert_eq!(r.chain.state(), ChainState::Fault);
}

#[test]
fn a_brake_write_error_stops() {
    let mut r = running(SafetyConfig::default());
    r.brake.fail.set(true);
    let pin = r.chain.pin_id(PinRole::Brake);
    assert_eq!(
        r.chain.cycle(true),
        Verdict::Stop {
            category: StopCategory::Zero,
            reason: StopReason::PinWriteError { pin }
        }
    );
    // The write and the retry to drop it both failed.
    assert_eq!(r.chain.counters().write_errors, 2);
    assert!(!r.chain.brake_energised());
}

#[test]
fn the_watchdog_toggles_every_cycle_until_stopped() {
    let mut r = running(SafetyConfig::default());
    let before = r.watchdog.count();
    let mut levels = Vec::new();
    for _ in 0..4 {
        r.chain.cycle(true);
        levels.push(r.watchdog.last().unwrap());
    }
    assert_eq!(r.watchdog.count(), before + 4);
    assert!(levels.windows(2).all(|w| w[0] != w[1]), "{levels:?}");
    r.chain.stop_watchdog();
    assert_eq!(r.watchdog.last(), Some(false));
    let held = r.watchdog.count();
    for _ in 0..4 {
        r.chain.cycle(true);
    }
    assert_eq!(r.watchdog.count(), held, "held steady: no more writes");
}

#[test]
fn the_brake_follows_drives_on_while_ready() {
    let mut r = running(SafetyConfig::default());
    assert_eq!(r.chain.cycle(false), Verdict::Run);
    assert_eq!(r.brake.last(), Some(false));
    assert_eq!(r.chain.cycle(true), Verdict::Run);
    assert_eq!(r.brake.last(), Some(true));
}

#[test]
fn low_closed_level_and_no_optional_pins() {
    let mut config = SafetyConfig::default();
    config.estop.closed_level = Level::Low;
    config.estop.debounce.close_cycles = 1;
    let estop = FakeInput::default(); // reads low: closed
    let watchdog = FakeOutput::default();
    let mut chain = SafetyChain::new(config, estop.clone(), watchdog);
    chain.cycle(false);
    chain.reset().unwrap();
    assert_eq!(chain.cycle(true), Verdict::Run);
    estop.high.set(true); // a pulled-up broken wire
    assert!(matches!(chain.cycle(true), Verdict::Stop { .. }));
}

#[test]
fn reasons_name_the_pin() {
    let pin = PinId {
        role: PinRole::EStop,
        name: PinName::new("gpiochip0:17").unwrap(),
    };
    let text = StopReason::EStopOpen { pin }.to_string();
    assert!(text.contains("e-stop input gpiochip0:17"), "{text}");
    let text = StopReason::PinWriteError {
        pin: PinId {
            role: PinRole::Brake,
            name: PinName::new("gpiochip0:27").unwrap(),
        },
    }
    .to_string();
    assert_eq!(text, "write error on brake output gpiochip0:27");
}
