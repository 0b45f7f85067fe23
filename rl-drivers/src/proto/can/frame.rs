//! One CAN frame, classic (CAN 2.0A with an 11-bit identifier, 2.0B with a 29-bit one) or
//! CAN FD, kept as Linux keeps it: the identifier with the `canid_t` flags (EFF `0x8000_0000`,
//! RTR `0x4000_0000`, ERR `0x2000_0000`), a length and up to 64 data bytes.
//!
//! The SocketCAN `struct can_frame` (16 bytes): `can_id u32 | len u8 | __pad u8 | __res0 u8 |
//! len8_dlc u8 | data[8]`. The kernel uses host byte order for `can_id`; the pcap link type
//! `LINKTYPE_CAN_SOCKETCAN` (227) stores it in network (big-endian) byte order ([`IdOrder`]).
//! The 72-byte `struct canfd_frame` is in [`fd`].

use core::fmt;

use embedded_can::{ExtendedId, Id, StandardId};

use super::fd::{self, FdFlags};

/// `canid_t` flag: the identifier is 29 bits (CAN 2.0B).
pub const EFF_FLAG: u32 = 0x8000_0000;
/// `canid_t` flag: a remote transmission request.
pub const RTR_FLAG: u32 = 0x4000_0000;
/// `canid_t` flag: an error frame (the other bits hold the error class).
pub const ERR_FLAG: u32 = 0x2000_0000;
/// Bits of a standard identifier.
pub const SFF_MASK: u32 = 0x0000_07FF;
/// Bits of an extended identifier (and of an error class).
pub const EFF_MASK: u32 = 0x1FFF_FFFF;
/// Bytes of a SocketCAN `struct can_frame`.
pub const CAN_FRAME_LEN: usize = 16;
/// Most data bytes of a classic frame.
pub const CLASSIC_MAX_LEN: usize = 8;

/// Byte order of `can_id` in a SocketCAN structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IdOrder {
    /// The host's order, as the kernel's sockets use it.
    Host,
    /// Network (big-endian) order, as pcap's link type 227 stores it.
    Network,
}

impl IdOrder {
    pub(crate) fn read(self, b: [u8; 4]) -> u32 {
        match self {
            IdOrder::Host => u32::from_ne_bytes(b),
            IdOrder::Network => u32::from_be_bytes(b),
        }
    }

    pub(crate) fn write(self, v: u32) -> [u8; 4] {
        match self {
            IdOrder::Host => v.to_ne_bytes(),
            IdOrder::Network => v.to_be_bytes(),
        }
    }
}

/// Why bytes are not a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DecodeError {
    /// Too few bytes for the structure (or a buffer too small to write one).
    Length {
        /// Bytes needed.
        expected: usize,
        /// Bytes there.
        got: usize,
    },
    /// A standard identifier with bits above bit 10 set (the `canid_t` value is given).
    Identifier {
        /// The raw `canid_t`.
        can_id: u32,
    },
    /// A data length beyond what the frame kind allows (8 classic, 64 FD), or an FD length
    /// that is no CAN FD length (9..=11, 13..=15, …).
    DataLength {
        /// The length field.
        len: usize,
        /// Whether the frame is CAN FD.
        fd: bool,
    },
    /// An RTR frame that is CAN FD or an error frame (CAN FD has no remote frames).
    RemoteFd,
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeError::Length { expected, got } => {
                write!(f, "{got} bytes, a frame needs {expected}")
            }
            DecodeError::Identifier { can_id } => write!(
                f,
                "can_id {can_id:#010x}: a standard identifier has bits above bit 10"
            ),
            DecodeError::DataLength { len, fd: true } => {
                write!(
                    f,
                    "data length {len} is no CAN FD length (0-8, 12, 16, 20, 24, 32, 48, 64)"
                )
            }
            DecodeError::DataLength { len, fd: false } => {
                write!(f, "data length {len} exceeds 8 bytes of a classic frame")
            }
            DecodeError::RemoteFd => f.write_str("CAN FD and error frames have no RTR form"),
        }
    }
}

