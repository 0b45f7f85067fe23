//! The mailbox header (ETG.1000.4 §5.6) that starts every message in the mailbox sync
//! managers, and the mailbox error reply a device sends for what it cannot handle.
//!
//! ```text
//! 0-1 length (bytes after the header)   2-3 address (station address of the sender)
//! 4   channel:6 | priority:2            5   type:4 | counter:3 | reserved:1
//! ```
//!
//! Types: 0 error reply, 1 AoE, 2 EoE, 3 CoE, 4 FoE, 5 SoE, 15 VoE. The counter (1..=7, 0
//! only in the first message after INIT) lets the device detect a repeated message.

use core::fmt;

/// Bytes of the header.
pub const HEADER_LEN: usize = 6;

/// A mailbox protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MailboxType {
    /// 0: error reply.
    Error,
    /// 1: ADS over EtherCAT.
    Aoe,
    /// 2: Ethernet over EtherCAT.
    Eoe,
    /// 3: CANopen over EtherCAT.
    Coe,
    /// 4: file access over EtherCAT.
    Foe,
    /// 5: servo drive profile over EtherCAT.
    Soe,
    /// 15: vendor specific.
    Voe,
    /// Any other code.
    Other(u8),
}

impl MailboxType {
    /// The 4-bit code.
    pub const fn code(self) -> u8 {
        match self {
            MailboxType::Error => 0,
            MailboxType::Aoe => 1,
            MailboxType::Eoe => 2,
            MailboxType::Coe => 3,
            MailboxType::Foe => 4,
            MailboxType::Soe => 5,
            MailboxType::Voe => 15,
            MailboxType::Other(c) => c & 0x0F,
        }
    }

    /// The type of a code.
    pub const fn from_code(code: u8) -> Self {
        match code & 0x0F {
            0 => MailboxType::Error,
            1 => MailboxType::Aoe,
            2 => MailboxType::Eoe,
            3 => MailboxType::Coe,
            4 => MailboxType::Foe,
            5 => MailboxType::Soe,
            15 => MailboxType::Voe,
            c => MailboxType::Other(c),
        }
    }

    /// The bit of the protocol in SII word 0x1C (mailbox protocols supported).
    pub const fn sii_bit(self) -> u16 {
        match self {
            MailboxType::Aoe => 0x01,
            MailboxType::Eoe => 0x02,
            MailboxType::Coe => 0x04,
            MailboxType::Foe => 0x08,
            MailboxType::Soe => 0x10,
            MailboxType::Voe => 0x20,
            MailboxType::Error | MailboxType::Other(_) => 0,
        }
    }
}

/// A mailbox header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MailboxHeader {
    /// Bytes of the message after the header.
    pub length: u16,
    /// Station address of the sender (0 from the master).
    pub address: u16,
    /// Channel (6 bits).
    pub channel: u8,
    /// Priority (2 bits).
    pub priority: u8,
    /// Protocol.
    pub kind: MailboxType,
    /// Repeat counter (3 bits).
    pub counter: u8,
}

impl MailboxHeader {
    /// A header of `kind` over `length` bytes with `counter`.
    pub const fn new(kind: MailboxType, length: u16, counter: u8) -> Self {
        Self {
            length,
            address: 0,
            channel: 0,
            priority: 0,
            kind,
            counter: counter & 0x07,
        }
    }

    /// Decodes the first 6 bytes.
    pub fn decode(bytes: &[u8]) -> Result<Self, MailboxError> {
        let Some(b) = bytes.get(..HEADER_LEN) else {
            return Err(MailboxError::TooShort {
                len: bytes.len(),
                need: HEADER_LEN,
            });
        };
        Ok(Self {
            length: u16::from_le_bytes([b[0], b[1]]),
            address: u16::from_le_bytes([b[2], b[3]]),
            channel: b[4] & 0x3F,
            priority: b[4] >> 6,
            kind: MailboxType::from_code(b[5]),
            counter: (b[5] >> 4) & 0x07,
        })
    }

    /// The 6 bytes.
    pub fn encode(&self) -> [u8; HEADER_LEN] {
        let l = self.length.to_le_bytes();
        let a = self.address.to_le_bytes();
        [
            l[0],
            l[1],
            a[0],
            a[1],
            (self.channel & 0x3F) | (self.priority << 6),
            self.kind.code() | ((self.counter & 0x07) << 4),
        ]
    }

