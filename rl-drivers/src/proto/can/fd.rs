//! CAN FD: the data lengths a DLC can express, the BRS and ESI flags, and the SocketCAN
//! `struct canfd_frame` (72 bytes): `can_id u32 | len u8 | flags u8 | __res0 u8 | __res1 u8 |
//! data[64]`.
//!
//! DLC 0..=8 are the lengths 0..=8; DLC 9..=15 are 12, 16, 20, 24, 32, 48 and 64 bytes (ISO
//! 11898-1:2015). Linux flags: `CANFD_BRS` 0x01 (bit-rate switch), `CANFD_ESI` 0x02 (error
//! state indicator), `CANFD_FDF` 0x04 (marks an FD frame in a `canfd_frame`).

use super::frame::{DecodeError, Frame, IdOrder};

/// Most data bytes of a CAN FD frame.
pub const FD_MAX_LEN: usize = 64;
/// Bytes of a SocketCAN `struct canfd_frame`.
pub const CANFD_FRAME_LEN: usize = 72;
/// Linux `CANFD_FDF`: set in `flags` of a `canfd_frame` holding a CAN FD frame.
pub const CANFD_FDF: u8 = 0x04;

/// Data lengths of DLC 9..=15.
const LONG_LENS: [usize; 7] = [12, 16, 20, 24, 32, 48, 64];

/// The CAN FD flags of a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct FdFlags(pub u8);

impl FdFlags {
    /// Bit-rate switch: the data phase runs at the higher rate.
    pub const BRS: u8 = 0x01;
    /// Error state indicator: the sender is error passive.
    pub const ESI: u8 = 0x02;

    /// Flags with BRS and ESI set as given.
    pub const fn new(brs: bool, esi: bool) -> Self {
        Self(((brs as u8) * Self::BRS) | ((esi as u8) * Self::ESI))
    }

    /// Whether the bit rate switches in the data phase.
    pub const fn brs(self) -> bool {
        self.0 & Self::BRS != 0
    }

    /// Whether the sender is error passive.
    pub const fn esi(self) -> bool {
        self.0 & Self::ESI != 0
    }

    /// Only the BRS and ESI bits (what travels in candump and cannelloni).
    pub const fn masked(self) -> Self {
        Self(self.0 & (Self::BRS | Self::ESI))
    }
}

/// Whether `len` is a CAN FD data length.
pub const fn is_fd_len(len: usize) -> bool {
    len <= 8 || matches!(len, 12 | 16 | 20 | 24 | 32 | 48 | 64)
}

/// The DLC of a data length (the smallest DLC that holds `len` bytes; 15 beyond 48).
pub fn len_to_dlc(len: usize) -> usize {
    if len <= 8 {
        return len;
    }
    9 + LONG_LENS.iter().position(|&l| l >= len).unwrap_or(6)
}

/// The data length of a DLC (0..=15; larger values are clamped to 64 bytes).
pub fn dlc_to_len(dlc: usize) -> usize {
    if dlc <= 8 {
        dlc
    } else {
        LONG_LENS[(dlc - 9).min(6)]
    }
}

/// Writes `frame` (CAN FD or not) as a 72-byte `struct canfd_frame`.
pub(crate) fn write_canfd_frame(
    frame: &Frame,
    out: &mut [u8],
    order: IdOrder,
) -> Result<usize, DecodeError> {
    let Some(out) = out.get_mut(..CANFD_FRAME_LEN) else {
        return Err(DecodeError::Length {
            expected: CANFD_FRAME_LEN,
            got: out.len(),
        });
    };
    out[..4].copy_from_slice(&order.write(frame.raw_id()));
    out[4] = frame.len() as u8;
    out[5] = frame.fd_flags().map_or(0, |f| f.masked().0 | CANFD_FDF);
    out[6] = 0;
    out[7] = 0;
    out[8..].fill(0);
    let data = frame.bytes();
    out[8..8 + data.len()].copy_from_slice(data);
    Ok(CANFD_FRAME_LEN)
}

/// Reads a 72-byte `struct canfd_frame` as a CAN FD frame.
pub(crate) fn read_canfd_frame(bytes: &[u8], order: IdOrder) -> Result<Frame, DecodeError> {
    if bytes.len() != CANFD_FRAME_LEN {
        return Err(DecodeError::Length {
            expected: CANFD_FRAME_LEN,
            got: bytes.len(),
        });
    }
    let can_id = order.read([bytes[0], bytes[1], bytes[2], bytes[3]]);
    let len = usize::from(bytes[4]);
    if len > FD_MAX_LEN {
        return Err(DecodeError::DataLength { len, fd: true });
    }
    Frame::from_raw(can_id, &bytes[8..8 + len], Some(FdFlags(bytes[5]).masked()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_can::{Id, StandardId};

    #[test]
    fn dlc_and_length_map_both_ways() {
        for dlc in 0..16 {
            assert_eq!(len_to_dlc(dlc_to_len(dlc)), dlc);
        }
        assert_eq!(len_to_dlc(9), 9, "9 bytes need the 12-byte DLC");
        assert_eq!(len_to_dlc(64), 15);
        assert!(is_fd_len(48) && !is_fd_len(49) && !is_fd_len(65));
    }

    #[test]
    fn the_canfd_frame_layout_holds_64_bytes_and_the_flags() {
        let id = Id::Standard(StandardId::new(0x123).unwrap());
        let data: [u8; 12] = core::array::from_fn(|i| i as u8);
        let f = Frame::fd(id, &data, FdFlags::new(true, false)).unwrap();
        let mut b = [0u8; CANFD_FRAME_LEN];
        assert_eq!(f.write_socketcan(&mut b, IdOrder::Network).unwrap(), 72);
        assert_eq!(&b[..8], &[0, 0, 1, 0x23, 12, 0x05, 0, 0]);
        assert_eq!(&b[8..20], &data);
        assert_eq!(Frame::read_socketcan(&b, IdOrder::Network).unwrap(), f);
        assert!(Frame::fd(id, &[0; 9], FdFlags::default()).is_none());
        b[4] = 13;
        assert_eq!(
            Frame::read_socketcan(&b, IdOrder::Network),
            Err(DecodeError::DataLength { len: 13, fd: true })
        );
    }
}
