//! The fifteen datagram commands (ETG.1000.4 §5.4, table "EtherCAT command types"): how each
//! addresses devices and which access it makes, and so how much it adds to the working counter
//! in every device it addresses.
//!
//! | code | name | addressing | access |
//! |---|---|---|---|
//! | 0 | NOP | none | none |
//! | 1, 2, 3 | APRD, APWR, APRW | auto-increment position | read, write, read-write |
//! | 4, 5, 6 | FPRD, FPWR, FPRW | configured station address | read, write, read-write |
//! | 7, 8, 9 | BRD, BWR, BRW | broadcast | read, write, read-write |
//! | 10, 11, 12 | LRD, LWR, LRW | logical (through FMMUs) | read, write, read-write |
//! | 13 | ARMW | position | the addressed device reads, every other writes |
//! | 14 | FRMW | station | the addressed device reads, every other writes |
//!
//! Working counter: an addressed device adds 1 for a successful read, 1 for a successful write,
//! and for a read-write command 1 for the read and 2 for the write (3 for both). ARMW and FRMW
//! add 1 in the device that reads and 1 in each device that writes. A device increments the
//! position (ADP) of every position-addressed and broadcast datagram it forwards.

use core::fmt;

/// A datagram command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Command {
    /// 0: no operation; devices ignore it.
    Nop = 0,
    /// 1: auto-increment physical read.
    Aprd = 1,
    /// 2: auto-increment physical write.
    Apwr = 2,
    /// 3: auto-increment physical read-write.
    Aprw = 3,
    /// 4: configured-address physical read.
    Fprd = 4,
    /// 5: configured-address physical write.
    Fpwr = 5,
    /// 6: configured-address physical read-write.
    Fprw = 6,
    /// 7: broadcast read (devices OR their data into the datagram).
    Brd = 7,
    /// 8: broadcast write.
    Bwr = 8,
    /// 9: broadcast read-write.
    Brw = 9,
    /// 10: logical read.
    Lrd = 10,
    /// 11: logical write.
    Lwr = 11,
    /// 12: logical read-write.
    Lrw = 12,
    /// 13: auto-increment read, multiple write.
    Armw = 13,
    /// 14: configured-address read, multiple write (distributes a reference clock's time).
    Frmw = 14,
}

/// How a command selects the devices it addresses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Addressing {
    /// No device (NOP).
    None,
    /// The device whose auto-increment position counter reaches 0 (ADP is incremented by
    /// every device).
    Position,
    /// The device whose configured station address (0x0010) equals ADP.
    Station,
    /// Every device.
    Broadcast,
    /// Every device with an FMMU mapping part of the 32-bit logical address range.
    Logical,
}

/// What an addressed device does with the datagram's data.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    /// Nothing.
    None,
    /// Copies its memory into the data (broadcast reads OR it in).
    Read,
    /// Copies the data into its memory.
    Write,
    /// Both: the data read replaces what was written on the way back.
    ReadWrite,
    /// The addressed device reads, every other device writes (ARMW, FRMW).
    ReadMultipleWrite,
}

impl Command {
    /// Every command, by code.
    pub const ALL: [Command; 15] = [
        Command::Nop,
        Command::Aprd,
        Command::Apwr,
        Command::Aprw,
        Command::Fprd,
        Command::Fpwr,
        Command::Fprw,
        Command::Brd,
        Command::Bwr,
        Command::Brw,
        Command::Lrd,
        Command::Lwr,
        Command::Lrw,
        Command::Armw,
        Command::Frmw,
    ];

    /// The command of a code (`None` above 14).
    pub const fn from_code(code: u8) -> Option<Self> {
        if (code as usize) < Self::ALL.len() {
            Some(Self::ALL[code as usize])
        } else {
            None
        }
    }

