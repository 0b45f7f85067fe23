//! Fieldbus memory management units (ESC register 0x0600 + 16·n, ETG.1000.4 §6.6): each maps
//! a range of the 32-bit logical address space to the ESC's physical memory, for reads
//! (device → master), writes, or both, so that one LRW datagram serves every device.
//!
//! ```text
//! 0-3 logical start   4-5 length (bytes)   6 logical start bit   7 logical stop bit
//! 8-9 physical start  10 physical start bit  11 type (bit 0 read, bit 1 write)  12 activate
//! ```

/// Bytes of one FMMU's registers.
pub const LEN: usize = 16;
/// The register of FMMU `n`.
pub const fn register(n: u8) -> u16 {
    0x0600 + 16 * n as u16
}
/// Type bit 0: read (the master reads device memory).
pub const TYPE_READ: u8 = 0x01;
/// Type bit 1: write.
pub const TYPE_WRITE: u8 = 0x02;

/// One FMMU's registers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Fmmu {
    /// Logical start address.
    pub logical_start: u32,
    /// Bytes.
    pub length: u16,
    /// First bit used in the first logical byte.
    pub logical_start_bit: u8,
    /// Last bit used in the last logical byte.
    pub logical_stop_bit: u8,
    /// Physical start address.
    pub physical_start: u16,
    /// First bit in the first physical byte.
    pub physical_start_bit: u8,
    /// [`TYPE_READ`] and/or [`TYPE_WRITE`].
    pub kind: u8,
    /// Bit 0: active.
    pub activate: u8,
}

impl Fmmu {
    /// A byte-aligned, active mapping of `length` bytes at `logical` onto `physical`.
    pub const fn bytes(logical: u32, physical: u16, length: u16, kind: u8) -> Self {
        Self {
            logical_start: logical,
            length,
            logical_start_bit: 0,
            logical_stop_bit: 7,
            physical_start: physical,
            physical_start_bit: 0,
            kind,
            activate: 1,
        }
    }

    /// Decodes 16 bytes.
    pub fn decode(b: &[u8; LEN]) -> Self {
        Self {
            logical_start: u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            length: u16::from_le_bytes([b[4], b[5]]),
            logical_start_bit: b[6],
            logical_stop_bit: b[7],
            physical_start: u16::from_le_bytes([b[8], b[9]]),
            physical_start_bit: b[10],
            kind: b[11],
            activate: b[12],
        }
    }

    /// The 16 bytes.
    pub fn encode(&self) -> [u8; LEN] {
        let mut b = [0u8; LEN];
        b[..4].copy_from_slice(&self.logical_start.to_le_bytes());
        b[4..6].copy_from_slice(&self.length.to_le_bytes());
        b[6] = self.logical_start_bit;
        b[7] = self.logical_stop_bit;
        b[8..10].copy_from_slice(&self.physical_start.to_le_bytes());
        b[10] = self.physical_start_bit;
        b[11] = self.kind;
        b[12] = self.activate;
        b
    }

    /// Whether it is active.
    pub const fn is_active(&self) -> bool {
        self.activate & 1 != 0 && self.length > 0
    }

    /// The part of the logical range `address..address + len` this FMMU maps, as `(offset in
    /// the datagram data, physical address, bytes)`, or `None` if they do not overlap.
    pub fn overlap(&self, address: u32, len: usize) -> Option<(usize, u16, usize)> {
        if !self.is_active() {
            return None;
        }
        let (a0, a1) = (u64::from(address), u64::from(address) + len as u64);
        let (f0, f1) = (
            u64::from(self.logical_start),
            u64::from(self.logical_start) + u64::from(self.length),
        );
        let (s, e) = (a0.max(f0), a1.min(f1));
        if s >= e {
            return None;
        }
        let physical = u64::from(self.physical_start) + (s - f0);
        Some((
            (s - a0) as usize,
            (physical & 0xFFFF) as u16,
            (e - s) as usize,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lan9252_fmmus_decode_and_map() {
        // soem-single-lan9252.pcapng frames 961 and 963.
        let out = [0, 0, 0, 0, 2, 0, 0, 7, 0x00, 0x11, 0, 2, 1, 0, 0, 0];
        let inp = [2, 0, 0, 0, 6, 0, 0, 7, 0x00, 0x14, 0, 1, 1, 0, 0, 0];
        let f0 = Fmmu::decode(&out);
        let f1 = Fmmu::decode(&inp);
        assert_eq!(f0, Fmmu::bytes(0, 0x1100, 2, TYPE_WRITE));
        assert_eq!(f1, Fmmu::bytes(2, 0x1400, 6, TYPE_READ));
        assert_eq!(f1.encode(), inp);
        // An LRW over logical 0..8 covers both: outputs at data 0..2, inputs at 2..8.
        assert_eq!(f0.overlap(0, 8), Some((0, 0x1100, 2)));
        assert_eq!(f1.overlap(0, 8), Some((2, 0x1400, 6)));
        assert_eq!(f1.overlap(4, 2), Some((0, 0x1402, 2)));
        assert_eq!(f1.overlap(8, 4), None);
        assert_eq!(register(1), 0x0610);
    }
}
