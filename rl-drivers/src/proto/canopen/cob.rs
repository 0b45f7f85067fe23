//! Node ids and the predefined connection set: which 11-bit identifier (COB-ID) carries which
//! function for which node (CiA 301 §7.3.5).
//!
//! | function | COB-ID | function | COB-ID |
//! |---|---|---|---|
//! | NMT | 0x000 | SYNC | 0x080 |
//! | EMCY | 0x080 + n | TIME | 0x100 |
//! | TPDO1..4 | 0x180 / 0x280 / 0x380 / 0x480 + n | RPDO1..4 | 0x200 / 0x300 / 0x400 / 0x500 + n |
//! | SDO server → client | 0x580 + n | SDO client → server | 0x600 + n |
//! | heartbeat (NMT error control) | 0x700 + n | | |

use core::fmt;

/// A CANopen node id, 1..=127.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeId(u8);

impl NodeId {
    /// `id` if it is 1..=127.
    pub const fn new(id: u8) -> Option<Self> {
        if id >= 1 && id <= 127 {
            Some(Self(id))
        } else {
            None
        }
    }

    /// The number.
    pub const fn get(self) -> u8 {
        self.0
    }
}

impl fmt::Display for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "node {}", self.0)
    }
}

/// What a frame of the predefined connection set carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Function {
    /// NMT node control (0x000).
    Nmt,
    /// SYNC (0x080).
    Sync,
    /// TIME stamp (0x100).
    Time,
    /// Emergency of a node.
    Emcy(NodeId),
    /// Transmit PDO 1..=4 of a node (node → master).
    Tpdo(u8, NodeId),
    /// Receive PDO 1..=4 of a node (master → node).
    Rpdo(u8, NodeId),
    /// SDO response (server → client).
    SdoTx(NodeId),
    /// SDO request (client → server).
    SdoRx(NodeId),
    /// Heartbeat / boot-up / node guarding reply.
    Heartbeat(NodeId),
}

/// SYNC COB-ID.
pub const SYNC: u16 = 0x080;
/// NMT COB-ID.
pub const NMT: u16 = 0x000;

impl Function {
    /// The default COB-ID of the function.
    pub const fn cob_id(self) -> u16 {
        match self {
            Function::Nmt => NMT,
            Function::Sync => SYNC,
            Function::Time => 0x100,
            Function::Emcy(id) => 0x080 + id.0 as u16,
            Function::Tpdo(k, id) => 0x080 + 0x100 * (k as u16) + id.0 as u16,
            Function::Rpdo(k, id) => 0x100 + 0x100 * (k as u16) + id.0 as u16,
            Function::SdoTx(id) => 0x580 + id.0 as u16,
            Function::SdoRx(id) => 0x600 + id.0 as u16,
            Function::Heartbeat(id) => 0x700 + id.0 as u16,
        }
    }

    /// The function of an 11-bit COB-ID in the predefined connection set (`None` for
    /// identifiers it does not assign).
    pub const fn from_cob_id(cob: u16) -> Option<Self> {
        let node = (cob & 0x7F) as u8;
        let code = cob >> 7;
        if node == 0 {
            return match cob {
                0x000 => Some(Function::Nmt),
                0x080 => Some(Function::Sync),
                0x100 => Some(Function::Time),
                _ => None,
            };
        }
        let id = NodeId(node);
        match code {
            0x1 => Some(Function::Emcy(id)),
            0x3 | 0x5 | 0x7 | 0x9 => Some(Function::Tpdo(((code - 1) / 2) as u8, id)),
            0x4 | 0x6 | 0x8 | 0xA => Some(Function::Rpdo(((code - 2) / 2) as u8, id)),
            0xB => Some(Function::SdoTx(id)),
            0xC => Some(Function::SdoRx(id)),
            0xE => Some(Function::Heartbeat(id)),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cob_ids_map_both_ways() {
        let n = NodeId::new(5).unwrap();
        let table = [
            (Function::Emcy(n), 0x085),
            (Function::Tpdo(1, n), 0x185),
            (Function::Tpdo(4, n), 0x485),
            (Function::Rpdo(1, n), 0x205),
            (Function::Rpdo(4, n), 0x505),
            (Function::SdoTx(n), 0x585),
            (Function::SdoRx(n), 0x605),
            (Function::Heartbeat(n), 0x705),
            (Function::Sync, 0x080),
            (Function::Nmt, 0x000),
        ];
        for (f, cob) in table {
            assert_eq!(f.cob_id(), cob, "{f:?}");
            assert_eq!(Function::from_cob_id(cob), Some(f), "{cob:#x}");
        }
        assert_eq!(Function::from_cob_id(0x680), None);
        assert_eq!(Function::from_cob_id(0x7E5), None, "LSS");
        assert!(NodeId::new(0).is_none() && NodeId::new(128).is_none());
    }
}
