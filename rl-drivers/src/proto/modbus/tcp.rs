//! Modbus TCP framing (*MODBUS Messaging on TCP/IP Implementation Guide V1.0b*, section 3.1):
//! the 7-byte MBAP header — transaction identifier, protocol identifier 0, the length of what
//! follows (unit identifier and PDU), the unit identifier — then the PDU. No CRC: TCP checks.

use super::pdu::{Request, Response};
use super::{MAX_PDU, ModbusError};

/// Bytes of the MBAP header.
pub const MBAP_LEN: usize = 7;
/// Bytes of the longest frame.
pub const MAX_FRAME: usize = MBAP_LEN + MAX_PDU;
/// The standard port.
pub const PORT: u16 = 502;

/// An MBAP header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Mbap {
    /// Pairs a response with its request.
    pub transaction: u16,
    /// The unit identifier (the serial address behind a gateway).
    pub unit: u8,
    /// Bytes of the PDU.
    pub pdu_len: usize,
}

impl Mbap {
    /// Decodes the header at the start of `bytes` (which may hold more).
    pub fn decode(bytes: &[u8]) -> Result<Self, ModbusError> {
        if bytes.len() < MBAP_LEN {
            return Err(ModbusError::TooShort {
                what: "MBAP header",
                need: MBAP_LEN,
                got: bytes.len(),
            });
        }
        let protocol = u16::from_be_bytes([bytes[2], bytes[3]]);
        if protocol != 0 {
            return Err(ModbusError::ProtocolId(protocol));
        }
        let length = u16::from_be_bytes([bytes[4], bytes[5]]);
        if !(2..=(MAX_PDU as u16 + 1)).contains(&length) {
            return Err(ModbusError::MbapLength(length));
        }
        Ok(Self {
            transaction: u16::from_be_bytes([bytes[0], bytes[1]]),
            unit: bytes[6],
            pdu_len: usize::from(length) - 1,
        })
    }

    /// Bytes of the whole frame.
    pub const fn frame_len(&self) -> usize {
        MBAP_LEN + self.pdu_len
    }
}

/// Frames `pdu` into `out`; returns the frame's length.
pub fn frame(transaction: u16, unit: u8, pdu: &[u8], out: &mut [u8]) -> Result<usize, ModbusError> {
    let n = MBAP_LEN + pdu.len();
    if out.len() < n {
        return Err(ModbusError::BufferTooSmall {
            need: n,
            got: out.len(),
        });
    }
    if pdu.is_empty() || pdu.len() > MAX_PDU {
        return Err(ModbusError::MbapLength(
            u16::try_from(pdu.len() + 1).unwrap_or(u16::MAX),
        ));
    }
    out[0..2].copy_from_slice(&transaction.to_be_bytes());
    out[2..4].copy_from_slice(&0u16.to_be_bytes());
    out[4..6].copy_from_slice(&((pdu.len() + 1) as u16).to_be_bytes());
    out[6] = unit;
    out[MBAP_LEN..n].copy_from_slice(pdu);
    Ok(n)
}

/// Frames a request.
pub fn encode_request(
    transaction: u16,
    unit: u8,
    request: &Request<'_>,
    out: &mut [u8],
) -> Result<usize, ModbusError> {
    let mut pdu = [0u8; MAX_PDU];
    let n = request.encode(&mut pdu)?;
    frame(transaction, unit, &pdu[..n], out)
}

/// Frames a response.
pub fn encode_response(
    transaction: u16,
    unit: u8,
    response: &Response<'_>,
    out: &mut [u8],
) -> Result<usize, ModbusError> {
    let mut pdu = [0u8; MAX_PDU];
    let n = response.encode(&mut pdu)?;
    frame(transaction, unit, &pdu[..n], out)
}

/// Decodes one whole frame: its header and PDU.
pub fn decode(frame: &[u8]) -> Result<(Mbap, &[u8]), ModbusError> {
    let h = Mbap::decode(frame)?;
    if frame.len() != h.frame_len() {
        return Err(ModbusError::MbapLength(
            u16::try_from(frame.len() - MBAP_LEN + 1).unwrap_or(u16::MAX),
        ));
    }
    Ok((h, &frame[MBAP_LEN..]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::proto::modbus::pdu::Registers;

    #[test]
    fn frames_and_answers_as_the_robotiq_manual_shows() {
        // An activation request to unit 2, transaction 0x339A, and the answer the 3-finger
        // gripper manual's Modbus TCP example (section 4.8) gives for it.
        let words = [0x0100, 0x0000, 0x0000];
        let r = Request::WriteMultipleRegisters {
            address: 0x03E8,
            values: Registers::Words(&words),
        };
        let mut out = [0u8; 32];
        let n = encode_request(0x339A, 2, &r, &mut out).unwrap();
        assert_eq!(
            &out[..n],
            &[
                0x33, 0x9A, 0, 0, 0x00, 0x0D, 0x02, 0x10, 0x03, 0xE8, 0x00, 0x03, 0x06, 0x01, 0x00,
                0, 0, 0, 0
            ]
        );
        let (h, pdu) = decode(&out[..n]).unwrap();
        assert_eq!((h.transaction, h.unit, h.pdu_len), (0x339A, 2, 12));
        assert_eq!(Request::decode(pdu), Ok(r));
        // The manual's answer: "33 9A 00 00 00 06 02 10 03 E8 00 03".
        let answer = [0x33, 0x9A, 0, 0, 0, 6, 2, 0x10, 0x03, 0xE8, 0, 3];
        let (h, pdu) = decode(&answer).unwrap();
        assert_eq!(h.pdu_len, 5);
        assert_eq!(Response::decode(pdu).unwrap().check_answers(&r), Ok(()));
    }

    #[test]
    fn bad_headers_are_named() {
        assert_eq!(
            Mbap::decode(&[0, 1, 0, 1, 0, 6, 9]),
            Err(ModbusError::ProtocolId(1))
        );
        assert_eq!(
            Mbap::decode(&[0, 1, 0, 0, 0, 1, 9]),
            Err(ModbusError::MbapLength(1))
        );
        assert!(
            decode(&[0, 1, 0, 0, 0, 6, 9, 3, 0, 0]).is_err(),
            "short frame"
        );
    }
}
