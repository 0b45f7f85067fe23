//! Any bytes: the SocketCAN layouts, a cannelloni datagram and the cannelloni TCP stream never
//! panic, and a decoded frame re-encodes to bytes that decode to the same frame.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::can::cannelloni::{self, StreamDecoder};
use rl_drivers::proto::can::{Frame, IdOrder};

fuzz_target!(|data: &[u8]| {
    for order in [IdOrder::Host, IdOrder::Network] {
        if let Ok(f) = Frame::read_socketcan(data, order) {
            let mut b = [0u8; 72];
            let n = f.write_socketcan(&mut b, order).unwrap();
            assert_eq!(Frame::read_socketcan(&b[..n], order).unwrap(), f);
        }
    }
    if let Ok((_, frames)) = cannelloni::read_datagram(data) {
        for f in frames.flatten() {
            let mut b = [0u8; cannelloni::MAX_FRAME_LEN];
            let n = cannelloni::encode_frame(&f, &mut b).unwrap();
            assert!(matches!(cannelloni::decode_frame(&b[..n]), Ok(cannelloni::Decoded::Frame(g, m)) if g == f && m == n));
        }
    }
    let mut d = StreamDecoder::new();
    for piece in data.chunks(7) {
        if d.feed(piece, |_| {}).is_err() {
            break;
        }
    }
});
