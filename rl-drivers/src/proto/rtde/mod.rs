//! Universal Robots' Real-Time Data Exchange (RTDE, TCP port 30004; Universal Robots,
//! *Real-Time Data Exchange (RTDE) Guide*, protocol versions 1 and 2): packages of a big-endian
//! header (`u16` size including the header, `u8` type) and a payload.
//!
//! - [`message`]: the control messages (protocol version, controller version, text messages,
//!   output and input recipe setup, start, pause) and data packages;
//! - [`types`]: the data types and their sizes;
//! - [`variables`]: every variable the controller knows, with its type and direction;
//! - [`recipe`]: a recipe (the types the controller answered a setup with) and the offsets of
//!   its fields in a data package.
//!
//! The session: request protocol version 2, ask the controller's version, set up one output
//! recipe (variables and frequency) and any number of input recipes, start; the controller
//! then sends a data package of the output recipe at the frequency (up to 500 Hz on e-Series),
//! and the client sends data packages of its input recipes whenever inputs change. Pause stops
//! the outputs. Everything is `no_std` and allocation-free; decoding never panics.

pub mod message;
pub mod recipe;
pub mod types;
pub mod variables;

use core::fmt;

pub use message::Message;
pub use recipe::Recipe;
pub use types::DataType;

/// The RTDE port.
pub const PORT: u16 = 30004;
/// The newest protocol version (frequency in the output setup, recipe ids in data packages,
/// text messages with a source).
pub const PROTOCOL_VERSION: u16 = 2;
/// Bytes of a package header.
pub const HEADER_LEN: usize = 3;
/// The largest package.
pub const MAX_PACKAGE: usize = u16::MAX as usize;

/// A package's type (its third byte).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PackageType {
    /// `V` (86): request protocol version.
    RequestProtocolVersion,
    /// `v` (118): get the controller's version.
    GetUrcontrolVersion,
    /// `M` (77): a text message.
    TextMessage,
    /// `U` (85): a data package.
    DataPackage,
    /// `O` (79): set up the outputs.
    SetupOutputs,
    /// `I` (73): set up inputs.
    SetupInputs,
    /// `S` (83): start the outputs.
    Start,
    /// `P` (80): pause the outputs.
    Pause,
}

impl PackageType {
    /// The type byte.
    pub const fn code(self) -> u8 {
        match self {
            Self::RequestProtocolVersion => b'V',
            Self::GetUrcontrolVersion => b'v',
            Self::TextMessage => b'M',
            Self::DataPackage => b'U',
            Self::SetupOutputs => b'O',
            Self::SetupInputs => b'I',
            Self::Start => b'S',
            Self::Pause => b'P',
        }
    }

    /// The type of a byte.
    pub const fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            b'V' => Self::RequestProtocolVersion,
            b'v' => Self::GetUrcontrolVersion,
            b'M' => Self::TextMessage,
            b'U' => Self::DataPackage,
            b'O' => Self::SetupOutputs,
            b'I' => Self::SetupInputs,
            b'S' => Self::Start,
            b'P' => Self::Pause,
            _ => return None,
        })
    }
}

/// Why bytes are not a valid RTDE package.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RtdeError {
    /// Fewer bytes than the part needs.
    TooShort {
        /// The part.
        what: &'static str,
        /// Bytes needed.
        need: usize,
        /// Bytes given.
        got: usize,
    },
    /// A header whose size is below 3.
    BadSize(u16),
    /// An unknown package type.
    UnknownType(u8),
    /// A payload longer than the message has.
    TooLong {
        /// The message.
        what: &'static str,
        /// Its length.
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// Text that is not UTF-8 (variable names and types are ASCII).
    NotText(&'static str),
    /// The output buffer is too small.
    BufferTooSmall {
        /// Bytes needed.
        need: usize,
        /// Bytes available.
        got: usize,
    },
    /// A type name the protocol does not define.
    UnknownDataType,
    /// A recipe with more fields than its capacity.
    RecipeTooLong(usize),
    /// A recipe the controller refused: a field was `NOT_FOUND` or `IN_USE`.
    RecipeRefused {
        /// The field's position.
        field: usize,
        /// `true` for `IN_USE` (another client writes it), `false` for `NOT_FOUND`.
        in_use: bool,
    },
    /// An answer's `accepted` byte that is neither 0 nor 1.
    NotAFlag {
        /// The answer.
        what: &'static str,
        /// The byte.
        value: u8,
    },
    /// A data package for another recipe.
    WrongRecipe {
        /// The recipe expected.
        expected: u8,
        /// The recipe given.
        got: u8,
    },
}

impl fmt::Display for RtdeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooShort { what, need, got } => write!(f, "{what}: {got} bytes, need {need}"),
            Self::BadSize(s) => write!(f, "package size {s} below the header's 3"),
            Self::UnknownType(t) => write!(f, "unknown package type {t} ({:?})", *t as char),
            Self::TooLong {
                what,
                expected,
                got,
            } => write!(f, "{what}: {got} bytes, expected {expected}"),
            Self::NotText(what) => write!(f, "{what}: not ASCII text"),
            Self::BufferTooSmall { need, got } => write!(f, "buffer of {got} bytes, need {need}"),
            Self::UnknownDataType => f.write_str("unknown data type"),
            Self::RecipeTooLong(n) => write!(f, "recipe of more than {n} fields"),
            Self::RecipeRefused { field, in_use } => write!(
                f,
                "recipe field {field} refused: {}",
                if *in_use { "IN_USE" } else { "NOT_FOUND" }
            ),
            Self::NotAFlag { what, value } => {
                write!(f, "{what}: accepted byte {value}, expected 0 or 1")
            }
            Self::WrongRecipe { expected, got } => {
                write!(f, "data package of recipe {got}, expected {expected}")
            }
        }
    }
}