    /// Decodes a whole message from a mailbox buffer: the header and the `length` bytes after
    /// it (the rest of the buffer is unused).
    pub fn split(buffer: &[u8]) -> Result<(Self, &[u8]), MailboxError> {
        let h = Self::decode(buffer)?;
        let end = HEADER_LEN + usize::from(h.length);
        match buffer.get(HEADER_LEN..end) {
            Some(body) => Ok((h, body)),
            None => Err(MailboxError::Length {
                declared: h.length,
                capacity: buffer.len() - HEADER_LEN,
            }),
        }
    }

    /// The counter that follows `counter` (1..=7, wrapping past 0).
    pub const fn next_counter(counter: u8) -> u8 {
        if counter >= 7 { 1 } else { counter + 1 }
    }
}

/// A mailbox error reply's detail code (ETG.1000.4 table "mailbox error reply").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MailboxErrorCode(pub u16);

impl MailboxErrorCode {
    /// 1: syntax of the header is wrong.
    pub const SYNTAX: Self = Self(1);
    /// 2: the protocol is not supported.
    pub const UNSUPPORTED_PROTOCOL: Self = Self(2);
    /// 3: the channel field is not 0.
    pub const INVALID_CHANNEL: Self = Self(3);
    /// 4: the service is not supported.
    pub const SERVICE_NOT_SUPPORTED: Self = Self(4);
    /// 5: the protocol's header is invalid.
    pub const INVALID_HEADER: Self = Self(5);
    /// 6: the data is too short.
    pub const SIZE_TOO_SHORT: Self = Self(6);
    /// 7: not enough memory.
    pub const NO_MEMORY: Self = Self(7);
    /// 8: the data size is inconsistent.
    pub const INVALID_SIZE: Self = Self(8);

    /// The name.
    pub const fn name(self) -> &'static str {
        match self.0 {
            1 => "syntax error",
            2 => "protocol not supported",
            3 => "invalid channel",
            4 => "service not supported",
            5 => "invalid protocol header",
            6 => "data too short",
            7 => "no more memory",
            8 => "inconsistent data size",
            _ => "unknown mailbox error",
        }
    }

    /// The body of an error reply (service 1, then this code).
    pub const fn reply_body(self) -> [u8; 4] {
        let c = self.0.to_le_bytes();
        [0x01, 0x00, c[0], c[1]]
    }

    /// The code of an error reply's body.
    pub fn from_reply(body: &[u8]) -> Option<Self> {
        match body {
            [0x01, 0x00, lo, hi, ..] => Some(Self(u16::from_le_bytes([*lo, *hi]))),
            _ => None,
        }
    }
}

impl fmt::Display for MailboxErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "mailbox error {} ({})", self.0, self.name())
    }
}

/// Why bytes are not a mailbox message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MailboxError {
    /// Shorter than a header.
    TooShort {
        /// Bytes given.
        len: usize,
        /// Bytes needed.
        need: usize,
    },
    /// The header's length exceeds the buffer.
    Length {
        /// The header's length.
        declared: u16,
        /// Bytes after the header.
        capacity: usize,
    },
}

impl fmt::Display for MailboxError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MailboxError::TooShort { len, need } => {
                write!(f, "mailbox message of {len} bytes, needs at least {need}")
            }
            MailboxError::Length { declared, capacity } => write!(
                f,
                "mailbox header declares {declared} bytes, the mailbox holds {capacity} after it"
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lan9252_sdo_request_header_decodes() {
        // soem-single-lan9252.pcapng frame 301: the start of SM0's write, an SDO upload of
        // 0x1C00:00 (SOEM's first mailbox message after PRE-OP).
        let b = [
            0x0a, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x20, 0x50, 0x00, 0x1c, 0x00, 0x00, 0x00,
            0x00, 0x00,
        ];
        let (h, body) = MailboxHeader::split(&b).unwrap();
        assert_eq!(
            h,
            MailboxHeader {
                length: 10,
                address: 0,
                channel: 0,
                priority: 0,
                kind: MailboxType::Coe,
                counter: 1
            }
        );
        assert_eq!(body.len(), 10);
        assert_eq!(h.encode(), b[..6]);
        assert_eq!(MailboxHeader::next_counter(7), 1);
        assert_eq!(
            MailboxHeader::split(&b[..10]),
            Err(MailboxError::Length {
                declared: 10,
                capacity: 4
            })
        );
        let e = MailboxErrorCode::UNSUPPORTED_PROTOCOL;
        assert_eq!(MailboxErrorCode::from_reply(&e.reply_body()), Some(e));
        assert_eq!(e.to_string(), "mailbox error 2 (protocol not supported)");
        assert_eq!(MailboxType::Coe.sii_bit(), 0x04);
    }
}
