//! The Franka codecs never panic on any input, and what they encode decodes to itself.

use proptest::prelude::*;
use rl_drivers::franka::command::{COMMAND_LEN, RobotCommand};
use rl_drivers::franka::connect::ConnectResponse;
use rl_drivers::franka::message::{HEADER_LEN, Header, Request, Response};
use rl_drivers::franka::state::{RobotState, STATE_LEN};

proptest! {
    #[test]
    fn decoders_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..1500)) {
        let mut s = RobotState::default();
        let _ = s.decode_into(&bytes);
        let _ = RobotCommand::decode(&bytes);
        let _ = ConnectResponse::decode(&bytes);
        let _ = Response::decode(&bytes, 1 << 20);
        if let Ok(h) = Header::decode(&bytes, 1 << 20) {
            let payload = &bytes[HEADER_LEN.min(bytes.len())..];
            let _ = Request::decode(&h, payload);
        }
    }

    #[test]
    fn full_length_records_decode_or_name_their_bad_field(
        state in proptest::collection::vec(any::<u8>(), STATE_LEN),
        command in proptest::collection::vec(any::<u8>(), COMMAND_LEN),
    ) {
        let mut s = RobotState::default();
        if let Err(e) = s.decode_into(&state) {
            prop_assert!(e.to_string().contains("invalid value"));
        }
        let c = RobotCommand::decode(&command).unwrap();
        let mut again = [0u8; COMMAND_LEN];
        c.encode(&mut again);
        // Booleans other than 0 and 1 read as true and write back as 1; everything else is kept.
        let mut expected: Vec<u8> = command.clone();
        for i in [312, 313, 370] {
            expected[i] = u8::from(expected[i] != 0);
        }
        prop_assert_eq!(&again[..], &expected[..]);
    }

    #[test]
    fn joints_round_trip_through_the_state_record(
        q in proptest::array::uniform7(-4.0f64..4.0),
        id in any::<u64>(),
    ) {
        let s = RobotState { message_id: id, q, ..RobotState::default() };
        let mut buf = [0u8; STATE_LEN];
        s.encode(&mut buf);
        let mut d = RobotState::default();
        d.decode_into(&buf).unwrap();
        prop_assert_eq!(d.message_id, id);
        for (got, sent) in d.q.iter().zip(q) {
            prop_assert_eq!(*got, f64::from(sent as f32));
        }
    }
}
