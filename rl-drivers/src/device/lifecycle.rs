//! The life cycle every device follows: the [`State`]s, the [`Operation`]s and the one truth
//! table of which operation each state allows ([`Operation::allowed_in`]), and the
//! [`Lifecycle`] that records transitions, faults and failed steps in a row.

use core::fmt;
use core::time::Duration;

use super::Error;
use super::error::{DeviceError, ErrorKind};

/// Where a device is in its life: `Closed -> open -> Open -> start -> Running -> stop -> Open ->
/// close -> Closed`. `Faulted` is entered when the device can no longer be trusted (a failed
/// start or stop, too many failed steps in a row, a lost connection); from there `stop` still
/// tries to bring the device to a safe state (end motion, switch power off) and `close`
/// disconnects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum State {
    /// Not connected (the initial state).
    Closed,
    /// Connected, not running: setters buffer values, `step` is refused.
    Open,
    /// Running: `step` talks to the device once per cycle.
    Running,
    /// Failed; [`Lifecycle::fault`] says why. Only `stop` (to a safe state) and `close` are
    /// accepted.
    Faulted,
}

impl fmt::Display for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            State::Closed => "closed",
            State::Open => "open",
            State::Running => "running",
            State::Faulted => "faulted",
        })
    }
}

/// A device call, named in errors so a message says what failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Operation {
    /// [`Device::open`](super::Device::open).
    Open,
    /// [`Device::start`](super::Device::start).
    Start,
    /// [`CyclicDevice::step`](super::CyclicDevice::step).
    Step,
    /// [`Device::stop`](super::Device::stop).
    Stop,
    /// [`Device::close`](super::Device::close).
    Close,
    /// A getter (reads a buffered value).
    Get,
    /// A setter (buffers a value for the next step).
    Set,
}

impl Operation {
    /// The states in which this operation is accepted. `stop` is accepted when faulted too: a
    /// device that failed must still be brought to a safe state.
    pub const fn allowed_in(self, state: State) -> bool {
        matches!(
            (self, state),
            (Operation::Open, State::Closed)
                | (Operation::Start, State::Open)
                | (Operation::Step, State::Running)
                | (Operation::Stop, State::Running | State::Faulted)
                | (Operation::Close, State::Open | State::Faulted)
                | (
                    Operation::Get | Operation::Set,
                    State::Open | State::Running
                )
        )
    }

    const fn name(self) -> &'static str {
        match self {
            Operation::Open => "open",
            Operation::Start => "start",
            Operation::Step => "step",
            Operation::Stop => "stop",
            Operation::Close => "close",
            Operation::Get => "get",
            Operation::Set => "set",
        }
    }
}

impl fmt::Display for Operation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Failed steps in a row that fault a device unless its driver sets another bound.
pub const DEFAULT_MAX_CONSECUTIVE_FAILURES: u32 = 10;

/// The run-time state machine shared by all drivers: checks that a call is allowed, records
/// transitions and faults, counts failed steps in a row (too many fault the device; a lost
/// connection faults it at once) and holds the caller's time budget of the step in progress.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lifecycle {
    state: State,
    fault: Option<Error>,
    consecutive_failures: u32,
    max_consecutive_failures: u32,
    step_budget: Option<Duration>,
}

impl Default for Lifecycle {
    fn default() -> Self {
        Self::new()
    }
}

impl Lifecycle {
    /// A closed device that faults after [`DEFAULT_MAX_CONSECUTIVE_FAILURES`] failed steps in a
    /// row.
    pub const fn new() -> Self {
        Self::with_failure_limit(DEFAULT_MAX_CONSECUTIVE_FAILURES)
    }

    /// A closed device that faults after `max_consecutive_failures` failed steps in a row (at
    /// least 1).
    pub const fn with_failure_limit(max_consecutive_failures: u32) -> Self {
        Self {
            state: State::Closed,
            fault: None,
            consecutive_failures: 0,
            max_consecutive_failures: if max_consecutive_failures == 0 {
                1
            } else {
                max_consecutive_failures
            },
            step_budget: None,
        }
    }

    /// The current state.
    pub const fn state(&self) -> State {
        self.state
    }

    /// Why the device faulted, if it faulted since it was last started (kept after a
    /// successful `stop` from the faulted state, so a report can still say why).
    pub const fn fault(&self) -> Option<Error> {
        self.fault
    }

    /// The current run of failed steps.
    pub const fn consecutive_failures(&self) -> u32 {
        self.consecutive_failures
    }

