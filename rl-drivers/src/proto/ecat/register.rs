//! ESC register addresses (ETG.1000.4 §6, Beckhoff's ESC datasheet section II) and the small
//! registers a master reads during a scan: the ESC's identity and the data-link status.

/// 0x0000: ESC type (u8).
pub const TYPE: u16 = 0x0000;
/// 0x0001: ESC revision (u8).
pub const REVISION: u16 = 0x0001;
/// 0x0002: ESC build (u16).
pub const BUILD: u16 = 0x0002;
/// 0x0004: FMMUs supported (u8).
pub const FMMU_COUNT: u16 = 0x0004;
/// 0x0005: sync managers supported (u8).
pub const SM_COUNT: u16 = 0x0005;
/// 0x0006: process RAM in KiB (u8).
pub const RAM_SIZE: u16 = 0x0006;
/// 0x0007: port descriptor (2 bits per port).
pub const PORT_DESCRIPTOR: u16 = 0x0007;
/// 0x0008: ESC features supported (u16; bit 2 distributed clocks, bit 3 64-bit DC).
pub const FEATURES: u16 = 0x0008;
/// 0x0010: configured station address (u16).
pub const STATION_ADDRESS: u16 = 0x0010;
/// 0x0012: configured station alias (u16, loaded from SII word 4).
pub const STATION_ALIAS: u16 = 0x0012;
/// 0x0100: DL control (u32; 0x0101 loop control of the ports).
pub const DL_CONTROL: u16 = 0x0100;
/// 0x0103: DL control byte 3 (RX FIFO size, low jitter).
pub const DL_CONTROL_3: u16 = 0x0103;
/// 0x0108: physical read/write offset (u16).
pub const PHYSICAL_RW_OFFSET: u16 = 0x0108;
/// 0x0110: DL status (u16).
pub const DL_STATUS: u16 = 0x0110;
/// 0x0120: AL control (u16).
pub const AL_CONTROL: u16 = 0x0120;
/// 0x0130: AL status (u16).
pub const AL_STATUS: u16 = 0x0130;
/// 0x0134: AL status code (u16).
pub const AL_STATUS_CODE: u16 = 0x0134;
/// 0x0140: PDI control (u8; 0x0141 bit 0 device emulation).
pub const PDI_CONTROL: u16 = 0x0140;
/// 0x0200: ECAT event mask (u16).
pub const ECAT_EVENT_MASK: u16 = 0x0200;
/// 0x0204: AL event mask (u32).
pub const AL_EVENT_MASK: u16 = 0x0204;
/// 0x0210: ECAT event request (u16).
pub const ECAT_EVENT: u16 = 0x0210;
/// 0x0220: AL event request (u32).
pub const AL_EVENT: u16 = 0x0220;
/// 0x0300: RX error counters (8 bytes, 2 per port).
pub const RX_ERROR_COUNTERS: u16 = 0x0300;
/// 0x0310: lost link counters (1 per port).
pub const LOST_LINK_COUNTERS: u16 = 0x0310;
/// 0x0400: watchdog divider (u16).
pub const WATCHDOG_DIVIDER: u16 = 0x0400;
/// 0x0410: PDI watchdog time (u16).
pub const WATCHDOG_PDI: u16 = 0x0410;
/// 0x0420: process data watchdog time (u16).
pub const WATCHDOG_PROCESS_DATA: u16 = 0x0420;
/// 0x0500: SII EEPROM configuration (bit 0 PDI access, bit 1 force ECAT access).
pub const SII_CONFIG: u16 = 0x0500;
/// 0x0502: SII control/status (u16).
pub const SII_CONTROL: u16 = 0x0502;
/// 0x0504: SII address (u32, in words).
pub const SII_ADDRESS: u16 = 0x0504;
/// 0x0508: SII data (4 or 8 bytes read, 2 written).
pub const SII_DATA: u16 = 0x0508;
/// 0x0600: first FMMU.
pub const FMMU0: u16 = 0x0600;
/// 0x0800: first sync manager.
pub const SM0: u16 = 0x0800;
/// 0x0900: DC receive time port 0 (u32; 0x0904, 0x0908, 0x090C ports 1-3). A write to 0x0900
/// latches the local time at each port as the frame passes.
pub const DC_RECEIVE_TIME_PORT0: u16 = 0x0900;
/// 0x0910: DC system time (u64).
pub const DC_SYSTEM_TIME: u16 = 0x0910;
/// 0x0918: DC receive time of the processing unit (u64, local time).
pub const DC_RECEIVE_TIME_UNIT: u16 = 0x0918;
/// 0x0920: DC system time offset (u64).
pub const DC_SYSTEM_TIME_OFFSET: u16 = 0x0920;
/// 0x0928: DC system time delay (u32: propagation delay from the reference clock).
pub const DC_SYSTEM_TIME_DELAY: u16 = 0x0928;
/// 0x092C: DC system time difference (u32: bit 31 sign, bits 0-30 mean deviation in ns).
pub const DC_SYSTEM_TIME_DIFFERENCE: u16 = 0x092C;
/// 0x0930: DC speed counter start (u16).
pub const DC_SPEED_COUNTER_START: u16 = 0x0930;
/// 0x0934: DC system time difference filter depth (u8).
pub const DC_FILTER_DEPTH: u16 = 0x0934;
/// 0x0980: DC cyclic unit control (u8).
pub const DC_CYCLIC_UNIT_CONTROL: u16 = 0x0980;
/// 0x0981: DC activation (bit 0 cyclic operation, bit 1 SYNC0, bit 2 SYNC1).
pub const DC_ACTIVATION: u16 = 0x0981;
/// 0x098E: SYNC0 status (u8).
pub const DC_SYNC0_STATUS: u16 = 0x098E;
/// 0x0990: start time of cyclic operation (u64, system time of the first SYNC0).
pub const DC_SYNC0_START: u16 = 0x0990;
/// 0x09A0: SYNC0 cycle time (u32, ns).
pub const DC_SYNC0_CYCLE: u16 = 0x09A0;
/// 0x09A4: SYNC1 cycle time (u32, ns).
pub const DC_SYNC1_CYCLE: u16 = 0x09A4;
/// 0x1000: start of process data RAM.
pub const PROCESS_RAM: u16 = 0x1000;

