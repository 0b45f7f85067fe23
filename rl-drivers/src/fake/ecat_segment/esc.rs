//! One EtherCAT slave controller (ESC) as the master sees it through datagrams: the register
//! space and process RAM, the addressing and working-counter rules, the SII EEPROM interface,
//! the AL control handshake, sync managers (mailbox and 3-buffer) and FMMUs, and the
//! distributed clock. The device's own processor (the PDI side) uses the `pdi_*` methods; the
//! firmware in `slave.rs` does that.
//!
//! Rules, after Beckhoff's ESC datasheet (section I "Technology" and section II "Registers")
//! and checked against the LAN9252 capture (`tests/ecat_lan9252.rs`):
//! - A device is addressed by position when ADP reaches 0 (every device increments ADP of
//!   position and broadcast datagrams), by station when ADP equals 0x0010 (or the alias 0x0012
//!   when DL control bit 24 enables it), logically through its FMMUs.
//! - Working counter: +1 for a performed read, +1 for a write, read-write commands +1 / +2; a
//!   refused access (a mailbox that is full or empty, a sync manager the PDI deactivated, the
//!   wrong direction, a blocked AL control, memory that does not exist) adds nothing.
//! - A mailbox sync manager fills when the master writes its last byte and empties when the
//!   master reads its last byte; a 3-buffer sync manager hands the PDI a complete write only.
//! - With device emulation off (0x0141 bit 0 clear), AL control behaves like a mailbox: after a
//!   write the master cannot write it again until the PDI has read it.
//! - A write to 0x0900 latches each port's receive time; a write to 0x0910 (FRMW distributing
//!   the reference clock) compares the time with the device's own and corrects its clock.

use crate::proto::ecat::command::{Access, Addressing, Command};
use crate::proto::ecat::datagram::DatagramHeader;
use crate::proto::ecat::fmmu::{self, Fmmu};
use crate::proto::ecat::register as reg;
use crate::proto::ecat::sync_manager::{self, SyncManager};

/// Start of process RAM.
const RAM: usize = reg::PROCESS_RAM as usize;
/// Sync managers modelled.
pub const SM_COUNT: usize = 8;
/// FMMUs modelled.
pub const FMMU_COUNT: usize = 8;

/// The ESC's identity registers and options.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EscIdentity {
    /// 0x0000 type.
    pub esc_type: u8,
    /// 0x0001 revision.
    pub revision: u8,
    /// 0x0002 build.
    pub build: u16,
    /// 0x0004 FMMUs.
    pub fmmus: u8,
    /// 0x0005 sync managers.
    pub sync_managers: u8,
    /// 0x0006 RAM in KiB.
    pub ram_kib: u8,
    /// 0x0007 port descriptor.
    pub port_descriptor: u8,
    /// 0x0008 features.
    pub features: u16,
    /// 0x0140 PDI control (the low byte of SII word 0).
    pub pdi_control: u8,
    /// 0x0141 bit 0: device emulation (the ESC mirrors AL control into AL status itself).
    pub device_emulation: bool,
    /// 0x0141 bits 1-7: enhanced link detection, DC SYNC out and latch in units.
    pub esc_config: u8,
    /// 0x0502 when idle: bit 6 reads 8 bytes, bit 7 two address bytes.
    pub sii_control: u16,
    /// 0x0200 ECAT event mask after power-on.
    pub event_mask: u16,
}

impl EscIdentity {
    /// A Beckhoff ET1100 as EtherCAT terminals and many drives carry it: 8 FMMUs, 8 sync
    /// managers, 8 KiB RAM, 64-bit distributed clocks, 8-byte SII reads.
    pub const ET1100: Self = Self {
        esc_type: 0x11,
        revision: 0x00,
        build: 0x0003,
        fmmus: 8,
        sync_managers: 8,
        ram_kib: 8,
        port_descriptor: 0x0F,
        features: 0x01FC,
        pdi_control: 0x05,
        device_emulation: false,
        esc_config: 0x0C,
        sii_control: reg::SII_READ_8,
        event_mask: 0x0000,
    };

    /// Microchip's LAN9252 as `soem-single-lan9252.pcapng` reads it: type 0xC0 revision 2,
    /// 3 FMMUs and 4 sync managers, 4 KiB RAM, port descriptor 0x1F, features 0x01CC, PDI
    /// control 0x89 and ESC configuration 0x0E (no device emulation), 4-byte SII reads with two address bytes, and the
    /// DL-status event enabled in the IRQ field after power-on (frame 2).
    pub const LAN9252: Self = Self {
        esc_type: 0xC0,
        revision: 0x02,
        build: 0x0000,
        fmmus: 3,
        sync_managers: 4,
        ram_kib: 4,
        port_descriptor: 0x1F,
        features: 0x01CC,
        pdi_control: 0x89,
        device_emulation: false,
        esc_config: 0x0E,
        sii_control: reg::SII_TWO_ADDRESS_BYTES,
        event_mask: 0x0004,
    };
}

/// When a frame passes this device, in the fake's time base (ns).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassTimes {
    /// Arrival at port 0 (and at the processing unit).
    pub port0: u64,
    /// Return through port 1, if that port leads on.
    pub port1: Option<u64>,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct SmRuntime {
    /// Mailbox: full. 3-buffer (ECAT writes): a complete write the PDI has not taken yet.
    full: bool,
    /// 3-buffer read direction: the master read the last byte since the PDI last wrote.
    read_done: bool,
}

