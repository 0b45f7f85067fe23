//! Standard output and standard error for every subcommand, in one place.
//!
//! The reader of `rl … | head` may go away before the command is done. Rust ignores SIGPIPE,
//! so the next write fails with `BrokenPipe`, and `println!` would panic. Everything the tool
//! prints goes through [`outln!`] / [`out!`] instead: a broken pipe becomes
//! [`CliError::closed_output`], which the caller returns with `?` so the command stops, and
//! `main` exits with status 0 printing nothing (the reader took what it wanted). Other write
//! errors are failures with a message. [`errln!`] writes to standard error and ignores errors:
//! a message that cannot be shown must not stop or crash the command.

use std::fmt;
use std::io::{self, Write};

use super::CliError;

/// Writes `args` to standard output (no newline added).
pub fn print(args: fmt::Arguments<'_>) -> Result<(), CliError> {
    let mut out = io::stdout().lock();
    out.write_fmt(args)
        .and_then(|()| out.flush())
        .map_err(|e| write_error("standard output", e))
}

/// Writes `args` to standard error, ignoring errors.
pub fn eprint(args: fmt::Arguments<'_>) {
    let _ = io::stderr().lock().write_fmt(args);
}

/// The error for a failed write to `what`: a closed pipe ends the command quietly.
pub fn write_error(what: &str, e: io::Error) -> CliError {
    if e.kind() == io::ErrorKind::BrokenPipe {
        CliError::closed_output()
    } else {
        CliError::failed(format!("cannot write to {what}: {e}"))
    }
}

/// `println!` to standard output that returns `Result<(), CliError>` (see the module docs).
macro_rules! outln {
    () => { $crate::cli::output::print(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::cli::output::print(format_args!("{}\n", format_args!($($arg)*))) };
}

/// `print!` to standard output that returns `Result<(), CliError>`.
macro_rules! out {
    ($($arg:tt)*) => { $crate::cli::output::print(format_args!($($arg)*)) };
}

/// `eprintln!` that never fails or panics.
macro_rules! errln {
    ($($arg:tt)*) => { $crate::cli::output::eprint(format_args!("{}\n", format_args!($($arg)*))) };
}

pub(crate) use {errln, out, outln};
