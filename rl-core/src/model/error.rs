//! Errors of model building.

use core::fmt;

/// Why a model could not be built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ModelError {
    /// More moving bodies than the model's capacity `N`.
    TooManyBodies {
        /// The capacity.
        capacity: usize,
    },
    /// More degrees of freedom than the model's capacity `N`.
    TooManyDofs {
        /// The capacity.
        capacity: usize,
        /// The DOF count that was asked for.
        needed: usize,
    },
    /// More tools than the model's capacity `N`.
    TooManyTools {
        /// The capacity.
        capacity: usize,
    },
    /// A name longer than [`super::name::NAME_CAPACITY`] bytes.
    NameTooLong {
        /// Its length in bytes.
        len: usize,
    },
    /// A parent index that does not name an existing body.
    UnknownParent {
        /// The index given.
        parent: usize,
    },
    /// A body index that does not exist.
    UnknownBody {
        /// The index given.
        body: usize,
    },
    /// A DOF index beyond the joint's DOF count.
    UnknownDof {
        /// The body.
        body: usize,
        /// The DOF index within the joint.
        dof: usize,
    },
    /// A mass or inertia that is negative, not finite, or not positive semi-definite.
    InvalidInertia {
        /// The body.
        body: usize,
    },
    /// A joint axis of zero length or not finite.
    InvalidAxis {
        /// The body.
        body: usize,
    },
    /// A mimic joint that cannot follow the joint it names (see
    /// [`super::ModelBuilder::set_mimic`]).
    InvalidMimic {
        /// The mimic joint's body.
        body: usize,
        /// Why.
        reason: &'static str,
    },
    /// A transform or value that is not finite.
    NotFinite {
        /// What it was.
        what: &'static str,
    },
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ModelError::TooManyBodies { capacity } => {
                write!(
                    f,
                    "more moving bodies than the model's capacity of {capacity}"
                )
            }
            ModelError::TooManyDofs { capacity, needed } => {
                write!(
                    f,
                    "{needed} degrees of freedom exceed the model's capacity of {capacity}"
                )
            }
            ModelError::TooManyTools { capacity } => {
                write!(f, "more tools than the model's capacity of {capacity}")
            }
            ModelError::NameTooLong { len } => {
                write!(
                    f,
                    "name of {len} bytes is longer than {}",
                    super::name::NAME_CAPACITY
                )
            }
            ModelError::UnknownParent { parent } => {
                write!(f, "parent body {parent} does not exist")
            }
            ModelError::UnknownBody { body } => write!(f, "body {body} does not exist"),
            ModelError::UnknownDof { body, dof } => {
                write!(f, "body {body}'s joint has no degree of freedom {dof}")
            }
            ModelError::InvalidInertia { body } => write!(
                f,
                "body {body} has a mass or inertia that is negative, not finite or not physical"
            ),
            ModelError::InvalidAxis { body } => {
                write!(f, "body {body}'s joint axis is zero or not finite")
            }
            ModelError::InvalidMimic { body, reason } => {
                write!(f, "body {body}'s joint cannot be a mimic joint: {reason}")
            }
            ModelError::NotFinite { what } => write!(f, "{what} is not finite"),
        }
    }
}

impl core::error::Error for ModelError {}
