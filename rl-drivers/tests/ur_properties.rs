//! The RTDE codec never panics on any input, and what it encodes decodes to itself: package
//! splitting, messages both ways in both protocol versions, recipes and their typed reads.

use proptest::prelude::*;
use rl_drivers::proto::rtde::types::Writer;
use rl_drivers::proto::rtde::variables::Var;
use rl_drivers::proto::rtde::{DataType, Header, Message, Recipe, split};

proptest! {
    #[test]
    fn decoders_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600), version in 1u16..=2) {
        let mut rest = &bytes[..];
        while let Ok(Some((h, payload, next))) = split(rest) {
            let _ = Message::decode_request(h, payload, version);
            let _ = Message::decode_answer(h, payload, version);
            rest = next;
        }
        if let Ok(text) = core::str::from_utf8(&bytes) {
            let _ = Recipe::<32>::from_types(text);
            for name in text.split(',') {
                let _ = Var::parse(name);
            }
        }
    }

    #[test]
    fn data_packages_round_trip(
        values in proptest::collection::vec((0usize..10, any::<u64>()), 1..20),
        recipe in 1u8..=255, version in 1u16..=2,
    ) {
        // A recipe of random types, a payload of random values, through a package.
        let mut r = Recipe::<32>::new();
        let mut payload = vec![0u8; 20 * 48];
        let mut w = Writer::new(&mut payload);
        for (t, bits) in &values {
            let t = DataType::ALL[*t];
            r.push(t).unwrap();
            w.put(&bits.to_be_bytes().repeat(6)[..t.size()]).unwrap();
        }
        let n = w.len();
        prop_assert_eq!(n, r.size());
        let m = Message::Data { recipe: Some(recipe), payload: &payload[..n] };
        let mut buf = vec![0u8; n + 8];
        let len = m.encode(version, &mut buf).unwrap();
        let (h, p, rest) = split(&buf[..len]).unwrap().unwrap();
        prop_assert!(rest.is_empty());
        prop_assert_eq!(Message::decode_request(h, p, version).unwrap(), m);
        let answer = Message::decode_answer(h, p, version).unwrap();
        if let Message::Data { payload: got, .. } = answer {
            let got = if version >= 2 { got } else { &got[1..] };
            prop_assert!(r.check(got).is_ok());
        }
        for (k, (t, bits)) in values.iter().enumerate() {
            match DataType::ALL[*t] {
                DataType::Double => prop_assert_eq!(r.f64(&payload[..n], k).map(f64::to_bits), Some(*bits)),
                DataType::Uint64 => prop_assert_eq!(r.u64(&payload[..n], k), Some(*bits)),
                _ => {}
            }
        }
    }

    #[test]
    fn headers_need_three_bytes_and_a_size_of_three(size in any::<u16>(), kind in any::<u8>()) {
        let b = [(size >> 8) as u8, size as u8, kind];
        match Header::decode(&b) {
            Ok(h) => prop_assert!(h.size >= 3),
            Err(_) => prop_assert!(size < 3),
        }
    }
}