/// What the PDI (the device's processor) sees of one distributed-clock SYNC0 configuration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sync0 {
    /// System time of the first pulse.
    pub start: u64,
    /// Cycle time in ns.
    pub cycle: u32,
}

/// One ESC.
#[derive(Clone, Debug)]
pub struct Esc {
    mem: Vec<u8>,
    id: EscIdentity,
    sii: Vec<u8>,
    sm: [SmRuntime; SM_COUNT],
    /// PDI copy of each 3-buffer output sync manager's last complete write.
    outputs: [Vec<u8>; SM_COUNT],
    al_control_pending: bool,
    /// When the master last wrote AL control (fake time).
    al_control_written: u64,
    /// When each mailbox sync manager was last filled by the master (fake time).
    mailbox_written: [u64; SM_COUNT],
    ecat_event: u16,
    /// Local clock = fake time + `clock_offset` + drift, plus the time control loop's
    /// correction.
    clock_offset: i64,
    drift_ppb: i64,
    correction: i64,
    /// The last time difference the control loop saw (0x092C).
    last_difference: i64,
    sync0: Option<Sync0>,
    /// Counts of refused accesses (for the segment's status).
    refused: u64,
}

fn u16_at(m: &[u8], a: usize) -> u16 {
    u16::from_le_bytes([m[a], m[a + 1]])
}

fn u32_at(m: &[u8], a: usize) -> u32 {
    u32::from_le_bytes([m[a], m[a + 1], m[a + 2], m[a + 3]])
}

fn u64_at(m: &[u8], a: usize) -> u64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&m[a..a + 8]);
    u64::from_le_bytes(b)
}

/// Whether the ECAT side may write register byte `a` (below 0x1000).
/// The part of an access to `len` bytes at `a` that lies in process RAM (start, length).
fn in_ram(a: usize, len: usize) -> Option<(usize, usize)> {
    let start = a.max(RAM);
    (a + len > RAM).then(|| (start, a + len - start))
}

fn ecat_writable(a: usize) -> bool {
    matches!(a,
        0x0010..=0x0011
        | 0x0100..=0x0103
        | 0x0108..=0x0109
        | 0x0120..=0x0121
        | 0x0200..=0x0201
        | 0x0300..=0x0313
        | 0x0400..=0x0401
        | 0x0410..=0x0411
        | 0x0420..=0x0421
        | 0x0442..=0x0443
        | 0x0500
        | 0x0502..=0x050F
        | 0x0600..=0x06FF
        | 0x0900..=0x0903
        | 0x0910..=0x0917
        | 0x0920..=0x0935
        | 0x0980..=0x0983
        | 0x0990..=0x0997
        | 0x09A0..=0x09A7
        | 0x09A8..=0x09A9)
        || (0x0800..0x0800 + 8 * SM_COUNT).contains(&a) && !matches!((a - 0x0800) % 8, 5 | 7)
}

impl Esc {
    /// A powered-up ESC with `sii` in its EEPROM, `open_ports` (bit n: port n leads to a
    /// neighbour) and a local clock `clock_offset` ns ahead of the fake's time base, running
    /// `drift_ppb` parts per billion fast.
    pub fn new(
        id: EscIdentity,
        sii: Vec<u8>,
        open_ports: u8,
        clock_offset: i64,
        drift_ppb: i64,
    ) -> Self {
        let size = RAM + usize::from(id.ram_kib) * 1024;
        let mut e = Self {
            mem: vec![0; size],
            id,
            sii,
            sm: [SmRuntime::default(); SM_COUNT],
            outputs: Default::default(),
            al_control_pending: false,
            al_control_written: 0,
            mailbox_written: [0; SM_COUNT],
            ecat_event: 0x0004, // DL status changed: the links came up
            clock_offset,
            drift_ppb,
            correction: 0,
            last_difference: 0,
            sync0: None,
            refused: 0,
        };
        let m = &mut e.mem;
        m[0x0000] = id.esc_type;
        m[0x0001] = id.revision;
        m[0x0002..0x0004].copy_from_slice(&id.build.to_le_bytes());
        m[0x0004] = id.fmmus;
        m[0x0005] = id.sync_managers;
        m[0x0006] = id.ram_kib;
        m[0x0007] = id.port_descriptor;
        m[0x0008..0x000A].copy_from_slice(&id.features.to_le_bytes());
        m[0x0110..0x0112]
            .copy_from_slice(&reg::DlStatus::with_open_ports(open_ports).0.to_le_bytes());
        m[0x0130] = 0x01; // INIT
        m[0x0120] = 0x01;
        m[0x0140] = id.pdi_control;
        m[0x0141] = u8::from(id.device_emulation) | (id.esc_config & 0xFE);
        m[0x0200..0x0202].copy_from_slice(&id.event_mask.to_le_bytes());
        m[0x0400..0x0402].copy_from_slice(&2498u16.to_le_bytes()); // 100 µs watchdog ticks
        m[0x0410..0x0412].copy_from_slice(&1000u16.to_le_bytes());
        m[0x0420..0x0422].copy_from_slice(&1000u16.to_le_bytes()); // 100 ms
        m[0x0502..0x0504].copy_from_slice(&id.sii_control.to_le_bytes());
        m[0x0934] = 0x04; // filter depths
        m[0x0935] = 0x0C;
        m[0x0930..0x0932].copy_from_slice(&0x1000u16.to_le_bytes());
        // Station alias and PDI configuration from the EEPROM, as the ESC loads them.
        if e.sii.len() >= 10 {
            let alias = u16_at(&e.sii, 8);
            e.mem[0x0012..0x0014].copy_from_slice(&alias.to_le_bytes());
        }
        e
    }

