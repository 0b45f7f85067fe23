//! The SDO protocol's 8-byte messages (CiA 301 §7.2.4.3): what a client asks
//! ([`Request`]) and what a server answers ([`Response`]), and the abort codes by name.
//!
//! The codec works on the 8-byte payload alone — on CAN it travels in COB-ID 0x600 + n
//! (client → server) and 0x580 + n (server → client); CANopen over EtherCAT (CoE) carries the
//! same bytes after its mailbox and CoE headers.
//!
//! Byte 0 is the command specifier; bytes 1–3 the index (u16, little-endian) and sub-index of
//! initiate and abort messages; bytes 4–7 expedited data, the size of a segmented transfer, or
//! the abort code. Client command specifiers (bits 7..5): 1 initiate download
//! (`0x20 | n << 2 | e << 1 | s`: `e` expedited, `s` size indicated, `n` bytes without data),
//! 0 download segment (`t << 4 | n << 1 | c`: toggle, bytes without data, last), 2 initiate
//! upload (0x40), 3 upload segment (`0x60 | t << 4`), 4 abort (0x80), 5 and 6 block
//! transfers. Server: 3 initiate download response (0x60), 1 download segment response
//! (`0x20 | t << 4`), 2 initiate upload response (`0x40 | n << 2 | e << 1 | s`), 0 upload
//! segment response (`t << 4 | n << 1 | c`), 4 abort.

use core::fmt;

/// Bytes of an SDO message.
pub const SDO_LEN: usize = 8;

/// An SDO abort code, with the names CiA 301 gives them (table 22).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct AbortCode(pub u32);

impl AbortCode {
    /// 0x0503_0000: toggle bit not alternated.
    pub const TOGGLE_BIT: Self = Self(0x0503_0000);
    /// 0x0504_0000: SDO protocol timed out.
    pub const TIMEOUT: Self = Self(0x0504_0000);
    /// 0x0504_0001: client/server command specifier not valid or unknown.
    pub const COMMAND_SPECIFIER: Self = Self(0x0504_0001);
    /// 0x0504_0005: out of memory.
    pub const OUT_OF_MEMORY: Self = Self(0x0504_0005);
    /// 0x0601_0000: unsupported access to an object.
    pub const UNSUPPORTED_ACCESS: Self = Self(0x0601_0000);
    /// 0x0601_0001: attempt to read a write-only object.
    pub const WRITE_ONLY: Self = Self(0x0601_0001);
    /// 0x0601_0002: attempt to write a read-only object.
    pub const READ_ONLY: Self = Self(0x0601_0002);
    /// 0x0602_0000: object does not exist in the object dictionary.
    pub const NO_OBJECT: Self = Self(0x0602_0000);
    /// 0x0604_0041: object cannot be mapped to the PDO.
    pub const NOT_MAPPABLE: Self = Self(0x0604_0041);
    /// 0x0604_0042: the mapped objects would exceed the PDO length.
    pub const PDO_TOO_LONG: Self = Self(0x0604_0042);
    /// 0x0604_0043: general parameter incompatibility.
    pub const PARAMETER_INCOMPATIBLE: Self = Self(0x0604_0043);
    /// 0x0607_0010: data type does not match, length of service parameter does not match.
    pub const LENGTH_MISMATCH: Self = Self(0x0607_0010);
    /// 0x0607_0012: length of service parameter too high.
    pub const LENGTH_TOO_HIGH: Self = Self(0x0607_0012);
    /// 0x0607_0013: length of service parameter too low.
    pub const LENGTH_TOO_LOW: Self = Self(0x0607_0013);
    /// 0x0609_0011: sub-index does not exist.
    pub const NO_SUB_INDEX: Self = Self(0x0609_0011);
    /// 0x0609_0030: invalid value for parameter.
    pub const INVALID_VALUE: Self = Self(0x0609_0030);
    /// 0x0609_0031: value of parameter written too high.
    pub const VALUE_TOO_HIGH: Self = Self(0x0609_0031);
    /// 0x0609_0032: value of parameter written too low.
    pub const VALUE_TOO_LOW: Self = Self(0x0609_0032);
    /// 0x0800_0000: general error.
    pub const GENERAL: Self = Self(0x0800_0000);
    /// 0x0800_0022: data cannot be transferred because of the present device state.
    pub const DEVICE_STATE: Self = Self(0x0800_0022);

