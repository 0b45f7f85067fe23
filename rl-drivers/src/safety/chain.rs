//! The [`SafetyChain`]: per cycle it reads the e-stop and enable inputs, debounces them, toggles
//! the watchdog output, drives the brake output and tells the controller whether it may move
//! ([`Verdict`]). Generic over `embedded_hal::digital` pins; `no_std`, no allocation, no panics.

use embedded_hal::digital::{InputPin, OutputPin};

use super::config::{Level, SafetyConfig};
use super::debounce::Debouncer;
use super::pin::{NoPin, PinId, PinRole};
use super::state::{Action, ChainState};
use super::verdict::{StopCategory, StopReason, Verdict};

/// What the chain has counted since it was made. All counters saturate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SafetyCounters {
    /// Calls of [`SafetyChain::cycle`].
    pub cycles: u64,
    /// Stops: each time the chain latched (a cycle returned [`Verdict::Stop`], or a
    /// [`may_start`](SafetyChain::may_start) or [`reset`](SafetyChain::reset) found an open
    /// input or a pin error while the chain was ready). Errors while already latched are not
    /// counted again here.
    pub stops: u64,
    /// Input readings that failed.
    pub read_errors: u64,
    /// Output writes that failed.
    pub write_errors: u64,
}

/// An emergency-stop chain over digital pins, checked once per control cycle.
///
/// - **E-stop** `EStop` (required): normally closed; the chain is closed only while it reads
///   [`closed_level`](super::InputConfig::closed_level). A pressed button, an open guard and a
///   broken wire all read open and stop. Opening takes effect after
///   [`open_cycles`](super::DebounceConfig::open_cycles) consecutive readings (default 1: at
///   once); closing after [`close_cycles`](super::DebounceConfig::close_cycles) (default 10).
/// - **Enable** `Enable` (optional, [`with_enable`](Self::with_enable)): a dead-man input,
///   debounced the same way; releasing it stops.
/// - **Watchdog** `Watchdog` (required): toggled every cycle, a charge pump for an external
///   relay that drops when the toggling stops (the loop stopped or stalled).
/// - **Brake** `Brake` (optional, [`with_brake`](Self::with_brake)): energised (brake released,
///   contactor closed) only while the chain allows motion and the controller reports the
///   drives on; de-energised on any stop (category 0: in the stop cycle; category 1: when the
///   drives are reported off or after [`max_cat1_cycles`](super::SafetyConfig::max_cat1_cycles)).
///
/// Fail safe: a pin that cannot be read counts as open, a pin that cannot be written stops;
/// both are counted, fault the chain ([`ChainState::Fault`]) and stop in category 0.
///
/// Every stop latches: releasing the e-stop never restarts motion by itself. After the inputs
/// read closed again the chain is [`ChainState::Latched`] until [`reset`](Self::reset). A new
/// chain is latched too (no automatic start at power-up): cycle it until the e-stop has read
/// closed for `close_cycles`, then reset it.
///
/// ```
/// use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
/// use rl_drivers::safety::{SafetyChain, SafetyConfig, Verdict, ChainState};
/// # struct Pin(bool);
/// # impl ErrorType for Pin { type Error = core::convert::Infallible; }
/// # impl InputPin for Pin {
/// #     fn is_high(&mut self) -> Result<bool, Self::Error> { Ok(self.0) }
/// #     fn is_low(&mut self) -> Result<bool, Self::Error> { Ok(!self.0) }
/// # }
/// # impl OutputPin for Pin {
/// #     fn set_high(&mut self) -> Result<(), Self::Error> { self.0 = true; Ok(()) }
/// #     fn set_low(&mut self) -> Result<(), Self::Error> { self.0 = false; Ok(()) }
/// # }
/// let (estop, watchdog, brake) = (Pin(true), Pin(false), Pin(false)); // e.g. Linux GPIO lines
/// let mut chain = SafetyChain::new(SafetyConfig::default(), estop, watchdog).with_brake(brake);
/// while chain.state() == ChainState::Open {
///     chain.cycle(false); // power-up: wait until the e-stop has read closed long enough
/// }
/// chain.reset().expect("chain closed"); // the operator's reset
/// chain.may_start().expect("chain closed");
/// for _ in 0..100 {
///     match chain.cycle(true) {
///         Verdict::Run => { /* compute and send the next set-points */ }
///         Verdict::Stop { category, reason } => { /* stop in `category`, log `reason` */ }
///         Verdict::Stopped => { /* stay at rest */ }
///     }
/// }
/// chain.stop_watchdog();
/// ```
#[derive(Debug)]
pub struct SafetyChain<EStop, Watchdog, Enable = NoPin, Brake = NoPin> {
    config: SafetyConfig,
    estop: EStop,
    watchdog: Watchdog,
    enable: Option<Enable>,
    brake: Option<Brake>,
    estop_debounce: Debouncer,
    enable_debounce: Debouncer,
    /// Stopped (or powered up) and not reset since.
    latched: bool,
    /// The stop that latched the chain (none at power-up).
    last_stop: Option<StopReason>,
    /// The first pin error since the last reset.
    fault: Option<StopReason>,
    /// The category of the stop in progress.
    stop_category: StopCategory,
    /// Cycles since the stop cycle (0 in the stop cycle).
    stop_age: u32,
    /// The brake output has dropped since the stop (it stays dropped until a reset).
    brake_dropped: bool,
    brake_energised: bool,
    watchdog_running: bool,
    /// The level the watchdog is written next cycle.
    watchdog_next: Level,
    counters: SafetyCounters,
}

