//! Any text: an EDS parses or is refused with a typed error naming the section and key, never
//! panics; the checks on a parsed dictionary never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::canopen::eds::Eds;
use rl_drivers::proto::canopen::pdo::{Direction, Entry};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = core::str::from_utf8(data) else { return };
    if let Ok(eds) = Eds::parse(text) {
        for (index, object) in &eds.objects {
            for (sub, s) in &object.subs {
                let bits = s.data_type.bits().unwrap_or(8) as u8;
                let _ = eds.check_mapping(Direction::Tpdo, Entry::new(*index, *sub, bits));
                let _ = eds.check_write(*index, *sub, 4);
                let _ = s.default.as_ref().map(|d| d.number(127));
            }
        }
    }
});