    /// The name CiA 301 gives the code (`None` if it is not a standard code).
    pub const fn name(self) -> Option<&'static str> {
        Some(match self.0 {
            0x0503_0000 => "toggle bit not alternated",
            0x0504_0000 => "SDO protocol timed out",
            0x0504_0001 => "client/server command specifier not valid or unknown",
            0x0504_0002 => "invalid block size",
            0x0504_0003 => "invalid sequence number",
            0x0504_0004 => "CRC error",
            0x0504_0005 => "out of memory",
            0x0601_0000 => "unsupported access to an object",
            0x0601_0001 => "attempt to read a write-only object",
            0x0601_0002 => "attempt to write a read-only object",
            0x0602_0000 => "object does not exist in the object dictionary",
            0x0604_0041 => "object cannot be mapped to the PDO",
            0x0604_0042 => {
                "the number and length of the objects to be mapped would exceed the PDO length"
            }
            0x0604_0043 => "general parameter incompatibility",
            0x0604_0047 => "general internal incompatibility in the device",
            0x0606_0000 => "access failed due to a hardware error",
            0x0607_0010 => "data type does not match, length of service parameter does not match",
            0x0607_0012 => "data type does not match, length of service parameter too high",
            0x0607_0013 => "data type does not match, length of service parameter too low",
            0x0609_0011 => "sub-index does not exist",
            0x0609_0030 => "invalid value for parameter",
            0x0609_0031 => "value of parameter written too high",
            0x0609_0032 => "value of parameter written too low",
            0x0609_0036 => "maximum value is less than minimum value",
            0x060A_0023 => "resource not available: SDO connection",
            0x0800_0000 => "general error",
            0x0800_0020 => "data cannot be transferred or stored to the application",
            0x0800_0021 => "data cannot be transferred or stored because of local control",
            0x0800_0022 => {
                "data cannot be transferred or stored because of the present device state"
            }
            0x0800_0023 => "object dictionary dynamic generation failed or no object dictionary",
            0x0800_0024 => "no data available",
            _ => return None,
        })
    }
}

impl fmt::Display for AbortCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(name) => write!(f, "{:#010x} ({name})", self.0),
            None => write!(f, "{:#010x} (not a standard abort code)", self.0),
        }
    }
}

impl fmt::Debug for AbortCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "AbortCode({self})")
    }
}

/// An object address: index and sub-index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Address {
    /// The index.
    pub index: u16,
    /// The sub-index.
    pub sub: u8,
}

impl Address {
    /// `index`, `sub`.
    pub const fn new(index: u16, sub: u8) -> Self {
        Self { index, sub }
    }
}

impl fmt::Display for Address {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:#06x}:{:02x}", self.index, self.sub)
    }
}

/// Up to 7 data bytes of one message (a segment, or 4 expedited bytes).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Chunk {
    bytes: [u8; 7],
    len: u8,
}

impl Chunk {
    /// The first at most 7 bytes of `data` (`None` if longer).
    pub fn new(data: &[u8]) -> Option<Self> {
        if data.len() > 7 {
            return None;
        }
        let mut bytes = [0; 7];
        bytes[..data.len()].copy_from_slice(data);
        Some(Self {
            bytes,
            len: data.len() as u8,
        })
    }

    /// The first at most 7 bytes of `data` (the rest is cut).
    pub fn truncated(data: &[u8]) -> Self {
        let n = data.len().min(7);
        let mut bytes = [0; 7];
        bytes[..n].copy_from_slice(&data[..n]);
        Self {
            bytes,
            len: n as u8,
        }
    }

