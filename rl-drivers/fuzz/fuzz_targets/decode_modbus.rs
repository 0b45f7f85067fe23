//! Any bytes: the Modbus and Robotiq decoders never panic, and a frame that decodes re-encodes
//! to the same bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::modbus::rtu::{self, FrameLength};
use rl_drivers::proto::modbus::{Request, Response, tcp};
use rl_drivers::proto::robotiq::Status;

fuzz_target!(|data: &[u8]| {
    if let Ok((unit, pdu)) = rtu::decode(data) {
        let mut again = [0u8; rtu::MAX_FRAME];
        if let Ok(r) = Request::decode(pdu) {
            let n = rtu::encode_request(unit, &r, &mut again).unwrap();
            assert_eq!(&again[..n], data);
            assert_eq!(rtu::request_len(data), FrameLength::Known(n));
        }
        if let Ok(r) = Response::decode(pdu) {
            let n = rtu::encode_response(unit, &r, &mut again).unwrap();
            assert_eq!(&again[..n], data);
            if let Response::ReadInputRegisters(regs) = r {
                let mut w = [0u16; 3];
                regs.copy_to(&mut w);
                let _ = Status::from_registers(w);
            }
        }
    }
    if let Ok((h, pdu)) = tcp::decode(data) {
        if let Ok(r) = Request::decode(pdu) {
            let mut again = [0u8; tcp::MAX_FRAME];
            let n = tcp::encode_request(h.transaction, h.unit, &r, &mut again).unwrap();
            assert_eq!(&again[..n], data);
        }
    }
    let _ = rtu::request_len(data);
    let _ = rtu::response_len(data);
});
