//! The device model: [`Device`] (open, start, stop, close), [`CyclicDevice`] (step once per
//! control cycle), the run-time [`State`] machine every driver enforces through [`Lifecycle`],
//! and the [`Error`] every driver returns, whose [`ErrorKind`] lets generic control code react
//! without knowing the device.

use core::fmt;
use core::time::Duration;

use crate::proto::{coach::CoachError, h7::DecodeError, r3::R3Error};

/// Where a device is in its life: `Closed -> open -> Open -> start -> Running -> stop -> Open ->
/// close -> Closed`. `Faulted` is entered when the device can no longer be trusted (a failed
/// start or stop, too many failed steps in a row); only [`Device::close`] leaves it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum State {
    /// Not connected (the initial state).
    Closed,
    /// Connected, not running: setters buffer values, `step` is refused.
    Open,
    /// Running: `step` talks to the device once per cycle.
    Running,
    /// Failed; [`Lifecycle::fault`] says why. Every call but `close` is refused.
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
    /// [`Device::open`].
    Open,
    /// [`Device::start`].
    Start,
    /// [`CyclicDevice::step`].
    Step,
    /// [`Device::stop`].
    Stop,
    /// [`Device::close`].
    Close,
    /// A getter (reads a buffered value).
    Get,
    /// A setter (buffers a value for the next step).
    Set,
}

impl Operation {
    /// The states in which this operation is accepted.
    pub const fn allowed_in(self, state: State) -> bool {
        matches!(
            (self, state),
            (Operation::Open, State::Closed)
                | (Operation::Start, State::Open)
                | (Operation::Step, State::Running)
                | (Operation::Stop, State::Running)
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

/// What kind of failure an error is, for code that handles any device (embedded-hal style).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The device did not answer within its deadline.
    Timeout,
    /// The device answered with something malformed or unexpected.
    Protocol,
    /// The operating system refused a socket operation.
    Io,
    /// The call is not allowed in the device's current state.
    State,
    /// The caller passed a value of the wrong size or range.
    InvalidArgument,
}

/// A device error that can be classified (the bound on [`Device::Error`]).
pub trait DeviceError: fmt::Debug + fmt::Display {
    /// The kind of failure.
    fn kind(&self) -> ErrorKind;
}

/// A malformed or unexpected answer, by protocol.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProtocolError {
    /// A Mitsubishi H7 real-time packet did not decode.
    H7(DecodeError),
    /// An R3 (MELFA text protocol) reply did not parse or reported an error.
    R3(R3Error),
    /// A Coach line did not parse.
    Coach(CoachError),
    /// The answer decoded but is not what was asked for.
    Unexpected(&'static str),
}

impl fmt::Display for ProtocolError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ProtocolError::H7(e) => write!(f, "H7 packet: {e}"),
            ProtocolError::R3(e) => write!(f, "R3 reply: {e}"),
            ProtocolError::Coach(e) => write!(f, "Coach line: {e}"),
            ProtocolError::Unexpected(what) => write!(f, "unexpected answer: {what}"),
        }
    }
}

/// The error of every driver in this crate: small and `Copy`, so it can be stored as the reason
/// of a fault and returned from the real-time path without allocating.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Error {
    /// No (valid) answer arrived within `waited`.
    Timeout {
        /// The call that waited.
        operation: Operation,
        /// How long it waited.
        waited: Duration,
    },
    /// The device answered with something malformed or unexpected.
    Protocol {
        /// The call that received it.
        operation: Operation,
        /// What was wrong.
        error: ProtocolError,
    },
    /// A socket operation failed.
    #[cfg(feature = "std")]
    Io {
        /// The call that failed.
        operation: Operation,
        /// The operating system's error kind (the full `io::Error` is not `Copy`).
        kind: std::io::ErrorKind,
        /// The raw OS error number, when there is one.
        os_code: Option<i32>,
    },
    /// The call is not allowed in the current state.
    State {
        /// The refused call.
        operation: Operation,
        /// The state the device was in.
        state: State,
    },
    /// An argument has the wrong size or is out of range.
    InvalidArgument {
        /// Which argument.
        what: &'static str,
        /// The expected length (or limit).
        expected: usize,
        /// The length (or value) given.
        got: usize,
    },
}

impl Error {
    /// Wraps an I/O error raised during `operation`.
    #[cfg(feature = "std")]
    pub fn io(operation: Operation, e: &std::io::Error) -> Self {
        Error::Io {
            operation,
            kind: e.kind(),
            os_code: e.raw_os_error(),
        }
    }

