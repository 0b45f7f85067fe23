//! CDR as ROS 2 puts it on the wire: XCDR version 1 "plain CDR", little-endian, after a 4-byte
//! encapsulation header.
//!
//! - Header: `00 01 00 00` (representation `CDR_LE`, options zero; OMG DDS-XTypes 1.3,
//!   7.6.3.1.2). A reader also takes `00 00` (big-endian) and ignores the options.
//! - Alignment counts from the first byte after the header: a primitive of size 1, 2, 4 or 8
//!   starts at a multiple of its size.
//! - `string`: `u32` length including the terminating NUL, the bytes, the NUL.
//! - `T[]`: `u32` count, then the elements; the first element is aligned only when there is
//!   one (PyPI `rosbags`' serializer, the reference this crate's tests compare bytes with).
//! - A nested message has no padding of its own: it aligns as its first field.
//!
//! Writing appends to a caller's `Vec<u8>` (reused from message to message, so steady-state
//! encoding allocates nothing once the buffer has grown); reading never panics: every read is
//! bounds-checked and fails with a [`DecodeError`] saying what and at which byte.

use core::fmt;

/// The encapsulation header ROS 2 writes: little-endian plain CDR.
pub const HEADER_LE: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Why a CDR message could not be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DecodeError {
    /// The message ends before a field does.
    TooShort {
        /// The field being read.
        field: &'static str,
        /// Its offset in the payload (after the 4-byte header).
        offset: usize,
        /// Bytes it needs.
        needed: usize,
        /// Bytes left.
        left: usize,
    },
    /// The encapsulation header is not plain CDR.
    Encapsulation {
        /// The representation identifier found (bytes 0-1, big-endian).
        representation: u16,
    },
    /// A string is not NUL-terminated UTF-8.
    BadString {
        /// The field.
        field: &'static str,
        /// Its offset in the payload.
        offset: usize,
    },
    /// A sequence claims more elements than the message can hold.
    BadLength {
        /// The field.
        field: &'static str,
        /// Its offset in the payload.
        offset: usize,
        /// The count it claims.
        count: u32,
    },
    /// Bytes are left after the last field (beyond the up to 3 bytes of padding a writer may
    /// add).
    Trailing {
        /// Bytes left over.
        left: usize,
    },
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooShort {
                field,
                offset,
                needed,
                left,
            } => write!(
                f,
                "CDR: {field} at byte {offset} needs {needed} bytes, {left} left"
            ),
            Self::Encapsulation { representation } => write!(
                f,
                "CDR: encapsulation {representation:#06x} is not plain CDR (0x0000 or 0x0001)"
            ),
            Self::BadString { field, offset } => {
                write!(
                    f,
                    "CDR: {field} at byte {offset} is not a NUL-terminated UTF-8 string"
                )
            }
            Self::BadLength {
                field,
                offset,
                count,
            } => write!(
                f,
                "CDR: {field} at byte {offset} claims {count} elements, more than the message holds"
            ),
            Self::Trailing { left } => {
                write!(f, "CDR: {left} bytes after the last field")
            }
        }
    }
}

impl std::error::Error for DecodeError {}

/// Appends a CDR message to a buffer.
#[derive(Debug)]
pub struct Writer<'a> {
    buf: &'a mut Vec<u8>,
    /// Where the payload starts (after the header).
    origin: usize,
}

impl<'a> Writer<'a> {
    /// Clears `buf` and writes the little-endian encapsulation header.
    pub fn new(buf: &'a mut Vec<u8>) -> Self {
        buf.clear();
        buf.extend_from_slice(&HEADER_LE);
        let origin = buf.len();
        Self { buf, origin }
    }

    fn align(&mut self, n: usize) {
        let pos = self.buf.len() - self.origin;
        let pad = (n - pos % n) % n;
        self.buf.resize(self.buf.len() + pad, 0);
    }

