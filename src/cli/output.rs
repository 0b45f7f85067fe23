//! Standard output and standard error for every subcommand, in one place.
//!
//! The reader of `rl … | head` may go away before the command is done. Rust ignores SIGPIPE,
//! so the next write fails with `BrokenPipe`, and `println!` would panic. Everything the tool
//! prints goes through [`outln!`] / [`out!`] instead: a broken pipe becomes
//! [`CliError::closed_output`], which the caller returns with `?` so the command stops, and
//! `main` exits with status 0 printing nothing (the reader took what it wanted). Other write
//! errors are failures with a message. [`errln!`] writes to standard error and ignores errors:
//! a message that cannot be shown must not stop or crash the command.
//!
//! Output files are written through [`Replacement`]: beside the destination, moved over it
//! only when complete.

use std::fmt;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

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

/// A file written beside its destination (`NAME.partial` in the same directory) and moved over
/// it only once complete: a command that fails part way leaves an existing file as it was, never
/// truncated or half written. Creating one is also the check that the destination's directory
/// takes a new file, made before any work. Dropped without [`Replacement::commit`], the partial
/// file is removed.
///
/// A destination that exists and is not a regular file (`/dev/null`, a FIFO, a terminal) is
/// written in place, as before; a symbolic link to a regular file has its target replaced (the
/// link stays), with the target's permissions.
#[derive(Debug)]
pub struct Replacement {
    path: PathBuf,
    /// `None`: written in place (not a regular file), or already moved into place.
    partial: Option<PathBuf>,
    writer: Option<BufWriter<File>>,
}

impl Replacement {
    /// Creates the partial file beside `path`; `path` itself is not touched.
    pub fn create(path: &Path) -> io::Result<Self> {
        let existing = std::fs::metadata(path).ok();
        if existing.as_ref().is_some_and(|m| !m.is_file()) {
            let file = File::create(path)?;
            return Ok(Self {
                path: path.to_path_buf(),
                partial: None,
                writer: Some(BufWriter::new(file)),
            });
        }
        // A link's target is what is replaced, so that the link keeps pointing at the result.
        let path = match existing {
            Some(_) => std::fs::canonicalize(path)?,
            None => path.to_path_buf(),
        };
        let mut name = path.file_name().unwrap_or_default().to_os_string();
        name.push(".partial");
        let partial = path.with_file_name(name);
        let file = File::create(&partial)?;
        if let Some(m) = existing {
            file.set_permissions(m.permissions())?;
        }
        Ok(Self {
            path,
            partial: Some(partial),
            writer: Some(BufWriter::new(file)),
        })
    }

    /// Where to write, for writers that take a path (the SVG plots): write it there, then
    /// [`Replacement::commit`].
    pub fn partial(&self) -> &Path {
        self.partial.as_deref().unwrap_or(&self.path)
    }

    /// Flushes what was written and moves the partial file over the destination.
    pub fn commit(mut self) -> io::Result<()> {
        if let Some(mut w) = self.writer.take() {
            w.flush()?;
        }
        if let Some(partial) = &self.partial {
            std::fs::rename(partial, &self.path)?;
            self.partial = None;
        }
        Ok(())
    }
}

impl Write for Replacement {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match &mut self.writer {
            Some(w) => w.write(buf),
            None => Err(io::Error::other("the replacement was already committed")),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        self.writer.as_mut().map_or(Ok(()), Write::flush)
    }
}

impl Drop for Replacement {
    fn drop(&mut self) {
        self.writer = None;
        if let Some(partial) = &self.partial {
            let _ = std::fs::remove_file(partial);
        }
    }
}
