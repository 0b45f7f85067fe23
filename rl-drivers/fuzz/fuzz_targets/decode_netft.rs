//! Any bytes: the Net F/T decoders never panic, and what decodes re-encodes to the same bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::netft::{Calibration, RdtRecord, RdtRequest, decode_tcp_request, records};

fuzz_target!(|data: &[u8]| {
    if let Ok(r) = RdtRequest::decode(data) {
        assert_eq!(&r.to_bytes()[..], data);
    }
    if let Ok(r) = RdtRecord::decode(data) {
        assert_eq!(&r.to_bytes()[..], data);
    }
    if let Ok(rs) = records(data) {
        let mut n = 0;
        for r in rs {
            assert_eq!(&r.to_bytes()[..], &data[36 * n..36 * (n + 1)]);
            n += 1;
        }
        assert_eq!(36 * n, data.len());
    }
    if let Ok(c) = Calibration::decode(data) {
        assert_eq!(&c.to_bytes()[..], data);
        let _ = c.to_si(&[i32::MIN, i32::MAX, 0, -1, 1, 7]);
    }
    let _ = decode_tcp_request(data);
});