/// A CAN frame: classic or CAN FD, data, remote or error. Invariants (every constructor and
/// decoder checks them): a standard identifier fits 11 bits; `len` ≤ 8 for a classic frame and
/// is a CAN FD length for an FD frame; a remote frame is classic, carries no data and keeps
/// its DLC in `len`; an error frame is classic with 8 data bytes.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Frame {
    can_id: u32,
    len: u8,
    fd: Option<FdFlags>,
    data: [u8; fd::FD_MAX_LEN],
}

impl Frame {
    /// A classic data frame with a standard identifier `id` (0..=0x7FF) — the form every
    /// CANopen frame takes. `None` if the identifier or the length is out of range.
    pub fn standard(id: u16, data: &[u8]) -> Option<Self> {
        Self::data_frame(Id::Standard(StandardId::new(id)?), data)
    }

    /// A classic data frame (at most 8 bytes).
    pub fn data_frame(id: Id, data: &[u8]) -> Option<Self> {
        if data.len() > CLASSIC_MAX_LEN {
            return None;
        }
        let mut d = [0; fd::FD_MAX_LEN];
        d[..data.len()].copy_from_slice(data);
        Some(Self {
            can_id: raw_id(id),
            len: data.len() as u8,
            fd: None,
            data: d,
        })
    }

    /// A classic remote frame requesting `dlc` (0..=8) bytes.
    pub fn remote(id: Id, dlc: usize) -> Option<Self> {
        if dlc > CLASSIC_MAX_LEN {
            return None;
        }
        Some(Self {
            can_id: raw_id(id) | RTR_FLAG,
            len: dlc as u8,
            fd: None,
            data: [0; fd::FD_MAX_LEN],
        })
    }

    /// A CAN FD frame; `data.len()` must be a CAN FD length (0..=8, 12, 16, 20, 24, 32, 48, 64).
    pub fn fd(id: Id, data: &[u8], flags: FdFlags) -> Option<Self> {
        if !fd::is_fd_len(data.len()) {
            return None;
        }
        let mut d = [0; fd::FD_MAX_LEN];
        d[..data.len()].copy_from_slice(data);
        Some(Self {
            can_id: raw_id(id),
            len: data.len() as u8,
            fd: Some(flags),
            data: d,
        })
    }

    /// A SocketCAN error frame: `class` (the `CAN_ERR_*` bits, masked to 29 bits) and its 8
    /// data bytes.
    pub fn error(class: u32, data: [u8; 8]) -> Self {
        let mut d = [0; fd::FD_MAX_LEN];
        d[..8].copy_from_slice(&data);
        Self {
            can_id: ERR_FLAG | (class & EFF_MASK),
            len: 8,
            fd: None,
            data: d,
        }
    }

    /// A frame from a raw `canid_t` (flags included), checked. `fd` makes it CAN FD.
    pub fn from_raw(can_id: u32, data: &[u8], fd: Option<FdFlags>) -> Result<Self, DecodeError> {
        let len = data.len();
        check_id(can_id)?;
        let remote = can_id & RTR_FLAG != 0 && can_id & ERR_FLAG == 0;
        match fd {
            Some(_) if remote => return Err(DecodeError::RemoteFd),
            Some(_) if can_id & ERR_FLAG != 0 => return Err(DecodeError::RemoteFd),
            Some(_) if !fd::is_fd_len(len) => {
                return Err(DecodeError::DataLength { len, fd: true });
            }
            None if len > CLASSIC_MAX_LEN => {
                return Err(DecodeError::DataLength { len, fd: false });
            }
            _ => {}
        }
        let mut d = [0; fd::FD_MAX_LEN];
        if !remote {
            d[..len].copy_from_slice(data);
        }
        Ok(Self {
            can_id,
            len: len as u8,
            fd,
            data: d,
        })
    }

    /// A remote frame from a raw `canid_t` (with [`RTR_FLAG`]) requesting `dlc` bytes.
    pub fn remote_from_raw(can_id: u32, dlc: usize) -> Result<Self, DecodeError> {
        check_id(can_id)?;
        if dlc > CLASSIC_MAX_LEN {
            return Err(DecodeError::DataLength {
                len: dlc,
                fd: false,
            });
        }
        Ok(Self {
            can_id: can_id | RTR_FLAG,
            len: dlc as u8,
            fd: None,
            data: [0; fd::FD_MAX_LEN],
        })
    }