impl<EStop, Watchdog> SafetyChain<EStop, Watchdog, NoPin, NoPin>
where
    EStop: InputPin,
    Watchdog: OutputPin,
{
    /// A chain of an e-stop input and a watchdog output, without enable input or brake output
    /// (add them with [`with_enable`](Self::with_enable) and [`with_brake`](Self::with_brake)).
    /// Touches no pin: the first [`cycle`](Self::cycle) reads and writes them. Starts open and
    /// latched.
    pub fn new(config: SafetyConfig, estop: EStop, watchdog: Watchdog) -> Self {
        Self {
            estop_debounce: Debouncer::new(config.estop.debounce),
            enable_debounce: Debouncer::new(config.enable.debounce),
            watchdog_next: config.watchdog.active_level,
            config,
            estop,
            watchdog,
            enable: None,
            brake: None,
            latched: true,
            last_stop: None,
            fault: None,
            stop_category: config.category,
            stop_age: 0,
            brake_dropped: true,
            brake_energised: false,
            watchdog_running: true,
            counters: SafetyCounters::default(),
        }
    }
}

impl<EStop, Watchdog, Brake> SafetyChain<EStop, Watchdog, NoPin, Brake> {
    /// The same chain with an enable (dead-man) input, configured by
    /// [`SafetyConfig::enable`]. It starts released.
    pub fn with_enable<Enable: InputPin>(
        self,
        enable: Enable,
    ) -> SafetyChain<EStop, Watchdog, Enable, Brake> {
        self.with_optional_pins(|_, brake| (Some(enable), brake))
    }
}

impl<EStop, Watchdog, Enable> SafetyChain<EStop, Watchdog, Enable, NoPin> {
    /// The same chain with a brake / contactor output, configured by [`SafetyConfig::brake`].
    /// It is de-energised until the first cycle that allows motion with the drives on.
    pub fn with_brake<Brake: OutputPin>(
        self,
        brake: Brake,
    ) -> SafetyChain<EStop, Watchdog, Enable, Brake> {
        self.with_optional_pins(|enable, _| (enable, Some(brake)))
    }
}

impl<EStop, Watchdog, Enable, Brake> SafetyChain<EStop, Watchdog, Enable, Brake> {
    /// The same chain, state and all, with its optional pins (enable, brake) replaced by what
    /// `pins` makes of them: the one place the typestate builders move every field.
    fn with_optional_pins<Enable2, Brake2>(
        self,
        pins: impl FnOnce(Option<Enable>, Option<Brake>) -> (Option<Enable2>, Option<Brake2>),
    ) -> SafetyChain<EStop, Watchdog, Enable2, Brake2> {
        let (enable, brake) = pins(self.enable, self.brake);
        SafetyChain {
            config: self.config,
            estop: self.estop,
            watchdog: self.watchdog,
            enable,
            brake,
            estop_debounce: self.estop_debounce,
            enable_debounce: self.enable_debounce,
            latched: self.latched,
            last_stop: self.last_stop,
            fault: self.fault,
            stop_category: self.stop_category,
            stop_age: self.stop_age,
            brake_dropped: self.brake_dropped,
            brake_energised: self.brake_energised,
            watchdog_running: self.watchdog_running,
            watchdog_next: self.watchdog_next,
            counters: self.counters,
        }
    }
}

