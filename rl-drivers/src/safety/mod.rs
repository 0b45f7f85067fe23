//! An emergency-stop chain over digital pins: the e-stop and enable inputs, the brake /
//! contactor and watchdog outputs of a Raspberry-Pi-class controller, checked once per control
//! cycle ([`SafetyChain::cycle`]) and generic over the `embedded_hal::digital` 1.0 traits
//! ([`InputPin`](embedded_hal::digital::InputPin),
//! [`OutputPin`](embedded_hal::digital::OutputPin)): Linux GPIO lines, a microcontroller's pins
//! or a test fake.
//!
//! - [`chain`]: the [`SafetyChain`], its [`SafetyCounters`].
//! - [`state`]: the [`ChainState`]s and the one truth table of what each allows
//!   ([`Action::allowed_in`]).
//! - [`verdict`]: what a cycle tells the controller ([`Verdict`]), how to stop
//!   ([`StopCategory`]) and why ([`StopReason`]).
//! - [`debounce`]: cycle-count debouncing, fast to open (default 1 cycle), slow to close
//!   (default 10).
//! - [`config`]: names, levels, debouncing, stop category ([`SafetyConfig`]).
//! - [`io`]: the chain as a control loop holds it, whatever its pins ([`SafetyIo`]), and how a
//!   run arms it ([`SafetyIo::arm`]).
//! - [`pin`]: pin names ([`PinName`], e.g. `gpiochip0:17`), roles, and [`NoPin`] for an input or
//!   output a chain does not have.
//!
//! The rules, in short: the e-stop is normally closed (a broken wire stops); opening stops in
//! the first cycle that reads it (with the default `open_cycles = 1`); every stop latches until
//! an explicit [`reset`](SafetyChain::reset) while the chain reads closed, so **releasing the
//! e-stop never restarts motion by itself**; pin read and write errors fail safe (stop, counted,
//! [`ChainState::Fault`]). This is a software layer on top of, never instead of, a hardwired
//! safety relay: the watchdog output lets that relay see a stalled loop.
//!
//! `no_std`, allocation-free, no panics.

pub mod chain;
pub mod config;
pub mod debounce;
pub mod io;
pub mod pin;
pub mod state;
pub mod verdict;

pub use chain::{SafetyChain, SafetyCounters};
pub use config::{DebounceConfig, InputConfig, Level, OutputConfig, SafetyConfig};
pub use debounce::Debouncer;
pub use io::SafetyIo;
pub use pin::{NoPin, PinId, PinName, PinNameTooLong, PinRole};
pub use state::{Action, ChainState};
pub use verdict::{StopCategory, StopReason, Verdict};

#[cfg(test)]
mod tests;
