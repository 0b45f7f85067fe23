//! Any bytes: UR's real-time message reader never panics, and what decodes re-encodes to a
//! message that decodes to the same state (byte for byte once re-encoded: reserved fields are
//! zero).
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::ur_realtime::{MAX_LEN, RealtimeState, split};

fuzz_target!(|data: &[u8]| {
    let _ = split(data);
    if let Ok(s) = RealtimeState::decode(data) {
        assert!(data.len() >= s.length);
        let mut a = [0u8; MAX_LEN];
        let n = s.encode(s.length, &mut a).expect("a decoded length encodes");
        assert_eq!(n, s.length);
        let t = RealtimeState::decode(&a[..n]).expect("an encoded state decodes");
        let mut b = [0u8; MAX_LEN];
        t.encode(t.length, &mut b).expect("a decoded length encodes");
        assert_eq!(&a[..n], &b[..n]);
    }
});
