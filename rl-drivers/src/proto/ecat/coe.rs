//! CANopen over EtherCAT (ETG.1000.6 §5.6.2): a 2-byte CoE header after the mailbox header,
//! then for SDO services the CANopen SDO message — the same 8 bytes as on CAN, decoded by
//! [`canopen::sdo`](crate::proto::canopen::sdo) — followed by whatever more the mailbox
//! carries:
//!
//! ```text
//! CoE header   number:9 | reserved:3 | service:4   (2 SDO request, 3 SDO response, 8 SDO info)
//! SDO          byte 0 command, 1-2 index, 3 sub-index, 4-7 data or size      (as on CAN)
//! then         normal transfers: the data after the 4-byte size, up to the mailbox's end;
//!              segments: all bytes after the command byte (at least 7)
//! ```
//!
//! CoE adds to CAN's SDO: *normal* transfers (initiate with the size, the data in the same
//! mailbox message), segments as long as the mailbox allows, and *complete access* (bit 4 of the
//! initiate command: the whole object, sub-index 0 as 16 bits, then every sub-index).

use core::fmt;

use super::mailbox::{self, MailboxHeader, MailboxType};
use crate::proto::canopen::sdo::{Request, Response, SDO_LEN};

/// Bytes of the CoE header.
pub const HEADER_LEN: usize = 2;
/// Bytes in front of an SDO message's data in a mailbox: mailbox, CoE and the 8-byte SDO.
pub const SDO_OVERHEAD: usize = mailbox::HEADER_LEN + HEADER_LEN + SDO_LEN;
/// Bytes in front of a segment's data: mailbox, CoE and the command byte.
pub const SEGMENT_OVERHEAD: usize = mailbox::HEADER_LEN + HEADER_LEN + 1;
/// Bit 4 of an initiate command: complete access (the whole object).
pub const COMPLETE_ACCESS: u8 = 0x10;

/// A CoE service.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CoeService {
    /// 1: emergency.
    Emergency,
    /// 2: SDO request.
    SdoRequest,
    /// 3: SDO response.
    SdoResponse,
    /// 4: TxPDO.
    TxPdo,
    /// 5: RxPDO.
    RxPdo,
    /// 6: TxPDO remote request.
    TxPdoRemote,
    /// 7: RxPDO remote request.
    RxPdoRemote,
    /// 8: SDO information.
    SdoInformation,
    /// Any other code.
    Other(u8),
}

impl CoeService {
    /// The 4-bit code.
    pub const fn code(self) -> u8 {
        match self {
            CoeService::Emergency => 1,
            CoeService::SdoRequest => 2,
            CoeService::SdoResponse => 3,
            CoeService::TxPdo => 4,
            CoeService::RxPdo => 5,
            CoeService::TxPdoRemote => 6,
            CoeService::RxPdoRemote => 7,
            CoeService::SdoInformation => 8,
            CoeService::Other(c) => c & 0x0F,
        }
    }

    /// The service of a code.
    pub const fn from_code(c: u8) -> Self {
        match c & 0x0F {
            1 => CoeService::Emergency,
            2 => CoeService::SdoRequest,
            3 => CoeService::SdoResponse,
            4 => CoeService::TxPdo,
            5 => CoeService::RxPdo,
            6 => CoeService::TxPdoRemote,
            7 => CoeService::RxPdoRemote,
            8 => CoeService::SdoInformation,
            c => CoeService::Other(c),
        }
    }
}

/// The CoE header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CoeHeader {
    /// PDO number (9 bits; 0 for SDO services).
    pub number: u16,
    /// Service.
    pub service: CoeService,
}

impl CoeHeader {
    /// A header of `service` with number 0.
    pub const fn new(service: CoeService) -> Self {
        Self { number: 0, service }
    }

    /// Decodes 2 bytes.
    pub fn decode(b: [u8; 2]) -> Self {
        let v = u16::from_le_bytes(b);
        Self {
            number: v & 0x01FF,
            service: CoeService::from_code((v >> 12) as u8),
        }
    }

    /// The 2 bytes.
    pub fn encode(&self) -> [u8; 2] {
        ((self.number & 0x01FF) | (u16::from(self.service.code()) << 12)).to_le_bytes()
    }
}

/// Why a CoE message does not decode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoeError {
    /// Shorter than the CoE header and an SDO message.
    TooShort {
        /// Bytes after the mailbox header.
        len: usize,
        /// Bytes needed.
        need: usize,
    },
    /// The buffer cannot hold the message.
    Full {
        /// Bytes needed.
        need: usize,
        /// Capacity.
        capacity: usize,
    },
}

impl fmt::Display for CoeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CoeError::TooShort { len, need } => {
                write!(f, "CoE message of {len} bytes, needs at least {need}")
            }
            CoeError::Full { need, capacity } => {
                write!(
                    f,
                    "CoE message needs {need} bytes, the mailbox holds {capacity}"
                )
            }
        }
    }
}

