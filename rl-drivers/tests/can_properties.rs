//! Property tests of the CAN and CANopen codecs: round trips, and arbitrary input never panics
//! (the short in-CI counterpart of the fuzz targets in `rl-drivers/fuzz`).

use embedded_can::{ExtendedId, Id, StandardId};
use proptest::prelude::*;
use rl_drivers::proto::can::candump::{self, Timestamp};
use rl_drivers::proto::can::cannelloni::{self, DatagramWriter, StreamDecoder};
use rl_drivers::proto::can::fd::{FdFlags, is_fd_len};
use rl_drivers::proto::can::{Frame, IdOrder};
use rl_drivers::proto::canopen::eds::Eds;
use rl_drivers::proto::canopen::sdo::{AbortCode, Address, Chunk, Request, Response};
use rl_drivers::proto::canopen::sdo_client::Client;

fn id() -> impl Strategy<Value = Id> {
    prop_oneof![
        (0u16..0x800).prop_map(|v| Id::Standard(StandardId::new(v).unwrap())),
        (0u32..0x2000_0000).prop_map(|v| Id::Extended(ExtendedId::new(v).unwrap())),
    ]
}

fn frame() -> impl Strategy<Value = Frame> {
    prop_oneof![
        (id(), proptest::collection::vec(any::<u8>(), 0..=8))
            .prop_map(|(id, d)| Frame::data_frame(id, &d).unwrap()),
        (id(), 0usize..=8).prop_map(|(id, dlc)| Frame::remote(id, dlc).unwrap()),
        (
            id(),
            proptest::collection::vec(any::<u8>(), 0..=64),
            any::<u8>()
        )
            .prop_filter_map("a CAN FD length", |(id, d, f)| is_fd_len(d.len())
                .then(|| Frame::fd(id, &d, FdFlags(f).masked()).unwrap())),
        (0u32..0x2000_0000, any::<[u8; 8]>()).prop_map(|(c, d)| Frame::error(c, d)),
    ]
}

fn address() -> impl Strategy<Value = Address> {
    (any::<u16>(), any::<u8>()).prop_map(|(i, s)| Address::new(i, s))
}

fn chunk(max: usize) -> impl Strategy<Value = Chunk> {
    proptest::collection::vec(any::<u8>(), 0..=max).prop_map(|d| Chunk::new(&d).unwrap())
}

fn request() -> impl Strategy<Value = Request> {
    prop_oneof![
        (
            address(),
            chunk(4).prop_filter("1..=4 bytes", |c| !c.as_slice().is_empty())
        )
            .prop_map(|(address, data)| Request::DownloadExpedited { address, data }),
        (address(), any::<Option<u32>>())
            .prop_map(|(address, size)| Request::DownloadInitiate { address, size }),
        (any::<bool>(), chunk(7), any::<bool>())
            .prop_map(|(toggle, data, last)| Request::DownloadSegment { toggle, data, last }),
        address().prop_map(|address| Request::UploadInitiate { address }),
        any::<bool>().prop_map(|toggle| Request::UploadSegment { toggle }),
        (address(), any::<u32>()).prop_map(|(address, c)| Request::Abort {
            address,
            code: AbortCode(c)
        }),
    ]
}

fn response() -> impl Strategy<Value = Response> {
    prop_oneof![
        address().prop_map(|address| Response::DownloadInitiate { address }),
        any::<bool>().prop_map(|toggle| Response::DownloadSegment { toggle }),
        (
            address(),
            chunk(4).prop_filter("1..=4 bytes", |c| !c.as_slice().is_empty())
        )
            .prop_map(|(address, data)| Response::UploadExpedited { address, data }),
        (address(), any::<Option<u32>>())
            .prop_map(|(address, size)| Response::UploadInitiate { address, size }),
        (any::<bool>(), chunk(7), any::<bool>())
            .prop_map(|(toggle, data, last)| Response::UploadSegment { toggle, data, last }),
        (address(), any::<u32>()).prop_map(|(address, c)| Response::Abort {
            address,
            code: AbortCode(c)
        }),
    ]
}

