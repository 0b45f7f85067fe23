//! The error every driver returns: small, `Copy` and allocation-free, so it can be stored as the
//! reason of a fault and returned from the real-time path. It names no protocol: each driver owns
//! its protocol's error type (in `proto::<protocol>`) and hands the generic layer a
//! [`ProtocolError`] — which protocol, and a short description rendered into a fixed buffer —
//! while [`ErrorKind`] lets generic control code react without knowing the device.

use core::fmt;
use core::time::Duration;

use super::{Operation, State};

/// What kind of failure an error is, for code that handles any device (embedded-hal style).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The device did not answer within its deadline.
    Timeout,
    /// The device answered with something malformed or unexpected.
    Protocol,
    /// The device answered, and reported an error or a fault of its own (a refused command, a
    /// drive fault, an emergency message, a limit switch).
    Device,
    /// The connection to the device is gone (the peer closed it, the link is down).
    Disconnected,
    /// The operating system refused a socket operation.
    Io,
    /// The call is not allowed in the device's current state.
    State,
    /// The caller passed a value of the wrong size or range.
    InvalidArgument,
}

impl ErrorKind {
    /// Whether the link to the device can no longer be trusted to carry a command: the
    /// controller then stops at once instead of bringing the arm to rest along its path.
    pub const fn is_link_loss(self) -> bool {
        matches!(self, ErrorKind::Disconnected | ErrorKind::Io)
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ErrorKind::Timeout => "timeout",
            ErrorKind::Protocol => "protocol",
            ErrorKind::Device => "device",
            ErrorKind::Disconnected => "disconnected",
            ErrorKind::Io => "io",
            ErrorKind::State => "state",
            ErrorKind::InvalidArgument => "invalid argument",
        })
    }
}

/// A device error that can be classified (the bound on [`Device::Error`](super::Device::Error)).
pub trait DeviceError: fmt::Debug + fmt::Display {
    /// The kind of failure.
    fn kind(&self) -> ErrorKind;
}

/// Bytes a [`Description`] holds: room for the longest reason any driver of this crate gives
/// (a drive's fault with its EMCY code and name, a unit object it cannot give with the SDO abort
/// code and its name; `tests/error_texts.rs` renders the worst case of each and fails if one is
/// cut). Longer text from elsewhere is cut at a character boundary and marked `…`.
pub const DESCRIPTION_CAPACITY: usize = 248;

/// A short text in a fixed buffer: the description of a protocol error, written with
/// [`core::fmt::Write`] without allocating. Text beyond [`DESCRIPTION_CAPACITY`] bytes is cut at
/// a character boundary and ends in `…`.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Description {
    bytes: [u8; DESCRIPTION_CAPACITY],
    len: u8,
    truncated: bool,
}

impl Description {
    /// An empty description.
    pub const fn new() -> Self {
        Self {
            bytes: [0; DESCRIPTION_CAPACITY],
            len: 0,
            truncated: false,
        }
    }

    /// `value` rendered through its `Display`, cut to the capacity.
    pub fn from_display(value: &dyn fmt::Display) -> Self {
        let mut d = Self::new();
        // `write_str` below never fails: text that does not fit is cut, not refused.
        let _ = fmt::write(&mut d, format_args!("{value}"));
        d
    }

    /// The text (without the `…` of a cut text).
    pub fn as_str(&self) -> &str {
        // Only whole characters are ever copied in, so the bytes are valid UTF-8.
        core::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or("")
    }

    /// Whether text was cut off.
    pub const fn is_truncated(&self) -> bool {
        self.truncated
    }
}

impl Default for Description {
    fn default() -> Self {
        Self::new()
    }
}

impl fmt::Write for Description {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        if self.truncated {
            return Ok(());
        }
        let len = usize::from(self.len);
        let room = DESCRIPTION_CAPACITY - len;
        let take = if s.len() <= room {
            s.len()
        } else {
            self.truncated = true;
            // The longest prefix that ends on a character boundary.
            (0..=room)
                .rev()
                .find(|&k| s.is_char_boundary(k))
                .unwrap_or(0)
        };
        self.bytes[len..len + take].copy_from_slice(&s.as_bytes()[..take]);
        // `take <= room <= DESCRIPTION_CAPACITY < 256`.
        const _: () = assert!(DESCRIPTION_CAPACITY < 256);
        self.len = (len + take) as u8;
        Ok(())
    }
}

impl fmt::Display for Description {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())?;
        if self.truncated {
            f.write_str("…")?;
        }
        Ok(())
    }
}

impl fmt::Debug for Description {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?}", self.as_str())?;
        if self.truncated {
            f.write_str("…")?;
        }
        Ok(())
    }
}

/// A protocol-level error as the generic layer sees it: where it came from (`"H7 packet"`,
/// `"R3 reply"`, `"SDO"`…) and what was wrong, rendered from the driver's own error type. The
/// driver keeps its typed error for callers that know the protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ProtocolError {
    /// What part of which protocol raised it, e.g. `"H7 packet"`.
    pub source: &'static str,
    /// What was wrong.
    pub description: Description,
}

