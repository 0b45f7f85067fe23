//! Any byte stream through the line reassembler and the line parser: never panics, and every
//! parsed line encodes again.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::coach::{LineBuffer, Message};

fuzz_target!(|data: &[u8]| {
    let mut lines = LineBuffer::<256>::new();
    let mut rest = data;
    while !rest.is_empty() {
        let n = lines.extend(rest);
        rest = &rest[n..];
        while let Some(line) = lines.next_line() {
            if let Ok(m) = line.and_then(Message::parse) {
                let mut buf = [0u8; 4096];
                assert!(m.encode(&mut buf).is_ok());
            }
        }
    }
});
