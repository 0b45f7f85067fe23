//! The safety chain over scripted pins (embedded-hal-mock): every read and write of every cycle
//! is expected in order, so the test also checks that a cycle reads each input once, toggles
//! the watchdog once and writes the brake once, and that `reset` and `may_start` read fresh.
//!
//! One long run through the transitions (power-up, reset, start, an e-stop in category 1, the
//! latch, a refused reset, an enable read error, the held watchdog), then short cases.

use embedded_hal_mock::eh1::MockError;
use embedded_hal_mock::eh1::digital::{Mock, State, Transaction};
use rl_drivers::safety::{
    ChainState, PinId, PinName, PinRole, SafetyChain, SafetyConfig, StopCategory, StopReason,
    Verdict,
};
use std::io::ErrorKind;

use State::{High, Low};

/// Clones of the four mocks the chain holds; each `expect_*` sets the transactions of the next
/// call after checking that the previous ones were all consumed.
struct Pins {
    estop: Mock,
    enable: Mock,
    watchdog: Mock,
    brake: Mock,
    /// The level the watchdog is written next.
    watchdog_next: State,
}

fn get(state: State) -> Transaction {
    Transaction::get(state)
}

fn read_error() -> Transaction {
    Transaction::get(High).with_error(MockError::Io(ErrorKind::BrokenPipe))
}

impl Pins {
    fn new() -> Self {
        Self {
            estop: Mock::new(&[]),
            enable: Mock::new(&[]),
            watchdog: Mock::new(&[]),
            brake: Mock::new(&[]),
            watchdog_next: High,
        }
    }

    /// One cycle: the inputs read these, the watchdog toggles, the brake is written `brake`.
    fn expect_cycle(&mut self, estop: Transaction, enable: Transaction, brake: State) {
        self.estop.update_expectations(&[estop]);
        self.enable.update_expectations(&[enable]);
        let level = self.watchdog_next;
        self.watchdog
            .update_expectations(&[Transaction::set(level)]);
        self.watchdog_next = if level == High { Low } else { High };
        self.brake.update_expectations(&[Transaction::set(brake)]);
    }

    /// A cycle with the watchdog held (no write).
    fn expect_cycle_held(&mut self, estop: State, enable: State, brake: State) {
        self.estop.update_expectations(&[get(estop)]);
        self.enable.update_expectations(&[get(enable)]);
        self.watchdog.update_expectations(&[]);
        self.brake.update_expectations(&[Transaction::set(brake)]);
    }

    /// `samples` fresh readings of both inputs (reset, may_start), no writes.
    fn expect_samples(&mut self, samples: usize) {
        let reads = vec![get(High); samples];
        self.estop.update_expectations(&reads);
        self.enable.update_expectations(&reads);
        self.watchdog.update_expectations(&[]);
        self.brake.update_expectations(&[]);
    }

    /// No pin access at all.
    fn expect_nothing(&mut self) {
        self.expect_samples(0);
    }

    fn done(&mut self) {
        self.estop.done();
        self.enable.done();
        self.watchdog.done();
        self.brake.done();
    }
}

fn name(text: &str) -> PinName {
    PinName::new(text).unwrap()
}

fn config() -> SafetyConfig {
    let mut config = SafetyConfig {
        category: StopCategory::One,
        max_cat1_cycles: 50,
        start_samples: 2,
        ..SafetyConfig::default()
    };
    config.estop.name = name("gpiochip0:17");
    config.estop.debounce.close_cycles = 3;
    config.enable.name = name("gpiochip0:22");
    config.enable.debounce.close_cycles = 3;
    config.brake.name = name("gpiochip0:27");
    config.watchdog.name = name("gpiochip0:5");
    config
}

type Chain = SafetyChain<Mock, Mock, Mock, Mock>;

fn chain(pins: &Pins, config: SafetyConfig) -> Chain {
    SafetyChain::new(config, pins.estop.clone(), pins.watchdog.clone())
        .with_enable(pins.enable.clone())
        .with_brake(pins.brake.clone())
}

