//! The Modbus and Robotiq codecs never panic on any input, and what they encode decodes to
//! itself: PDUs, RTU frames (with their CRC), TCP frames, the gripper's registers.

use proptest::prelude::*;
use rl_drivers::proto::modbus::rtu::{self, FrameLength};
use rl_drivers::proto::modbus::{Registers, Request, Response, tcp};
use rl_drivers::proto::robotiq::{Command, Status};

proptest! {
    #[test]
    fn decoders_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let _ = Request::decode(&bytes);
        let _ = Response::decode(&bytes);
        if let Ok((_, pdu)) = rtu::decode(&bytes) {
            let _ = Request::decode(pdu);
            let _ = Response::decode(pdu);
        }
        if let Ok((_, pdu)) = tcp::decode(&bytes) {
            let _ = Request::decode(pdu);
        }
        // A length said from a prefix never exceeds what the rest of the frame allows.
        for n in 0..bytes.len().min(16) {
            if let FrameLength::Known(len) = rtu::request_len(&bytes[..n]) {
                prop_assert!(len <= 13 + 255);
            }
            let _ = rtu::response_len(&bytes[..n]);
        }
    }

    #[test]
    fn requests_round_trip_through_rtu_and_tcp(
        kind in 0usize..5, address in any::<u16>(), other in any::<u16>(),
        count in 1u16..=125, values in proptest::collection::vec(any::<u16>(), 1..=121),
        unit in any::<u8>(), tid in any::<u16>(),
    ) {
        let r = match kind {
            0 => Request::ReadHoldingRegisters { address, count },
            1 => Request::ReadInputRegisters { address, count },
            2 => Request::WriteSingleRegister { address, value: other },
            3 => Request::WriteMultipleRegisters { address, values: Registers::Words(&values) },
            _ => Request::ReadWriteMultipleRegisters {
                read_address: address, read_count: count, write_address: other,
                values: Registers::Words(&values),
            },
        };
        let mut frame = [0u8; rtu::MAX_FRAME];
        let n = rtu::encode_request(unit, &r, &mut frame).unwrap();
        prop_assert_eq!(rtu::request_len(&frame[..n]), FrameLength::Known(n));
        let (u, pdu) = rtu::decode(&frame[..n]).unwrap();
        prop_assert_eq!(u, unit);
        prop_assert_eq!(Request::decode(pdu).unwrap(), r);
        // Any single flipped bit breaks the CRC or the unit.
        let mut bad = frame;
        bad[n / 2] ^= 0x10;
        prop_assert!(rtu::decode(&bad[..n]).map(|(u, p)| (u, p.to_vec())) != Ok((unit, pdu.to_vec())));
        let mut t = [0u8; tcp::MAX_FRAME];
        let m = tcp::encode_request(tid, unit, &r, &mut t).unwrap();
        let (h, pdu) = tcp::decode(&t[..m]).unwrap();
        prop_assert_eq!((h.transaction, h.unit), (tid, unit));
        prop_assert_eq!(Request::decode(pdu).unwrap(), r);
    }

    #[test]
    fn read_responses_round_trip(values in proptest::collection::vec(any::<u16>(), 1..=125), unit in any::<u8>()) {
        let r = Response::ReadInputRegisters(Registers::Words(&values));
        let mut frame = [0u8; rtu::MAX_FRAME];
        let n = rtu::encode_response(unit, &r, &mut frame).unwrap();
        prop_assert_eq!(rtu::response_len(&frame[..3]), FrameLength::Known(n));
        let (_, pdu) = rtu::decode(&frame[..n]).unwrap();
        prop_assert_eq!(Response::decode(pdu).unwrap(), r);
    }

    #[test]
    fn gripper_registers_round_trip(a in any::<u16>(), b in any::<u16>(), c in any::<u16>()) {
        // Status: every bit of the used bytes means something, but bits 1 and 2 of the
        // gripper status and byte 1 (reserved).
        let s = Status::from_registers([a & 0xF900, b, c]);
        prop_assert_eq!(s.to_registers(), [a & 0xF900, b, c]);
        // Command: the action request's four bits, the position, speed and force.
        let cmd = Command::from_registers([a & 0x3900, b & 0x00FF, c]);
        prop_assert_eq!(cmd.to_registers(), [a & 0x3900, b & 0x00FF, c]);
    }
}
