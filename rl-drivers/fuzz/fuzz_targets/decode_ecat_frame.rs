//! Any bytes: an EtherCAT frame decodes or is refused with an error, never a panic; a decoded
//! frame's datagrams all decode and re-encode to the same header bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::ecat::datagram::{DatagramHeader, HEADER_LEN};
use rl_drivers::proto::ecat::frame::Frame;

fuzz_target!(|data: &[u8]| {
    if let Ok(f) = Frame::decode(data) {
        for d in f.datagrams() {
            let d = d.expect("checked by decode");
            let mut b = [0u8; HEADER_LEN];
            d.header.encode(&mut b);
            assert_eq!(DatagramHeader::decode(&b), Ok(d.header));
        }
    }
});
