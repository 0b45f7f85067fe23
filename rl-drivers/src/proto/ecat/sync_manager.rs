//! Sync manager channels (ESC register 0x0800 + 8·n, ETG.1000.4 §6.7): a window of the ESC's
//! memory that the master and the device's processor (PDI) exchange through, either as a
//! mailbox (one buffer, handshake: the writer fills it, the reader empties it) or as a 3-buffer
//! (the reader always finds the latest complete write).
//!
//! ```text
//! 0-1 physical start   2-3 length   4 control   5 status   6 activate   7 PDI control
//! control:  bits 0-1 mode (0 3-buffer, 2 mailbox), bits 2-3 direction (0 ECAT reads, 1 ECAT
//!           writes), bit 4 ECAT event, bit 5 AL (PDI) event, bit 6 watchdog
//! status:   bit 0 written (interrupt write), bit 1 read (interrupt read), bit 3 mailbox full,
//!           bits 4-5 last written 3-buffer, bit 6 read buffer in use, bit 7 write buffer in use
//! activate: bit 0 enable, bit 1 repeat request
//! PDI:      bit 0 deactivate (the device's processor refuses the channel), bit 1 repeat ack
//! ```
//!
//! Conventional use: SM0 mailbox out (master → device), SM1 mailbox in, SM2 outputs, SM3 inputs.

use core::fmt;

/// Bytes of one channel's registers.
pub const LEN: usize = 8;
/// The register of channel `n`.
pub const fn register(n: u8) -> u16 {
    0x0800 + 8 * n as u16
}

/// Control bits 0-1: 3-buffer mode.
pub const MODE_BUFFERED: u8 = 0x00;
/// Control bits 0-1: mailbox mode.
pub const MODE_MAILBOX: u8 = 0x02;
/// Control bits 2-3: ECAT reads (device → master).
pub const DIR_READ: u8 = 0x00;
/// Control bits 2-3: ECAT writes (master → device).
pub const DIR_WRITE: u8 = 0x04;
/// Control bit 4: interrupt in the ECAT event request register.
pub const IRQ_ECAT: u8 = 0x10;
/// Control bit 5: interrupt in the AL event request register (for the PDI).
pub const IRQ_PDI: u8 = 0x20;
/// Control bit 6: the watchdog is triggered by writes.
pub const WATCHDOG: u8 = 0x40;
/// Status bit 3: the mailbox is full.
pub const STATUS_MAILBOX_FULL: u8 = 0x08;
/// Activate bit 0: enabled.
pub const ACTIVATE_ENABLE: u8 = 0x01;
/// PDI control bit 0: deactivated by the device.
pub const PDI_DEACTIVATE: u8 = 0x01;

/// A channel's registers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SyncManager {
    /// Physical start address in the ESC's memory.
    pub start: u16,
    /// Bytes.
    pub length: u16,
    /// Control byte.
    pub control: u8,
    /// Status byte (read-only for the master).
    pub status: u8,
    /// Activate byte.
    pub activate: u8,
    /// PDI control byte (read-only for the master).
    pub pdi_control: u8,
}

/// What a channel is configured for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// Mailbox, master → device.
    MailboxOut,
    /// Mailbox, device → master.
    MailboxIn,
    /// 3-buffer, master → device (outputs).
    Outputs,
    /// 3-buffer, device → master (inputs).
    Inputs,
}

impl SyncManager {
    /// The usual control byte of a kind: mailboxes with PDI interrupts (0x26, 0x22), outputs
    /// with watchdog and PDI interrupt (0x64), inputs (0x20), as SOEM and TwinCAT write them.
    pub const fn control_of(kind: Kind) -> u8 {
        match kind {
            Kind::MailboxOut => MODE_MAILBOX | DIR_WRITE | IRQ_PDI,
            Kind::MailboxIn => MODE_MAILBOX | DIR_READ | IRQ_PDI,
            Kind::Outputs => MODE_BUFFERED | DIR_WRITE | IRQ_PDI | WATCHDOG,
            Kind::Inputs => MODE_BUFFERED | DIR_READ | IRQ_PDI,
        }
    }

