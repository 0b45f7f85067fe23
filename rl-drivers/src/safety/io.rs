//! The chain as a controller sees it: one object-safe trait, [`SafetyIo`], so a runtime can
//! hold any [`SafetyChain`] (whatever its pins) behind one pointer and call
//! it once per cycle without knowing the pins' types.

use core::time::Duration;

use super::chain::{SafetyChain, SafetyCounters};
use super::state::ChainState;
use super::verdict::{StopCategory, StopReason, Verdict};
use embedded_hal::digital::{InputPin, OutputPin};

/// A safety chain in a control loop (implemented by every [`SafetyChain`]).
pub trait SafetyIo {
    /// One control cycle (see [`SafetyChain::cycle`]).
    fn cycle(&mut self, drives_on: bool) -> Verdict;
    /// Whether motion may start now (see [`SafetyChain::may_start`]).
    fn may_start(&mut self) -> Result<(), StopReason>;
    /// Clears a latched stop while the chain reads closed (see [`SafetyChain::reset`]).
    fn reset(&mut self) -> Result<(), StopReason>;
    /// Holds the watchdog output steady (the external relay drops).
    fn stop_watchdog(&mut self);
    /// Lets the watchdog toggle again.
    fn start_watchdog(&mut self);
    /// The chain's state.
    fn state(&self) -> ChainState;
    /// What it counted.
    fn counters(&self) -> SafetyCounters;
    /// How it stops.
    fn category(&self) -> StopCategory;
    /// Cycles a closed reading takes to count as closed.
    fn close_cycles(&self) -> u32;
    /// Whether the brake or contactor output is energised (drives may be powered).
    fn brake_energised(&self) -> bool;

    /// Arms the chain before a run: cycles it with the drives off, `period` apart (`sleep`
    /// waits), until a closed chain has read closed long enough, then resets it and asks
    /// [`may_start`](Self::may_start). Motion never starts with the chain open or the enable
    /// released: the error says which input. Takes `close_cycles + 1` periods.
    fn arm(&mut self, period: Duration, sleep: &mut dyn FnMut(Duration)) -> Result<(), StopReason> {
        self.start_watchdog();
        for _ in 0..=self.close_cycles() {
            let _ = self.cycle(false);
            sleep(period);
        }
        self.reset()?;
        self.may_start()
    }
}

impl<EStop, Watchdog, Enable, Brake> SafetyIo for SafetyChain<EStop, Watchdog, Enable, Brake>
where
    EStop: InputPin,
    Watchdog: OutputPin,
    Enable: InputPin,
    Brake: OutputPin,
{
    fn cycle(&mut self, drives_on: bool) -> Verdict {
        SafetyChain::cycle(self, drives_on)
    }
    fn may_start(&mut self) -> Result<(), StopReason> {
        SafetyChain::may_start(self)
    }
    fn reset(&mut self) -> Result<(), StopReason> {
        SafetyChain::reset(self)
    }
    fn stop_watchdog(&mut self) {
        SafetyChain::stop_watchdog(self);
    }
    fn start_watchdog(&mut self) {
        SafetyChain::start_watchdog(self);
    }
    fn state(&self) -> ChainState {
        SafetyChain::state(self)
    }
    fn counters(&self) -> SafetyCounters {
        SafetyChain::counters(self)
    }
    fn category(&self) -> StopCategory {
        self.config().category
    }
    fn close_cycles(&self) -> u32 {
        let c = self.config();
        u32::from(
            c.estop
                .debounce
                .close_cycles
                .max(c.enable.debounce.close_cycles),
        )
        .max(1)
    }
    fn brake_energised(&self) -> bool {
        SafetyChain::brake_energised(self)
    }
}