    /// The identity.
    pub fn identity(&self) -> &EscIdentity {
        &self.id
    }

    /// The EEPROM image.
    pub fn sii(&self) -> &[u8] {
        &self.sii
    }

    /// Accesses refused so far (mailbox busy, direction, deactivated sync manager…).
    pub fn refused(&self) -> u64 {
        self.refused
    }

    /// The configured station address.
    pub fn station_address(&self) -> u16 {
        u16_at(&self.mem, 0x0010)
    }

    /// Register or RAM bytes (for the PDI and for tests).
    pub fn memory(&self, address: u16, len: usize) -> &[u8] {
        let a = usize::from(address);
        &self.mem[a.min(self.mem.len())..(a + len).min(self.mem.len())]
    }

    /// Sync manager `n` as configured.
    pub fn sm(&self, n: usize) -> SyncManager {
        let a = 0x0800 + 8 * n;
        let mut b = [0u8; 8];
        b.copy_from_slice(&self.mem[a..a + 8]);
        SyncManager::decode(&b)
    }

    /// FMMU `n` as configured.
    pub fn fmmu(&self, n: usize) -> Fmmu {
        let a = 0x0600 + 16 * n;
        let mut b = [0u8; 16];
        b.copy_from_slice(&self.mem[a..a + 16]);
        Fmmu::decode(&b)
    }

    // ---- distributed clock -------------------------------------------------------------

    /// The local clock at fake time `t`.
    pub fn local_time(&self, t: u64) -> u64 {
        let drift = (i128::from(t) * i128::from(self.drift_ppb) / 1_000_000_000) as i64;
        t.wrapping_add_signed(self.clock_offset + drift + self.correction)
    }

    /// The system time at fake time `t` (local time + 0x0920).
    pub fn system_time(&self, t: u64) -> u64 {
        self.local_time(t)
            .wrapping_add(u64_at(&self.mem, reg::DC_SYSTEM_TIME_OFFSET as usize))
    }

    /// The propagation delay the master wrote (0x0928).
    pub fn system_time_delay(&self) -> u32 {
        u32_at(&self.mem, reg::DC_SYSTEM_TIME_DELAY as usize)
    }

    /// The last difference between the distributed time and this clock (ns, signed).
    pub fn time_difference(&self) -> i64 {
        self.last_difference
    }

    /// The SYNC0 configuration while SYNC0 generation is active.
    pub fn sync0(&self) -> Option<Sync0> {
        self.sync0
    }

    /// SYNC0 pulses generated up to fake time `t` (0 when inactive or not started).
    pub fn sync0_pulses(&self, t: u64) -> u64 {
        match self.sync0 {
            Some(s) if s.cycle > 0 => {
                let now = self.system_time(t);
                if now < s.start {
                    0
                } else {
                    (now - s.start) / u64::from(s.cycle) + 1
                }
            }
            _ => 0,
        }
    }

    fn latch_receive_times(&mut self, times: &PassTimes) {
        let p0 = self.local_time(times.port0);
        self.mem[0x0900..0x0904].copy_from_slice(&(p0 as u32).to_le_bytes());
        let p1 = times.port1.map_or(0, |t| self.local_time(t) as u32);
        self.mem[0x0904..0x0908].copy_from_slice(&p1.to_le_bytes());
        self.mem[0x0908..0x0910].fill(0);
        self.mem[0x0918..0x0920].copy_from_slice(&p0.to_le_bytes());
    }

    fn compare_system_time(&mut self, received: u64, t: u64) {
        let expected = received.wrapping_add(u64::from(self.system_time_delay()));
        let diff = expected.wrapping_sub(self.system_time(t)) as i64;
        self.last_difference = diff;
        // The ESC's control loop slews the clock, it never jumps: a proportional step of 1/4
        // of the difference per frame, at most 1 µs, converges within a few frames once the
        // master has set the offset (0x0920) and keeps a drifting clock within a few ns.
        self.correction += (diff / 4).clamp(-1_000, 1_000);
        let mag = (diff.unsigned_abs().min(0x7FFF_FFFF)) as u32;
        let v = if diff < 0 { mag | 0x8000_0000 } else { mag };
        self.mem[0x092C..0x0930].copy_from_slice(&v.to_le_bytes());
    }

    fn activation_written(&mut self, t: u64) {
        let act = self.mem[reg::DC_ACTIVATION as usize];
        let cycle = u32_at(&self.mem, reg::DC_SYNC0_CYCLE as usize);
        let start = u64_at(&self.mem, reg::DC_SYNC0_START as usize);
        let want = reg::DC_ACTIVATE_CYCLIC | reg::DC_ACTIVATE_SYNC0;
        self.sync0 = None;
        self.mem[0x0984] = 0;
        if act & want == want {
            if start < self.system_time(t) {
                // A start time in the past: the ESC waits for the counter to wrap (never).
                self.mem[0x0984] = 0x04; // start time out of near future
            } else {
                self.sync0 = Some(Sync0 { start, cycle });
                self.mem[0x0984] = 0x01;
            }
        }
    }