    /// How long the step in progress may wait for the device, when its caller bounded it
    /// ([`step_within`](Self::step_within)); `None` otherwise.
    pub const fn step_budget(&self) -> Option<Duration> {
        self.step_budget
    }

    /// Refuses `operation` with [`Error::State`] unless the current state allows it.
    pub fn check(&self, operation: Operation) -> Result<(), Error> {
        if operation.allowed_in(self.state) {
            Ok(())
        } else {
            Err(Error::State {
                operation,
                state: self.state,
            })
        }
    }

    /// Records the successful end of a transition (`open`, `start`, `stop`, `close`).
    pub fn complete(&mut self, operation: Operation) {
        self.state = match operation {
            Operation::Open | Operation::Stop => State::Open,
            Operation::Start => State::Running,
            Operation::Close => State::Closed,
            Operation::Step | Operation::Get | Operation::Set => self.state,
        };
        if matches!(operation, Operation::Start | Operation::Close) {
            self.fault = None;
        }
        if matches!(operation, Operation::Start) {
            self.consecutive_failures = 0;
        }
    }

    /// Enters [`State::Faulted`] with `cause` as the reason (the first cause is kept if the
    /// device was faulted already) and returns `cause`.
    pub fn fail(&mut self, cause: Error) -> Error {
        if self.state != State::Faulted || self.fault.is_none() {
            self.fault = Some(cause);
        }
        self.state = State::Faulted;
        cause
    }

    /// Records a good step: the run of failures ends.
    pub fn step_succeeded(&mut self) {
        self.consecutive_failures = 0;
    }

    /// Records a failed step and returns its error: a lost connection faults the device at
    /// once, other failures after the limit in a row.
    pub fn step_failed(&mut self, e: Error) -> Error {
        self.consecutive_failures = self.consecutive_failures.saturating_add(1);
        if e.kind() == ErrorKind::Disconnected
            || self.consecutive_failures >= self.max_consecutive_failures
        {
            self.fail(e);
        }
        e
    }

    /// Runs the transition `operation` of `driver`: refuses it in the wrong state, runs `body`,
    /// then records the new state — or, if `body` failed, faults the device with its error.
    /// A `stop` that fails leaves the device faulted; one that succeeds (from `Running` or
    /// `Faulted`) leaves it `Open`. `close` always ends `Closed`: dropping the connection
    /// cannot be refused.
    pub fn transition<D: ?Sized>(
        driver: &mut D,
        operation: Operation,
        lifecycle: fn(&mut D) -> &mut Lifecycle,
        body: impl FnOnce(&mut D) -> Result<(), Error>,
    ) -> Result<(), Error> {
        lifecycle(driver).check(operation)?;
        match body(driver) {
            Ok(()) => {
                lifecycle(driver).complete(operation);
                Ok(())
            }
            Err(e) if operation == Operation::Close => {
                lifecycle(driver).complete(operation);
                Err(e)
            }
            // A failed open leaves the device closed: there is nothing to stop.
            Err(e) if operation == Operation::Open => Err(e),
            Err(e) => Err(lifecycle(driver).fail(e)),
        }
    }

    /// Runs one step of `driver`: refuses it unless running, runs `body`, and counts the
    /// result (see [`step_failed`](Self::step_failed)).
    pub fn step<D: ?Sized>(
        driver: &mut D,
        lifecycle: fn(&mut D) -> &mut Lifecycle,
        body: impl FnOnce(&mut D) -> Result<(), Error>,
    ) -> Result<(), Error> {
        lifecycle(driver).check(Operation::Step)?;
        match body(driver) {
            Ok(()) => {
                lifecycle(driver).step_succeeded();
                Ok(())
            }
            Err(e) => Err(lifecycle(driver).step_failed(e)),
        }
    }

