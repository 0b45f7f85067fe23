//! NMT: the master's node control command (COB-ID 0, `[command, node]`, node 0 = all) and the
//! state a node reports in its heartbeat (CiA 301 §7.2.8.3).

use core::fmt;

use super::NodeId;
use crate::proto::can::Frame;

/// An NMT node control command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Command {
    /// 0x01: enter operational.
    Start,
    /// 0x02: enter stopped.
    Stop,
    /// 0x80: enter pre-operational.
    EnterPreOperational,
    /// 0x81: reset the application.
    ResetNode,
    /// 0x82: reset communication.
    ResetCommunication,
}

impl Command {
    /// The command specifier byte.
    pub const fn specifier(self) -> u8 {
        match self {
            Command::Start => 0x01,
            Command::Stop => 0x02,
            Command::EnterPreOperational => 0x80,
            Command::ResetNode => 0x81,
            Command::ResetCommunication => 0x82,
        }
    }

    /// The command of a specifier byte.
    pub const fn from_specifier(cs: u8) -> Option<Self> {
        match cs {
            0x01 => Some(Command::Start),
            0x02 => Some(Command::Stop),
            0x80 => Some(Command::EnterPreOperational),
            0x81 => Some(Command::ResetNode),
            0x82 => Some(Command::ResetCommunication),
            _ => None,
        }
    }

    /// The NMT frame for `node` (`None`: all nodes).
    pub fn frame(self, node: Option<NodeId>) -> Frame {
        let n = node.map_or(0, NodeId::get);
        Frame::standard(super::cob::NMT, &[self.specifier(), n]).unwrap_or_else(no_frame)
    }

    /// Decodes an NMT frame's data: the command and its target (`None`: all nodes).
    pub fn decode(data: &[u8]) -> Option<(Self, Option<NodeId>)> {
        match data {
            [cs, node] => Some((Self::from_specifier(*cs)?, NodeId::new(*node))),
            _ => None,
        }
    }
}

/// A frame that cannot fail to build (identifier < 0x800, at most 8 bytes); never reached.
pub(crate) fn no_frame() -> Frame {
    Frame::error(0, [0; 8])
}

/// The NMT state a node reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum State {
    /// 0x00: the boot-up message (the node entered pre-operational after a reset).
    BootUp,
    /// 0x04: stopped.
    Stopped,
    /// 0x05: operational (PDOs exchanged).
    Operational,
    /// 0x7F: pre-operational (SDO only).
    PreOperational,
}

impl State {
    /// The state byte.
    pub const fn to_byte(self) -> u8 {
        match self {
            State::BootUp => 0x00,
            State::Stopped => 0x04,
            State::Operational => 0x05,
            State::PreOperational => 0x7F,
        }
    }

    /// The state of a heartbeat byte (bit 7, the node-guarding toggle, ignored).
    pub const fn from_byte(b: u8) -> Option<Self> {
        match b & 0x7F {
            0x00 => Some(State::BootUp),
            0x04 => Some(State::Stopped),
            0x05 => Some(State::Operational),
            0x7F => Some(State::PreOperational),
            _ => None,
        }
    }
}

impl fmt::Display for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            State::BootUp => "boot-up",
            State::Stopped => "stopped",
            State::Operational => "operational",
            State::PreOperational => "pre-operational",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_and_states_have_the_reference_codes() {
        let f = Command::Start.frame(NodeId::new(3));
        assert_eq!((f.standard_id(), f.bytes()), (Some(0), &[1u8, 3][..]));
        let all = Command::ResetCommunication.frame(None);
        assert_eq!(all.bytes(), &[0x82, 0]);
        assert_eq!(
            Command::decode(&[0x80, 0]),
            Some((Command::EnterPreOperational, None))
        );
        assert_eq!(Command::decode(&[0x03, 1]), None);
        assert_eq!(State::from_byte(0x7F), Some(State::PreOperational));
        assert_eq!(
            State::from_byte(0x85),
            Some(State::Operational),
            "toggle bit"
        );
        assert_eq!(State::from_byte(0x01), None);
    }
}
