//! Modbus RTU framing on a serial line (*MODBUS over Serial Line V1.02*, section 2.5): the
//! unit address, the PDU, and a CRC-16 (polynomial 0xA001 reflected, initial 0xFFFF) sent low
//! byte first. A frame is delimited by at least 3.5 character times of silence; above
//! 19200 baud the specification fixes that at 1.75 ms (and the 1.5-character inter-character
//! limit at 0.75 ms).
//!
//! A receiver that reads byte by byte learns a frame's length from its first bytes:
//! [`request_len`] for a server, [`response_len`] for a client. Test vectors are the Robotiq
//! 2F-85/140 manual's (section 4.7, "Modbus RTU example").

use core::time::Duration;

use super::pdu::{Request, Response};
use super::{MAX_PDU, ModbusError};

/// Bytes of the shortest frame (address, function, CRC).
pub const MIN_FRAME: usize = 4;
/// Bytes of the longest frame.
pub const MAX_FRAME: usize = MAX_PDU + 3;
/// The broadcast address: every server acts, none answers.
pub const BROADCAST: u8 = 0;

/// The CRC-16 of Modbus RTU.
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut crc: u16 = 0xFFFF;
    for &b in bytes {
        crc ^= u16::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xA001
            } else {
                crc >> 1
            };
        }
    }
    crc
}

/// Frames `pdu` for `unit` into `out`; returns the frame's length.
pub fn frame(unit: u8, pdu: &[u8], out: &mut [u8]) -> Result<usize, ModbusError> {
    let n = pdu.len() + 3;
    if out.len() < n {
        return Err(ModbusError::BufferTooSmall {
            need: n,
            got: out.len(),
        });
    }
    out[0] = unit;
    out[1..=pdu.len()].copy_from_slice(pdu);
    let crc = crc16(&out[..=pdu.len()]);
    out[n - 2..n].copy_from_slice(&crc.to_le_bytes());
    Ok(n)
}

/// Frames a request.
pub fn encode_request(
    unit: u8,
    request: &Request<'_>,
    out: &mut [u8],
) -> Result<usize, ModbusError> {
    let mut pdu = [0u8; MAX_PDU];
    let n = request.encode(&mut pdu)?;
    frame(unit, &pdu[..n], out)
}

/// Frames a response.
pub fn encode_response(
    unit: u8,
    response: &Response<'_>,
    out: &mut [u8],
) -> Result<usize, ModbusError> {
    let mut pdu = [0u8; MAX_PDU];
    let n = response.encode(&mut pdu)?;
    frame(unit, &pdu[..n], out)
}

/// Checks a whole frame's CRC; returns its unit address and PDU.
pub fn decode(frame: &[u8]) -> Result<(u8, &[u8]), ModbusError> {
    if frame.len() < MIN_FRAME {
        return Err(ModbusError::TooShort {
            what: "RTU frame",
            need: MIN_FRAME,
            got: frame.len(),
        });
    }
    if frame.len() > MAX_FRAME {
        return Err(ModbusError::TooLong {
            what: "RTU frame",
            expected: MAX_FRAME,
            got: frame.len(),
        });
    }
    let body = frame.len() - 2;
    let computed = crc16(&frame[..body]);
    let received = u16::from_le_bytes([frame[body], frame[body + 1]]);
    if computed != received {
        return Err(ModbusError::Crc { computed, received });
    }
    Ok((frame[0], &frame[1..body]))
}

/// What the first bytes of a frame say about its length.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameLength {
    /// The frame has this many bytes in all.
    Known(usize),
    /// At least this many bytes are needed to tell.
    AtLeast(usize),
    /// The function is not one this codec frames: only the silence after it ends the frame.
    Unknown,
}

/// The length of a request frame from its first bytes (server side).
pub fn request_len(prefix: &[u8]) -> FrameLength {
    let Some(&function) = prefix.get(1) else {
        return FrameLength::AtLeast(2);
    };
    match function {
        0x03 | 0x04 | 0x06 => FrameLength::Known(8),
        0x10 => match prefix.get(6) {
            Some(&bc) => FrameLength::Known(9 + usize::from(bc)),
            None => FrameLength::AtLeast(7),
        },
        0x17 => match prefix.get(10) {
            Some(&bc) => FrameLength::Known(13 + usize::from(bc)),
            None => FrameLength::AtLeast(11),
        },
        _ => FrameLength::Unknown,
    }
}

/// The length of a response frame from its first bytes (client side).
pub fn response_len(prefix: &[u8]) -> FrameLength {
    let Some(&function) = prefix.get(1) else {
        return FrameLength::AtLeast(2);
    };
    if function & 0x80 != 0 {
        return FrameLength::Known(5);
    }
    match function {
        0x03 | 0x04 | 0x17 => match prefix.get(2) {
            Some(&bc) => FrameLength::Known(5 + usize::from(bc)),
            None => FrameLength::AtLeast(3),
        },
        0x06 | 0x10 => FrameLength::Known(8),
        _ => FrameLength::Unknown,
    }
}