fn estop() -> PinId {
    PinId {
        role: PinRole::EStop,
        name: name("gpiochip0:17"),
    }
}

fn enable() -> PinId {
    PinId {
        role: PinRole::Enable,
        name: name("gpiochip0:22"),
    }
}

#[test]
fn a_run_through_every_transition() {
    let mut pins = Pins::new();
    let mut chain = chain(&pins, config());

    // Power-up: open and latched until the inputs have read closed for close_cycles.
    pins.expect_nothing();
    assert_eq!(
        chain.may_start(),
        Err(StopReason::EStopOpen { pin: estop() })
    );
    assert_eq!(chain.reset(), Err(StopReason::EStopOpen { pin: estop() }));
    for i in 0..3 {
        assert_eq!(chain.state(), ChainState::Open, "cycle {i}");
        pins.expect_cycle(get(High), get(High), Low);
        assert_eq!(chain.cycle(false), Verdict::Stopped);
    }
    assert_eq!(chain.state(), ChainState::Latched);
    pins.expect_nothing();
    assert_eq!(chain.may_start(), Err(StopReason::Latched));

    // The operator's reset reads fresh, once; may_start samples twice.
    pins.expect_samples(1);
    chain.reset().unwrap();
    assert_eq!(chain.state(), ChainState::Ready);
    pins.expect_samples(2);
    chain.may_start().unwrap();

    // Running: the brake is energised while the drives are on.
    pins.expect_cycle(get(High), get(High), Low);
    assert_eq!(chain.cycle(false), Verdict::Run);
    for _ in 0..3 {
        pins.expect_cycle(get(High), get(High), High);
        assert_eq!(chain.cycle(true), Verdict::Run);
    }

    // E-stop: category 1 holds the brake until the drives are reported off.
    pins.expect_cycle(get(Low), get(High), High);
    assert_eq!(
        chain.cycle(true),
        Verdict::Stop {
            category: StopCategory::One,
            reason: StopReason::EStopOpen { pin: estop() }
        }
    );
    pins.expect_cycle(get(Low), get(High), High);
    assert_eq!(chain.cycle(true), Verdict::Stopped);
    pins.expect_cycle(get(Low), get(High), Low);
    assert_eq!(chain.cycle(false), Verdict::Stopped);
    assert_eq!(chain.state(), ChainState::Open);

    // Reset while open is refused without touching a pin.
    pins.expect_nothing();
    assert_eq!(chain.reset(), Err(StopReason::EStopOpen { pin: estop() }));

    // Released e-stop: latched, never running again by itself.
    for _ in 0..3 {
        pins.expect_cycle(get(High), get(High), Low);
        assert_eq!(chain.cycle(true), Verdict::Stopped);
    }
    assert_eq!(chain.state(), ChainState::Latched);
    for _ in 0..5 {
        pins.expect_cycle(get(High), get(High), Low);
        assert_eq!(chain.cycle(true), Verdict::Stopped);
    }
    pins.expect_samples(1);
    chain.reset().unwrap();
    pins.expect_cycle(get(High), get(High), High);
    assert_eq!(chain.cycle(true), Verdict::Run);

    // Enable released: stop, refused reset, latched after it is held again.
    pins.expect_cycle(get(High), get(Low), High);
    assert_eq!(
        chain.cycle(true),
        Verdict::Stop {
            category: StopCategory::One,
            reason: StopReason::EnableReleased { pin: enable() }
        }
    );
    pins.expect_nothing();
    assert_eq!(
        chain.reset(),
        Err(StopReason::EnableReleased { pin: enable() })
    );
    for _ in 0..3 {
        pins.expect_cycle(get(High), get(High), Low);
        assert_eq!(chain.cycle(false), Verdict::Stopped);
    }
    pins.expect_samples(1);
    chain.reset().unwrap();

    // A read error on the enable: category 0 whatever the configuration, the brake drops now.
    pins.expect_cycle(get(High), get(High), High);
    assert_eq!(chain.cycle(true), Verdict::Run);
    pins.expect_cycle(get(High), read_error(), Low);
    assert_eq!(
        chain.cycle(true),
        Verdict::Stop {
            category: StopCategory::Zero,
            reason: StopReason::PinReadError { pin: enable() }
        }
    );
    assert_eq!(chain.state(), ChainState::Fault);

    // The end of the run: the watchdog is held low, no more writes to it.
    pins.watchdog.update_expectations(&[Transaction::set(Low)]);
    pins.estop.update_expectations(&[]);
    pins.enable.update_expectations(&[]);
    pins.brake.update_expectations(&[]);
    chain.stop_watchdog();
    for _ in 0..3 {
        pins.expect_cycle_held(High, High, Low);
        assert_eq!(chain.cycle(true), Verdict::Stopped);
    }

    let counters = chain.counters();
    assert_eq!(counters.cycles, 28);
    assert_eq!(counters.stops, 3);
    assert_eq!(counters.read_errors, 1);
    assert_eq!(counters.write_errors, 0);
    pins.expect_nothing();
    pins.done();
}