    /// The bytes.
    pub fn as_slice(&self) -> &[u8] {
        &self.bytes[..usize::from(self.len)]
    }
}

impl fmt::Debug for Chunk {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:02x?}", self.as_slice())
    }
}

/// A client → server message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request {
    /// Write 1..=4 bytes in one message.
    DownloadExpedited {
        /// The object.
        address: Address,
        /// The data (1..=4 bytes).
        data: Chunk,
    },
    /// Start a segmented write of `size` bytes (if indicated).
    DownloadInitiate {
        /// The object.
        address: Address,
        /// Bytes to follow, if the client said.
        size: Option<u32>,
    },
    /// One segment of a segmented write.
    DownloadSegment {
        /// The toggle bit (0 for the first segment).
        toggle: bool,
        /// 0..=7 data bytes.
        data: Chunk,
        /// Whether this is the last segment.
        last: bool,
    },
    /// Read an object.
    UploadInitiate {
        /// The object.
        address: Address,
    },
    /// Ask for the next segment of a read.
    UploadSegment {
        /// The toggle bit.
        toggle: bool,
    },
    /// Abort the transfer.
    Abort {
        /// The object.
        address: Address,
        /// Why.
        code: AbortCode,
    },
    /// A block transfer (command specifier 5 or 6), which this codec does not carry further.
    Block {
        /// The command byte.
        command: u8,
    },
}

/// A server → client message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Response {
    /// The write may proceed (or, expedited, is done).
    DownloadInitiate {
        /// The object.
        address: Address,
    },
    /// A segment was written.
    DownloadSegment {
        /// The toggle bit of the acknowledged segment.
        toggle: bool,
    },
    /// The read's data, 1..=4 bytes in this message (or 4 unsized bytes).
    UploadExpedited {
        /// The object.
        address: Address,
        /// The data.
        data: Chunk,
    },
    /// A segmented read of `size` bytes (if indicated) begins.
    UploadInitiate {
        /// The object.
        address: Address,
        /// Bytes to follow, if the server said.
        size: Option<u32>,
    },
    /// One segment of a read.
    UploadSegment {
        /// The toggle bit.
        toggle: bool,
        /// 0..=7 data bytes.
        data: Chunk,
        /// Whether this is the last segment.
        last: bool,
    },
    /// The transfer was aborted.
    Abort {
        /// The object.
        address: Address,
        /// Why.
        code: AbortCode,
    },
}

/// Why 8 bytes are not an SDO message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DecodeError {
    /// Not 8 bytes.
    Length {
        /// The length found.
        len: usize,
    },
    /// A command specifier the direction does not have.
    Command {
        /// Byte 0.
        byte: u8,
    },
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeError::Length { len } => write!(f, "SDO message of {len} bytes, expected 8"),
            DecodeError::Command { byte } => write!(f, "unknown SDO command byte {byte:#04x}"),
        }
    }
}

fn address(b: &[u8; 8]) -> Address {
    Address::new(u16::from_le_bytes([b[1], b[2]]), b[3])
}

fn put_address(b: &mut [u8; 8], a: Address) {
    b[1..3].copy_from_slice(&a.index.to_le_bytes());
    b[3] = a.sub;
}

fn u32_at(b: &[u8; 8]) -> u32 {
    u32::from_le_bytes([b[4], b[5], b[6], b[7]])
}

fn bytes8(data: &[u8]) -> Result<&[u8; 8], DecodeError> {
    data.try_into()
        .map_err(|_| DecodeError::Length { len: data.len() })
}

/// Expedited data: 4 − n bytes when the size is indicated, else all 4.
fn expedited(b: &[u8; 8]) -> Chunk {
    let n = if b[0] & 0x01 != 0 {
        4 - usize::from((b[0] >> 2) & 0x03)
    } else {
        4
    };
    Chunk::truncated(&b[4..4 + n])
}