/// An SDO message inside a CoE mailbox message: the 8 CANopen bytes and what follows them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SdoMessage<'a> {
    /// The CoE header.
    pub coe: CoeHeader,
    /// The 8-byte SDO message (shorter segments are padded with zeros).
    pub head: [u8; SDO_LEN],
    /// Bytes after the 8 (normal-transfer data; the rest of a long segment).
    pub rest: &'a [u8],
    /// Bytes of the SDO part as received (at least 1).
    pub len: usize,
}

impl<'a> SdoMessage<'a> {
    /// Splits the body of a CoE mailbox message (the bytes after the mailbox header).
    pub fn parse(body: &'a [u8]) -> Result<Self, CoeError> {
        if body.len() < HEADER_LEN + 1 {
            return Err(CoeError::TooShort {
                len: body.len(),
                need: HEADER_LEN + SDO_LEN,
            });
        }
        let coe = CoeHeader::decode([body[0], body[1]]);
        let sdo = &body[HEADER_LEN..];
        let mut head = [0u8; SDO_LEN];
        let n = sdo.len().min(SDO_LEN);
        head[..n].copy_from_slice(&sdo[..n]);
        Ok(Self {
            coe,
            head,
            rest: sdo.get(SDO_LEN..).unwrap_or(&[]),
            len: sdo.len(),
        })
    }

    /// The command byte.
    pub const fn command(&self) -> u8 {
        self.head[0]
    }

    /// Whether an initiate message asks for (or answers with) complete access.
    pub const fn complete_access(&self) -> bool {
        self.head[0] & COMPLETE_ACCESS != 0
    }

    /// Decodes the 8 bytes as a client request (complete access bit ignored).
    pub fn request(&self) -> Result<Request, crate::proto::canopen::sdo::DecodeError> {
        Request::decode(&self.head)
    }

    /// Decodes the 8 bytes as a server response (complete access bit ignored).
    pub fn response(&self) -> Result<Response, crate::proto::canopen::sdo::DecodeError> {
        Response::decode(&self.head)
    }

    /// The data of a segment (download request or upload response): every byte after the
    /// command byte when the message is longer than 8 bytes, else the 7 − n bytes the command
    /// says.
    pub fn segment_data(&self, sdo_part: &'a [u8]) -> &'a [u8] {
        let body = sdo_part.get(1..).unwrap_or(&[]);
        if self.len > SDO_LEN {
            body
        } else {
            let unused = usize::from((self.head[0] >> 1) & 0x07);
            &body[..(7usize.saturating_sub(unused)).min(body.len())]
        }
    }

    /// The normal-transfer data after an initiate: the bytes after the 8, at most `size`.
    pub fn normal_data(&self, size: usize) -> &'a [u8] {
        &self.rest[..size.min(self.rest.len())]
    }
}

/// The SDO part (after mailbox and CoE headers) of a CoE body.
pub fn sdo_part(body: &[u8]) -> &[u8] {
    body.get(HEADER_LEN..).unwrap_or(&[])
}

/// Writes a CoE SDO message into `out` (a mailbox buffer): mailbox header (CoE, `counter`),
/// CoE header (`service`), the 8 bytes `head` and `rest`. Returns the bytes written.
pub fn write_sdo(
    out: &mut [u8],
    counter: u8,
    service: CoeService,
    head: &[u8; SDO_LEN],
    rest: &[u8],
) -> Result<usize, CoeError> {
    let need = SDO_OVERHEAD + rest.len();
    if need > out.len() {
        return Err(CoeError::Full {
            need,
            capacity: out.len(),
        });
    }
    let h = MailboxHeader::new(
        MailboxType::Coe,
        (HEADER_LEN + SDO_LEN + rest.len()) as u16,
        counter,
    );
    out[..mailbox::HEADER_LEN].copy_from_slice(&h.encode());
    let c = mailbox::HEADER_LEN;
    out[c..c + HEADER_LEN].copy_from_slice(&CoeHeader::new(service).encode());
    out[c + HEADER_LEN..c + HEADER_LEN + SDO_LEN].copy_from_slice(head);
    out[SDO_OVERHEAD..need].copy_from_slice(rest);
    Ok(need)
}