impl<EStop, Watchdog, Enable, Brake> SafetyChain<EStop, Watchdog, Enable, Brake>
where
    EStop: InputPin,
    Watchdog: OutputPin,
    Enable: InputPin,
    Brake: OutputPin,
{
    /// One control cycle; call it once per period, before the controller commands the drives.
    /// `drives_on` is whether the drives are powered (enabled) right now.
    ///
    /// In order: reads and debounces the inputs, toggles the watchdog, latches a stop if one is
    /// found, drives the brake output, and returns [`Verdict::Run`] while motion may go on,
    /// [`Verdict::Stop`] in the cycle that found a stop, then [`Verdict::Stopped`] until a
    /// [`reset`](Self::reset). Does not allocate, does not panic.
    pub fn cycle(&mut self, drives_on: bool) -> Verdict {
        self.counters.cycles = self.counters.cycles.saturating_add(1);
        let mut found: Option<(StopReason, StopCategory)> = None;

        // Inputs: a failed reading counts as open.
        let estop_closed = match self.estop.is_high() {
            Ok(high) => Level::from_high(high) == self.config.estop.closed_level,
            Err(_) => {
                self.read_error(PinRole::EStop, &mut found);
                false
            }
        };
        self.estop_debounce.update(estop_closed);
        let enable_result = self.enable.as_mut().map(InputPin::is_high);
        if let Some(result) = enable_result {
            let held = match result {
                Ok(high) => Level::from_high(high) == self.config.enable.closed_level,
                Err(_) => {
                    self.read_error(PinRole::Enable, &mut found);
                    false
                }
            };
            self.enable_debounce.update(held);
        }

        // The charge pump: toggled every cycle, whatever the state.
        if self.watchdog_running {
            let level = self.watchdog_next;
            if write_level(&mut self.watchdog, level).is_ok() {
                self.watchdog_next = level.inverted();
            } else {
                self.write_error(PinRole::Watchdog, &mut found);
            }
        }

        // A new stop?
        let mut new_stop = None;
        if !self.latched {
            if found.is_none() {
                found = self
                    .reason_for(self.state())
                    .map(|reason| (reason, self.config.category));
            }
            if let Some((reason, category)) = found {
                self.latch(reason, category);
                new_stop = Some((reason, category));
            }
        }

        // The brake / contactor.
        if self.brake.is_some() && self.drive_brake(drives_on).is_err() {
            let mut failed = None;
            self.write_error(PinRole::Brake, &mut failed);
            if let (false, Some((reason, category))) = (self.latched, failed) {
                self.latch(reason, category);
                new_stop = Some((reason, category));
            }
            // Try once more to drop it.
            self.brake_energised = false;
            if let Some(brake) = self.brake.as_mut() {
                let inactive = self.config.brake.active_level.inverted();
                if write_level(brake, inactive).is_err() {
                    self.counters.write_errors = self.counters.write_errors.saturating_add(1);
                }
            }
        }
        if self.latched {
            self.stop_age = self.stop_age.saturating_add(1);
        }

        match new_stop {
            Some((reason, category)) => Verdict::Stop { category, reason },
            None if self.latched => Verdict::Stopped,
            None => Verdict::Run,
        }
    }

    /// Whether motion may start now: refuses unless the chain is [`ChainState::Ready`]
    /// (the reason says why: e-stop open, enable released, a pin error, or
    /// [`StopReason::Latched`]), then reads the inputs fresh
    /// [`start_samples`](SafetyConfig::start_samples) times back to back; every reading must
    /// succeed and read closed (held). A failed check latches the chain like a stop.
    pub fn may_start(&mut self) -> Result<(), StopReason> {
        let state = self.state();
        if !Action::Start.allowed_in(state) {
            return Err(self.reason_for(state).unwrap_or(StopReason::Latched));
        }
        self.sample_inputs(self.config.start_samples.max(1))
    }

    /// Clears the latch after a stop (the operator's reset). Refused while the e-stop reads
    /// open or the enable is released (debounced: the input must have read closed for
    /// `close_cycles` cycles), and unless one fresh reading of each input succeeds and reads
    /// closed. Also clears a [`ChainState::Fault`]; an output that still cannot be written
    /// faults the chain again in the next cycle. In [`ChainState::Ready`] it changes nothing.
    pub fn reset(&mut self) -> Result<(), StopReason> {
        let state = self.state();
        if !Action::Reset.allowed_in(state) {
            return Err(self.reason_for(state).unwrap_or(StopReason::Latched));
        }
        if !self.estop_debounce.is_closed() {
            return Err(StopReason::EStopOpen {
                pin: self.pin_id(PinRole::EStop),
            });
        }
        if self.enable.is_some() && !self.enable_debounce.is_closed() {
            return Err(StopReason::EnableReleased {
                pin: self.pin_id(PinRole::Enable),
            });
        }
        self.sample_inputs(1)?;
        self.latched = false;
        self.fault = None;
        self.stop_age = 0;
        self.brake_dropped = false;
        Ok(())
    }

    /// Holds the watchdog output steady at its inactive level (the end of a run): the external
    /// relay drops. A failed write is a pin error like any other.
    pub fn stop_watchdog(&mut self) {
        self.watchdog_running = false;
        let inactive = self.config.watchdog.active_level.inverted();
        if write_level(&mut self.watchdog, inactive).is_err() {
            let mut found = None;
            self.write_error(PinRole::Watchdog, &mut found);
            if let (false, Some((reason, category))) = (self.latched, found) {
                self.latch(reason, category);
            }
        }
        self.watchdog_next = self.config.watchdog.active_level;
    }

    /// Toggles the watchdog again from the next cycle on (a new run).
    pub fn start_watchdog(&mut self) {
        self.watchdog_running = true;
    }

    /// Reads each input `samples` times; on the first open reading or error, latches (if not
    /// yet) and says why.
    fn sample_inputs(&mut self, samples: u8) -> Result<(), StopReason> {
        for _ in 0..samples {
            let estop = self.estop.is_high().map(Level::from_high);
            let closed_level = self.config.estop.closed_level;
            self.check_fresh(
                PinRole::EStop,
                estop.map(|l| l == closed_level).map_err(|_| ()),
            )?;
            if let Some(enable) = self.enable.as_mut() {
                let held = enable.is_high().map(Level::from_high);
                let closed_level = self.config.enable.closed_level;
                self.check_fresh(
                    PinRole::Enable,
                    held.map(|l| l == closed_level).map_err(|_| ()),
                )?;
            }
        }
        Ok(())
    }

    fn check_fresh(&mut self, role: PinRole, closed: Result<bool, ()>) -> Result<(), StopReason> {
        let mut found = None;
        match closed {
            Ok(true) => return Ok(()),
            Ok(false) => {
                let pin = self.pin_id(role);
                let reason = if role == PinRole::Enable {
                    self.enable_debounce.force_open();
                    StopReason::EnableReleased { pin }
                } else {
                    self.estop_debounce.force_open();
                    StopReason::EStopOpen { pin }
                };
                found = Some((reason, self.config.category));
            }
            Err(()) => {
                if role == PinRole::Enable {
                    self.enable_debounce.force_open();
                } else {
                    self.estop_debounce.force_open();
                }
                self.read_error(role, &mut found);
            }
        }
        let Some((reason, category)) = found else {
            return Ok(());
        };
        if !self.latched {
            self.latch(reason, category);
        }
        Err(reason)
    }

    /// Decides and writes the brake output.
    fn drive_brake(&mut self, drives_on: bool) -> Result<(), ()> {
        let in_cat1_window = self.latched
            && self.stop_category == StopCategory::One
            && !self.brake_dropped
            && self.stop_age < self.config.max_cat1_cycles;
        let energise =
            drives_on && (Action::ReleaseBrake.allowed_in(self.state()) || in_cat1_window);
        if self.latched && !energise {
            self.brake_dropped = true;
        }
        let level = if energise {
            self.config.brake.active_level
        } else {
            self.config.brake.active_level.inverted()
        };
        let Some(brake) = self.brake.as_mut() else {
            return Ok(());
        };
        write_level(brake, level).map_err(|_| ())?;
        self.brake_energised = energise;
        Ok(())
    }
}