    // ---- physical access (ECAT side) ----------------------------------------------------

    fn sm_covering(&self, a: usize) -> Option<usize> {
        (0..usize::from(self.id.sync_managers).min(SM_COUNT)).find(|&n| {
            let s = self.sm(n);
            s.activate & sync_manager::ACTIVATE_ENABLE != 0
                && s.length > 0
                && (usize::from(s.start)..s.end() as usize).contains(&a)
        })
    }

    /// Checks an ECAT access to `a..a + len` against the sync managers: `Err(())` if refused.
    fn check_sm(&self, a: usize, len: usize, write: bool) -> Result<(), ()> {
        let mut n_seen = [false; SM_COUNT];
        for x in a..a + len {
            let Some(n) = self.sm_covering(x) else {
                continue;
            };
            if n_seen[n] {
                continue;
            }
            n_seen[n] = true;
            let s = self.sm(n);
            if s.pdi_control & sync_manager::PDI_DEACTIVATE != 0 || s.is_write() != write {
                return Err(());
            }
            if s.is_mailbox() && (self.sm[n].full == write) {
                // Writing a full mailbox, or reading an empty one.
                return Err(());
            }
        }
        Ok(())
    }

    /// Sync manager bookkeeping after an ECAT access to `a..a + len`.
    fn after_sm_access(&mut self, a: usize, len: usize, write: bool) {
        for n in 0..usize::from(self.id.sync_managers).min(SM_COUNT) {
            let s = self.sm(n);
            if s.activate & sync_manager::ACTIVATE_ENABLE == 0 || s.length == 0 {
                continue;
            }
            let last = s.end() as usize - 1;
            if !(a..a + len).contains(&last) {
                continue;
            }
            let status = 0x0805 + 8 * n;
            if write {
                self.sm[n].full = true;
                if !s.is_mailbox() {
                    let w = &self.mem[usize::from(s.start)..s.end() as usize];
                    self.outputs[n].clear();
                    self.outputs[n].extend_from_slice(w);
                }
                self.mem[status] =
                    (self.mem[status] & !0x02) | 0x01 | if s.is_mailbox() { 0x08 } else { 0 };
            } else {
                if s.is_mailbox() {
                    self.sm[n].full = false;
                    self.mem[status] &= !0x08;
                } else {
                    self.sm[n].read_done = true;
                }
                self.mem[status] = (self.mem[status] & !0x01) | 0x02;
            }
            self.ecat_event |= 1 << (4 + n);
        }
    }

    /// Whether the master may access `len` bytes at `a` (`write`): within the ESC's memory and,
    /// in process RAM, as the sync managers there allow. A refusal is counted.
    fn admit(&mut self, a: usize, len: usize, write: bool) -> bool {
        let ok = a + len <= self.mem.len()
            && in_ram(a, len).is_none_or(|(start, n)| self.check_sm(start, n, write).is_ok());
        if !ok {
            self.refused += 1;
        }
        ok
    }

    /// Reads `out.len()` bytes at `address` for the master (`or` for broadcast reads).
    fn phys_read(&mut self, address: u16, out: &mut [u8], or: bool, times: &PassTimes) -> bool {
        let (a, len) = (usize::from(address), out.len());
        if len == 0 {
            return true;
        }
        if !self.admit(a, len, false) {
            return false;
        }
        // Live registers.
        let sys = self.system_time(times.port0).to_le_bytes();
        for (k, o) in out.iter_mut().enumerate() {
            let x = a + k;
            let v = match x {
                0x0910..=0x0917 => sys[x - 0x0910],
                _ => self.mem[x],
            };
            *o = if or { *o | v } else { v };
        }
        // Reading clears events.
        if (a..a + len).contains(&0x0110) {
            self.ecat_event &= !0x0004;
        }
        if (a..a + len).contains(&0x0130) {
            self.ecat_event &= !0x0008;
        }
        for n in 0..SM_COUNT {
            if (a..a + len).contains(&(0x0805 + 8 * n)) {
                self.ecat_event &= !(1 << (4 + n));
            }
        }
        if let Some((start, n)) = in_ram(a, len) {
            self.after_sm_access(start, n, false);
        }
        true
    }