    /// The Linux `canid_t`: identifier and flags.
    pub const fn raw_id(&self) -> u32 {
        self.can_id
    }

    /// The identifier without flags: 11 or 29 bits (for an error frame, the error class).
    pub const fn id_bits(&self) -> u32 {
        if self.can_id & EFF_FLAG != 0 || self.can_id & ERR_FLAG != 0 {
            self.can_id & EFF_MASK
        } else {
            self.can_id & SFF_MASK
        }
    }

    /// The standard identifier of a classic data frame, `None` for any other frame — what a
    /// CANopen receiver dispatches on.
    pub const fn standard_id(&self) -> Option<u16> {
        if self.can_id & (EFF_FLAG | RTR_FLAG | ERR_FLAG) == 0 && self.fd.is_none() {
            Some((self.can_id & SFF_MASK) as u16)
        } else {
            None
        }
    }

    /// Whether this is an error frame.
    pub const fn is_error_frame(&self) -> bool {
        self.can_id & ERR_FLAG != 0
    }

    /// Whether this is a CAN FD frame.
    pub const fn is_fd(&self) -> bool {
        self.fd.is_some()
    }

    /// The CAN FD flags (`None` for a classic frame).
    pub const fn fd_flags(&self) -> Option<FdFlags> {
        self.fd
    }

    /// The data length (a remote frame's requested DLC).
    pub const fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether the frame carries no data.
    pub const fn is_empty(&self) -> bool {
        self.len == 0 || self.can_id & RTR_FLAG != 0 && self.can_id & ERR_FLAG == 0
    }

    /// The data bytes (empty for a remote frame).
    pub fn bytes(&self) -> &[u8] {
        if self.is_remote() {
            &[]
        } else {
            &self.data[..usize::from(self.len)]
        }
    }

    fn is_remote(&self) -> bool {
        self.can_id & RTR_FLAG != 0 && self.can_id & ERR_FLAG == 0
    }

    /// Writes the SocketCAN structure: 16 bytes `struct can_frame` for a classic frame, 72
    /// bytes `struct canfd_frame` for CAN FD. Returns the bytes written.
    pub fn write_socketcan(&self, out: &mut [u8], order: IdOrder) -> Result<usize, DecodeError> {
        if self.fd.is_some() {
            return fd::write_canfd_frame(self, out, order);
        }
        let Some(out) = out.get_mut(..CAN_FRAME_LEN) else {
            return Err(DecodeError::Length {
                expected: CAN_FRAME_LEN,
                got: out.len(),
            });
        };
        out[..4].copy_from_slice(&order.write(self.can_id));
        out[4] = self.len;
        out[5..8].fill(0);
        out[8..16].fill(0);
        let n = self.bytes().len();
        out[8..8 + n].copy_from_slice(self.bytes());
        Ok(CAN_FRAME_LEN)
    }

    /// Reads a SocketCAN structure: 16 bytes are a `struct can_frame`, 72 a `struct
    /// canfd_frame` (the kernel tells them apart by the size of the read, and so does this).
    pub fn read_socketcan(bytes: &[u8], order: IdOrder) -> Result<Self, DecodeError> {
        if bytes.len() == fd::CANFD_FRAME_LEN {
            return fd::read_canfd_frame(bytes, order);
        }
        if bytes.len() != CAN_FRAME_LEN {
            return Err(DecodeError::Length {
                expected: CAN_FRAME_LEN,
                got: bytes.len(),
            });
        }
        let can_id = order.read([bytes[0], bytes[1], bytes[2], bytes[3]]);
        let len = usize::from(bytes[4]);
        if can_id & RTR_FLAG != 0 && can_id & ERR_FLAG == 0 {
            return Self::remote_from_raw(can_id & !RTR_FLAG, len);
        }
        if len > CLASSIC_MAX_LEN {
            return Err(DecodeError::DataLength { len, fd: false });
        }
        Self::from_raw(can_id, &bytes[8..8 + len], None)
    }
}

/// The `canid_t` of an identifier (EFF flag for an extended one).
fn raw_id(id: Id) -> u32 {
    match id {
        Id::Standard(s) => u32::from(s.as_raw()),
        Id::Extended(e) => e.as_raw() | EFF_FLAG,
    }
}

