//! Process data objects (CiA 301 §7.2.2): the communication parameters (0x1400 + k for RPDO
//! k + 1, 0x1800 + k for TPDO k + 1: sub 1 COB-ID with bit 31 "not valid", sub 2 transmission
//! type), the mapping parameters (0x1600 + k, 0x1A00 + k: sub 0 the count, then entries
//! `index << 16 | sub << 8 | bits`) and the packing of mapped values into the frame's bytes
//! (little-endian, in mapping order).
//!
//! To remap a PDO: write the COB-ID with bit 31 set, sub 0 of the mapping = 0, the entries,
//! sub 0 = their count, then the COB-ID without bit 31.

use core::fmt;

/// COB-ID bit 31: the PDO is not valid (disabled).
pub const COB_ID_INVALID: u32 = 0x8000_0000;
/// COB-ID bit 30: no RTR allowed on this PDO.
pub const COB_ID_NO_RTR: u32 = 0x4000_0000;
/// Transmission type: on every SYNC (1..=240: on every n-th).
pub const TRANSMISSION_SYNC: u8 = 1;
/// Transmission type: event-driven, manufacturer-specific.
pub const TRANSMISSION_EVENT_VENDOR: u8 = 254;
/// Transmission type: event-driven, device profile.
pub const TRANSMISSION_EVENT_PROFILE: u8 = 255;
/// Most entries in one mapping.
pub const MAX_ENTRIES: usize = 8;

/// Which way a PDO goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Direction {
    /// Receive PDO: master → node.
    Rpdo,
    /// Transmit PDO: node → master.
    Tpdo,
}

impl Direction {
    /// The communication parameter index of PDO `number` (1..=512).
    pub const fn comm_index(self, number: u16) -> u16 {
        match self {
            Direction::Rpdo => 0x1400 + number - 1,
            Direction::Tpdo => 0x1800 + number - 1,
        }
    }

    /// The mapping parameter index of PDO `number`.
    pub const fn mapping_index(self, number: u16) -> u16 {
        match self {
            Direction::Rpdo => 0x1600 + number - 1,
            Direction::Tpdo => 0x1A00 + number - 1,
        }
    }
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Direction::Rpdo => "RPDO",
            Direction::Tpdo => "TPDO",
        })
    }
}

/// One mapped object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Entry {
    /// The object's index.
    pub index: u16,
    /// Its sub-index.
    pub sub: u8,
    /// Its length in bits.
    pub bits: u8,
}

impl Entry {
    /// `index:sub` of `bits` bits.
    pub const fn new(index: u16, sub: u8, bits: u8) -> Self {
        Self { index, sub, bits }
    }

    /// The 32-bit value of a mapping sub-index.
    pub const fn to_u32(self) -> u32 {
        (self.index as u32) << 16 | (self.sub as u32) << 8 | self.bits as u32
    }

    /// The entry of a mapping sub-index's value.
    pub const fn from_u32(v: u32) -> Self {
        Self {
            index: (v >> 16) as u16,
            sub: (v >> 8) as u8,
            bits: v as u8,
        }
    }
}

/// Why a mapping is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MappingError {
    /// More than 8 entries.
    TooManyEntries,
    /// The entries exceed 64 bits.
    TooLong {
        /// Bits mapped.
        bits: u32,
    },
    /// An entry is not a whole number of bytes (this master packs bytes).
    NotByteAligned {
        /// The entry.
        entry: Entry,
    },
}

impl fmt::Display for MappingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MappingError::TooManyEntries => write!(f, "more than {MAX_ENTRIES} mapped objects"),
            MappingError::TooLong { bits } => write!(f, "{bits} bits mapped, a PDO holds 64"),
            MappingError::NotByteAligned { entry } => write!(
                f,
                "object {:#06x}:{:02x} has {} bits, not whole bytes",
                entry.index, entry.sub, entry.bits
            ),
        }
    }
}

/// A PDO's mapping: its entries and where each lands in the 8 data bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mapping {
    entries: [Entry; MAX_ENTRIES],
    count: usize,
}

impl Default for Mapping {
    /// Nothing mapped.
    fn default() -> Self {
        Self {
            entries: [Entry::new(0, 0, 0); MAX_ENTRIES],
            count: 0,
        }
    }
}

