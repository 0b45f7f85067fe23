//! Heartbeat (COB-ID 0x700 + node): one byte, the producer's NMT state; the boot-up message is
//! the same frame with state 0 (CiA 301 §7.2.8.3.2).

use super::nmt::State;
use super::{Function, NodeId};
use crate::proto::can::Frame;

/// The heartbeat (or boot-up) frame of `node`.
pub fn frame(node: NodeId, state: State) -> Frame {
    Frame::standard(Function::Heartbeat(node).cob_id(), &[state.to_byte()])
        .unwrap_or_else(super::nmt::no_frame)
}

/// A heartbeat's state from its data (`None`: not one byte, or no NMT state).
pub fn decode(data: &[u8]) -> Option<State> {
    match data {
        [b] => State::from_byte(*b),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_heartbeat_is_one_state_byte() {
        let f = frame(NodeId::new(2).unwrap(), State::Operational);
        assert_eq!((f.standard_id(), f.bytes()), (Some(0x702), &[5u8][..]));
        assert_eq!(decode(&[0x7F]), Some(State::PreOperational));
        assert_eq!(decode(&[5, 0]), None);
    }
}