proptest! {
    #[test]
    fn socketcan_layouts_round_trip(f in frame(), network in any::<bool>()) {
        let order = if network { IdOrder::Network } else { IdOrder::Host };
        let mut b = [0u8; 72];
        let n = f.write_socketcan(&mut b, order).unwrap();
        prop_assert_eq!(Frame::read_socketcan(&b[..n], order).unwrap(), f);
    }

    #[test]
    fn candump_lines_round_trip(f in frame(), secs in 0u64..10_000_000_000, micros in 0u32..1_000_000) {
        let mut line = String::new();
        let ts = Timestamp { secs, micros };
        candump::write_line(&mut line, ts, "can0", &f).unwrap();
        let l = candump::parse_line(&line).unwrap();
        prop_assert_eq!((l.timestamp, l.interface, l.frame), (ts, "can0", f));
    }

    #[test]
    fn cannelloni_datagrams_and_streams_round_trip(frames in proptest::collection::vec(frame(), 0..20), seq in any::<u8>(), cut in any::<proptest::sample::Index>()) {
        let mut buf = [0u8; 2048];
        let mut w = DatagramWriter::new(&mut buf, seq).unwrap();
        for f in &frames {
            w.push(f).unwrap();
        }
        let bytes = w.as_bytes().to_vec();
        let (h, it) = cannelloni::read_datagram(&bytes).unwrap();
        prop_assert_eq!(h.seq, seq);
        let got: Vec<Frame> = it.collect::<Result<_, _>>().unwrap();
        prop_assert_eq!(&got, &frames);
        // The same frames as a TCP stream, split at an arbitrary point.
        let stream = &bytes[cannelloni::HEADER_LEN..];
        let at = cut.index(stream.len() + 1);
        let mut d = StreamDecoder::new();
        let mut out = Vec::new();
        d.feed(&stream[..at], |f| out.push(f)).unwrap();
        d.feed(&stream[at..], |f| out.push(f)).unwrap();
        prop_assert_eq!(out, frames);
    }

    #[test]
    fn sdo_messages_round_trip(r in request(), s in response()) {
        prop_assert_eq!(Request::decode(&r.encode()), Ok(r));
        prop_assert_eq!(Response::decode(&s.encode()), Ok(s));
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        let _ = Frame::read_socketcan(&bytes, IdOrder::Host);
        if let Ok((_, frames)) = cannelloni::read_datagram(&bytes) {
            for f in frames {
                let _ = f;
            }
        }
        let mut d = StreamDecoder::new();
        let _ = d.feed(&bytes, |_| {});
        let _ = Request::decode(&bytes);
        let _ = Response::decode(&bytes);
        // An SDO client fed arbitrary answers ends, aborts or asks on; it never panics.
        let mut c = Client::new();
        c.upload(Address::new(0x1008, 0));
        for chunk in bytes.chunks(8) {
            let _ = c.on_response(chunk);
        }
        let text = String::from_utf8_lossy(&bytes);
        let _ = candump::parse_line(&text);
        let _ = candump::parse_frame(&text);
        let _ = Eds::parse(&text);
    }

    #[test]
    fn arbitrary_candump_and_eds_like_text_never_panics(
        line in "\\([0-9]{1,11}\\.[0-9]{0,7}\\) [a-z0-9]{0,5} [0-9A-Fa-fR#.]{0,40}( [RTX])?",
        eds in "(\\[[0-9A-Fa-fsub]{1,9}\\]\n|[A-Za-z]{1,12}=[0-9a-fx$NODEID+]{0,12}\n){0,30}",
    ) {
        let _ = candump::parse_line(&line);
        let _ = Eds::parse(&format!("[MandatoryObjects]\nSupportedObjects=2\n1=0x1000\n2=0x1018\n{eds}"));
    }
}
