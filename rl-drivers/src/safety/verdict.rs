//! What a cycle tells the controller ([`Verdict`]), how to stop ([`StopCategory`]) and why
//! ([`StopReason`]). Small `Copy` types, no allocation.

use core::fmt;

use super::pin::PinId;

/// Stop categories of IEC 60204-1 §9.2.2 that the chain can ask for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum StopCategory {
    /// Uncontrolled stop: power is removed at once. The brake output drops in the cycle that
    /// finds the stop.
    #[default]
    Zero,
    /// Controlled stop: the controller brings the axes to rest with the drives powered, then
    /// power is removed. The brake output drops when the controller reports the drives off
    /// (`drives_on == false`) or after [`max_cat1_cycles`](super::SafetyConfig::max_cat1_cycles),
    /// whichever comes first.
    One,
}

impl fmt::Display for StopCategory {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            StopCategory::Zero => "category 0 (uncontrolled: power removed at once)",
            StopCategory::One => "category 1 (controlled: come to rest, then remove power)",
        })
    }
}

/// Why the chain stopped, or why it refuses a start or a reset.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StopReason {
    /// The e-stop input reads open: a pressed button, an open safety door or a broken wire.
    EStopOpen {
        /// The e-stop input.
        pin: PinId,
    },
    /// The enable (dead-man) input is released.
    EnableReleased {
        /// The enable input.
        pin: PinId,
    },
    /// An input could not be read; it counts as open.
    PinReadError {
        /// The input that failed.
        pin: PinId,
    },
    /// An output could not be written.
    PinWriteError {
        /// The output that failed.
        pin: PinId,
    },
    /// The chain is latched after a stop (or since power-up) and needs a
    /// [`reset`](super::SafetyChain::reset) while it reads closed. Only
    /// [`may_start`](super::SafetyChain::may_start) gives this reason.
    Latched,
}

impl StopReason {
    /// The pin concerned, if any.
    pub const fn pin(&self) -> Option<PinId> {
        match *self {
            StopReason::EStopOpen { pin }
            | StopReason::EnableReleased { pin }
            | StopReason::PinReadError { pin }
            | StopReason::PinWriteError { pin } => Some(pin),
            StopReason::Latched => None,
        }
    }

    /// Whether this is a pin error (the chain is faulted rather than merely open).
    pub const fn is_pin_error(&self) -> bool {
        matches!(
            self,
            StopReason::PinReadError { .. } | StopReason::PinWriteError { .. }
        )
    }
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StopReason::EStopOpen { pin } => write!(
                f,
                "emergency stop: {pin} reads open (button pressed, guard open or wire broken)"
            ),
            StopReason::EnableReleased { pin } => write!(f, "enable released: {pin} is not held"),
            StopReason::PinReadError { pin } => {
                write!(f, "read error on {pin} (counted as open)")
            }
            StopReason::PinWriteError { pin } => write!(f, "write error on {pin}"),
            StopReason::Latched => f.write_str(
                "safety chain latched after a stop: reset it while the chain reads closed",
            ),
        }
    }
}

impl core::error::Error for StopReason {}

/// What the controller must do after a [`cycle`](super::SafetyChain::cycle).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Verdict {
    /// The chain is closed and not latched: motion may go on.
    Run,
    /// A stop was found in this cycle (given once, in the cycle that found it): stop in
    /// `category` now.
    Stop {
        /// How to stop.
        category: StopCategory,
        /// Why.
        reason: StopReason,
    },
    /// The chain is latched after an earlier stop: no motion until a
    /// [`reset`](super::SafetyChain::reset).
    Stopped,
}

impl Verdict {
    /// Whether motion may go on.
    pub const fn is_run(&self) -> bool {
        matches!(self, Verdict::Run)
    }
}