/// Writes a CoE SDO segment: the command byte `command` (toggle, last; the unused-bytes field is
/// set here) and `data`, padded to 7 bytes when shorter. Returns the bytes written.
pub fn write_segment(
    out: &mut [u8],
    counter: u8,
    service: CoeService,
    command: u8,
    data: &[u8],
) -> Result<usize, CoeError> {
    let body = data.len().max(7);
    let need = SEGMENT_OVERHEAD + body;
    if need > out.len() {
        return Err(CoeError::Full {
            need,
            capacity: out.len(),
        });
    }
    let unused = 7usize.saturating_sub(data.len()) as u8;
    let h = MailboxHeader::new(MailboxType::Coe, (HEADER_LEN + 1 + body) as u16, counter);
    out[..mailbox::HEADER_LEN].copy_from_slice(&h.encode());
    let c = mailbox::HEADER_LEN;
    out[c..c + HEADER_LEN].copy_from_slice(&CoeHeader::new(service).encode());
    out[c + HEADER_LEN] = (command & !0x0E) | (unused << 1);
    out[SEGMENT_OVERHEAD..SEGMENT_OVERHEAD + data.len()].copy_from_slice(data);
    out[SEGMENT_OVERHEAD + data.len()..need].fill(0);
    Ok(need)
}

/// A CoE emergency message's fields (the CANopen EMCY payload).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Emergency {
    /// The error code (as 0x603F).
    pub error_code: u16,
    /// The error register (0x1001).
    pub error_register: u8,
    /// Manufacturer-specific bytes.
    pub data: [u8; 5],
}

impl Emergency {
    /// Decodes the 8 bytes after the CoE header.
    pub fn decode(b: &[u8]) -> Option<Self> {
        let b = b.get(..8)?;
        let mut data = [0u8; 5];
        data.copy_from_slice(&b[3..8]);
        Some(Self {
            error_code: u16::from_le_bytes([b[0], b[1]]),
            error_register: b[2],
            data,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::proto::canopen::sdo::Address;

    #[test]
    fn the_lan9252_complete_access_exchange_decodes() {
        // soem-single-lan9252.pcapng frame 301: upload 0x1C00:00 with complete access.
        let req = [
            0x0a, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x20, 0x50, 0x00, 0x1c, 0x00, 0x00, 0x00,
            0x00, 0x00,
        ];
        let (h, body) = MailboxHeader::split(&req).unwrap();
        assert_eq!(h.kind, MailboxType::Coe);
        let m = SdoMessage::parse(body).unwrap();
        assert_eq!(m.coe.service, CoeService::SdoRequest);
        assert!(m.complete_access());
        assert_eq!(
            m.request(),
            Ok(Request::UploadInitiate {
                address: Address::new(0x1C00, 0)
            })
        );
        // Frame 406: the normal response, 6 bytes: sub 0 = 4 as 16 bits, then 1, 2, 3, 4.
        let resp = [
            0x10, 0x00, 0x00, 0x00, 0x00, 0x13, 0x00, 0x30, 0x51, 0x00, 0x1c, 0x00, 0x06, 0x00,
            0x00, 0x00, 0x04, 0x00, 0x01, 0x02, 0x03, 0x04,
        ];
        let (_, body) = MailboxHeader::split(&resp).unwrap();
        let m = SdoMessage::parse(body).unwrap();
        assert_eq!(m.coe.service, CoeService::SdoResponse);
        assert!(m.complete_access());
        assert_eq!(
            m.response(),
            Ok(Response::UploadInitiate {
                address: Address::new(0x1C00, 0),
                size: Some(6)
            })
        );
        assert_eq!(m.normal_data(6), &[4, 0, 1, 2, 3, 4]);
        let mut out = [0u8; 32];
        let n = write_sdo(&mut out, 1, CoeService::SdoResponse, &m.head, m.rest).unwrap();
        assert_eq!(&out[..n], &resp[..]);
    }

    #[test]
    fn segments_carry_what_the_mailbox_allows() {
        let mut out = [0u8; 64];
        let n = write_segment(&mut out, 2, CoeService::SdoRequest, 0x01, b"abc").unwrap();
        assert_eq!(n, SEGMENT_OVERHEAD + 7);
        let (_, body) = MailboxHeader::split(&out[..n]).unwrap();
        let m = SdoMessage::parse(body).unwrap();
        // t = 0, 4 unused bytes, last.
        assert_eq!(m.command(), (4 << 1) | 1);
        assert_eq!(m.segment_data(sdo_part(body)), b"abc");
        let long = [7u8; 20];
        let n = write_segment(&mut out, 3, CoeService::SdoRequest, 0x10, &long).unwrap();
        let (_, body) = MailboxHeader::split(&out[..n]).unwrap();
        let m = SdoMessage::parse(body).unwrap();
        assert_eq!(m.segment_data(sdo_part(body)), &long[..]);
        assert!(matches!(
            write_segment(&mut out[..20], 1, CoeService::SdoRequest, 0, &long),
            Err(CoeError::Full { .. })
        ));
        assert_eq!(
            SdoMessage::parse(&[0x00]),
            Err(CoeError::TooShort { len: 1, need: 10 })
        );
        assert_eq!(
            CoeHeader::decode(CoeHeader::new(CoeService::SdoInformation).encode()).service,
            CoeService::SdoInformation
        );
    }
}
