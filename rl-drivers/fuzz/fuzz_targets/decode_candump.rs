//! Any text: a candump log line parses or is refused with its column, never panics; a parsed
//! frame writes back to text that parses to the same frame.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::can::candump;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = core::str::from_utf8(data) else { return };
    match candump::parse_line(text) {
        Ok(l) => {
            let mut out = String::new();
            candump::write_line(&mut out, l.timestamp, l.interface, &l.frame).unwrap();
            assert_eq!(candump::parse_line(&out).unwrap().frame, l.frame);
        }
        Err(e) => assert!(e.column <= text.len()),
    }
    let _ = candump::parse_frame(text);
});
