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
    /// A body index beyond the model's bodies.
    UnknownBody {
        /// The index given.
        body: usize,
    },
    /// The mass matrix (or a joint's block of the articulated inertia) is not positive
    /// definite at DOF `dof`: the bodies that DOF's joint moves have no mass or inertia along
    /// it (a massless subtree), or an inertia in the model is not physical.
    NotPositiveDefinite {
        /// The degree of freedom (index into `q̇`); [`crate::Model::dof_body`] gives its joint.
        dof: usize,
    },
    /// A physical parameter that cannot be: negative or not finite.
    NotPhysical {
        /// The parameter's name (`"armature"`, `"damping"`, `"friction"`).
        argument: &'static str,
        /// The element (a DOF for the armature).
        index: usize,
    },
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
            Error::UnknownBody { body } => write!(f, "body {body} does not exist"),
            Error::NotPositiveDefinite { dof } => write!(
                f,
                "the mass matrix is singular at degree of freedom {dof}: the bodies its joint \
                 moves have no mass or inertia along it (a massless subtree)"
            ),
            Error::NotPhysical { argument, index } => {
                write!(f, "`{argument}` element {index} is negative or not finite")
            }
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