impl Mapping {
    /// A mapping of `entries` (checked: at most 8, at most 64 bits, whole bytes).
    pub fn new(entries: &[Entry]) -> Result<Self, MappingError> {
        if entries.len() > MAX_ENTRIES {
            return Err(MappingError::TooManyEntries);
        }
        let mut bits = 0u32;
        for &e in entries {
            if e.bits % 8 != 0 || e.bits == 0 {
                return Err(MappingError::NotByteAligned { entry: e });
            }
            bits += u32::from(e.bits);
        }
        if bits > 64 {
            return Err(MappingError::TooLong { bits });
        }
        let mut all = [Entry::new(0, 0, 0); MAX_ENTRIES];
        all[..entries.len()].copy_from_slice(entries);
        Ok(Self {
            entries: all,
            count: entries.len(),
        })
    }

    /// The entries.
    pub fn entries(&self) -> &[Entry] {
        &self.entries[..self.count]
    }

    /// The PDO's data length in bytes.
    pub fn len(&self) -> usize {
        self.entries().iter().map(|e| usize::from(e.bits / 8)).sum()
    }

    /// Whether nothing is mapped.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Where `index:sub` lands: byte offset and length, if it is mapped.
    pub fn locate(&self, index: u16, sub: u8) -> Option<Field> {
        let mut offset = 0;
        for e in self.entries() {
            let len = usize::from(e.bits / 8);
            if e.index == index && e.sub == sub {
                return Some(Field { offset, len });
            }
            offset += len;
        }
        None
    }
}

/// A mapped object's place in a PDO's data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    /// Byte offset.
    pub offset: usize,
    /// Bytes (1..=8).
    pub len: usize,
}

impl Field {
    /// Writes the low `len` bytes of `value`, little-endian, into `data`.
    pub fn put(self, data: &mut [u8], value: i64) {
        let bytes = value.to_le_bytes();
        if let Some(dst) = data.get_mut(self.offset..self.offset + self.len) {
            dst.copy_from_slice(&bytes[..self.len]);
        }
    }

    /// Reads the field as a signed integer (sign-extended from `len` bytes); `None` if `data`
    /// is too short.
    pub fn get_signed(self, data: &[u8]) -> Option<i64> {
        let raw = self.get_unsigned(data)?;
        let shift = 64 - 8 * self.len as u32;
        Some(((raw << shift) as i64) >> shift)
    }

    /// Reads the field as an unsigned integer; `None` if `data` is too short.
    pub fn get_unsigned(self, data: &[u8]) -> Option<u64> {
        let src = data.get(self.offset..self.offset + self.len)?;
        let mut b = [0u8; 8];
        b[..self.len].copy_from_slice(src);
        Some(u64::from_le_bytes(b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mapping_places_objects_in_order() {
        // CSP: controlword, target position, torque offset.
        let m = Mapping::new(&[
            Entry::new(0x6040, 0, 16),
            Entry::new(0x607A, 0, 32),
            Entry::new(0x60B2, 0, 16),
        ])
        .unwrap();
        assert_eq!(m.len(), 8);
        assert_eq!(Entry::new(0x607A, 0, 32).to_u32(), 0x607A_0020);
        assert_eq!(Entry::from_u32(0x6041_0010), Entry::new(0x6041, 0, 16));
        let mut d = [0u8; 8];
        m.locate(0x6040, 0).unwrap().put(&mut d, 0x0F);
        let target = m.locate(0x607A, 0).unwrap();
        target.put(&mut d, -2);
        m.locate(0x60B2, 0).unwrap().put(&mut d, -100);
        assert_eq!(d, [0x0F, 0, 0xFE, 0xFF, 0xFF, 0xFF, 0x9C, 0xFF]);
        assert_eq!(target.get_signed(&d), Some(-2));
        assert_eq!(target.get_unsigned(&d), Some(0xFFFF_FFFE));
        assert_eq!(target.get_signed(&d[..5]), None);
        assert_eq!(m.locate(0x6041, 0), None);
        assert_eq!(
            Mapping::new(&[Entry::new(0x6064, 0, 32); 3]),
            Err(MappingError::TooLong { bits: 96 })
        );
        assert!(Mapping::new(&[Entry::new(0x2000, 1, 1)]).is_err());
        assert_eq!(Direction::Tpdo.mapping_index(1), 0x1A00);
        assert_eq!(Direction::Rpdo.comm_index(4), 0x1403);
    }
}
