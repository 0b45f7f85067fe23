//! Property tests of the codecs: round trips, and arbitrary bytes never panic (the short in-CI
//! counterpart of the fuzz targets in `rl-drivers/fuzz`).

use proptest::prelude::*;
use rl_drivers::proto::coach::{LineBuffer, MAX_VALUES, Message, Values, write_g6};
use rl_drivers::proto::h7::{Command, Data, IoType, MxtType, PACKET_LEN, Packet};
use rl_drivers::proto::r3::{DState, EMDAT_CHUNK_LEN, EmdatChunks, Reply, Request};

fn data() -> impl Strategy<Value = Data> {
    proptest::collection::vec(any::<u8>(), 40).prop_map(|v| {
        let mut d = [0u8; 40];
        d.copy_from_slice(&v);
        Data(d)
    })
}

fn mxt() -> impl Strategy<Value = MxtType> {
    (0u16..12).prop_map(|c| MxtType::from_code(c).unwrap())
}

fn io() -> impl Strategy<Value = IoType> {
    (0u16..3).prop_map(|c| IoType::from_code(c).unwrap())
}

prop_compose! {
    fn packet()(
        command in prop_oneof![Just(Command::Null), Just(Command::Move), Just(Command::End)],
        types in (mxt(), mxt(), mxt(), mxt(), mxt()),
        ios in (io(), io()),
        words in any::<[u16; 8]>(),
        c_count in any::<u32>(),
        blocks in (data(), data(), data(), data()),
    ) -> Packet {
        Packet {
            command,
            send_type: types.0,
            recv_type: types.1,
            reserve: words[0],
            dat: blocks.0,
            send_io_type: ios.0,
            recv_io_type: ios.1,
            bit_top: words[1],
            bit_mask: words[2],
            io_data: words[3],
            t_count: words[4],
            c_count,
            recv_type1: types.2,
            reserve1: words[5],
            dat1: blocks.1,
            recv_type2: types.3,
            reserve2: words[6],
            dat2: blocks.2,
            recv_type3: types.4,
            reserve3: words[7],
            dat3: blocks.3,
        }
    }
}

fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e3..1e3f64,
        -1e-3..1e-3f64,
        any::<f64>().prop_filter("finite", |v| v.is_finite())
    ]
}

/// Bytes of the longest Coach line: [`MAX_VALUES`] numbers of at most 14 bytes each
/// (`-1.23457e+308 `) after the command and model fields.
const LINE: usize = MAX_VALUES * 14 + 64;

fn values() -> impl Strategy<Value = Values> {
    proptest::collection::vec(finite(), 1..MAX_VALUES).prop_map(|v| Values::from_slice(&v).unwrap())
}

fn message() -> impl Strategy<Value = Message> {
    let pose = || proptest::array::uniform6(finite());
    prop_oneof![
        (any::<u32>(), any::<u32>(), pose()).prop_map(|(model, body, pose)| Message::BodyPose {
            model,
            body,
            pose
        }),
        (any::<u32>(), any::<u32>(), any::<u32>(), pose()).prop_map(
            |(model, body, shape, pose)| Message::ShapePose {
                model,
                body,
                shape,
                pose
            }
        ),
        (any::<u32>(), values())
            .prop_map(|(model, values)| Message::JointPosition { model, values }),
        (any::<u32>(), values())
            .prop_map(|(model, values)| Message::JointVelocity { model, values }),
        (any::<u32>(), values()).prop_map(|(model, values)| Message::JointTorque { model, values }),
        any::<u32>().prop_map(|model| Message::Request { model }),
        (any::<u32>(), values()).prop_map(|(model, values)| Message::Reply { model, values }),
        Just(Message::Empty),
    ]
}

