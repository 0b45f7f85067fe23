//! Errors of the algorithms.

use core::fmt;

/// Why an algorithm refused its input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error {
    /// A vector argument has the wrong length.
    Dimension {
        /// The argument's name (`"q"`, `"qd"`, `"tau"`, ...).
        argument: &'static str,
        /// The length the model needs.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A tool index beyond the model's tools.
    UnknownTool {
        /// The index given.
        tool: usize,
    },
    /// A matrix that should be positive definite is not (a massless body on a joint, or a
    /// singular configuration).
    NotPositiveDefinite,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Dimension {
                argument,
                expected,
                got,
            } => {
                write!(
                    f,
                    "`{argument}` has {got} elements, the model needs {expected}"
                )
            }
            Error::UnknownTool { tool } => write!(f, "tool {tool} does not exist"),
            Error::NotPositiveDefinite => f.write_str("matrix is not positive definite"),
        }
    }
}

impl core::error::Error for Error {}

/// Checks that `x` has exactly `expected` elements.
#[inline]
pub(crate) fn check_len(argument: &'static str, x: &[f64], expected: usize) -> Result<(), Error> {
    if x.len() == expected {
        Ok(())
    } else {
        Err(Error::Dimension {
            argument,
            expected,
            got: x.len(),
        })
    }
}
