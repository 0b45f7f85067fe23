//! Errors of rl-plan: what is wrong and where (file, element, line, coordinate).

use std::fmt;
use std::path::PathBuf;

/// Why a space, a checker, a problem or a plan was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum PlanError {
    /// A configuration has the wrong number of coordinates.
    Length {
        /// What was given (`"start"`, `"goal"`, `"waypoint 3"`).
        what: String,
        /// Coordinates the space has.
        expected: usize,
        /// Coordinates given.
        got: usize,
    },
    /// A coordinate is outside the space's bounds (or not finite).
    OutsideBounds {
        /// What was given.
        what: String,
        /// The coordinate's name (the model's joint name).
        coordinate: String,
        /// The value.
        value: f64,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// A joint cannot be planned for as it is (a prismatic or free joint without position
    /// limits, which a sampler cannot draw from): give bounds.
    Unbounded {
        /// The coordinate.
        coordinate: String,
    },
    /// A name the space or the model does not know.
    UnknownName {
        /// What kind of name (`"joint"`, `"coordinate"`, `"link"`).
        what: &'static str,
        /// The name.
        name: String,
    },
    /// The start or goal configuration is in collision (or outside the bounds), so no planner
    /// can succeed.
    InvalidEndpoint {
        /// `"start"` or `"goal"`.
        which: &'static str,
        /// What the checker found.
        reason: String,
    },
    /// A model, scene or mesh failed to load (the loader's message names file and element).
    Load(String),
    /// A problem or scenario file is malformed.
    File {
        /// The file.
        path: PathBuf,
        /// Line (1-based), 0 when unknown.
        line: u32,
        /// Column (1-based), 0 when unknown.
        column: u32,
        /// Which element or field.
        element: String,
        /// What is wrong.
        message: String,
    },
    /// Something this crate does not do (named precisely).
    Unsupported(String),
    /// A bad setting (`what` = the setting, `message` = why).
    Setting {
        /// The setting.
        what: String,
        /// Why it is refused.
        message: String,
    },
    /// Writing output failed.
    Io(String),
    /// Planning was cancelled (a [`crate::budget::Cancel`] was requested).
    Cancelled,
}

impl PlanError {
    /// A malformed-file error at `element` of `path`.
    pub fn file(
        path: impl Into<PathBuf>,
        element: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self::File {
            path: path.into(),
            line: 0,
            column: 0,
            element: element.into(),
            message: message.into(),
        }
    }

    /// The same error placed at a line and column (only for [`PlanError::File`]).
    pub fn at_position(mut self, l: u32, c: u32) -> Self {
        if let Self::File { line, column, .. } = &mut self {
            *line = l;
            *column = c;
        }
        self
    }

    /// A bad setting.
    pub fn setting(what: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Setting {
            what: what.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for PlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Length {
                what,
                expected,
                got,
            } => write!(f, "{what} has {got} coordinates, the space has {expected}"),
            Self::OutsideBounds {
                what,
                coordinate,
                value,
                lower,
                upper,
            } => write!(
                f,
                "{what}: {coordinate} = {value} is outside its bounds [{lower}, {upper}]"
            ),
            Self::Unbounded { coordinate } => write!(
                f,
                "{coordinate} has no position limits; give it bounds to plan (a sampler cannot \
                 draw from an unbounded interval)"
            ),
            Self::UnknownName { what, name } => write!(f, "unknown {what} \"{name}\""),
            Self::InvalidEndpoint { which, reason } => {
                write!(f, "the {which} configuration is invalid: {reason}")
            }
            Self::Load(m) => f.write_str(m),
            Self::File {
                path,
                line,
                column,
                element,
                message,
            } => {
                write!(f, "{}", path.display())?;
                if *line > 0 {
                    write!(f, ":{line}:{column}")?;
                }
                write!(f, ": {element}: {message}")
            }
            Self::Unsupported(m) => write!(f, "not supported: {m}"),
            Self::Setting { what, message } => write!(f, "{what}: {message}"),
            Self::Io(m) => f.write_str(m),
            Self::Cancelled => f.write_str("planning was cancelled"),
        }
    }
}

impl std::error::Error for PlanError {}

impl From<rl_sg::SgError> for PlanError {
    fn from(e: rl_sg::SgError) -> Self {
        Self::Load(e.to_string())
    }
}

impl From<rl_core::loader::LoadError> for PlanError {
    fn from(e: rl_core::loader::LoadError) -> Self {
        Self::Load(e.to_string())
    }
}