    /// The code on the wire.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The short name the ETG and Wireshark use (`"LRW"`).
    pub const fn name(self) -> &'static str {
        match self {
            Command::Nop => "NOP",
            Command::Aprd => "APRD",
            Command::Apwr => "APWR",
            Command::Aprw => "APRW",
            Command::Fprd => "FPRD",
            Command::Fpwr => "FPWR",
            Command::Fprw => "FPRW",
            Command::Brd => "BRD",
            Command::Bwr => "BWR",
            Command::Brw => "BRW",
            Command::Lrd => "LRD",
            Command::Lwr => "LWR",
            Command::Lrw => "LRW",
            Command::Armw => "ARMW",
            Command::Frmw => "FRMW",
        }
    }

    /// How it addresses devices.
    pub const fn addressing(self) -> Addressing {
        match self {
            Command::Nop => Addressing::None,
            Command::Aprd | Command::Apwr | Command::Aprw | Command::Armw => Addressing::Position,
            Command::Fprd | Command::Fpwr | Command::Fprw | Command::Frmw => Addressing::Station,
            Command::Brd | Command::Bwr | Command::Brw => Addressing::Broadcast,
            Command::Lrd | Command::Lwr | Command::Lrw => Addressing::Logical,
        }
    }

    /// The access it makes.
    pub const fn access(self) -> Access {
        match self {
            Command::Nop => Access::None,
            Command::Aprd | Command::Fprd | Command::Brd | Command::Lrd => Access::Read,
            Command::Apwr | Command::Fpwr | Command::Bwr | Command::Lwr => Access::Write,
            Command::Aprw | Command::Fprw | Command::Brw | Command::Lrw => Access::ReadWrite,
            Command::Armw | Command::Frmw => Access::ReadMultipleWrite,
        }
    }

    /// Whether the 32-bit address is one logical address rather than ADP + ADO.
    pub const fn is_logical(self) -> bool {
        matches!(self.addressing(), Addressing::Logical)
    }

    /// Whether each device increments ADP as the datagram passes (position and broadcast
    /// addressing).
    pub const fn increments_position(self) -> bool {
        matches!(
            self.addressing(),
            Addressing::Position | Addressing::Broadcast
        )
    }

    /// What one addressed device adds to the working counter for a successful `read` and
    /// `write` (read-write commands: 1 + 2).
    pub const fn wkc_increment(self, read: bool, write: bool) -> u16 {
        match self.access() {
            Access::None => 0,
            Access::Read => read as u16,
            Access::Write => write as u16,
            Access::ReadWrite => read as u16 + 2 * write as u16,
            Access::ReadMultipleWrite => (read || write) as u16,
        }
    }

    /// The working counter a datagram returns when `devices` devices take part fully (each
    /// reads and writes what the command asks): 1 per device for reads or writes, 3 for
    /// read-write, 1 for ARMW/FRMW.
    pub const fn expected_wkc(self, devices: u16) -> u16 {
        devices.saturating_mul(self.wkc_increment(true, true))
    }
}

impl fmt::Display for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_names_and_working_counter_rules() {
        for (code, c) in Command::ALL.iter().enumerate() {
            assert_eq!(c.code() as usize, code);
            assert_eq!(Command::from_code(code as u8), Some(*c));
        }
        assert_eq!(Command::from_code(15), None);
        assert_eq!(Command::Lrw.name(), "LRW");
        assert_eq!(Command::Frmw.to_string(), "FRMW");
        // ETG: 1 per read, 1 per write, read-write 1 + 2.
        assert_eq!(Command::Fprd.wkc_increment(true, false), 1);
        assert_eq!(Command::Bwr.wkc_increment(false, true), 1);
        assert_eq!(Command::Lrw.wkc_increment(true, true), 3);
        assert_eq!(Command::Lrw.wkc_increment(true, false), 1);
        assert_eq!(Command::Lrw.wkc_increment(false, true), 2);
        assert_eq!(Command::Frmw.wkc_increment(false, true), 1);
        assert_eq!(Command::Nop.wkc_increment(true, true), 0);
        assert_eq!(Command::Brd.expected_wkc(3), 3);
        assert!(Command::Brd.increments_position() && Command::Aprd.increments_position());
        assert!(!Command::Fprd.increments_position() && !Command::Lrw.increments_position());
        assert!(Command::Lrd.is_logical() && !Command::Frmw.is_logical());
    }
}