/// A package header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Header {
    /// Bytes of the whole package, header included.
    pub size: u16,
    /// The type byte (an unknown one is kept: its package can be skipped).
    pub kind: u8,
}

impl Header {
    /// Decodes the header at the start of `bytes` (which may hold more).
    pub fn decode(bytes: &[u8]) -> Result<Self, RtdeError> {
        if bytes.len() < HEADER_LEN {
            return Err(RtdeError::TooShort {
                what: "package header",
                need: HEADER_LEN,
                got: bytes.len(),
            });
        }
        let size = u16::from_be_bytes([bytes[0], bytes[1]]);
        if usize::from(size) < HEADER_LEN {
            return Err(RtdeError::BadSize(size));
        }
        Ok(Self {
            size,
            kind: bytes[2],
        })
    }

    /// The package's type, if known.
    pub const fn package_type(&self) -> Option<PackageType> {
        PackageType::from_code(self.kind)
    }

    /// Bytes of the payload.
    pub const fn payload_len(&self) -> usize {
        self.size as usize - HEADER_LEN
    }
}

/// A package split off a byte stream: its header, its payload, and the bytes after it.
pub type Split<'a> = (Header, &'a [u8], &'a [u8]);

/// Splits the first complete package off `bytes`: its header and payload, and the bytes after
/// it. `Ok(None)` while it is incomplete.
pub fn split(bytes: &[u8]) -> Result<Option<Split<'_>>, RtdeError> {
    if bytes.len() < HEADER_LEN {
        return Ok(None);
    }
    let h = Header::decode(bytes)?;
    let n = usize::from(h.size);
    if bytes.len() < n {
        return Ok(None);
    }
    Ok(Some((h, &bytes[HEADER_LEN..n], &bytes[n..])))
}

/// Writes a header for a payload of `payload_len` bytes of type `kind` into `out`.
pub fn write_header(
    kind: PackageType,
    payload_len: usize,
    out: &mut [u8],
) -> Result<(), RtdeError> {
    let size = payload_len + HEADER_LEN;
    if size > MAX_PACKAGE {
        return Err(RtdeError::TooLong {
            what: "package",
            expected: MAX_PACKAGE,
            got: size,
        });
    }
    if out.len() < HEADER_LEN {
        return Err(RtdeError::BufferTooSmall {
            need: HEADER_LEN,
            got: out.len(),
        });
    }
    out[..2].copy_from_slice(&(size as u16).to_be_bytes());
    out[2] = kind.code();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packages_split_at_their_size() {
        // Two packages back to back, the second cut: "V" accepted, then the start of a "v".
        let bytes = [0, 4, b'V', 1, 0, 19, b'v', 0, 0];
        let (h, payload, rest) = split(&bytes).unwrap().unwrap();
        assert_eq!(
            (h.size, h.package_type()),
            (4, Some(PackageType::RequestProtocolVersion))
        );
        assert_eq!(payload, &[1]);
        assert_eq!(split(rest).unwrap(), None);
        assert_eq!(split(&[0, 2, b'V']), Err(RtdeError::BadSize(2)));
        let h = Header::decode(&[0, 3, b'X']).unwrap();
        assert_eq!(h.package_type(), None);
    }
}
