//! Any bytes: decoding never panics, and a decoded packet re-encodes to the same bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::h7::Packet;

fuzz_target!(|data: &[u8]| {
    if let Ok(p) = Packet::decode(data) {
        assert_eq!(&p.to_bytes()[..], data);
        for (ty, block) in p.blocks() {
            let _ = block.view(ty);
        }
    }
});