fn segment(b: &[u8; 8]) -> (bool, Chunk, bool) {
    let n = 7 - usize::from((b[0] >> 1) & 0x07);
    let data = Chunk::truncated(&b[1..1 + n]);
    (b[0] & 0x10 != 0, data, b[0] & 0x01 != 0)
}

fn put_segment(toggle: bool, data: &Chunk, last: bool) -> [u8; 8] {
    let mut b = [0u8; 8];
    let n = data.as_slice().len();
    b[0] = (u8::from(toggle) << 4) | (((7 - n) as u8) << 1) | u8::from(last);
    b[1..1 + n].copy_from_slice(data.as_slice());
    b
}

fn put_expedited(command: u8, a: Address, data: &Chunk) -> [u8; 8] {
    let mut b = [0u8; 8];
    let n = data.as_slice().len().min(4);
    b[0] = command | (((4 - n) as u8) << 2) | 0x03;
    put_address(&mut b, a);
    b[4..4 + n].copy_from_slice(&data.as_slice()[..n]);
    b
}

fn put_initiate(command: u8, a: Address, size: Option<u32>) -> [u8; 8] {
    let mut b = [0u8; 8];
    b[0] = command | u8::from(size.is_some());
    put_address(&mut b, a);
    b[4..].copy_from_slice(&size.unwrap_or(0).to_le_bytes());
    b
}

fn put_abort(a: Address, code: AbortCode) -> [u8; 8] {
    let mut b = [0u8; 8];
    b[0] = 0x80;
    put_address(&mut b, a);
    b[4..].copy_from_slice(&code.0.to_le_bytes());
    b
}

impl Request {
    /// Decodes a client → server message.
    pub fn decode(data: &[u8]) -> Result<Self, DecodeError> {
        let b = bytes8(data)?;
        Ok(match b[0] >> 5 {
            1 if b[0] & 0x02 != 0 => Request::DownloadExpedited {
                address: address(b),
                data: expedited(b),
            },
            1 => Request::DownloadInitiate {
                address: address(b),
                size: (b[0] & 0x01 != 0).then(|| u32_at(b)),
            },
            0 => {
                let (toggle, data, last) = segment(b);
                Request::DownloadSegment { toggle, data, last }
            }
            2 => Request::UploadInitiate {
                address: address(b),
            },
            3 => Request::UploadSegment {
                toggle: b[0] & 0x10 != 0,
            },
            4 => Request::Abort {
                address: address(b),
                code: AbortCode(u32_at(b)),
            },
            5 | 6 => Request::Block { command: b[0] },
            _ => return Err(DecodeError::Command { byte: b[0] }),
        })
    }

    /// The 8 bytes.
    pub fn encode(&self) -> [u8; 8] {
        match *self {
            Request::DownloadExpedited { address, data } => put_expedited(0x20, address, &data),
            Request::DownloadInitiate { address, size } => put_initiate(0x20, address, size),
            Request::DownloadSegment { toggle, data, last } => put_segment(toggle, &data, last),
            Request::UploadInitiate { address } => put_initiate(0x40, address, None),
            Request::UploadSegment { toggle } => {
                [0x60 | (u8::from(toggle) << 4), 0, 0, 0, 0, 0, 0, 0]
            }
            Request::Abort { address, code } => put_abort(address, code),
            Request::Block { command } => [command, 0, 0, 0, 0, 0, 0, 0],
        }
    }
}

impl Response {
    /// Decodes a server → client message.
    pub fn decode(data: &[u8]) -> Result<Self, DecodeError> {
        let b = bytes8(data)?;
        Ok(match b[0] >> 5 {
            3 => Response::DownloadInitiate {
                address: address(b),
            },
            1 => Response::DownloadSegment {
                toggle: b[0] & 0x10 != 0,
            },
            2 if b[0] & 0x02 != 0 => Response::UploadExpedited {
                address: address(b),
                data: expedited(b),
            },
            2 => Response::UploadInitiate {
                address: address(b),
                size: (b[0] & 0x01 != 0).then(|| u32_at(b)),
            },
            0 => {
                let (toggle, data, last) = segment(b);
                Response::UploadSegment { toggle, data, last }
            }
            4 => Response::Abort {
                address: address(b),
                code: AbortCode(u32_at(b)),
            },
            _ => return Err(DecodeError::Command { byte: b[0] }),
        })
    }