fn numbers(m: &Message) -> Vec<f64> {
    match m {
        Message::BodyPose { pose, .. } | Message::ShapePose { pose, .. } => pose.to_vec(),
        Message::JointPosition { values, .. }
        | Message::JointVelocity { values, .. }
        | Message::JointTorque { values, .. }
        | Message::Reply { values, .. } => values.to_vec(),
        Message::Request { .. } | Message::Empty => vec![],
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn h7_packets_round_trip(p in packet()) {
        let bytes = p.to_bytes();
        prop_assert_eq!(Packet::decode(&bytes), Ok(p));
    }

    #[test]
    fn h7_decoding_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        if let Ok(p) = Packet::decode(&bytes) {
            prop_assert_eq!(bytes.len(), PACKET_LEN);
            prop_assert_eq!(&p.to_bytes()[..], &bytes[..]);
        }
    }

    #[test]
    fn h7_decoding_mutated_packets_never_panics(p in packet(), at in 0..PACKET_LEN, byte in any::<u8>()) {
        let mut bytes = p.to_bytes();
        bytes[at] = byte;
        if let Ok(q) = Packet::decode(&bytes) {
            prop_assert_eq!(q.to_bytes(), bytes);
        }
    }

    #[test]
    fn r3_requests_round_trip(robot in any::<u8>(), slot in any::<u8>(), body in "[A-Z]{1,10}[A-Z0-9=;., ]{0,40}") {
        let mut buf = [0u8; 128];
        let n = Request { robot, slot, body: &body }.encode(&mut buf).unwrap();
        let r = Request::parse(&buf[..n]).unwrap();
        prop_assert_eq!((r.robot, r.slot, r.body), (robot, slot, body.as_str()));
        prop_assert_eq!(format!("{}{}", r.name(), r.args()), body.clone());
    }

    #[test]
    fn dstate_round_trips(run in any::<u8>(), stop in any::<u8>(), error_no in any::<u32>(), step_no in any::<u32>(), mech_no in any::<u32>()) {
        let s = DState { run, stop, error_no, step_no, mech_no };
        let mut buf = [0u8; 64];
        let n = s.encode(&mut buf).unwrap();
        prop_assert_eq!(DState::parse(std::str::from_utf8(&buf[..n]).unwrap()), Ok(s));
    }

    #[test]
    fn r3_parsing_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let _ = Request::parse(&bytes);
        if let Ok(Reply::Ok(payload)) = Reply::parse(&bytes) {
            let _ = DState::parse(payload);
        }
        if let Ok(text) = std::str::from_utf8(&bytes) {
            let _ = DState::parse(text);
            for chunk in EmdatChunks::new(text).flatten() {
                prop_assert!(chunk.len() <= EMDAT_CHUNK_LEN);
            }
        }
    }

    #[test]
    fn emdat_chunks_rejoin_to_the_program(lines in proptest::collection::vec("[ -~]{1,120}", 1..12)) {
        let program = lines.join("\u{b}");
        let chunks: Vec<&str> = EmdatChunks::new(&program).map(Result::unwrap).collect();
        prop_assert!(chunks.iter().all(|c| c.len() <= EMDAT_CHUNK_LEN));
        prop_assert_eq!(chunks.join("\u{b}"), program);
    }

    #[test]
    fn coach_lines_round_trip_to_six_digits(m in message()) {
        let mut buf = [0u8; LINE];
        let n = m.encode(&mut buf).unwrap();
        prop_assert_eq!(buf[n - 1], b'\n');
        let back = Message::parse(&buf[..n]).unwrap();
        prop_assert_eq!(std::mem::discriminant(&back), std::mem::discriminant(&m));
        prop_assert_eq!(back.model(), m.model());
        let (a, b) = (numbers(&m), numbers(&back));
        prop_assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            prop_assert!((x - y).abs() <= 5e-6 * x.abs(), "{} became {}", x, y);
        }
        // Text is stable: encoding what was parsed gives the same line.
        let mut again = [0u8; LINE];
        let m2 = back.encode(&mut again).unwrap();
        prop_assert_eq!(&again[..m2], &buf[..n]);
    }

    #[test]
    fn g6_matches_rust_parsing_of_six_digits(v in finite()) {
        let mut s = String::new();
        write_g6(&mut s, v).unwrap();
        let back: f64 = s.parse().unwrap();
        let sci: f64 = format!("{v:.5e}").parse().unwrap();
        prop_assert_eq!(back, sci, "{} printed as {}", v, s);
    }

    #[test]
    fn g6_prints_like_glibc_printf(v in finite()) {
        let mut ours = String::new();
        write_g6(&mut ours, v).unwrap();
        let mut buf = [0u8; 64];
        // SAFETY: the buffer is 64 bytes and its length is passed; the format takes one double.
        let n = unsafe { libc::snprintf(buf.as_mut_ptr().cast(), buf.len(), c"%g".as_ptr(), v) };
        let theirs = std::str::from_utf8(&buf[..n as usize]).unwrap();
        prop_assert_eq!(ours.as_str(), theirs);
    }

    #[test]
    fn coach_parsing_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let _ = Message::parse(&bytes);
        let mut lines = LineBuffer::<64>::new();
        let mut rest = &bytes[..];
        while !rest.is_empty() {
            let n = lines.extend(rest);
            rest = &rest[n..];
            while let Some(line) = lines.next_line() {
                let _ = line.and_then(Message::parse);
            }
        }
    }

    #[test]
    fn coach_parsing_number_soup_never_panics(text in "[0-9 .eE+\\-naifNI\t\r\n]{0,300}") {
        for line in text.split('\n') {
            if let Ok(m) = Message::parse(line.as_bytes()) {
                let mut buf = [0u8; 4096];
                prop_assert!(m.encode(&mut buf).is_ok());
            }
        }
    }

    #[test]
    fn lines_survive_any_split(msgs in proptest::collection::vec(message(), 1..8), cuts in proptest::collection::vec(1usize..40, 1..20)) {
        let mut stream = Vec::new();
        for m in &msgs {
            let mut buf = [0u8; LINE];
            let n = m.encode(&mut buf).unwrap();
            stream.extend_from_slice(&buf[..n]);
        }
        let mut lines = LineBuffer::<{ 2 * LINE }>::new();
        let mut parsed = Vec::new();
        let mut rest = &stream[..];
        let mut i = 0;
        while !rest.is_empty() {
            let k = cuts[i % cuts.len()].min(rest.len());
            i += 1;
            prop_assert_eq!(lines.extend(&rest[..k]), k);
            rest = &rest[k..];
            while let Some(line) = lines.next_line() {
                parsed.push(Message::parse(line.unwrap()).unwrap());
            }
        }
        prop_assert_eq!(parsed.len(), msgs.len());
        for (p, m) in parsed.iter().zip(&msgs) {
            prop_assert_eq!(std::mem::discriminant(p), std::mem::discriminant(m));
        }
    }
}