    /// Checks that a caller's slice has exactly `expected` elements.
    pub fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), Error> {
        if expected == got {
            Ok(())
        } else {
            Err(Error::InvalidArgument {
                what,
                expected,
                got,
            })
        }
    }
}

impl DeviceError for Error {
    fn kind(&self) -> ErrorKind {
        match self {
            Error::Timeout { .. } => ErrorKind::Timeout,
            Error::Protocol { .. } => ErrorKind::Protocol,
            #[cfg(feature = "std")]
            Error::Io { .. } => ErrorKind::Io,
            Error::State { .. } => ErrorKind::State,
            Error::InvalidArgument { .. } => ErrorKind::InvalidArgument,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Timeout { operation, waited } => {
                write!(f, "{operation}: no answer within {} µs", waited.as_micros())
            }
            Error::Protocol { operation, error } => write!(f, "{operation}: {error}"),
            #[cfg(feature = "std")]
            Error::Io {
                operation,
                kind,
                os_code,
            } => match os_code {
                Some(code) => write!(f, "{operation}: I/O error {kind} (os error {code})"),
                None => write!(f, "{operation}: I/O error {kind}"),
            },
            Error::State { operation, state } => {
                write!(f, "{operation} is not allowed while the device is {state}")
            }
            Error::InvalidArgument {
                what,
                expected,
                got,
            } => {
                write!(f, "{what}: expected {expected}, got {got}")
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for Error {}

/// A device with a life cycle (RL's `rl::hal::Device`).
pub trait Device {
    /// The device's error type.
    type Error: DeviceError;

    /// Connects to the device (`Closed -> Open`).
    fn open(&mut self) -> Result<(), Self::Error>;
    /// Brings the device into operation (`Open -> Running`).
    fn start(&mut self) -> Result<(), Self::Error>;
    /// Ends operation (`Running -> Open`).
    fn stop(&mut self) -> Result<(), Self::Error>;
    /// Disconnects (`Open | Faulted -> Closed`).
    fn close(&mut self) -> Result<(), Self::Error>;
    /// The current state.
    fn state(&self) -> State;
    /// Why the device faulted, if it is [`State::Faulted`].
    fn fault(&self) -> Option<Self::Error>;
}

/// A device that exchanges data once per control cycle (RL's `rl::hal::CyclicDevice`).
pub trait CyclicDevice: Device {
    /// Sends the buffered commands and receives fresh measurements. Does not allocate.
    fn step(&mut self) -> Result<(), Self::Error>;
    /// The device's control period: call `step` once per period.
    fn update_period(&self) -> Duration;
}

/// The run-time state machine shared by all drivers: checks that a call is allowed and records
/// transitions and faults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lifecycle {
    state: State,
    fault: Option<Error>,
}

impl Default for Lifecycle {
    fn default() -> Self {
        Self::new()
    }
}

impl Lifecycle {
    /// A closed device.
    pub const fn new() -> Self {
        Self {
            state: State::Closed,
            fault: None,
        }
    }

    /// The current state.
    pub const fn state(&self) -> State {
        self.state
    }

    /// Why the device faulted.
    pub const fn fault(&self) -> Option<Error> {
        self.fault
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
        if operation == Operation::Close {
            self.fault = None;
        }
    }

    /// Enters [`State::Faulted`] with `cause` as the reason and returns `cause`.
    pub fn fail(&mut self, cause: Error) -> Error {
        self.state = State::Faulted;
        self.fault = Some(cause);
        cause
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn a_fault_refuses_everything_but_close_and_says_why() {
        let mut l = Lifecycle::new();
        l.complete(Operation::Open);
        l.complete(Operation::Start);
        let cause = Error::Timeout {
            operation: Operation::Step,
            waited: Duration::from_millis(5),
        };
        l.fail(cause);
        assert_eq!(l.fault(), Some(cause));
        for op in [
            Operation::Open,
            Operation::Start,
            Operation::Step,
            Operation::Stop,
            Operation::Get,
        ] {
            let e = l.check(op).unwrap_err();
            assert_eq!(e.kind(), ErrorKind::State);
        }
        l.check(Operation::Close).unwrap();
        l.complete(Operation::Close);
        assert_eq!((l.state(), l.fault()), (State::Closed, None));
    }
}