#[test]
fn a_wire_break_stops_in_the_first_cycle_and_names_the_pin() {
    let mut pins = Pins::new();
    let config = SafetyConfig {
        category: StopCategory::Zero,
        ..config()
    };
    let mut chain = chain(&pins, config);
    for _ in 0..3 {
        pins.expect_cycle(get(High), get(High), Low);
        chain.cycle(false);
    }
    pins.expect_samples(1);
    chain.reset().unwrap();
    pins.expect_cycle(get(High), get(High), High);
    assert_eq!(chain.cycle(true), Verdict::Run);
    // A broken wire reads low (the pull-down wins): open, brake dropped in the same cycle.
    pins.expect_cycle(get(Low), get(High), Low);
    let verdict = chain.cycle(true);
    let Verdict::Stop { category, reason } = verdict else {
        panic!("expected a stop, got {verdict:?}");
    };
    assert_eq!(category, StopCategory::Zero);
    assert_eq!(
        reason.to_string(),
        "emergency stop: e-stop input gpiochip0:17 reads open (button pressed, guard open or wire broken)"
    );
    pins.expect_nothing();
    pins.done();
}

#[test]
fn write_errors_fail_safe_and_are_counted() {
    let mut pins = Pins::new();
    let mut chain = chain(&pins, config());
    for _ in 0..3 {
        pins.expect_cycle(get(High), get(High), Low);
        chain.cycle(false);
    }
    pins.expect_samples(1);
    chain.reset().unwrap();

    // The watchdog write fails: stop in category 0, the brake drops in the same cycle.
    pins.estop.update_expectations(&[get(High)]);
    pins.enable.update_expectations(&[get(High)]);
    let failed = Transaction::set(pins.watchdog_next);
    pins.watchdog
        .update_expectations(&[failed.with_error(MockError::Io(ErrorKind::BrokenPipe))]);
    pins.brake.update_expectations(&[Transaction::set(Low)]);
    assert_eq!(
        chain.cycle(true),
        Verdict::Stop {
            category: StopCategory::Zero,
            reason: StopReason::PinWriteError {
                pin: chain.pin_id(PinRole::Watchdog)
            }
        }
    );
    assert_eq!(chain.state(), ChainState::Fault);
    assert_eq!(chain.counters().write_errors, 1);
    assert_eq!(
        chain.fault().unwrap().to_string(),
        "write error on watchdog output gpiochip0:5"
    );
    // The watchdog toggles again (the failed level is retried); reset clears the fault.
    pins.expect_cycle(get(High), get(High), Low);
    assert_eq!(chain.cycle(true), Verdict::Stopped);
    pins.expect_samples(1);
    chain.reset().unwrap();
    pins.expect_nothing();
    pins.done();
}
