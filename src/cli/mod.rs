//! One module per `rl` subcommand. Each exposes its clap arguments and a `run` function.

pub mod capacity;
pub mod cell;
pub mod fake_robot;
pub mod jitter;
pub mod model;
pub mod otg;
pub mod output;
pub mod placement;
pub mod plan;
pub mod progress;
pub mod run;
pub mod scene;
pub mod traj;
pub mod view;

use std::fmt;
use std::time::Duration;

/// A command's failure: a message for the user and the process exit code.
///
/// Exit code 2 means bad usage (flags, files, values); 1 means the command ran and failed.
#[derive(Debug)]
pub struct CliError {
    message: String,
    code: u8,
}

/// The exit code when standard output was closed by its reader (`rl … | head`).
const CLOSED_OUTPUT: u8 = 0;

impl CliError {
    /// Bad usage: a flag, a file or a value the user gave is wrong (exit code 2).
    pub fn usage(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            code: 2,
        }
    }

    /// The command ran and failed (exit code 1).
    pub fn failed(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            code: 1,
        }
    }

    /// Standard output was closed by its reader: the command stops, nothing more is shown
    /// and the exit status is 0 (see [`output`]).
    pub fn closed_output() -> Self {
        Self {
            message: String::new(),
            code: CLOSED_OUTPUT,
        }
    }

    /// Whether this is [`CliError::closed_output`].
    pub fn is_closed_output(&self) -> bool {
        self.message.is_empty() && self.code == CLOSED_OUTPUT
    }

    /// The same error with `what: ` before its message (the flag a file came from, say).
    pub fn prefixed(self, what: &str) -> Self {
        if self.is_closed_output() {
            return self;
        }
        Self {
            message: format!("{what}: {}", self.message),
            code: self.code,
        }
    }

    /// The process exit code for this error.
    pub fn exit_code(&self) -> u8 {
        self.code
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// What a subcommand returns.
impl From<rl::devices::SpecError> for CliError {
    fn from(e: rl::devices::SpecError) -> Self {
        if e.is_input() {
            Self::usage(e.message())
        } else {
            Self::failed(e.message())
        }
    }
}

pub type CliResult = Result<std::process::ExitCode, CliError>;

/// Parses `500ms`, `30s`, `2m`, `1h`, `250us`, or a bare number of seconds.
pub fn parse_duration(text: &str) -> Result<Duration, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}` is not a duration: expected e.g. 500ms, 30s, 2m"))?;
    let seconds = match unit.trim() {
        "" | "s" => value,
        "us" | "µs" => value / 1e6,
        "ms" => value / 1e3,
        "m" | "min" => value * 60.0,
        "h" => value * 3600.0,
        other => {
            return Err(format!(
                "unknown unit `{other}` in `{text}`: use us, ms, s, m or h"
            ));
        }
    };
    Duration::try_from_secs_f64(seconds).map_err(|e| format!("`{text}`: {e}"))
}
