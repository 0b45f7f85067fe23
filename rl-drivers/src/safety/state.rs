//! The chain's [`ChainState`]s, the [`Action`]s the controller asks for, and the one truth
//! table of which action each state allows ([`Action::allowed_in`]).

use core::fmt;

/// Where the chain is. Derived each cycle, in this order of priority: a pin error latched
/// (`Fault`), the e-stop open (`Open`), the enable released (`EnableReleased`), latched after a
/// stop (`Latched`), else `Ready`.
///
/// Every stop latches: **closing the e-stop or holding the enable again never restarts motion
/// by itself**; the chain goes from `Open` or `EnableReleased` to `Latched` and waits for an
/// explicit [`reset`](super::SafetyChain::reset). A new chain starts `Open` (it has not yet read
/// the e-stop closed) and latched, so it needs a reset after power-up too (no automatic start).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ChainState {
    /// E-stop closed, enable held (or none configured), not latched: motion is allowed.
    Ready,
    /// The e-stop reads open (debounced), or has not yet read closed for `close_cycles`.
    Open,
    /// The e-stop is closed but the enable input is released (debounced).
    EnableReleased,
    /// The inputs read closed again after a stop (or since power-up); waiting for a reset.
    Latched,
    /// A pin could not be read or written; latched until a reset succeeds.
    Fault,
}

impl fmt::Display for ChainState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ChainState::Ready => "ready",
            ChainState::Open => "open",
            ChainState::EnableReleased => "enable released",
            ChainState::Latched => "latched",
            ChainState::Fault => "fault",
        })
    }
}

/// What the controller asks of the chain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Action {
    /// Keep moving ([`Verdict::Run`](super::Verdict::Run)).
    Run,
    /// Start motion ([`may_start`](super::SafetyChain::may_start)).
    Start,
    /// Energise the brake / contactor output (while the drives are on). A category-1 stop
    /// keeps it energised for a bounded time after the stop; that window is the only exception.
    ReleaseBrake,
    /// Clear the latch ([`reset`](super::SafetyChain::reset)); it also needs fresh readings
    /// that are closed and succeed.
    Reset,
}

impl Action {
    /// The states in which this action is accepted. Motion and the brake only in `Ready`; a
    /// reset in `Latched` and `Fault` (and in `Ready`, where it changes nothing), never while
    /// the e-stop reads open or the enable is released.
    pub const fn allowed_in(self, state: ChainState) -> bool {
        matches!(
            (self, state),
            (
                Action::Run | Action::Start | Action::ReleaseBrake,
                ChainState::Ready
            ) | (
                Action::Reset,
                ChainState::Ready | ChainState::Latched | ChainState::Fault
            )
        )
    }
}

impl fmt::Display for Action {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Action::Run => "run",
            Action::Start => "start",
            Action::ReleaseBrake => "release brake",
            Action::Reset => "reset",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const STATES: [ChainState; 5] = [
        ChainState::Ready,
        ChainState::Open,
        ChainState::EnableReleased,
        ChainState::Latched,
        ChainState::Fault,
    ];

    #[test]
    fn only_ready_allows_motion_and_the_brake() {
        for state in STATES {
            for action in [Action::Run, Action::Start, Action::ReleaseBrake] {
                assert_eq!(
                    action.allowed_in(state),
                    state == ChainState::Ready,
                    "{action} in {state}"
                );
            }
        }
    }

    #[test]
    fn reset_is_refused_while_open_or_released() {
        assert!(!Action::Reset.allowed_in(ChainState::Open));
        assert!(!Action::Reset.allowed_in(ChainState::EnableReleased));
        assert!(Action::Reset.allowed_in(ChainState::Latched));
        assert!(Action::Reset.allowed_in(ChainState::Fault));
        assert!(Action::Reset.allowed_in(ChainState::Ready));
    }
}
