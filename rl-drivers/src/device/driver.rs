//! What a concrete driver writes to become a [`Device`](super::Device) and a
//! [`CyclicDevice`](super::CyclicDevice): its [`Driver`] sequences (what `open`, `start`,
//! `stop`, `close` and one step do on its link). [`impl_cyclic_device!`] implements both traits
//! from them through [`Lifecycle`](super::Lifecycle), which refuses a call its state does not
//! allow ([`Operation::allowed_in`](super::Operation::allowed_in)), records transitions and
//! faults, counts failed steps in a row and holds a step's time budget: no driver writes that
//! plumbing itself.
//!
//! The trait is private to the crate: its sequences skip the state checks, so only the
//! generated `Device` and `CyclicDevice` methods may call them.

use core::time::Duration;

use super::Error;

/// The part of a cyclic device that is its own: each method runs only once the device's
/// [`Lifecycle`](super::Lifecycle) has accepted the call, and its error faults the device as
/// [`Lifecycle::transition`](super::Lifecycle::transition) and
/// [`Lifecycle::step`](super::Lifecycle::step) describe.
pub(crate) trait Driver {
    /// What a successful `stop` does, in a few words for a report
    /// ([`Device::stop_description`](super::Device::stop_description)).
    const STOP_DESCRIPTION: &'static str;

    /// Whether the device answers at its own ticks
    /// ([`CyclicDevice::runs_own_cycle`](super::CyclicDevice::runs_own_cycle)).
    const RUNS_OWN_CYCLE: bool = false;

    /// Connects (`Closed -> Open`); an error leaves the device closed.
    fn open_sequence(&mut self) -> Result<(), Error>;

    /// Brings the device into operation (`Open -> Running`).
    fn start_sequence(&mut self) -> Result<(), Error>;

    /// Brings the device to a safe state (`Running | Faulted -> Open`).
    fn stop_sequence(&mut self) -> Result<(), Error>;

    /// Disconnects (`Open | Faulted -> Closed`, even when it fails).
    fn close_sequence(&mut self) -> Result<(), Error>;

    /// The control period
    /// ([`CyclicDevice::update_period`](super::CyclicDevice::update_period)).
    fn period(&self) -> Duration;

    /// One cycle's exchange; the caller's bound on its wait, if any, is the lifecycle's
    /// [`step_budget`](super::Lifecycle::step_budget). Does not allocate.
    fn exchange(&mut self) -> Result<(), Error>;
}

/// The outcome of a sequence that tries every step even after one failed (a stop still switches
/// the power off when its first step failed): the first error, or success.
#[derive(Debug, Default)]
pub(crate) struct FirstError(Option<Error>);

impl FirstError {
    /// Records one step's result; only the first error is kept.
    pub(crate) fn keep(&mut self, result: Result<(), Error>) {
        if let Err(e) = result {
            self.0.get_or_insert(e);
        }
    }

    /// `Ok`, or the first error kept.
    pub(crate) fn into_result(self) -> Result<(), Error> {
        self.0.map_or(Ok(()), Err)
    }
}

