//! One module per `rl` subcommand. Each exposes its clap arguments and a `run` function.

pub mod fake_robot;
pub mod jitter;
pub mod model;
pub mod run;
pub mod traj;

use std::fmt;

/// A command's failure: a message for the user and the process exit code.
///
/// Exit code 2 means bad usage (flags, files, values); 1 means the command ran and failed.
#[derive(Debug)]
pub struct CliError {
    message: String,
    code: u8,
}

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
pub type CliResult = Result<std::process::ExitCode, CliError>;
