//! A compile-time life cycle on top of the run-time one: `Closed -> Opened -> Started`, where
//! each state has only the calls that are allowed in it, so stepping a device that was never
//! started does not compile.
//!
//! ```
//! # #[cfg(feature = "std")] {
//! use rl_drivers::typestate::Started;
//! use rl_drivers::{JointPositionActuator, MitsubishiH7};
//!
//! fn cycle(robot: &mut Started<MitsubishiH7>, q: &[f64]) -> Result<(), rl_drivers::Error> {
//!     robot.device_mut().set_joint_position(q)?;
//!     robot.step()
//! }
//! # }
//! ```
//!
//! Stepping an opened (not started) device is a compile error:
//!
//! ```compile_fail
//! fn cycle(robot: &mut rl_drivers::typestate::Opened<rl_drivers::MitsubishiH7>) {
//!     let _ = robot.step();
//! }
//! ```
//!
//! and so is stopping a closed one:
//!
//! ```compile_fail
//! fn end(robot: rl_drivers::typestate::Closed<rl_drivers::MitsubishiH7>) {
//!     let _ = robot.stop();
//! }
//! ```
//!
//! A failed transition hands back the error and the bare device, whose run-time state (for
//! example [`State::Faulted`](crate::State::Faulted)) says what may follow. `device_mut` exists
//! for setters and getters; life-cycle calls made through it are still checked at run time.

use crate::{CyclicDevice, Device};

/// A closed device.
#[derive(Debug)]
pub struct Closed<D>(D);

/// An opened, not started device.
#[derive(Debug)]
pub struct Opened<D>(D);

/// A started device: the only state that can step.
#[derive(Debug)]
pub struct Started<D>(D);

/// A failed transition: the error and the device in whatever run-time state it reached.
pub type Failed<D> = (<D as Device>::Error, D);

macro_rules! access {
    ($t:ident) => {
        impl<D: Device> $t<D> {
            /// The device (for getters).
            pub fn device(&self) -> &D {
                &self.0
            }

            /// The device (for setters).
            pub fn device_mut(&mut self) -> &mut D {
                &mut self.0
            }

            /// Gives up the compile-time checks.
            pub fn into_inner(self) -> D {
                self.0
            }
        }
    };
}

access!(Closed);
access!(Opened);
access!(Started);

impl<D: Device> Closed<D> {
    /// Wraps a device that is closed; hands it back if it is in another state.
    pub fn new(device: D) -> Result<Self, D> {
        if device.state() == crate::State::Closed {
            Ok(Closed(device))
        } else {
            Err(device)
        }
    }

    /// Opens the device.
    pub fn open(mut self) -> Result<Opened<D>, Failed<D>> {
        match self.0.open() {
            Ok(()) => Ok(Opened(self.0)),
            Err(e) => Err((e, self.0)),
        }
    }
}

impl<D: Device> Opened<D> {
    /// Starts the device.
    pub fn start(mut self) -> Result<Started<D>, Failed<D>> {
        match self.0.start() {
            Ok(()) => Ok(Started(self.0)),
            Err(e) => Err((e, self.0)),
        }
    }

    /// Closes the device.
    pub fn close(mut self) -> Result<Closed<D>, Failed<D>> {
        match self.0.close() {
            Ok(()) => Ok(Closed(self.0)),
            Err(e) => Err((e, self.0)),
        }
    }
}

impl<D: Device> Started<D> {
    /// Stops the device.
    pub fn stop(mut self) -> Result<Opened<D>, Failed<D>> {
        match self.0.stop() {
            Ok(()) => Ok(Opened(self.0)),
            Err(e) => Err((e, self.0)),
        }
    }
}

impl<D: CyclicDevice> Started<D> {
    /// One control cycle ([`CyclicDevice::step`]).
    pub fn step(&mut self) -> Result<(), D::Error> {
        self.0.step()
    }
}
