//! Short fixed-capacity names for bodies, joints and tools.

use core::fmt;

/// The longest name a model keeps, in bytes.
pub const NAME_CAPACITY: usize = 62;

/// A UTF-8 name of at most [`NAME_CAPACITY`] bytes, stored inline (`Copy`, no allocation).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Name {
    len: u8,
    bytes: [u8; NAME_CAPACITY],
}

impl Default for Name {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Name {
    /// The empty name.
    pub const EMPTY: Self = Self {
        len: 0,
        bytes: [0; NAME_CAPACITY],
    };

    /// A name from a string, or `None` if it is longer than [`NAME_CAPACITY`] bytes.
    pub fn try_new(s: &str) -> Option<Self> {
        if s.len() > NAME_CAPACITY {
            return None;
        }
        let mut bytes = [0; NAME_CAPACITY];
        bytes[..s.len()].copy_from_slice(s.as_bytes());
        Some(Self {
            len: s.len() as u8,
            bytes,
        })
    }

    /// The name as a string slice.
    pub fn as_str(&self) -> &str {
        // Built from a &str and never split inside a character.
        core::str::from_utf8(&self.bytes[..self.len as usize]).unwrap_or("")
    }
}

impl fmt::Debug for Name {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}

impl fmt::Display for Name {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}