    /// A `uint8` (also `byte`, `char`, `bool`).
    pub fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }

    /// An `int32`.
    pub fn i32(&mut self, v: i32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `uint32`.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float64`.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A sequence length. Lengths beyond `u32::MAX` cannot be written; messages here are far
    /// smaller.
    fn len(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }

    /// A `string`.
    pub fn string(&mut self, s: &str) {
        self.len(s.len() + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }

    /// A `float64[]`.
    pub fn f64_seq(&mut self, values: &[f64]) {
        self.len(values.len());
        for &v in values {
            self.f64(v);
        }
    }

    /// A `string[]`.
    pub fn string_seq<S: AsRef<str>>(&mut self, values: &[S]) {
        self.len(values.len());
        for s in values {
            self.string(s.as_ref());
        }
    }

    /// The count of a sequence of nested messages (the caller writes each after it).
    pub fn seq_len(&mut self, n: usize) {
        self.len(n);
    }
}

/// Reads a CDR message, field by field.
#[derive(Debug)]
pub struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    /// Checks the encapsulation header of `message` (little-endian plain CDR; big-endian is
    /// refused: no ROS 2 writer on a little-endian host produces it, and this crate does not
    /// byte-swap).
    pub fn new(message: &'a [u8]) -> Result<Self, DecodeError> {
        let Some((header, data)) = message.split_first_chunk::<4>() else {
            return Err(DecodeError::TooShort {
                field: "encapsulation header",
                offset: 0,
                needed: 4,
                left: message.len(),
            });
        };
        let representation = u16::from_be_bytes([header[0], header[1]]);
        if representation != 0x0001 {
            return Err(DecodeError::Encapsulation { representation });
        }
        Ok(Self { data, pos: 0 })
    }

    fn take(
        &mut self,
        field: &'static str,
        align: usize,
        n: usize,
    ) -> Result<&'a [u8], DecodeError> {
        let start = self.pos.next_multiple_of(align);
        let left = self.data.len().saturating_sub(start);
        if left < n {
            return Err(DecodeError::TooShort {
                field,
                offset: start,
                needed: n,
                left,
            });
        }
        self.pos = start + n;
        Ok(&self.data[start..start + n])
    }

    /// A `uint8`.
    pub fn u8(&mut self, field: &'static str) -> Result<u8, DecodeError> {
        Ok(self.take(field, 1, 1)?[0])
    }

    /// An `int32`.
    pub fn i32(&mut self, field: &'static str) -> Result<i32, DecodeError> {
        let b = self.take(field, 4, 4)?;
        Ok(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A `uint32`.
    pub fn u32(&mut self, field: &'static str) -> Result<u32, DecodeError> {
        let b = self.take(field, 4, 4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A `float64`.
    pub fn f64(&mut self, field: &'static str) -> Result<f64, DecodeError> {
        let b = self.take(field, 8, 8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(f64::from_le_bytes(a))
    }

    /// A sequence count, checked against the bytes left (each element takes at least
    /// `min_size` bytes).
    pub fn seq_len(&mut self, field: &'static str, min_size: usize) -> Result<usize, DecodeError> {
        let count = self.u32(field)?;
        let offset = self.pos;
        let left = self.data.len() - self.pos;
        if (count as usize).saturating_mul(min_size.max(1)) > left {
            return Err(DecodeError::BadLength {
                field,
                offset,
                count,
            });
        }
        Ok(count as usize)
    }

    /// A `string`.
    pub fn string(&mut self, field: &'static str) -> Result<&'a str, DecodeError> {
        let n = self.seq_len(field, 1)?;
        let offset = self.pos;
        let bytes = self.take(field, 1, n)?;
        match bytes.split_last() {
            Some((0, text)) => {
                core::str::from_utf8(text).map_err(|_| DecodeError::BadString { field, offset })
            }
            _ => Err(DecodeError::BadString { field, offset }),
        }
    }

    /// A `float64[]`, appended to `out` (cleared first).
    pub fn f64_seq(&mut self, field: &'static str, out: &mut Vec<f64>) -> Result<(), DecodeError> {
        let n = self.seq_len(field, 8)?;
        out.clear();
        for _ in 0..n {
            out.push(self.f64(field)?);
        }
        Ok(())
    }

    /// A `string[]`.
    pub fn string_seq(&mut self, field: &'static str) -> Result<Vec<String>, DecodeError> {
        let n = self.seq_len(field, 5)?;
        (0..n)
            .map(|_| self.string(field).map(str::to_owned))
            .collect()
    }

    /// Checks that nothing but up to 3 bytes of padding follows the last field.
    pub fn finish(self) -> Result<(), DecodeError> {
        let left = self.data.len() - self.pos;
        if left > 3 {
            Err(DecodeError::Trailing { left })
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strings_and_alignment() {
        let mut buf = Vec::new();
        let mut w = Writer::new(&mut buf);
        w.string("hello");
        w.f64(1.0);
        // Header, u32 6, "hello\0" (payload bytes 0..10), pad to 16, the double.
        assert_eq!(buf.len(), 4 + 16 + 8);
        assert_eq!(&buf[..14], b"\x00\x01\x00\x00\x06\x00\x00\x00hello\x00");
        let mut r = Reader::new(&buf).expect("header");
        assert_eq!(r.string("s"), Ok("hello"));
        assert_eq!(r.f64("d"), Ok(1.0));
        assert_eq!(r.finish(), Ok(()));
    }

    #[test]
    fn truncated_and_lying_messages_are_typed_errors() {
        assert!(matches!(
            Reader::new(&[0, 1]),
            Err(DecodeError::TooShort { needed: 4, .. })
        ));
        assert_eq!(
            Reader::new(&[0, 7, 0, 0]).err(),
            Some(DecodeError::Encapsulation { representation: 7 })
        );
        let mut r = Reader::new(&[0, 1, 0, 0, 0xff, 0xff, 0xff, 0xff]).expect("header");
        assert!(matches!(
            r.string("name"),
            Err(DecodeError::BadLength { field: "name", .. })
        ));
        let mut r = Reader::new(&[0, 1, 0, 0, 2, 0, 0, 0, b'a', b'b']).expect("header");
        assert!(matches!(
            r.string("name"),
            Err(DecodeError::BadString { .. })
        ));
        let mut r = Reader::new(&[0, 1, 0, 0, 1, 0]).expect("header");
        assert!(matches!(
            r.u32("count"),
            Err(DecodeError::TooShort { left: 2, .. })
        ));
    }
}