impl ProtocolError {
    /// `error` of `source`, described by its `Display`.
    pub fn new(source: &'static str, error: &dyn fmt::Display) -> Self {
        Self {
            source,
            description: Description::from_display(error),
        }
    }

    /// A fixed description: the answer decoded but is not what was asked for.
    pub fn unexpected(source: &'static str, what: &'static str) -> Self {
        Self::new(source, &what)
    }
}

impl fmt::Display for ProtocolError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.source, self.description)
    }
}

/// The error of every driver: small and `Copy`, so it can be stored as the reason of a fault and
/// returned from the real-time path without allocating.
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
    /// The device reported an error or fault of its own (a refused command, a drive fault).
    Device {
        /// The call during which it was reported.
        operation: Operation,
        /// What the device reported.
        error: ProtocolError,
    },
    /// The connection is gone: the peer closed it or the link went down.
    Disconnected {
        /// The call that found out.
        operation: Operation,
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
    /// Wraps an I/O error raised during `operation`: a closed or reset connection is
    /// [`Error::Disconnected`], an expired deadline [`Error::Timeout`] of `waited`.
    #[cfg(feature = "std")]
    pub fn io(operation: Operation, e: &std::io::Error) -> Self {
        use std::io::ErrorKind as K;
        match e.kind() {
            K::ConnectionAborted
            | K::ConnectionReset
            | K::BrokenPipe
            | K::UnexpectedEof
            | K::NotConnected => Error::Disconnected { operation },
            kind => Error::Io {
                operation,
                kind,
                os_code: e.raw_os_error(),
            },
        }
    }

    /// A malformed or unexpected answer to `operation`.
    pub fn protocol(operation: Operation, source: &'static str, error: &dyn fmt::Display) -> Self {
        Error::Protocol {
            operation,
            error: ProtocolError::new(source, error),
        }
    }

    /// An error the device reported during `operation`.
    pub fn device(operation: Operation, source: &'static str, error: &dyn fmt::Display) -> Self {
        Error::Device {
            operation,
            error: ProtocolError::new(source, error),
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

    /// The call that failed, where the error names one.
    pub fn operation(&self) -> Option<Operation> {
        match self {
            Error::Timeout { operation, .. }
            | Error::Protocol { operation, .. }
            | Error::Device { operation, .. }
            | Error::Disconnected { operation }
            | Error::State { operation, .. } => Some(*operation),
            #[cfg(feature = "std")]
            Error::Io { operation, .. } => Some(*operation),
            Error::InvalidArgument { .. } => None,
        }
    }
}

impl DeviceError for Error {
    fn kind(&self) -> ErrorKind {
        match self {
            Error::Timeout { .. } => ErrorKind::Timeout,
            Error::Protocol { .. } => ErrorKind::Protocol,
            Error::Device { .. } => ErrorKind::Device,
            Error::Disconnected { .. } => ErrorKind::Disconnected,
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
            Error::Device { operation, error } => {
                write!(f, "{operation}: the device reported {error}")
            }
            Error::Disconnected { operation } => {
                write!(f, "{operation}: the connection to the device is gone")
            }
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

#[cfg(test)]
mod tests {
    use super::*;
    use core::fmt::Write;

    #[test]
    fn descriptions_cut_long_text_at_a_character_boundary() {
        let mut d = Description::new();
        for _ in 0..DESCRIPTION_CAPACITY {
            d.write_str("é").unwrap();
        }
        assert!(d.is_truncated());
        assert_eq!(d.as_str().len(), DESCRIPTION_CAPACITY);
        assert!(d.as_str().chars().all(|c| c == 'é'));
        assert!(d.to_string().ends_with('…'));
        let short = Description::from_display(&"controller error 1234");
        assert_eq!(short.to_string(), "controller error 1234");
        assert!(!short.is_truncated());
    }

    #[test]
    fn protocol_errors_name_their_source() {
        let e = Error::protocol(Operation::Step, "H7 packet", &"length 100, expected 196");
        assert_eq!(e.kind(), ErrorKind::Protocol);
        assert_eq!(e.to_string(), "step: H7 packet: length 100, expected 196");
        let d = Error::device(Operation::Start, "R3 reply", &"error 4220");
        assert_eq!(d.kind(), ErrorKind::Device);
        assert_eq!(
            d.to_string(),
            "start: the device reported R3 reply: error 4220"
        );
    }

    #[test]
    fn closed_connections_are_disconnections() {
        let e = Error::io(
            Operation::Step,
            &std::io::Error::from(std::io::ErrorKind::ConnectionReset),
        );
        assert_eq!(
            e,
            Error::Disconnected {
                operation: Operation::Step
            }
        );
        assert!(e.kind().is_link_loss());
        assert!(!ErrorKind::Timeout.is_link_loss());
    }
}