    /// The 8 bytes.
    pub fn encode(&self) -> [u8; 8] {
        match *self {
            Response::DownloadInitiate { address } => {
                let mut b = [0u8; 8];
                b[0] = 0x60;
                put_address(&mut b, address);
                b
            }
            Response::DownloadSegment { toggle } => {
                [0x20 | (u8::from(toggle) << 4), 0, 0, 0, 0, 0, 0, 0]
            }
            Response::UploadExpedited { address, data } => put_expedited(0x40, address, &data),
            Response::UploadInitiate { address, size } => put_initiate(0x40, address, size),
            Response::UploadSegment { toggle, data, last } => put_segment(toggle, &data, last),
            Response::Abort { address, code } => put_abort(address, code),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expedited_messages_have_the_reference_command_bytes() {
        let a = Address::new(0x6040, 0);
        for (len, cmd) in [(4, 0x23), (3, 0x27), (2, 0x2B), (1, 0x2F)] {
            let r = Request::DownloadExpedited {
                address: a,
                data: Chunk::new(&[0x0F, 0, 0, 0][..len]).unwrap(),
            };
            let b = r.encode();
            assert_eq!(b[0], cmd);
            assert_eq!(&b[1..4], &[0x40, 0x60, 0]);
            assert_eq!(Request::decode(&b), Ok(r));
        }
        let up = Request::UploadInitiate {
            address: Address::new(0x1018, 1),
        }
        .encode();
        assert_eq!(up, [0x40, 0x18, 0x10, 1, 0, 0, 0, 0]);
        for (len, cmd) in [(4, 0x43), (3, 0x47), (2, 0x4B), (1, 0x4F)] {
            let r = Response::UploadExpedited {
                address: a,
                data: Chunk::new(&[1, 2, 3, 4][..len]).unwrap(),
            };
            assert_eq!(r.encode()[0], cmd);
            assert_eq!(Response::decode(&r.encode()), Ok(r));
        }
        assert_eq!(Response::DownloadInitiate { address: a }.encode()[0], 0x60);
    }

    #[test]
    fn segments_and_aborts_round_trip() {
        let s = Response::UploadSegment {
            toggle: true,
            data: Chunk::new(b"abc").unwrap(),
            last: true,
        };
        // t = 1, n = 4 bytes without data, c = 1.
        assert_eq!(s.encode()[0], 0x10 | (4 << 1) | 1);
        assert_eq!(Response::decode(&s.encode()), Ok(s));
        let abort = Response::Abort {
            address: Address::new(0x2000, 3),
            code: AbortCode::NO_OBJECT,
        };
        assert_eq!(abort.encode(), [0x80, 0, 0x20, 3, 0, 0, 0x02, 0x06]);
        assert_eq!(
            AbortCode(0x0609_0011).to_string(),
            "0x06090011 (sub-index does not exist)"
        );
        assert_eq!(AbortCode(0x1234).name(), None);
        assert_eq!(
            Request::decode(&[0xE0, 0, 0, 0, 0, 0, 0, 0]),
            Err(DecodeError::Command { byte: 0xE0 })
        );
        assert_eq!(
            Response::decode(&[0; 7]),
            Err(DecodeError::Length { len: 7 })
        );
        // Unsized expedited upload: all four bytes.
        let r = Response::decode(&[0x42, 0x64, 0x60, 0, 1, 2, 3, 4]).unwrap();
        assert!(
            matches!(r, Response::UploadExpedited { data, .. } if data.as_slice() == [1, 2, 3, 4])
        );
    }
}