    /// [`step`](Self::step) with the caller's bound on its wait: `body` finds `budget` in
    /// [`step_budget`](Self::step_budget), which is `None` again afterwards.
    pub fn step_within<D: ?Sized>(
        driver: &mut D,
        lifecycle: fn(&mut D) -> &mut Lifecycle,
        budget: Duration,
        body: impl FnOnce(&mut D) -> Result<(), Error>,
    ) -> Result<(), Error> {
        lifecycle(driver).step_budget = Some(budget);
        let result = Self::step(driver, lifecycle, body);
        lifecycle(driver).step_budget = None;
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::time::Duration;

    #[test]
    fn transitions_follow_the_life_cycle() {
        let mut l = Lifecycle::new();
        assert_eq!(
            l.check(Operation::Step),
            Err(Error::State {
                operation: Operation::Step,
                state: State::Closed
            })
        );
        assert!(l.check(Operation::Start).is_err(), "start before open");
        l.check(Operation::Open).unwrap();
        l.complete(Operation::Open);
        assert_eq!(l.state(), State::Open);
        assert!(l.check(Operation::Step).is_err(), "step before start");
        l.complete(Operation::Start);
        l.check(Operation::Step).unwrap();
        assert!(l.check(Operation::Close).is_err(), "close while running");
        l.complete(Operation::Stop);
        l.complete(Operation::Close);
        assert_eq!(l.state(), State::Closed);
    }

    fn timeout() -> Error {
        Error::Timeout {
            operation: Operation::Step,
            waited: Duration::from_millis(5),
        }
    }

    #[test]
    fn a_faulted_device_may_only_be_stopped_or_closed_and_says_why() {
        let mut l = Lifecycle::new();
        l.complete(Operation::Open);
        l.complete(Operation::Start);
        let cause = timeout();
        l.fail(cause);
        assert_eq!(l.fault(), Some(cause));
        for op in [
            Operation::Open,
            Operation::Start,
            Operation::Step,
            Operation::Get,
            Operation::Set,
        ] {
            let e = l.check(op).unwrap_err();
            assert_eq!(e.kind(), ErrorKind::State);
        }
        l.check(Operation::Stop).unwrap();
        l.check(Operation::Close).unwrap();
        // A later failure does not replace the first cause.
        l.fail(Error::Disconnected {
            operation: Operation::Stop,
        });
        assert_eq!(l.fault(), Some(cause));
        l.complete(Operation::Stop);
        assert_eq!((l.state(), l.fault()), (State::Open, Some(cause)));
        l.complete(Operation::Close);
        assert_eq!((l.state(), l.fault()), (State::Closed, None));
    }

    #[test]
    fn failed_steps_fault_after_the_limit_and_a_lost_link_at_once() {
        let mut l = Lifecycle::with_failure_limit(3);
        l.complete(Operation::Open);
        l.complete(Operation::Start);
        l.step_failed(timeout());
        l.step_failed(timeout());
        l.step_succeeded();
        l.step_failed(timeout());
        l.step_failed(timeout());
        assert_eq!(l.state(), State::Running);
        l.step_failed(timeout());
        assert_eq!((l.state(), l.consecutive_failures()), (State::Faulted, 3));

        let mut l = Lifecycle::new();
        l.complete(Operation::Open);
        l.complete(Operation::Start);
        let lost = Error::Disconnected {
            operation: Operation::Step,
        };
        l.step_failed(lost);
        assert_eq!((l.state(), l.fault()), (State::Faulted, Some(lost)));
    }

    struct Toy {
        lifecycle: Lifecycle,
        fail_start: bool,
        stops: u32,
    }

    fn lc(t: &mut Toy) -> &mut Lifecycle {
        &mut t.lifecycle
    }

    #[test]
    fn the_transition_helper_records_success_and_faults() {
        let mut t = Toy {
            lifecycle: Lifecycle::new(),
            fail_start: true,
            stops: 0,
        };
        Lifecycle::transition(&mut t, Operation::Open, lc, |_| Ok(())).unwrap();
        let e = Lifecycle::transition(&mut t, Operation::Start, lc, |t| {
            if t.fail_start { Err(timeout()) } else { Ok(()) }
        })
        .unwrap_err();
        assert_eq!(
            (t.lifecycle.state(), t.lifecycle.fault()),
            (State::Faulted, Some(e))
        );
        // Stop from the faulted state runs the stop sequence and leaves the device open.
        Lifecycle::transition(&mut t, Operation::Stop, lc, |t| {
            t.stops += 1;
            Ok(())
        })
        .unwrap();
        assert_eq!((t.lifecycle.state(), t.stops), (State::Open, 1));
        t.fail_start = false;
        Lifecycle::transition(&mut t, Operation::Start, lc, |_| Ok(())).unwrap();
        assert_eq!(
            (t.lifecycle.state(), t.lifecycle.fault()),
            (State::Running, None)
        );
        assert!(Lifecycle::transition(&mut t, Operation::Open, lc, |_| Ok(())).is_err());
        Lifecycle::step(&mut t, lc, |_| Err(timeout())).unwrap_err();
        assert_eq!(t.lifecycle.consecutive_failures(), 1);
        Lifecycle::step(&mut t, lc, |_| Ok(())).unwrap();
        assert_eq!(t.lifecycle.consecutive_failures(), 0);
    }
}
