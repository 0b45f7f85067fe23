//! The chain's configuration: per pin a name and an active level, the debouncing of the inputs,
//! the stop category and its bound, the sampling before a start. All `Copy`, no allocation.

use core::fmt;

use super::pin::{PinName, PinRole};
use super::verdict::StopCategory;

/// A digital level.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Level {
    /// Logic high.
    #[default]
    High,
    /// Logic low.
    Low,
}

impl Level {
    /// The level a pin that reads `is_high` has.
    pub const fn from_high(is_high: bool) -> Self {
        if is_high { Level::High } else { Level::Low }
    }

    /// The other level.
    pub const fn inverted(self) -> Self {
        match self {
            Level::High => Level::Low,
            Level::Low => Level::High,
        }
    }
}

impl fmt::Display for Level {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Level::High => "high",
            Level::Low => "low",
        })
    }
}

/// Cycle-count debouncing of an input, asymmetric on purpose: **opening is fast, closing is
/// slow**. The debounced state turns to open after `open_cycles` consecutive open readings and
/// back to closed after `close_cycles` consecutive closed readings; one reading of the current
/// state restarts the count. A value of 0 is read as 1 (the next reading decides).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DebounceConfig {
    /// Consecutive open (stop) readings before the input counts as open. Default
    /// [`DEFAULT_OPEN_CYCLES`] (1: the first open reading stops at once). Raise it only to ride
    /// out one-cycle glitches on a noisy line; every extra cycle delays the stop by one period.
    pub open_cycles: u16,
    /// Consecutive closed readings before the input counts as closed again. Default
    /// [`DEFAULT_CLOSE_CYCLES`]: a contact that bounces while released must settle before a
    /// [`reset`](super::SafetyChain::reset) is accepted.
    pub close_cycles: u16,
}

/// Default [`DebounceConfig::open_cycles`]: stop on the first open reading.
pub const DEFAULT_OPEN_CYCLES: u16 = 1;
/// Default [`DebounceConfig::close_cycles`].
pub const DEFAULT_CLOSE_CYCLES: u16 = 10;

impl Default for DebounceConfig {
    fn default() -> Self {
        Self {
            open_cycles: DEFAULT_OPEN_CYCLES,
            close_cycles: DEFAULT_CLOSE_CYCLES,
        }
    }
}

/// One input of the chain (the e-stop or the enable).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct InputConfig {
    /// The pin's name in messages, such as `gpiochip0:17`.
    pub name: PinName,
    /// The level that means closed (e-stop: chain closed, motion allowed) or held (enable).
    /// Default high: a normally-closed contact pulls the line high, a broken wire reads low.
    pub closed_level: Level,
    /// Debouncing by cycle count.
    pub debounce: DebounceConfig,
}

impl InputConfig {
    /// An input named `name`, closed when high, with the default debouncing.
    pub const fn named(name: PinName) -> Self {
        Self {
            name,
            closed_level: Level::High,
            debounce: DebounceConfig {
                open_cycles: DEFAULT_OPEN_CYCLES,
                close_cycles: DEFAULT_CLOSE_CYCLES,
            },
        }
    }
}

/// One output of the chain (the brake or the watchdog).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct OutputConfig {
    /// The pin's name in messages.
    pub name: PinName,
    /// The level that energises the output (brake released, contactor closed). Default high.
    pub active_level: Level,
}

impl OutputConfig {
    /// An output named `name`, energised when high.
    pub const fn named(name: PinName) -> Self {
        Self {
            name,
            active_level: Level::High,
        }
    }
}

/// Default [`SafetyConfig::max_cat1_cycles`]: half a second at 1 kHz.
pub const DEFAULT_MAX_CAT1_CYCLES: u32 = 500;
/// Default [`SafetyConfig::start_samples`].
pub const DEFAULT_START_SAMPLES: u8 = 3;

/// The whole chain's configuration. [`Default`] gives: e-stop named `estop`, closed when high;
/// enable named `enable`, held when high; both debounced with open after 1 cycle and closed
/// after 10; brake named `brake`, energised when high; watchdog named `watchdog`, resting low;
/// stop category 0; category-1 bound 500 cycles; 3 samples before a start.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SafetyConfig {
    /// The emergency-stop input (normally closed).
    pub estop: InputConfig,
    /// The enable (dead-man) input, used only when the chain has one
    /// ([`SafetyChain::with_enable`](super::SafetyChain::with_enable)).
    pub enable: InputConfig,
    /// The brake / contactor output, used only when the chain has one
    /// ([`SafetyChain::with_brake`](super::SafetyChain::with_brake)).
    pub brake: OutputConfig,
    /// The watchdog (charge pump) output. It toggles between both levels, starting with
    /// `active_level`; [`stop_watchdog`](super::SafetyChain::stop_watchdog) holds it at the
    /// other level.
    pub watchdog: OutputConfig,
    /// How the controller stops when the e-stop opens or the enable is released. Pin errors
    /// always stop in category 0.
    pub category: StopCategory,
    /// Category 1 only: the most cycles the brake output stays energised after a stop (the
    /// stop cycle counts as the first) while the controller still reports the drives on.
    /// 0 drops it in the stop cycle, as category 0 does.
    pub max_cat1_cycles: u32,
    /// Fresh readings of each input that [`may_start`](super::SafetyChain::may_start) takes
    /// back to back; all must read closed. 0 is read as 1.
    pub start_samples: u8,
}

impl Default for SafetyConfig {
    fn default() -> Self {
        Self {
            estop: InputConfig::named(PinRole::EStop.default_name()),
            enable: InputConfig::named(PinRole::Enable.default_name()),
            brake: OutputConfig::named(PinRole::Brake.default_name()),
            watchdog: OutputConfig::named(PinRole::Watchdog.default_name()),
            category: StopCategory::Zero,
            max_cat1_cycles: DEFAULT_MAX_CAT1_CYCLES,
            start_samples: DEFAULT_START_SAMPLES,
        }
    }
}