    /// Writes `data` at `address` for the master.
    fn phys_write(&mut self, address: u16, data: &[u8], times: &PassTimes) -> bool {
        let (a, len) = (usize::from(address), data.len());
        if len == 0 {
            return true;
        }
        if !self.admit(a, len, true) {
            return false;
        }
        let touches = |r: u16| (a..a + len).contains(&usize::from(r));
        if touches(reg::AL_CONTROL) || touches(reg::AL_CONTROL + 1) {
            if self.id.device_emulation {
                // The ESC itself answers (no firmware): AL status follows AL control.
            } else if self.al_control_pending {
                self.refused += 1;
                return false;
            }
        }
        let mut sii_command = false;
        let mut sync_written = false;
        for (k, &v) in data.iter().enumerate() {
            let x = a + k;
            if x >= RAM || ecat_writable(x) {
                match x {
                    0x0300..=0x0313 | 0x0442..=0x0443 => self.mem[x] = 0, // a write clears
                    0x0900..=0x0903 | 0x0910..=0x0917 => {}               // triggers, below
                    0x0502 => {
                        // Bits 0 (write enable) written; the others are status.
                        self.mem[x] = (self.mem[x] & !0x01) | (v & 0x01);
                    }
                    0x0503 => {
                        self.mem[x] = (self.mem[x] & !0x07) | (v & 0x07);
                        sii_command = true;
                    }
                    0x0981 => {
                        self.mem[x] = v;
                        sync_written = true;
                    }
                    _ => self.mem[x] = v,
                }
            }
        }
        if touches(reg::AL_CONTROL) {
            if self.id.device_emulation {
                let c = self.mem[0x0120] & 0x0F;
                self.mem[0x0130] = c;
            } else {
                self.al_control_pending = true;
                self.al_control_written = times.port0;
            }
        }
        if touches(reg::DC_RECEIVE_TIME_PORT0) {
            self.latch_receive_times(times);
        }
        if touches(reg::DC_SYSTEM_TIME) && len >= 4 && a <= 0x0910 && a + len >= 0x0914 {
            let mut b = [0u8; 8];
            let off = 0x0910 - a;
            let n = (len - off).min(8);
            b[..n].copy_from_slice(&data[off..off + n]);
            let mut received = u64::from_le_bytes(b);
            if n == 4 {
                // A 32-bit write compares the low halves.
                let own = self.system_time(times.port0);
                received |= own & 0xFFFF_FFFF_0000_0000;
            }
            self.compare_system_time(received, times.port0);
        }
        if sync_written {
            self.activation_written(times.port0);
        }
        if a < 0x0800 + 8 * SM_COUNT && a + len > 0x0800 {
            // A channel the master disabled forgets its buffer state.
            for n in 0..SM_COUNT {
                if self.mem[0x0806 + 8 * n] & sync_manager::ACTIVATE_ENABLE == 0 {
                    self.sm[n] = SmRuntime::default();
                    self.mem[0x0805 + 8 * n] = 0;
                }
            }
        }
        if sii_command {
            self.sii_command();
        }
        if let Some((start, n)) = in_ram(a, len) {
            self.after_sm_access(start, n, true);
            for n in 0..SM_COUNT {
                let s = self.sm(n);
                if s.is_mailbox() && s.is_write() && (a..a + len).contains(&(s.end() as usize - 1))
                {
                    self.mailbox_written[n] = times.port0;
                }
            }
        }
        true
    }

    fn sii_command(&mut self) {
        let ctl = u16_at(&self.mem, 0x0502);
        let owned_by_pdi = self.mem[0x0500] & 0x01 != 0 && self.mem[0x0500] & 0x02 == 0;
        let cmd = ctl & reg::SII_CMD_MASK;
        let mut status = self.id.sii_control;
        if owned_by_pdi && cmd != 0 {
            status |= reg::SII_ERROR_COMMAND;
        } else {
            let word = u32_at(&self.mem, 0x0504) as usize;
            match cmd {
                reg::SII_CMD_READ => {
                    let n = if self.id.sii_control & reg::SII_READ_8 != 0 {
                        8
                    } else {
                        4
                    };
                    for k in 0..n {
                        // An erased or absent EEPROM cell reads 0xFF.
                        self.mem[0x0508 + k] = self.sii.get(word * 2 + k).copied().unwrap_or(0xFF);
                    }
                }
                reg::SII_CMD_WRITE => {
                    if ctl & reg::SII_WRITE_ENABLE == 0 {
                        status |= reg::SII_ERROR_WRITE_ENABLE;
                    } else if word * 2 + 2 <= self.sii.len() {
                        let (lo, hi) = (self.mem[0x0508], self.mem[0x0509]);
                        self.sii[word * 2] = lo;
                        self.sii[word * 2 + 1] = hi;
                    } else {
                        status |= reg::SII_ERROR_COMMAND;
                    }
                }
                reg::SII_CMD_RELOAD | 0 => {}
                _ => status |= reg::SII_ERROR_COMMAND,
            }
        }
        // The fake EEPROM answers at once: never busy when the master polls.
        self.mem[0x0502..0x0504].copy_from_slice(&status.to_le_bytes());
    }

    // ---- datagrams ---------------------------------------------------------------------------

    /// Processes one datagram as it passes through this device: addressing, the access, the
    /// working counter, the ADP increment and the IRQ field.
    pub fn process(
        &mut self,
        header: &mut DatagramHeader,
        data: &mut [u8],
        wkc: &mut u16,
        times: &PassTimes,
    ) {
        let Some(command) = header.command() else {
            return; // Unknown commands pass untouched.
        };
        // The IRQ field precedes the data: it shows the events before this datagram's access
        // (a read of DL status clears its event for the next datagram, not this one).
        header.irq |= self.ecat_event & u16_at(&self.mem, 0x0200);
        let increment = match command.addressing() {
            Addressing::None => 0,
            Addressing::Position => {
                let hit = header.adp() == 0;
                header.address =
                    (header.address & 0xFFFF_0000) | u32::from(header.adp().wrapping_add(1));
                self.physical(command, header.ado(), data, hit, false, times)
            }
            Addressing::Broadcast => {
                header.address =
                    (header.address & 0xFFFF_0000) | u32::from(header.adp().wrapping_add(1));
                self.physical(command, header.ado(), data, true, true, times)
            }
            Addressing::Station => {
                let alias_active = self.mem[0x0103] & 0x01 != 0;
                let hit = header.adp() == self.station_address()
                    || (alias_active && header.adp() == u16_at(&self.mem, 0x0012));
                self.physical(command, header.ado(), data, hit, false, times)
            }
            Addressing::Logical => self.logical(command, header.address, data, times),
        };
        *wkc = wkc.wrapping_add(increment);
    }