/// Time on the wire of one character of `bits` bits (start, data, parity, stop) at `baud`.
pub fn char_time(baud: u32, bits: u32) -> Duration {
    Duration::from_nanos(u64::from(bits) * 1_000_000_000 / u64::from(baud.max(1)))
}

/// Time on the wire of `bytes` characters.
pub fn wire_time(bytes: usize, baud: u32, bits: u32) -> Duration {
    char_time(baud, bits) * u32::try_from(bytes).unwrap_or(u32::MAX)
}

/// The silence that ends a frame: 3.5 characters, or 1.75 ms above 19200 baud.
pub fn frame_gap(baud: u32, bits: u32) -> Duration {
    if baud > 19_200 {
        Duration::from_micros(1750)
    } else {
        char_time(baud, bits) * 7 / 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::proto::modbus::pdu::Registers;

    /// Frames from the Robotiq 2F-85/140 manual (section 4.7): each must carry our CRC.
    const MANUAL: [&[u8]; 8] = [
        // Activation request / open at full speed and force.
        &[
            0x09, 0x10, 0x03, 0xE8, 0x00, 0x03, 0x06, 0x09, 0x00, 0x00, 0x00, 0xFF, 0xFF, 0x72,
            0x19,
        ],
        &[0x09, 0x10, 0x03, 0xE8, 0x00, 0x03, 0x01, 0x30],
        // Read the gripper status: one register, three registers.
        &[0x09, 0x04, 0x07, 0xD0, 0x00, 0x01, 0x30, 0x0F],
        &[0x09, 0x04, 0x02, 0x11, 0x00, 0x54, 0xA1],
        &[0x09, 0x04, 0x02, 0x31, 0x00, 0x4D, 0x61],
        &[0x09, 0x04, 0x07, 0xD0, 0x00, 0x03, 0xB1, 0xCE],
        &[
            0x09, 0x04, 0x06, 0x39, 0x00, 0x00, 0x00, 0xBB, 0x10, 0x71, 0x06,
        ],
        &[
            0x09, 0x04, 0x06, 0xB9, 0x00, 0x00, 0xFF, 0xBD, 0x00, 0x5C, 0x9A,
        ],
    ];

    #[test]
    fn the_manuals_frames_carry_our_crc() {
        for f in MANUAL {
            let (unit, pdu) = decode(f).unwrap_or_else(|e| panic!("{f:02X?}: {e}"));
            assert_eq!(unit, 9);
            let mut again = [0u8; 32];
            let n = frame(unit, pdu, &mut again).unwrap();
            assert_eq!(&again[..n], f);
        }
        let mut bad = [0u8; 8];
        bad.copy_from_slice(MANUAL[2]);
        bad[7] ^= 1;
        assert!(matches!(decode(&bad), Err(ModbusError::Crc { .. })));
    }

    #[test]
    fn requests_and_responses_frame_as_the_manual_shows() {
        let words = [0x0900, 0x0000, 0xFFFF];
        let r = Request::WriteMultipleRegisters {
            address: 0x03E8,
            values: Registers::Words(&words),
        };
        let mut out = [0u8; 32];
        let n = encode_request(9, &r, &mut out).unwrap();
        assert_eq!(&out[..n], MANUAL[0]);
        let read = Request::ReadInputRegisters {
            address: 0x07D0,
            count: 3,
        };
        let n = encode_request(9, &read, &mut out).unwrap();
        assert_eq!(&out[..n], MANUAL[5]);
        let (_, pdu) = decode(MANUAL[6]).unwrap();
        let resp = Response::decode(pdu).unwrap();
        assert_eq!(resp.check_answers(&read), Ok(()));
        let n = encode_response(9, &resp, &mut out).unwrap();
        assert_eq!(&out[..n], MANUAL[6]);
    }

    #[test]
    fn lengths_from_prefixes() {
        assert_eq!(request_len(&[9]), FrameLength::AtLeast(2));
        assert_eq!(request_len(MANUAL[2]), FrameLength::Known(8));
        assert_eq!(request_len(&MANUAL[0][..5]), FrameLength::AtLeast(7));
        assert_eq!(request_len(MANUAL[0]), FrameLength::Known(15));
        assert_eq!(request_len(&[9, 0x2B]), FrameLength::Unknown);
        assert_eq!(response_len(&MANUAL[6][..2]), FrameLength::AtLeast(3));
        assert_eq!(response_len(MANUAL[6]), FrameLength::Known(11));
        assert_eq!(response_len(MANUAL[1]), FrameLength::Known(8));
        assert_eq!(response_len(&[9, 0x84]), FrameLength::Known(5));
    }

    #[test]
    fn timing_at_115200_baud() {
        // 8N1: 10 bits a character.
        assert_eq!(char_time(115_200, 10), Duration::from_nanos(86_805));
        assert_eq!(frame_gap(115_200, 10), Duration::from_micros(1750));
        assert_eq!(frame_gap(9600, 11), Duration::from_nanos(4_010_415));
    }
}
