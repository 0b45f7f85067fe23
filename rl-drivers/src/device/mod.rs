//! The device model: [`Device`] (open, start, stop, close), [`CyclicDevice`] (step once per
//! control cycle), the run-time [`State`] machine every driver enforces through [`Lifecycle`],
//! and the [`Error`] every driver returns, whose [`ErrorKind`] lets generic control code react
//! without knowing the device.
//!
//! Nothing here names a protocol: a driver owns its protocol's error type and reports it as a
//! [`ProtocolError`] (a source and a short, allocation-free description). A driver implements
//! its transitions with [`Lifecycle::transition`] and its step with [`Lifecycle::step`], which
//! do the state checks, the fault bookkeeping and the count of failed steps in a row; a driver
//! of this crate writes only its sequences (the crate-private `Driver` trait) and has both
//! traits implemented from them.

// Every driver of the crate needs `std`: without it the trait and its macro have no user.
#[cfg_attr(not(feature = "std"), allow(dead_code, unused_imports, unused_macros))]
mod driver;
mod error;
mod lifecycle;

use core::time::Duration;

#[cfg_attr(not(feature = "std"), allow(unused_imports))]
pub(crate) use driver::{Driver, FirstError, impl_cyclic_device};
pub use error::{DESCRIPTION_CAPACITY, Description, DeviceError, Error, ErrorKind, ProtocolError};
pub use lifecycle::{DEFAULT_MAX_CONSECUTIVE_FAILURES, Lifecycle, Operation, State};

/// A device with a life cycle (RL's `rl::hal::Device`).
pub trait Device {
    /// The device's error type.
    type Error: DeviceError;

    /// Connects to the device (`Closed -> Open`).
    fn open(&mut self) -> Result<(), Self::Error>;
    /// Brings the device into operation (`Open -> Running`).
    fn start(&mut self) -> Result<(), Self::Error>;
    /// Ends operation and brings the device to a safe state (`Running | Faulted -> Open`): from
    /// the faulted state too, so a device that failed still ends its motion and switches its
    /// power off where the link allows.
    fn stop(&mut self) -> Result<(), Self::Error>;
    /// Disconnects (`Open | Faulted -> Closed`).
    fn close(&mut self) -> Result<(), Self::Error>;
    /// The current state.
    fn state(&self) -> State;
    /// Why the device faulted, if it faulted since it was last started.
    fn fault(&self) -> Option<Self::Error>;
    /// What a successful [`stop`](Self::stop) does on this device, in a few words for a report
    /// (e.g. "end packet sent, program stopped, servo off").
    fn stop_description(&self) -> &'static str {
        "stopped"
    }
}

/// A device that exchanges data once per control cycle (RL's `rl::hal::CyclicDevice`).
pub trait CyclicDevice: Device {
    /// Sends the buffered commands and receives fresh measurements, within one period. Does
    /// not allocate.
    fn step(&mut self) -> Result<(), Self::Error>;

    /// [`step`](Self::step), waiting at most `budget` for the device's answer: a loop passes
    /// the time left before its next deadline, so a reply that has not come by then is counted
    /// lost and the cycle goes on. Drivers that never wait ignore it.
    fn step_within(&mut self, budget: Duration) -> Result<(), Self::Error> {
        let _ = budget;
        self.step()
    }
    /// The device's control period: call `step` once per period.
    fn update_period(&self) -> Duration;

    /// Whether the device runs its own cycle and answers at its own ticks (a robot controller
    /// with its own interpolation cycle), rather than when it is asked. A caller's loop should
    /// then phase-lock to the replies, so each command reaches the device before its tick.
    fn runs_own_cycle(&self) -> bool {
        false
    }
}