fn check_id(can_id: u32) -> Result<(), DecodeError> {
    if can_id & (EFF_FLAG | ERR_FLAG) == 0 && can_id & EFF_MASK & !SFF_MASK != 0 {
        return Err(DecodeError::Identifier { can_id });
    }
    Ok(())
}

impl embedded_can::Frame for Frame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        Self::data_frame(id.into(), data)
    }

    fn new_remote(id: impl Into<Id>, dlc: usize) -> Option<Self> {
        Self::remote(id.into(), dlc)
    }

    fn is_extended(&self) -> bool {
        self.can_id & EFF_FLAG != 0
    }

    fn is_remote_frame(&self) -> bool {
        self.is_remote()
    }

    fn id(&self) -> Id {
        if self.can_id & EFF_FLAG != 0 || self.can_id & ERR_FLAG != 0 {
            // An error class is at most 29 bits, so this never fails.
            Id::Extended(ExtendedId::new(self.can_id & EFF_MASK).unwrap_or(ExtendedId::ZERO))
        } else {
            Id::Standard(
                StandardId::new((self.can_id & SFF_MASK) as u16).unwrap_or(StandardId::ZERO),
            )
        }
    }

    fn dlc(&self) -> usize {
        fd::len_to_dlc(usize::from(self.len))
    }

    fn data(&self) -> &[u8] {
        self.bytes()
    }
}

impl fmt::Debug for Frame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Frame({self})")
    }
}

/// The candump form without timestamp and interface: `123#0F00`, `12345678#R`, `123##1AA`.
impl fmt::Display for Frame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        super::candump::write_frame(f, self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_can::Frame as _;

    #[test]
    fn the_can_frame_layout_is_linux_s() {
        // RPDO1 of node 1: controlword 0x000F, target 0x1000 (the reference's worked example).
        let f = Frame::standard(0x201, &[0x0F, 0, 0, 0x10, 0, 0]).unwrap();
        let mut b = [0xAA; 16];
        assert_eq!(f.write_socketcan(&mut b, IdOrder::Network).unwrap(), 16);
        assert_eq!(b, [0, 0, 2, 1, 6, 0, 0, 0, 0x0F, 0, 0, 0x10, 0, 0, 0, 0]);
        assert_eq!(Frame::read_socketcan(&b, IdOrder::Network).unwrap(), f);
        f.write_socketcan(&mut b, IdOrder::Host).unwrap();
        assert_eq!(&b[..4], &0x201u32.to_ne_bytes());
    }

    #[test]
    fn identifiers_flags_and_lengths_are_checked() {
        let ext = Id::Extended(ExtendedId::new(0x1234_5678).unwrap());
        let f = Frame::data_frame(ext, &[1, 2]).unwrap();
        assert!(f.is_extended());
        assert_eq!(f.raw_id(), 0x9234_5678);
        assert_eq!(f.standard_id(), None);
        assert!(Frame::standard(0x800, &[]).is_none());
        assert!(Frame::standard(0x7FF, &[0; 9]).is_none());
        let r = Frame::remote(Id::Standard(StandardId::new(0x701).unwrap()), 1).unwrap();
        assert!(r.is_remote_frame() && r.bytes().is_empty() && r.dlc() == 1);
        assert_eq!(
            Frame::from_raw(0x800, &[], None),
            Err(DecodeError::Identifier { can_id: 0x800 })
        );
        let mut b = [0u8; 16];
        b[4] = 9;
        assert_eq!(
            Frame::read_socketcan(&b, IdOrder::Host),
            Err(DecodeError::DataLength { len: 9, fd: false })
        );
        assert!(matches!(
            Frame::read_socketcan(&b[..15], IdOrder::Host),
            Err(DecodeError::Length { .. })
        ));
        let e = Frame::error(0x04, [0, 4, 0, 0, 0, 0, 0, 0]);
        assert!(e.is_error_frame() && !e.is_extended() && e.len() == 8);
        e.write_socketcan(&mut b, IdOrder::Host).unwrap();
        assert_eq!(Frame::read_socketcan(&b, IdOrder::Host).unwrap(), e);
    }
}
