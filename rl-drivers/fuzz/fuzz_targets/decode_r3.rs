//! Any bytes as an R3 request, reply, DSTATE payload or program: parsing never panics.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::r3::{DState, EMDAT_CHUNK_LEN, EmdatChunks, Reply, Request};

fuzz_target!(|data: &[u8]| {
    if let Ok(r) = Request::parse(data) {
        let mut buf = [0u8; 1024];
        if let Ok(n) = r.encode(&mut buf) {
            assert_eq!(Request::parse(&buf[..n]), Ok(r));
        }
    }
    if let Ok(Reply::Ok(payload)) = Reply::parse(data) {
        let _ = DState::parse(payload);
    }
    if let Ok(text) = core::str::from_utf8(data) {
        for chunk in EmdatChunks::new(text).flatten() {
            assert!(chunk.len() <= EMDAT_CHUNK_LEN);
        }
    }
});