impl<EStop, Watchdog, Enable, Brake> SafetyChain<EStop, Watchdog, Enable, Brake> {
    /// Where the chain is (see [`ChainState`] for the order of priority).
    pub fn state(&self) -> ChainState {
        if self.fault.is_some() {
            ChainState::Fault
        } else if !self.estop_debounce.is_closed() {
            ChainState::Open
        } else if self.enable.is_some() && !self.enable_debounce.is_closed() {
            ChainState::EnableReleased
        } else if self.latched {
            ChainState::Latched
        } else {
            ChainState::Ready
        }
    }

    /// The counters.
    pub fn counters(&self) -> SafetyCounters {
        self.counters
    }

    /// The stop that latched the chain, kept after a reset until the next stop (`None` before
    /// the first stop).
    pub fn last_stop(&self) -> Option<StopReason> {
        self.last_stop
    }

    /// The first pin error since the last reset, if any.
    pub fn fault(&self) -> Option<StopReason> {
        self.fault
    }

    /// Whether the chain is latched (stopped, or powered up, and not reset since).
    pub fn is_latched(&self) -> bool {
        self.latched
    }

    /// Whether the brake output was last written energised (brake released, contactor closed).
    /// Always `false` without a brake output.
    pub fn brake_energised(&self) -> bool {
        self.brake_energised
    }