    /// An enabled channel of `kind` over `start..start + length`.
    pub const fn new(kind: Kind, start: u16, length: u16) -> Self {
        Self {
            start,
            length,
            control: Self::control_of(kind),
            status: 0,
            activate: ACTIVATE_ENABLE,
            pdi_control: 0,
        }
    }

    /// Decodes 8 bytes.
    pub fn decode(b: &[u8; LEN]) -> Self {
        Self {
            start: u16::from_le_bytes([b[0], b[1]]),
            length: u16::from_le_bytes([b[2], b[3]]),
            control: b[4],
            status: b[5],
            activate: b[6],
            pdi_control: b[7],
        }
    }

    /// The 8 bytes.
    pub fn encode(&self) -> [u8; LEN] {
        let s = self.start.to_le_bytes();
        let l = self.length.to_le_bytes();
        [
            s[0],
            s[1],
            l[0],
            l[1],
            self.control,
            self.status,
            self.activate,
            self.pdi_control,
        ]
    }

    /// Whether the control byte selects mailbox mode.
    pub const fn is_mailbox(&self) -> bool {
        self.control & 0x03 == MODE_MAILBOX
    }

    /// Whether the master writes this channel.
    pub const fn is_write(&self) -> bool {
        self.control & 0x0C == DIR_WRITE
    }

    /// Whether the master enabled it and the device did not deactivate it.
    pub const fn is_active(&self) -> bool {
        self.activate & ACTIVATE_ENABLE != 0 && self.pdi_control & PDI_DEACTIVATE == 0
    }

    /// Whether `addr..addr + len` overlaps the channel's window.
    pub const fn overlaps(&self, addr: u16, len: u16) -> bool {
        let (a, b) = (addr as u32, addr as u32 + len as u32);
        let (s, e) = (self.start as u32, self.start as u32 + self.length as u32);
        self.length > 0 && a < e && s < b
    }

    /// The physical end (exclusive).
    pub const fn end(&self) -> u32 {
        self.start as u32 + self.length as u32
    }
}

impl fmt::Display for SyncManager {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:#06x}+{} {} {}{}",
            self.start,
            self.length,
            if self.is_mailbox() {
                "mailbox"
            } else {
                "buffered"
            },
            if self.is_write() { "write" } else { "read" },
            if self.is_active() { "" } else { " (inactive)" }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lan9252_configuration_decodes() {
        // soem-single-lan9252.pcapng frame 271: FPWR 0x0800, 16 bytes (SM0 and SM1).
        let bytes = [
            0x00, 0x10, 0x80, 0x00, 0x26, 0x00, 0x01, 0x00, 0x80, 0x10, 0x80, 0x00, 0x22, 0x00,
            0x01, 0x00,
        ];
        let sm0 = SyncManager::decode(bytes[..8].try_into().unwrap());
        let sm1 = SyncManager::decode(bytes[8..].try_into().unwrap());
        assert_eq!(sm0, SyncManager::new(Kind::MailboxOut, 0x1000, 0x80));
        assert_eq!(sm1, SyncManager::new(Kind::MailboxIn, 0x1080, 0x80));
        assert!(sm0.is_mailbox() && sm0.is_write() && !sm1.is_write());
        assert_eq!(sm0.encode(), bytes[..8]);
        // Frame 957: SM2 outputs 0x1100, 2 bytes, control 0x64.
        let sm2 = SyncManager::decode(&[0x00, 0x11, 0x02, 0x00, 0x64, 0x00, 0x01, 0x00]);
        assert_eq!(sm2, SyncManager::new(Kind::Outputs, 0x1100, 2));
        assert!(sm2.overlaps(0x1101, 4) && !sm2.overlaps(0x1102, 4));
        assert_eq!(register(3), 0x0818);
    }
}