/// 0x0502 bit 0: ECAT write enable (with a write command).
pub const SII_WRITE_ENABLE: u16 = 0x0001;
/// 0x0502 bit 6: reads return 8 bytes (else 4).
pub const SII_READ_8: u16 = 0x0040;
/// 0x0502 bit 7: two address bytes (EEPROMs above 16 kbit).
pub const SII_TWO_ADDRESS_BYTES: u16 = 0x0080;
/// 0x0502 bits 8-10: read command.
pub const SII_CMD_READ: u16 = 0x0100;
/// 0x0502 bits 8-10: write command.
pub const SII_CMD_WRITE: u16 = 0x0200;
/// 0x0502 bits 8-10: reload command.
pub const SII_CMD_RELOAD: u16 = 0x0400;
/// 0x0502 bits 8-10 mask.
pub const SII_CMD_MASK: u16 = 0x0700;
/// 0x0502 bit 11: checksum error in the ESC configuration area.
pub const SII_CHECKSUM_ERROR: u16 = 0x0800;
/// 0x0502 bit 13: command error (acknowledge error).
pub const SII_ERROR_COMMAND: u16 = 0x2000;
/// 0x0502 bit 14: write enable error.
pub const SII_ERROR_WRITE_ENABLE: u16 = 0x4000;
/// 0x0502 bit 15: busy.
pub const SII_BUSY: u16 = 0x8000;

/// 0x0008 bit 2: distributed clocks supported.
pub const FEATURE_DC: u16 = 0x0004;
/// 0x0008 bit 3: 64-bit DC system time.
pub const FEATURE_DC64: u16 = 0x0008;

/// 0x0981 bit 0: cyclic operation enabled.
pub const DC_ACTIVATE_CYCLIC: u8 = 0x01;
/// 0x0981 bit 1: SYNC0 generated.
pub const DC_ACTIVATE_SYNC0: u8 = 0x02;

/// The data-link status register (0x0110).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct DlStatus(pub u16);

impl DlStatus {
    /// Bit 0: the PDI (the device's processor) is operational.
    pub const fn pdi_operational(self) -> bool {
        self.0 & 0x0001 != 0
    }

    /// Bits 4-7: physical link on port `n` (0..=3).
    pub const fn link(self, n: u8) -> bool {
        self.0 & (0x0010 << n) != 0
    }

    /// Bit 8 + 2n: port `n`'s loop is closed (frames do not leave through it).
    pub const fn loop_closed(self, n: u8) -> bool {
        self.0 & (0x0100 << (2 * n)) != 0
    }

    /// Bit 9 + 2n: communication established on port `n`.
    pub const fn communication(self, n: u8) -> bool {
        self.0 & (0x0200 << (2 * n)) != 0
    }

    /// Whether port `n` forwards to a neighbour: loop open with communication.
    pub const fn port_open(self, n: u8) -> bool {
        !self.loop_closed(n) && self.communication(n)
    }

    /// The status of a device whose `open` ports (bit n = port n) have a neighbour.
    pub const fn with_open_ports(open: u8) -> Self {
        let mut v = 0x0001u16 | 0x0002 | 0x0004; // PDI operational, watchdog, enhanced link
        let mut n = 0;
        while n < 4 {
            if open & (1 << n) != 0 {
                v |= (0x0010 << n) | (0x0200 << (2 * n));
            } else {
                v |= 0x0100 << (2 * n);
            }
            n += 1;
        }
        Self(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lan9252_dl_status_decodes() {
        // soem-single-lan9252.pcapng frame 94: 0x0110 = 0x5617, a single device whose port 0
        // leads to the master and whose other ports are closed.
        let s = DlStatus(0x5617);
        assert!(s.pdi_operational() && s.link(0) && s.port_open(0));
        assert!(!s.port_open(1) && s.loop_closed(1) && s.loop_closed(3));
        assert_eq!(DlStatus::with_open_ports(0b0001), s);
        let mid = DlStatus::with_open_ports(0b0011);
        assert!(mid.port_open(0) && mid.port_open(1) && !mid.port_open(2));
    }
}