    fn physical(
        &mut self,
        command: Command,
        ado: u16,
        data: &mut [u8],
        addressed: bool,
        broadcast: bool,
        times: &PassTimes,
    ) -> u16 {
        match command.access() {
            Access::None => 0,
            Access::Read if addressed => u16::from(self.phys_read(ado, data, broadcast, times)),
            Access::Write if addressed => u16::from(self.phys_write(ado, data, times)),
            Access::ReadWrite if addressed => {
                let incoming = data.to_vec();
                let r = self.phys_read(ado, data, broadcast, times);
                let w = self.phys_write(ado, &incoming, times);
                command.wkc_increment(r, w)
            }
            Access::ReadMultipleWrite => {
                if addressed {
                    u16::from(self.phys_read(ado, data, false, times))
                } else {
                    let incoming = data.to_vec();
                    u16::from(self.phys_write(ado, &incoming, times))
                }
            }
            _ => 0,
        }
    }

    fn logical(
        &mut self,
        command: Command,
        address: u32,
        data: &mut [u8],
        times: &PassTimes,
    ) -> u16 {
        let access = command.access();
        let (mut read, mut write) = (false, false);
        let incoming = data.to_vec();
        for n in 0..usize::from(self.id.fmmus).min(FMMU_COUNT) {
            let f = self.fmmu(n);
            let Some((offset, physical, len)) = f.overlap(address, data.len()) else {
                continue;
            };
            if f.kind & fmmu::TYPE_WRITE != 0 && matches!(access, Access::Write | Access::ReadWrite)
            {
                write |= self.phys_write(physical, &incoming[offset..offset + len], times);
            }
            if f.kind & fmmu::TYPE_READ != 0 && matches!(access, Access::Read | Access::ReadWrite) {
                read |= self.phys_read(physical, &mut data[offset..offset + len], false, times);
            }
        }
        command.wkc_increment(read, write)
    }

    // ---- the PDI side ------------------------------------------------------------------------

    /// When a pending AL control write arrived (`None`: nothing pending).
    pub fn al_control_pending_since(&self) -> Option<u64> {
        (self.al_control_pending && !self.id.device_emulation).then_some(self.al_control_written)
    }

    /// When mailbox sync manager `n` was filled, if the master's message is waiting.
    pub fn mailbox_pending_since(&self, n: usize) -> Option<u64> {
        let s = self.sm(n);
        (s.is_mailbox() && s.is_write() && self.sm[n].full).then_some(self.mailbox_written[n])
    }

    /// Takes a pending AL control write (the handshake: the master may write again).
    pub fn pdi_take_al_control(&mut self) -> Option<u16> {
        if self.id.device_emulation || !self.al_control_pending {
            return None;
        }
        self.al_control_pending = false;
        Some(u16_at(&self.mem, 0x0120))
    }

    /// Sets AL status and status code.
    pub fn pdi_set_al_status(&mut self, status: u16, code: u16) {
        if u16_at(&self.mem, 0x0130) != status {
            self.ecat_event |= 0x0008;
        }
        self.mem[0x0130..0x0132].copy_from_slice(&status.to_le_bytes());
        self.mem[0x0134..0x0136].copy_from_slice(&code.to_le_bytes());
    }

    /// AL status.
    pub fn al_status(&self) -> u16 {
        u16_at(&self.mem, 0x0130)
    }

    /// AL status code.
    pub fn al_status_code(&self) -> u16 {
        u16_at(&self.mem, 0x0134)
    }

    /// Deactivates (or reactivates) sync manager `n` from the PDI side.
    pub fn pdi_deactivate_sm(&mut self, n: usize, deactivate: bool) {
        let a = 0x0807 + 8 * n;
        if deactivate {
            self.mem[a] |= sync_manager::PDI_DEACTIVATE;
            self.sm[n] = SmRuntime::default();
            self.mem[0x0805 + 8 * n] &= !0x08;
        } else {
            self.mem[a] &= !sync_manager::PDI_DEACTIVATE;
        }
    }

    /// Takes a message the master wrote into mailbox sync manager `n` (empties it).
    pub fn pdi_mailbox_take(&mut self, n: usize) -> Option<Vec<u8>> {
        let s = self.sm(n);
        if !s.is_mailbox() || !s.is_write() || !self.sm[n].full {
            return None;
        }
        self.sm[n].full = false;
        let status = 0x0805 + 8 * n;
        // Read completely by the PDI: "interrupt read" replaces "interrupt write" and "full".
        self.mem[status] = (self.mem[status] & !0x09) | 0x02;
        self.ecat_event |= 1 << (4 + n);
        Some(self.mem[usize::from(s.start)..s.end() as usize].to_vec())
    }

    /// Puts a message into mailbox sync manager `n` for the master (`false` if it is still
    /// full or the message does not fit).
    pub fn pdi_mailbox_put(&mut self, n: usize, message: &[u8]) -> bool {
        let s = self.sm(n);
        if !s.is_mailbox()
            || s.is_write()
            || self.sm[n].full
            || message.len() > usize::from(s.length)
        {
            return false;
        }
        let start = usize::from(s.start);
        self.mem[start..s.end() as usize].fill(0);
        self.mem[start..start + message.len()].copy_from_slice(message);
        self.sm[n].full = true;
        let status = 0x0805 + 8 * n;
        self.mem[status] = (self.mem[status] & !0x02) | 0x08 | 0x01;
        self.ecat_event |= 1 << (4 + n);
        true
    }

