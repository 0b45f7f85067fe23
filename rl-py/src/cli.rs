//! What the tool's device table (`src/cli/run/device.rs`, compiled into [`crate::control`])
//! needs of the tool: its error type. Messages are passed on unchanged.

use std::fmt;

/// An error of the device table: the tool's text, and whether it was the caller's input
/// (exit code 2) or the device (1).
#[derive(Debug)]
pub struct CliError {
    message: String,
    code: u8,
}

impl CliError {
    /// Bad input.
    pub fn usage(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            code: 2,
        }
    }

    /// A failure.
    pub fn failed(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            code: 1,
        }
    }

    /// The tool's exit code for it.
    #[allow(dead_code)]
    pub fn exit_code(&self) -> u8 {
        self.code
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}
