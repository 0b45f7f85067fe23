//! What can go wrong when the viewer starts: a model or scene that does not load, an address
//! that cannot be bound, a path file that does not parse. Each error says what and where.

use std::fmt;
use std::path::PathBuf;

/// Why the viewer could not start (or a file could not be read).
#[derive(Debug)]
pub enum ViewError {
    /// A model, environment or SRDF file did not load.
    Load {
        /// The file (or `"the embedded default robot"`).
        what: String,
        /// What the loader said.
        reason: String,
    },
    /// A file could not be read.
    Io {
        /// The file.
        path: PathBuf,
        /// The system's message.
        reason: String,
    },
    /// A path file (`rl plan --out` / `--trajectory` CSV) is malformed.
    Path {
        /// The file.
        path: PathBuf,
        /// The line (1-based), 0 for the file as a whole.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A listener could not be bound.
    Bind {
        /// `"HTTP"` or `"Coach"`.
        what: &'static str,
        /// The address asked for.
        addr: String,
        /// The system's message.
        reason: String,
    },
    /// The arguments do not fit together (no model, too many joints, ...).
    Invalid(String),
}

impl fmt::Display for ViewError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            // Loaders often name the file already.
            ViewError::Load { what, reason } if reason.contains(what.as_str()) => {
                f.write_str(reason)
            }
            ViewError::Load { what, reason } => write!(f, "{what}: {reason}"),
            ViewError::Io { path, reason } => write!(f, "{}: {reason}", path.display()),
            ViewError::Path { path, line, reason } if *line > 0 => {
                write!(f, "{}:{line}: {reason}", path.display())
            }
            ViewError::Path { path, reason, .. } => write!(f, "{}: {reason}", path.display()),
            ViewError::Bind { what, addr, reason } => {
                write!(f, "{what} listener on {addr}: {reason}")
            }
            ViewError::Invalid(s) => f.write_str(s),
        }
    }
}

impl std::error::Error for ViewError {}
