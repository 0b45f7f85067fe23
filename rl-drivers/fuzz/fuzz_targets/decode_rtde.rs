//! Any bytes: the RTDE decoders never panic, and a message that decodes re-encodes to the same
//! bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::rtde::{Message, Recipe, split};

fuzz_target!(|data: &[u8]| {
    let mut rest = data;
    while let Ok(Some((h, payload, next))) = split(rest) {
        let whole = &rest[..usize::from(h.size)];
        for version in [1, 2] {
            for m in [
                Message::decode_request(h, payload, version),
                Message::decode_answer(h, payload, version),
            ]
            .into_iter()
            .flatten()
            {
                let mut again = vec![0u8; whole.len() + 8];
                let n = m.encode(version, &mut again).unwrap();
                assert_eq!(&again[..n], whole);
                if let Message::OutputsRecipe { types, .. } | Message::InputsRecipe { types, .. } = m {
                    let _ = Recipe::<64>::from_types(types);
                }
            }
        }
        rest = next;
    }
});