    /// Whether the watchdog toggles every cycle (until [`stop_watchdog`](Self::stop_watchdog)).
    pub fn watchdog_running(&self) -> bool {
        self.watchdog_running
    }

    /// The debounced e-stop input: `true` = closed.
    pub fn estop_closed(&self) -> bool {
        self.estop_debounce.is_closed()
    }

    /// The debounced enable input: `true` = held (also `true` without an enable input).
    pub fn enable_held(&self) -> bool {
        self.enable.is_none() || self.enable_debounce.is_closed()
    }

    /// The configuration.
    pub fn config(&self) -> &SafetyConfig {
        &self.config
    }

    /// A pin as messages name it.
    pub fn pin_id(&self, role: PinRole) -> PinId {
        let name = match role {
            PinRole::EStop => self.config.estop.name,
            PinRole::Enable => self.config.enable.name,
            PinRole::Brake => self.config.brake.name,
            PinRole::Watchdog => self.config.watchdog.name,
        };
        PinId { role, name }
    }

    /// The pins back: e-stop, watchdog, enable, brake.
    pub fn into_parts(self) -> (EStop, Watchdog, Option<Enable>, Option<Brake>) {
        (self.estop, self.watchdog, self.enable, self.brake)
    }

    /// Why `state` refuses motion (`None` for `Ready`).
    fn reason_for(&self, state: ChainState) -> Option<StopReason> {
        match state {
            ChainState::Ready => None,
            ChainState::Open => Some(StopReason::EStopOpen {
                pin: self.pin_id(PinRole::EStop),
            }),
            ChainState::EnableReleased => Some(StopReason::EnableReleased {
                pin: self.pin_id(PinRole::Enable),
            }),
            ChainState::Latched => Some(StopReason::Latched),
            ChainState::Fault => Some(self.fault.unwrap_or(StopReason::Latched)),
        }
    }

    fn latch(&mut self, reason: StopReason, category: StopCategory) {
        self.latched = true;
        self.last_stop = Some(reason);
        self.stop_category = category;
        self.stop_age = 0;
        self.brake_dropped = category == StopCategory::Zero;
        self.counters.stops = self.counters.stops.saturating_add(1);
    }

    fn read_error(&mut self, role: PinRole, found: &mut Option<(StopReason, StopCategory)>) {
        self.counters.read_errors = self.counters.read_errors.saturating_add(1);
        self.pin_error(StopReason::PinReadError {
            pin: self.pin_id(role),
        });
        found.get_or_insert((
            StopReason::PinReadError {
                pin: self.pin_id(role),
            },
            StopCategory::Zero,
        ));
    }

    fn write_error(&mut self, role: PinRole, found: &mut Option<(StopReason, StopCategory)>) {
        self.counters.write_errors = self.counters.write_errors.saturating_add(1);
        let reason = StopReason::PinWriteError {
            pin: self.pin_id(role),
        };
        self.pin_error(reason);
        found.get_or_insert((reason, StopCategory::Zero));
    }

    /// Faults the chain; a pin error ends a category-1 window (the brake drops).
    fn pin_error(&mut self, reason: StopReason) {
        self.fault.get_or_insert(reason);
        self.brake_dropped = true;
    }
}

fn write_level<P: OutputPin>(pin: &mut P, level: Level) -> Result<(), P::Error> {
    match level {
        Level::High => pin.set_high(),
        Level::Low => pin.set_low(),
    }
}