    /// Whether mailbox sync manager `n` (device → master) is still full.
    pub fn mailbox_full(&self, n: usize) -> bool {
        self.sm[n].full
    }

    /// Takes the latest complete write of 3-buffer sync manager `n` (`None` if nothing new).
    pub fn pdi_take_outputs(&mut self, n: usize) -> Option<&[u8]> {
        if !self.sm[n].full {
            return None;
        }
        self.sm[n].full = false;
        Some(&self.outputs[n])
    }

    /// Writes inputs into 3-buffer sync manager `n` (device → master).
    pub fn pdi_write_inputs(&mut self, n: usize, inputs: &[u8]) {
        let s = self.sm(n);
        let start = usize::from(s.start);
        let len = inputs.len().min(usize::from(s.length));
        if start + len <= self.mem.len() {
            self.mem[start..start + len].copy_from_slice(&inputs[..len]);
            self.sm[n].read_done = false;
        }
    }

    /// Takes a write of the SII EEPROM control by the PDI (EEPROM emulation is not modelled).
    pub fn pdi_owns_sii(&self) -> bool {
        self.mem[0x0500] & 0x01 != 0
    }

    /// The process data watchdog time in ns (0x0400 divider, 0x0420 count).
    pub fn watchdog_ns(&self) -> u64 {
        let divider = u64::from(u16_at(&self.mem, 0x0400)) + 2;
        u64::from(u16_at(&self.mem, 0x0420)) * divider * 40
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::proto::ecat::datagram::physical;

    fn esc() -> Esc {
        let mut sii = vec![0u8; 256];
        sii[0x10..0x14].copy_from_slice(&0x1234_5678u32.to_le_bytes()); // vendor word 8
        Esc::new(EscIdentity::ET1100, sii, 0b0001, 1_000, 0)
    }

    fn run(e: &mut Esc, cmd: Command, address: u32, data: &mut [u8]) -> (u16, DatagramHeader) {
        let mut h = DatagramHeader::new(cmd, address, data.len() as u16);
        let mut wkc = 0;
        e.process(&mut h, data, &mut wkc, &PassTimes::default());
        (wkc, h)
    }

    #[test]
    fn addressing_and_working_counters() {
        let mut e = esc();
        let mut d = [0u8; 2];
        // BRD of the type register: wkc 1, ADP incremented.
        let (wkc, h) = run(&mut e, Command::Brd, physical(0, 0), &mut d);
        assert_eq!((wkc, h.adp(), d[0]), (1, 1, 0x11));
        // APWR station address at position 0, then FPRD by it.
        let (wkc, _) = run(
            &mut e,
            Command::Apwr,
            physical(0, 0x0010),
            &mut [0x01, 0x10],
        );
        assert_eq!(wkc, 1);
        let (wkc, _) = run(&mut e, Command::Fprd, physical(0x1001, 0x0010), &mut d);
        assert_eq!((wkc, d), (1, [0x01, 0x10]));
        // Another position or station: not addressed.
        assert_eq!(run(&mut e, Command::Aprd, physical(0xFFFF, 0), &mut d).0, 0);
        assert_eq!(run(&mut e, Command::Fprd, physical(0x1002, 0), &mut d).0, 0);
        // Read-only registers ignore writes but count them.
        assert_eq!(
            run(&mut e, Command::Fpwr, physical(0x1001, 0x0000), &mut [0]).0,
            1
        );
        assert_eq!(e.memory(0, 1), [0x11]);
        // FPRW: 3.
        assert_eq!(
            run(&mut e, Command::Fprw, physical(0x1001, 0x0200), &mut [4, 0]).0,
            3
        );
        // Beyond the memory: refused.
        assert_eq!(
            run(&mut e, Command::Fprd, physical(0x1001, 0xF000), &mut d).0,
            0
        );
    }

    #[test]
    fn the_al_control_handshake_without_device_emulation() {
        let mut e = esc();
        assert_eq!(
            run(&mut e, Command::Bwr, physical(0, 0x0120), &mut [0x11]).0,
            1
        );
        // Not yet read by the PDI: refused (soem-single-lan9252.pcapng frame 6).
        assert_eq!(
            run(&mut e, Command::Bwr, physical(0, 0x0120), &mut [0x11]).0,
            0
        );
        assert_eq!(e.pdi_take_al_control(), Some(0x11));
        assert_eq!(
            run(&mut e, Command::Bwr, physical(0, 0x0120), &mut [0x12]).0,
            1
        );
    }

    #[test]
    fn mailboxes_fill_on_the_last_byte_and_refuse_when_busy() {
        let mut e = esc();
        let sm0 = SyncManager::new(sync_manager::Kind::MailboxOut, 0x1000, 16);
        let sm1 = SyncManager::new(sync_manager::Kind::MailboxIn, 0x1010, 16);
        let mut b = [0u8; 16];
        b[..8].copy_from_slice(&sm0.encode());
        b[8..].copy_from_slice(&sm1.encode());
        run(&mut e, Command::Bwr, physical(0, 0x0800), &mut b);
        // Reading an empty mailbox in: refused.
        assert_eq!(
            run(&mut e, Command::Brd, physical(0, 0x1010), &mut [0; 16]).0,
            0
        );
        // A write of the whole mailbox out fills it; a second is refused.
        assert_eq!(
            run(&mut e, Command::Bwr, physical(0, 0x1000), &mut [7; 16]).0,
            1
        );
        assert_eq!(e.memory(0x0805, 1)[0] & 0x08, 0x08);
        assert_eq!(
            run(&mut e, Command::Bwr, physical(0, 0x1000), &mut [8; 16]).0,
            0
        );
        assert_eq!(e.pdi_mailbox_take(0), Some(vec![7; 16]));
        assert!(e.pdi_mailbox_put(1, b"answer"));
        let mut r = [0u8; 16];
        assert_eq!(run(&mut e, Command::Brd, physical(0, 0x1010), &mut r).0, 1);
        assert_eq!(&r[..6], b"answer");
        assert!(!e.mailbox_full(1));
        // Writing into the read mailbox: wrong direction.
        assert_eq!(
            run(&mut e, Command::Bwr, physical(0, 0x1010), &mut [0; 4]).0,
            0
        );
    }

    #[test]
    fn sii_reads_through_the_eeprom_interface() {
        let mut e = esc();
        let mut cmd = [0x00, 0x01, 0x08, 0x00, 0x00, 0x00];
        assert_eq!(
            run(&mut e, Command::Bwr, physical(0, 0x0502), &mut cmd).0,
            1
        );
        let mut d = [0u8; 8];
        run(&mut e, Command::Brd, physical(0, 0x0508), &mut d);
        assert_eq!(&d[..4], &0x1234_5678u32.to_le_bytes());
        assert_eq!(
            u16::from_le_bytes(e.memory(0x0502, 2).try_into().unwrap()) & 0x8700,
            0
        );
    }

    #[test]
    fn logical_access_through_fmmus_counts_read_and_write() {
        let mut e = esc();
        let out = SyncManager::new(sync_manager::Kind::Outputs, 0x1100, 2);
        let inp = SyncManager::new(sync_manager::Kind::Inputs, 0x1200, 2);
        let mut b = [0u8; 16];
        b[..8].copy_from_slice(&out.encode());
        b[8..].copy_from_slice(&inp.encode());
        run(&mut e, Command::Bwr, physical(0, 0x0810), &mut b);
        let mut f = [0u8; 32];
        f[..16].copy_from_slice(&Fmmu::bytes(0x100, 0x1100, 2, fmmu::TYPE_WRITE).encode());
        f[16..].copy_from_slice(&Fmmu::bytes(0x102, 0x1200, 2, fmmu::TYPE_READ).encode());
        run(&mut e, Command::Bwr, physical(0, 0x0600), &mut f);
        e.pdi_write_inputs(3, &[0xAB, 0xCD]);
        let mut image = [1, 2, 0, 0];
        assert_eq!(run(&mut e, Command::Lrw, 0x100, &mut image).0, 3);
        assert_eq!(image, [1, 2, 0xAB, 0xCD]);
        assert_eq!(e.pdi_take_outputs(2), Some(&[1u8, 2][..]));
        assert_eq!(e.pdi_take_outputs(2), None);
        // The PDI deactivates the outputs: only the read counts.
        e.pdi_deactivate_sm(2, true);
        assert_eq!(run(&mut e, Command::Lrw, 0x100, &mut image).0, 1);
        assert_eq!(run(&mut e, Command::Lrd, 0x200, &mut image).0, 0);
    }

    #[test]
    fn distributed_clock_latch_offset_and_sync0() {
        let mut e = esc();
        let times = PassTimes {
            port0: 5_000,
            port1: None,
        };
        let mut h = DatagramHeader::new(Command::Bwr, physical(0, 0x0900), 4);
        let mut wkc = 0;
        e.process(&mut h, &mut [0; 4], &mut wkc, &times);
        assert_eq!(e.memory(0x0918, 8), &6_000u64.to_le_bytes()); // offset 1000
        // Offset so that system time = fake time, then FRMW-style compare keeps it.
        run(
            &mut e,
            Command::Bwr,
            physical(0, 0x0920),
            &mut (-1000i64 as u64).to_le_bytes(),
        );
        assert_eq!(e.system_time(10_000), 10_000);
        let mut h = DatagramHeader::new(Command::Fpwr, physical(0, 0x0910), 8);
        e.process(
            &mut h,
            &mut 20_000u64.to_le_bytes(),
            &mut wkc,
            &PassTimes {
                port0: 20_000,
                port1: None,
            },
        );
        assert_eq!(e.time_difference(), 0);
        // SYNC0 every 1 ms from system time 1 ms.
        run(
            &mut e,
            Command::Bwr,
            physical(0, 0x09A0),
            &mut 1_000_000u32.to_le_bytes(),
        );
        run(
            &mut e,
            Command::Bwr,
            physical(0, 0x0990),
            &mut 1_000_000u64.to_le_bytes(),
        );
        run(&mut e, Command::Bwr, physical(0, 0x0981), &mut [0x03]);
        assert!(e.sync0().is_some());
        assert_eq!(e.sync0_pulses(999_999), 0);
        assert_eq!(e.sync0_pulses(3_500_000), 3);
    }
}
