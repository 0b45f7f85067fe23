//! Reading an input file within a size limit: the one reader every loader of the workspace
//! uses (models, scenes, meshes, planning problems, EDS files, the viewer's files).
//!
//! A hostile or mistaken path must not take the machine's memory or hang the program:
//! `/dev/zero` (a character device that never ends), a FIFO (whose `open` blocks until a
//! writer comes), a symbolic link to either, a file that grows while it is read. So:
//!
//! 1. the path's metadata (`stat`, following links, without opening anything) must say *regular
//!    file*; anything else is refused with [`ReadErrorKind::NotRegular`] before it is opened;
//! 2. the file is opened non-blocking (a FIFO swapped in after the check opens at once instead of
//!    waiting for a writer) and checked again on the open handle;
//! 3. its size is compared with the limit, then at most `limit + 1` bytes are read (through
//!    [`std::io::Read::take`]): a file that reports no size (`/proc`) or grows is still cut
//!    off, and [`ReadErrorKind::TooLarge`] says so.
//!
//! Memory is bounded by the limit plus one read buffer, whatever the path names.

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::string::{String, ToString};
use std::vec::Vec;

/// Why a file was not read.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ReadErrorKind {
    /// Nothing at that path.
    NotFound,
    /// Not a regular file: what it is instead (`"a FIFO"`, `"a character device"`, …).
    NotRegular {
        /// What the path names.
        file_type: &'static str,
    },
    /// Larger than the reader's limit (by its size, or by what could be read from it).
    TooLarge {
        /// The limit in bytes.
        limit: u64,
    },
    /// The bytes are not UTF-8 text (for text formats).
    NotUtf8 {
        /// The offset of the first byte that is not.
        byte: usize,
    },
    /// Any other I/O error (permission denied, …): the system's message.
    Io(String),
}

impl fmt::Display for ReadErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotFound => f.write_str("no such file"),
            Self::NotRegular { file_type } => {
                write!(f, "{file_type}, not a regular file: refused unread")
            }
            Self::TooLarge { limit } => write!(
                f,
                "larger than the limit of {limit} bytes for this kind of file: refused"
            ),
            Self::NotUtf8 { byte } => write!(f, "not UTF-8 text (byte {byte})"),
            Self::Io(e) => write!(f, "cannot read: {e}"),
        }
    }
}

/// A file that was not read: which and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadError {
    /// The path as given.
    pub path: PathBuf,
    /// Why.
    pub kind: ReadErrorKind,
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.kind)
    }
}

impl std::error::Error for ReadError {}

/// What `meta` describes, for a file that is not regular.
fn file_type(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if meta.is_dir() {
        "a directory"
    } else {
        "not a regular file"
    }
}

fn io_kind(e: &std::io::Error) -> ReadErrorKind {
    if e.kind() == std::io::ErrorKind::NotFound {
        ReadErrorKind::NotFound
    } else {
        ReadErrorKind::Io(e.to_string())
    }
}

/// Opens `path` for reading without blocking on a FIFO (see the module docs).
fn open(path: &Path) -> std::io::Result<std::fs::File> {
    let mut o = std::fs::OpenOptions::new();
    o.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY);
    }
    o.open(path)
}

/// The bytes of the regular file at `path`, refused above `max_bytes` without reading more
/// than `max_bytes + 1` of them, and refused unread when `path` names anything but a regular
/// file (a FIFO, a device, a directory; symbolic links are followed to what they name).
pub fn read_bytes(path: &Path, max_bytes: u64) -> Result<Vec<u8>, ReadError> {
    let fail = |kind| ReadError {
        path: path.to_path_buf(),
        kind,
    };
    let meta = std::fs::metadata(path).map_err(|e| fail(io_kind(&e)))?;
    if !meta.is_file() {
        return Err(fail(ReadErrorKind::NotRegular {
            file_type: file_type(&meta),
        }));
    }
    if meta.len() > max_bytes {
        return Err(fail(ReadErrorKind::TooLarge { limit: max_bytes }));
    }
    let file = open(path).map_err(|e| fail(io_kind(&e)))?;
    // The path may name something else now than when it was looked at.
    let meta = file.metadata().map_err(|e| fail(io_kind(&e)))?;
    if !meta.is_file() {
        return Err(fail(ReadErrorKind::NotRegular {
            file_type: file_type(&meta),
        }));
    }
    let expected = usize::try_from(meta.len().min(max_bytes)).unwrap_or(0);
    let mut bytes = Vec::with_capacity(expected.saturating_add(1));
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| fail(io_kind(&e)))?;
    if bytes.len() as u64 > max_bytes {
        return Err(fail(ReadErrorKind::TooLarge { limit: max_bytes }));
    }
    Ok(bytes)
}

/// [`read_bytes`], as UTF-8 text.
pub fn read_text(path: &Path, max_bytes: u64) -> Result<String, ReadError> {
    let bytes = read_bytes(path, max_bytes)?;
    String::from_utf8(bytes).map_err(|e| ReadError {
        path: path.to_path_buf(),
        kind: ReadErrorKind::NotUtf8 {
            byte: e.utf8_error().valid_up_to(),
        },
    })
}

/// How a loader prints text taken from its input (a name, a value) in a message: up to
/// `max` characters as they are, a longer one cut there with its length, so that an error about
/// a 20 MB attribute is a line, not 20 MB.
#[derive(Clone, Copy, Debug)]
pub struct Clipped<'a>(pub &'a str, pub usize);

impl Clipped<'_> {
    /// Characters shown of a name or value in an error message.
    pub const NAME: usize = 80;
}

impl fmt::Display for Clipped<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Self(s, max) = *self;
        match s.char_indices().nth(max) {
            None => f.write_str(s),
            Some((end, _)) => write!(f, "{}… ({} bytes in all)", &s[..end], s.len()),
        }
    }
}

/// Names in a message: the first `shown`, then how many more (`a, b, c and 99 997 more`), each
/// [`Clipped`].
#[derive(Clone, Copy, Debug)]
pub struct FirstNames<'a, S: AsRef<str>> {
    /// The names (maybe only the first few of them).
    pub names: &'a [S],
    /// How many there are in all (at least `names.len()`).
    pub total: usize,
}

impl<S: AsRef<str>> fmt::Display for FirstNames<'_, S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const SHOWN: usize = 5;
        for (i, n) in self.names.iter().take(SHOWN).enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{}", Clipped(n.as_ref(), Clipped::NAME))?;
        }
        let shown = self.names.len().min(SHOWN);
        let total = self.total.max(self.names.len());
        if total > shown {
            write!(f, " and {} more", total - shown)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_text_is_clipped_with_its_length() {
        assert_eq!(Clipped("abc", 5).to_string(), "abc");
        assert_eq!(Clipped("abcdef", 3).to_string(), "abc… (6 bytes in all)");
        assert_eq!(Clipped("ääää", 2).to_string(), "ää… (8 bytes in all)");
        let names = ["a", "b", "c", "d", "e", "f", "g"];
        assert_eq!(
            FirstNames {
                names: &names,
                total: 100
            }
            .to_string(),
            "a, b, c, d, e and 95 more"
        );
        assert_eq!(
            FirstNames {
                names: &names[..2],
                total: 2
            }
            .to_string(),
            "a, b"
        );
    }
}