mod ur_realtime {
    use proptest::prelude::*;
    use rl_drivers::proto::ur_realtime::{LENGTHS, MAX_LEN, RealtimeState, split};

    fn state() -> impl Strategy<Value = RealtimeState> {
        (
            proptest::array::uniform6(-1e3f64..1e3),
            proptest::array::uniform6(-1e3f64..1e3),
            0u64..(1 << 18),
            -1i32..9,
            proptest::array::uniform6(235i32..256),
            1i32..12,
            0i32..6,
        )
            .prop_map(
                |(q, f, inputs, robot, joints, safety, program)| RealtimeState {
                    time: f[0].abs(),
                    q_actual: q,
                    q_target: q,
                    tcp_force: f,
                    digital_input_bits: inputs,
                    digital_outputs: inputs ^ 0x3,
                    robot_mode: robot,
                    joint_modes: joints,
                    safety_mode: safety,
                    safety_status: safety,
                    program_state: program,
                    ..RealtimeState::default()
                },
            )
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        #[test]
        fn ur_realtime_messages_round_trip(s in state(), k in 0..LENGTHS.len()) {
            let len = LENGTHS[k];
            let mut buf = [0u8; MAX_LEN];
            prop_assert_eq!(s.encode(len, &mut buf), Ok(len));
            let d = RealtimeState::decode(&buf[..len]).unwrap();
            prop_assert_eq!(d.q_actual, s.q_actual);
            prop_assert_eq!(d.tcp_force, s.tcp_force);
            prop_assert_eq!(d.digital_input_bits, s.digital_input_bits);
            prop_assert_eq!(d.joint_modes, s.joint_modes);
            prop_assert_eq!(d.safety_mode, s.safety_mode);
            if len >= 1060 {
                prop_assert_eq!(d.digital_outputs, s.digital_outputs);
                prop_assert_eq!(d.program_state, s.program_state);
            }
        }

        #[test]
        fn ur_realtime_decoding_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..1300)) {
            let _ = split(&bytes);
            let _ = RealtimeState::decode(&bytes);
        }

        #[test]
        fn ur_realtime_mutated_messages_never_panic(s in state(), k in 0..LENGTHS.len(), at in 0..MAX_LEN, byte in any::<u8>()) {
            let len = LENGTHS[k];
            let mut buf = [0u8; MAX_LEN];
            s.encode(len, &mut buf).unwrap();
            buf[at % len] = byte;
            // A mutated length field may name a shorter layout: then that is what decodes.
            if let Ok(d) = RealtimeState::decode(&buf[..len]) {
                prop_assert!(LENGTHS.contains(&d.length) && d.length <= len);
            }
        }
    }
}