/// Implements [`Device`](crate::device::Device) and
/// [`CyclicDevice`](crate::device::CyclicDevice) for `$driver`, a [`Driver`] whose
/// [`Lifecycle`](crate::device::Lifecycle) is the field `$lifecycle`.
macro_rules! impl_cyclic_device {
    ($driver:ty, $lifecycle:ident) => {
        impl $crate::device::Device for $driver {
            type Error = $crate::device::Error;

            $crate::device::impl_cyclic_device!(
                @transitions $lifecycle;
                open Open open_sequence,
                start Start start_sequence,
                stop Stop stop_sequence,
                close Close close_sequence
            );

            fn state(&self) -> $crate::device::State {
                self.$lifecycle.state()
            }

            fn fault(&self) -> Option<Self::Error> {
                self.$lifecycle.fault()
            }

            fn stop_description(&self) -> &'static str {
                <Self as $crate::device::Driver>::STOP_DESCRIPTION
            }
        }

        impl $crate::device::CyclicDevice for $driver {
            fn step(&mut self) -> Result<(), Self::Error> {
                $crate::device::Lifecycle::step(
                    self,
                    |d| &mut d.$lifecycle,
                    <Self as $crate::device::Driver>::exchange,
                )
            }

            fn step_within(&mut self, budget: ::core::time::Duration) -> Result<(), Self::Error> {
                $crate::device::Lifecycle::step_within(
                    self,
                    |d| &mut d.$lifecycle,
                    budget,
                    <Self as $crate::device::Driver>::exchange,
                )
            }

            fn update_period(&self) -> ::core::time::Duration {
                <Self as $crate::device::Driver>::period(self)
            }

            fn runs_own_cycle(&self) -> bool {
                <Self as $crate::device::Driver>::RUNS_OWN_CYCLE
            }
        }
    };
    // Each transition: the `Device` method, its `Operation` and the `Driver` sequence it runs.
    (@transitions $lifecycle:ident; $($method:ident $operation:ident $sequence:ident),+) => {
        $(
            fn $method(&mut self) -> Result<(), Self::Error> {
                $crate::device::Lifecycle::transition(
                    self,
                    $crate::device::Operation::$operation,
                    |d| &mut d.$lifecycle,
                    <Self as $crate::device::Driver>::$sequence,
                )
            }
        )+
    };
}

pub(crate) use impl_cyclic_device;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::{CyclicDevice, Device, Lifecycle, Operation, State};

    /// A driver that records what its sequences saw.
    struct Toy {
        life: Lifecycle,
        fail_stop: bool,
        budgets: [Option<Duration>; 2],
        steps: usize,
    }

    impl Driver for Toy {
        const STOP_DESCRIPTION: &'static str = "toy stopped";
        const RUNS_OWN_CYCLE: bool = true;

        fn open_sequence(&mut self) -> Result<(), Error> {
            Ok(())
        }
        fn start_sequence(&mut self) -> Result<(), Error> {
            Ok(())
        }
        fn stop_sequence(&mut self) -> Result<(), Error> {
            if self.fail_stop {
                Err(Error::Disconnected {
                    operation: Operation::Stop,
                })
            } else {
                Ok(())
            }
        }
        fn close_sequence(&mut self) -> Result<(), Error> {
            Ok(())
        }
        fn period(&self) -> Duration {
            Duration::from_millis(4)
        }
        fn exchange(&mut self) -> Result<(), Error> {
            self.budgets[self.steps % 2] = self.life.step_budget();
            self.steps += 1;
            Ok(())
        }
    }

    impl_cyclic_device!(Toy, life);

    #[test]
    fn the_generated_device_follows_the_lifecycle() {
        let mut t = Toy {
            life: Lifecycle::new(),
            fail_stop: true,
            budgets: [None; 2],
            steps: 0,
        };
        assert_eq!(
            t.step(),
            Err(Error::State {
                operation: Operation::Step,
                state: State::Closed
            })
        );
        assert_eq!(t.steps, 0, "a refused step does not reach the driver");
        t.open().unwrap();
        t.start().unwrap();
        let budget = Duration::from_micros(700);
        t.step_within(budget).unwrap();
        t.step().unwrap();
        assert_eq!(t.budgets, [Some(budget), None]);
        assert_eq!(t.life.step_budget(), None);
        let e = t.stop().unwrap_err();
        assert_eq!((t.state(), t.fault()), (State::Faulted, Some(e)));
        t.fail_stop = false;
        t.stop().unwrap();
        t.close().unwrap();
        assert_eq!(t.state(), State::Closed);
        assert_eq!(t.stop_description(), "toy stopped");
        assert_eq!(t.update_period(), Duration::from_millis(4));
        assert!(t.runs_own_cycle());
    }
}
