//! Bits a classic CAN frame occupies on the wire, for the bus-load arithmetic.
//!
//! A standard data frame of `n` bytes: SOF 1, identifier 11, RTR 1, IDE 1, r0 1, DLC 4, data
//! 8n, CRC 15, CRC delimiter 1, ACK slot and delimiter 2, EOF 7, intermission 3: 47 + 8n bits
//! (111 for 8 bytes, 47 for a SYNC without data). An extended frame adds SRR 1, IDE moved, 18
//! identifier bits and r1: 67 + 8n. Bit stuffing inserts one bit after five equal ones between
//! SOF and the end of the CRC; the worst case is `⌊(g − 1) / 4⌋` for `g` bits there (34 + 8n
//! standard, 54 + 8n extended): 135 bits for 8 bytes standard. (Bosch CAN 2.0 specification;
//! the reference's numbers in `shared/reference/canopen.md`.)

/// Bits of a standard (11-bit identifier) frame with `len` data bytes, without stuff bits.
pub const fn standard_frame_bits(len: usize) -> u32 {
    47 + 8 * len as u32
}

/// Bits of an extended (29-bit identifier) frame with `len` data bytes, without stuff bits.
pub const fn extended_frame_bits(len: usize) -> u32 {
    67 + 8 * len as u32
}

/// The most stuff bits a standard frame with `len` data bytes can need.
pub const fn standard_stuff_bits_max(len: usize) -> u32 {
    (34 + 8 * len as u32 - 1) / 4
}

/// The most stuff bits an extended frame with `len` data bytes can need.
pub const fn extended_stuff_bits_max(len: usize) -> u32 {
    (54 + 8 * len as u32 - 1) / 4
}

/// Worst-case bits of a standard frame with `len` data bytes (stuffing included).
pub const fn standard_frame_bits_worst(len: usize) -> u32 {
    standard_frame_bits(len) + standard_stuff_bits_max(len)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_s_frame_times() {
        assert_eq!(standard_frame_bits(8), 111);
        assert_eq!(standard_frame_bits_worst(8), 135);
        assert_eq!(standard_frame_bits(0), 47, "SYNC");
        assert_eq!(extended_frame_bits(8), 131);
    }
}
