//! The attachment rmw_zenoh sends with every sample (since its Jazzy release 0.2.4 and Rolling
//! 0.6.0, "Change serialization format in attachment_helpers.cpp"): Zenoh's serializer writing
//! the sequence number (`i64`), the source timestamp (`i64`, ns since the UNIX epoch) and the
//! publisher's GID (16 bytes, a sequence: LEB128 length `0x10` first) — 33 bytes:
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 8 | sequence number, little-endian, from 1 per publisher |
//! | 8 | 8 | source timestamp, little-endian, ns since the UNIX epoch |
//! | 16 | 1 | `0x10` |
//! | 17 | 16 | GID |
//!
//! rmw_zenoh drops a sample that comes without one; so does this crate (counted).

use core::fmt;

/// Its length.
pub const LEN: usize = 33;

/// What an attachment carries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Attachment {
    /// Per publisher, from 1.
    pub sequence_number: i64,
    /// When it was published, ns since the UNIX epoch (the publisher's clock).
    pub source_timestamp: i64,
    /// The publisher's GID.
    pub source_gid: [u8; 16],
}

/// An attachment that is not rmw_zenoh's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadAttachment {
    /// Its length.
    pub len: usize,
}

impl fmt::Display for BadAttachment {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "attachment of {} bytes is not rmw_zenoh's (33: sequence number, timestamp, GID)",
            self.len
        )
    }
}

impl std::error::Error for BadAttachment {}

impl Attachment {
    /// The 33 bytes.
    pub fn to_bytes(&self) -> [u8; LEN] {
        let mut b = [0u8; LEN];
        b[..8].copy_from_slice(&self.sequence_number.to_le_bytes());
        b[8..16].copy_from_slice(&self.source_timestamp.to_le_bytes());
        b[16] = 16;
        b[17..].copy_from_slice(&self.source_gid);
        b
    }

    /// Reads the 33 bytes.
    pub fn from_bytes(b: &[u8]) -> Result<Self, BadAttachment> {
        let bad = BadAttachment { len: b.len() };
        if b.len() != LEN || b[16] != 16 {
            return Err(bad);
        }
        let mut seq = [0u8; 8];
        seq.copy_from_slice(&b[..8]);
        let mut ts = [0u8; 8];
        ts.copy_from_slice(&b[8..16]);
        let mut gid = [0u8; 16];
        gid.copy_from_slice(&b[17..]);
        Ok(Self {
            sequence_number: i64::from_le_bytes(seq),
            source_timestamp: i64::from_le_bytes(ts),
            source_gid: gid,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_refusals() {
        let a = Attachment {
            sequence_number: 7,
            source_timestamp: 1_700_000_000_000_000_000,
            source_gid: [3; 16],
        };
        let b = a.to_bytes();
        assert_eq!(&b[..8], &[7, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(b[16], 0x10);
        assert_eq!(Attachment::from_bytes(&b), Ok(a));
        assert_eq!(
            Attachment::from_bytes(&b[..32]),
            Err(BadAttachment { len: 32 })
        );
        let mut keyed = b;
        keyed[16] = 15;
        assert!(Attachment::from_bytes(&keyed).is_err());
    }
}
