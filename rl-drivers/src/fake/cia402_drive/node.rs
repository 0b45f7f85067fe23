//! One simulated CiA 402 node: its object dictionary (from the EDS, with the node's id put
//! into `$NODEID` defaults), SDO server, NMT state, heartbeat producer, PDOs, the power state
//! machine and the motor. It is fed frames and the time, and answers with frames to send
//! (some of them later: TPDOs leave a configurable delay after the SYNC).

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use super::motor::{Drive, Motor, MotorLimits, Targets};
use crate::cia402::{Mode, PowerState, Statusword, object as obj};
use crate::proto::can::Frame;
use crate::proto::canopen::eds::Eds;
use crate::proto::canopen::emcy::Emergency;
use crate::proto::canopen::nmt;
use crate::proto::canopen::object::{AccessType, DataType};
use crate::proto::canopen::pdo::{COB_ID_INVALID, Entry};
use crate::proto::canopen::sdo::{AbortCode, Address};
use crate::proto::canopen::sdo_server::{self, Dictionary};
use crate::proto::canopen::{Function, NodeId, heartbeat};

/// EMCY code the fake sends when SYNC stops while it is enabled (communication error).
pub const EMCY_SYNC_LOST: u16 = 0x8100;
/// EMCY code of an RPDO shorter than its mapping.
pub const EMCY_PDO_LENGTH: u16 = 0x8210;

#[derive(Clone, Debug)]
struct Value {
    bytes: Vec<u8>,
    data_type: DataType,
    access: AccessType,
    mappable: bool,
    default: Vec<u8>,
}

/// Faults injected into this node, pending.
#[derive(Clone, Copy, Debug, Default)]
pub struct Injected {
    pub heartbeat_silent_until: Option<Instant>,
    pub sdo_abort: Option<(Address, AbortCode)>,
    pub drop_tpdos: u32,
    pub late_tpdos: u32,
    pub late_by: Duration,
    pub corrupt_tpdos: u32,
    pub warning: bool,
    pub following_error_syncs: u32,
}

/// What a node has done, for the fake's status.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NodeCounters {
    /// SYNCs taken (in operational).
    pub syncs: u64,
    /// RPDOs taken.
    pub rpdos: u64,
    /// TPDOs sent (or scheduled).
    pub tpdos: u64,
    /// SDO requests answered.
    pub sdo_requests: u64,
    /// EMCYs sent.
    pub emcy: u64,
    /// Heartbeats sent.
    pub heartbeats: u64,
    /// Faults entered.
    pub faults: u64,
    /// Times SYNC stopped while enabled.
    pub sync_timeouts: u64,
}

/// One fake node.
#[derive(Debug)]
pub struct Node {
    pub(super) id: NodeId,
    od: BTreeMap<(u16, u8), Value>,
    pub(super) nmt: nmt::State,
    pub(super) power: PowerState,
    previous_controlword: u16,
    sdo: sdo_server::Server,
    pub(super) motor: Motor,
    rpdo_buffer: [Option<[u8; 8]>; 4],
    tpdo_syncs: [u32; 4],
    tpdo_last: [Option<(Instant, Vec<u8>)>; 4],
    last_sync: Option<Instant>,
    next_heartbeat: Option<Instant>,
    fault_reaction_until: Option<Instant>,
    pub(super) injected: Injected,
    pub(super) counters: NodeCounters,
    tpdo_delay: Duration,
    sync_loss_periods: u32,
}

/// A frame to send now or at a time.
pub type Outbox = Vec<(Instant, Frame)>;

fn frame(id: u16, data: &[u8]) -> Frame {
    Frame::standard(id, data).unwrap_or_else(|| crate::proto::canopen::sync::frame(None))
}

fn encode_default(eds_default: Option<i128>, data_type: DataType, text: Option<&str>) -> Vec<u8> {
    match data_type.bits() {
        Some(bits) => {
            let n = bits.div_ceil(8) as usize;
            let v = eds_default.unwrap_or(0);
            v.to_le_bytes()[..n].to_vec()
        }
        None => text.unwrap_or("").as_bytes().to_vec(),
    }
}

impl Node {
    /// A node with the dictionary of `eds`, standing at `position` counts. `timing`: the
    /// TPDO delay, and the SYNC periods missed before an enabled drive faults.
    pub fn new(
        id: NodeId,
        eds: &Eds,
        position: f64,
        limits: MotorLimits,
        timing: (Duration, u32),
        now: Instant,
    ) -> Self {
        let (tpdo_delay, sync_loss_periods) = timing;
        let mut od = BTreeMap::new();
        for (index, object) in &eds.objects {
            for (sub, s) in &object.subs {
                let (number, text) = match &s.default {
                    Some(crate::proto::canopen::eds::DefaultValue::Text(t)) => {
                        (None, Some(t.as_str()))
                    }
                    Some(d) => (d.number(id.get()), None),
                    None => (None, None),
                };
                let bytes = encode_default(number, s.data_type, text);
                od.insert(
                    (*index, *sub),
                    Value {
                        default: bytes.clone(),
                        bytes,
                        data_type: s.data_type,
                        access: s.access,
                        mappable: s.pdo_mappable,
                    },
                );
            }
        }
        let mut n = Self {
            id,
            od,
            nmt: nmt::State::PreOperational,
            power: PowerState::SwitchOnDisabled,
            previous_controlword: 0,
            sdo: sdo_server::Server::new(),
            motor: Motor::new(position, limits),
            rpdo_buffer: [None; 4],
            tpdo_syncs: [0; 4],
            tpdo_last: [None, None, None, None],
            last_sync: None,
            next_heartbeat: None,
            fault_reaction_until: None,
            injected: Injected::default(),
            counters: NodeCounters::default(),
            tpdo_delay,
            sync_loss_periods,
        };
        n.publish();
        n.schedule_heartbeat(now);
        n
    }

    /// The boot-up message (sent when the node starts or is reset).
    pub fn boot_up(&self) -> Frame {
        heartbeat::frame(self.id, nmt::State::BootUp)
    }

    // ---- dictionary ----

    fn get(&self, index: u16, sub: u8) -> i64 {
        let Some(v) = self.od.get(&(index, sub)) else {
            return 0;
        };
        let mut b = [0u8; 8];
        let n = v.bytes.len().min(8);
        b[..n].copy_from_slice(&v.bytes[..n]);
        let raw = i64::from_le_bytes(b);
        if v.data_type.is_signed() && n < 8 && n > 0 {
            let shift = 64 - 8 * n as u32;
            (raw << shift) >> shift
        } else {
            raw
        }
    }

    fn set(&mut self, index: u16, sub: u8, value: i64) {
        if let Some(v) = self.od.get_mut(&(index, sub)) {
            let n = v.bytes.len().min(8);
            v.bytes[..n].copy_from_slice(&value.to_le_bytes()[..n]);
        }
    }

    pub(super) fn mode(&self) -> Mode {
        Mode::from_code(self.get(0x6060, 0) as i8).unwrap_or(Mode::CyclicPosition)
    }

    fn targets(&self) -> Targets {
        Targets {
            position: self.get(0x607A, 0) as i32,
            velocity: self.get(0x60FF, 0) as i32,
            torque: self.get(0x6071, 0) as i16,
            torque_offset: self.get(0x60B2, 0) as i16,
            max_torque: self.get(0x6072, 0) as u16,
        }
    }

    fn statusword(&self) -> u16 {
        let mut sw = self.power.statusword_bits() | Statusword::REMOTE;
        if matches!(
            self.power,
            PowerState::ReadyToSwitchOn
                | PowerState::SwitchedOn
                | PowerState::OperationEnabled
                | PowerState::QuickStopActive
        ) {
            sw |= Statusword::VOLTAGE_ENABLED;
        }
        let window = self.get(0x6065, 0) as u32;
        let fe = self.motor.following_error().abs();
        if fe <= f64::from(window.max(1)) {
            sw |= Statusword::TARGET_REACHED;
        }
        if self.power == PowerState::OperationEnabled {
            sw |= Statusword::FOLLOWS_TARGET;
        }
        if self.motor.at_limit {
            sw |= Statusword::INTERNAL_LIMIT;
        }
        if (window > 0 && fe > f64::from(window)) || self.injected.following_error_syncs > 0 {
            sw |= Statusword::FOLLOWING_ERROR;
        }
        if self.injected.warning {
            sw |= Statusword::WARNING;
        }
        sw
    }

    /// Writes the actual values into the dictionary.
    fn publish(&mut self) {
        let sw = self.statusword();
        self.set(0x6041, 0, i64::from(sw));
        self.set(0x6061, 0, self.get(0x6060, 0));
        self.set(0x6064, 0, self.motor.position.round() as i64);
        self.set(0x606C, 0, self.motor.velocity.round() as i64);
        self.set(0x6077, 0, self.motor.torque.round() as i64);
        self.set(0x60F4, 0, self.motor.following_error().round() as i64);
    }

    fn pdo_valid(&self, comm: u16) -> bool {
        self.get(comm, 1) as u32 & COB_ID_INVALID == 0
    }

    fn mapping(&self, map: u16) -> Vec<Entry> {
        let n = self.get(map, 0).clamp(0, 8) as u8;
        (1..=n)
            .map(|s| Entry::from_u32(self.get(map, s) as u32))
            .collect()
    }

    fn check_entry(&self, e: Entry, rpdo: bool) -> Result<(), AbortCode> {
        if e.to_u32() == 0 {
            return Ok(());
        }
        let v = self.od.get(&(e.index, e.sub)).ok_or(AbortCode::NO_OBJECT)?;
        let ok_access = if rpdo {
            v.access.writable()
        } else {
            v.access.readable()
        };
        if !v.mappable || !ok_access || v.data_type.bits() != Some(u32::from(e.bits)) {
            return Err(AbortCode::NOT_MAPPABLE);
        }
        Ok(())
    }

    /// The special rules a real drive applies to some writes.
    fn check_write(&self, a: Address, data: &[u8]) -> Result<(), AbortCode> {
        let value = {
            let mut b = [0u8; 8];
            let n = data.len().min(8);
            b[..n].copy_from_slice(&data[..n]);
            u64::from_le_bytes(b)
        };
        match a.index {
            0x1400..=0x1403 | 0x1800..=0x1803 if a.sub == 1 => {
                let new = value as u32;
                let old = self.get(a.index, 1) as u32;
                // A valid PDO's COB-ID may not change (disable it first).
                if old & COB_ID_INVALID == 0
                    && new & COB_ID_INVALID == 0
                    && new & 0x7FF != old & 0x7FF
                {
                    return Err(AbortCode::INVALID_VALUE);
                }
            }
            // Transmission types 241..=251 are reserved.
            0x1400..=0x1403 | 0x1800..=0x1803
                if a.sub == 2 && (241..=251).contains(&(value as u8)) =>
            {
                return Err(AbortCode::INVALID_VALUE);
            }
            0x1600..=0x1603 | 0x1A00..=0x1A03 => {
                let rpdo = a.index < 0x1A00;
                let comm = a.index - 0x200;
                if self.pdo_valid(comm) {
                    return Err(AbortCode::UNSUPPORTED_ACCESS);
                }
                if a.sub == 0 {
                    let n = value as u8;
                    if n > 8 {
                        return Err(AbortCode::VALUE_TOO_HIGH);
                    }
                    let mut bits = 0u32;
                    for s in 1..=n {
                        let e = Entry::from_u32(self.get(a.index, s) as u32);
                        self.check_entry(e, rpdo)?;
                        bits += u32::from(e.bits);
                    }
                    if bits > 64 {
                        return Err(AbortCode::PDO_TOO_LONG);
                    }
                } else {
                    if self.get(a.index, 0) != 0 {
                        return Err(AbortCode::UNSUPPORTED_ACCESS);
                    }
                    self.check_entry(Entry::from_u32(value as u32), rpdo)?;
                }
            }
            0x6060 => {
                let supported = self.get(0x6502, 0) as u32;
                let ok = Mode::from_code(value as u8 as i8)
                    .is_some_and(|m| m.is_supported_by(supported));
                if !ok {
                    return Err(AbortCode::INVALID_VALUE);
                }
            }
            _ => {}
        }
        Ok(())
    }

    // ---- frames in ----

    /// Handles one frame; answers go to `out`.
    pub fn on_frame(&mut self, f: &Frame, now: Instant, out: &mut Outbox) {
        let Some(id) = f.standard_id() else { return };
        let data = f.bytes();
        match Function::from_cob_id(id) {
            Some(Function::Nmt) => {
                if let Some((command, target)) = nmt::Command::decode(data) {
                    if target.is_none() || target == Some(self.id) {
                        self.on_nmt(command, now, out);
                    }
                }
            }
            Some(Function::Sync) if self.get(0x1005, 0) as u32 & 0x7FF == 0x080 => {
                self.on_sync(now, out)
            }
            Some(Function::SdoRx(node)) if node == self.id && self.nmt != nmt::State::Stopped => {
                self.counters.sdo_requests += 1;
                let mut server = std::mem::take(&mut self.sdo);
                let answer = server.on_request(data, self);
                self.sdo = server;
                if let Some(a) = answer {
                    out.push((now, frame(Function::SdoTx(self.id).cob_id(), &a)));
                }
                self.after_write(now, out);
            }
            Some(Function::Rpdo(k @ 1..=4, node))
                if node == self.id && self.nmt == nmt::State::Operational =>
            {
                let k = usize::from(k - 1);
                let comm = 0x1400 + k as u16;
                if !self.pdo_valid(comm) || self.get(comm, 1) as u32 & 0x7FF != u32::from(id) {
                    return;
                }
                let need: usize = self
                    .mapping(0x1600 + k as u16)
                    .iter()
                    .map(|e| usize::from(e.bits / 8))
                    .sum();
                if data.len() < need {
                    self.emcy(EMCY_PDO_LENGTH, 0x10, now, out);
                    return;
                }
                let mut b = [0u8; 8];
                b[..data.len()].copy_from_slice(data);
                self.counters.rpdos += 1;
                if self.get(comm, 2) as u8 <= 240 {
                    self.rpdo_buffer[k] = Some(b);
                } else {
                    self.apply_rpdo(k, &b, now, out);
                }
            }
            _ => {}
        }
    }

    fn on_nmt(&mut self, command: nmt::Command, now: Instant, out: &mut Outbox) {
        use nmt::Command as C;
        match command {
            C::Start => self.nmt = nmt::State::Operational,
            C::Stop => self.nmt = nmt::State::Stopped,
            C::EnterPreOperational => self.nmt = nmt::State::PreOperational,
            C::ResetNode | C::ResetCommunication => {
                for ((index, _), v) in self.od.iter_mut() {
                    if command == C::ResetNode || (0x1000..0x2000).contains(index) {
                        v.bytes = v.default.clone();
                    }
                }
                if command == C::ResetNode {
                    self.power = PowerState::SwitchOnDisabled;
                    self.previous_controlword = 0;
                }
                self.rpdo_buffer = [None; 4];
                self.last_sync = None;
                self.nmt = nmt::State::PreOperational;
                out.push((now, self.boot_up()));
                self.publish();
            }
        }
        if self.nmt != nmt::State::Operational {
            self.rpdo_buffer = [None; 4];
            // SYNC monitoring starts again with the first SYNC in Operational: a master that
            // comes back after a pause is not faulted for the SYNC it sent before it.
            self.last_sync = None;
        }
    }

    fn apply_rpdo(&mut self, k: usize, data: &[u8; 8], now: Instant, out: &mut Outbox) {
        let mut at = 0;
        for e in self.mapping(0x1600 + k as u16) {
            let n = usize::from(e.bits / 8);
            if e.to_u32() != 0 {
                let mut b = [0u8; 8];
                b[..n].copy_from_slice(&data[at..at + n]);
                self.set(e.index, e.sub, i64::from_le_bytes(b));
            }
            at += n;
        }
        self.after_write(now, out);
    }

    /// Reacts to writes of the controlword and the mode.
    fn after_write(&mut self, now: Instant, out: &mut Outbox) {
        let cw = self.get(0x6040, 0) as u16;
        if cw != self.previous_controlword {
            let before = self.power;
            self.power = self.power.on_controlword(cw, self.previous_controlword);
            self.previous_controlword = cw;
            if before == PowerState::Fault && self.power == PowerState::SwitchOnDisabled {
                // Fault reset: errors cleared, announced with an error-reset EMCY.
                self.set(0x603F, 0, 0);
                self.set(0x1001, 0, 0);
                self.emcy(0, 0, now, out);
            }
            if before != PowerState::OperationEnabled && self.power == PowerState::OperationEnabled
            {
                // Take over the actual position as the target: no jump on enable.
                let p = self.motor.position.round() as i64;
                self.set(0x607A, 0, p);
                self.motor.demand = self.motor.position;
            }
        }
        self.publish();
    }

    fn on_sync(&mut self, now: Instant, out: &mut Outbox) {
        if self.nmt != nmt::State::Operational {
            return;
        }
        self.counters.syncs += 1;
        let dt = self
            .last_sync
            .map_or(0.0, |t| now.duration_since(t).as_secs_f64().min(0.1));
        self.last_sync = Some(now);
        self.simulate(dt, now);
        if self.injected.following_error_syncs > 0 {
            self.injected.following_error_syncs -= 1;
        }
        // TPDOs latch the values at the SYNC and leave after the drive's delay.
        for k in 0..4u16 {
            let comm = 0x1800 + k;
            let ty = self.get(comm, 2) as u8;
            if !self.pdo_valid(comm) || ty == 0 || ty > 240 {
                continue;
            }
            let i = usize::from(k);
            self.tpdo_syncs[i] += 1;
            if self.tpdo_syncs[i] < u32::from(ty) {
                continue;
            }
            self.tpdo_syncs[i] = 0;
            let mut data = self.tpdo_data(k);
            let mut at = now + self.tpdo_delay;
            if self.injected.drop_tpdos > 0 {
                self.injected.drop_tpdos -= 1;
                continue;
            }
            if self.injected.late_tpdos > 0 {
                self.injected.late_tpdos -= 1;
                at += self.injected.late_by;
            }
            if self.injected.corrupt_tpdos > 0 && !data.is_empty() {
                self.injected.corrupt_tpdos -= 1;
                data.pop();
            }
            let cob = self.get(comm, 1) as u32 & 0x7FF;
            out.push((at, frame(cob as u16, &data)));
            self.counters.tpdos += 1;
        }
        // Synchronous RPDOs received since the last SYNC take effect now.
        for k in 0..4 {
            if let Some(b) = self.rpdo_buffer[k].take() {
                self.apply_rpdo(k, &b, now, out);
            }
        }
    }

    fn tpdo_data(&self, k: u16) -> Vec<u8> {
        let mut data = Vec::with_capacity(8);
        for e in self.mapping(0x1A00 + k) {
            let n = usize::from(e.bits / 8);
            data.extend_from_slice(&self.get(e.index, e.sub).to_le_bytes()[..n]);
        }
        data
    }

    fn simulate(&mut self, dt: f64, now: Instant) {
        let drive = match self.power {
            PowerState::OperationEnabled => Drive::Enabled,
            PowerState::QuickStopActive | PowerState::FaultReactionActive => Drive::QuickStop,
            _ => Drive::Off,
        };
        let mode = self.mode();
        let targets = self.targets();
        self.motor.advance(dt, drive, mode, targets);
        if self.power == PowerState::QuickStopActive && self.motor.velocity == 0.0 {
            // Quick stop option code 2: after the stop, switch on disabled.
            self.power = PowerState::SwitchOnDisabled;
        }
        if self.power == PowerState::FaultReactionActive
            && self.fault_reaction_until.is_none_or(|t| now >= t)
        {
            self.power = PowerState::Fault;
            self.fault_reaction_until = None;
        }
        self.publish();
    }

    /// Enters the fault state with `code`, sending the EMCY.
    pub fn fault(&mut self, code: u16, register: u8, now: Instant, out: &mut Outbox) {
        if matches!(
            self.power,
            PowerState::Fault | PowerState::FaultReactionActive
        ) {
            return;
        }
        self.counters.faults += 1;
        self.power = PowerState::FaultReactionActive;
        self.fault_reaction_until = Some(now + Duration::from_millis(2));
        self.set(0x603F, 0, i64::from(code));
        self.set(0x1001, 0, i64::from(register | 0x01));
        self.emcy(code, register | 0x01, now, out);
        self.publish();
    }

    fn emcy(&mut self, code: u16, register: u8, now: Instant, out: &mut Outbox) {
        self.counters.emcy += 1;
        let e = Emergency {
            code,
            register,
            vendor: [self.id.get(), 0, 0, 0, 0],
        };
        out.push((now, e.frame(self.id)));
    }

    fn schedule_heartbeat(&mut self, now: Instant) {
        let ms = self.get(0x1017, 0) as u16;
        self.next_heartbeat = (ms > 0).then(|| now + Duration::from_millis(u64::from(ms)));
    }

    /// Time-driven work: heartbeats, the SYNC watchdog, the end of a fault reaction, and
    /// event-driven TPDOs.
    pub fn tick(&mut self, now: Instant, out: &mut Outbox) {
        let ms = self.get(0x1017, 0) as u16;
        match (ms, self.next_heartbeat) {
            (0, _) => self.next_heartbeat = None,
            (_, None) => self.schedule_heartbeat(now),
            (_, Some(t)) if now >= t => {
                let silent = self
                    .injected
                    .heartbeat_silent_until
                    .is_some_and(|u| now < u);
                if !silent {
                    out.push((now, heartbeat::frame(self.id, self.nmt)));
                    self.counters.heartbeats += 1;
                }
                self.next_heartbeat = Some(t + Duration::from_millis(u64::from(ms)));
                if self.next_heartbeat.is_some_and(|n| n < now) {
                    self.schedule_heartbeat(now);
                }
            }
            _ => {}
        }
        // SYNC watchdog: the communication cycle period (0x1006, µs) tells how often SYNC
        // comes; `sync_loss_periods` (2) periods without one fault an enabled drive.
        let period_us = self.get(0x1006, 0) as u32;
        if period_us > 0
            && self.nmt == nmt::State::Operational
            && self.power == PowerState::OperationEnabled
        {
            if let Some(t) = self.last_sync {
                let limit = u64::from(self.sync_loss_periods) * u64::from(period_us);
                if now.duration_since(t) > Duration::from_micros(limit) {
                    self.counters.sync_timeouts += 1;
                    self.fault(EMCY_SYNC_LOST, 0x10, now, out);
                }
            }
        }
        if self.power == PowerState::FaultReactionActive
            && self.fault_reaction_until.is_some_and(|t| now >= t)
        {
            self.simulate(0.0, now);
        }
        if self.nmt == nmt::State::Operational {
            self.event_tpdos(now, out);
        }
    }

    fn event_tpdos(&mut self, now: Instant, out: &mut Outbox) {
        for k in 0..4u16 {
            let comm = 0x1800 + k;
            let ty = self.get(comm, 2) as u8;
            if !self.pdo_valid(comm) || ty < 254 {
                continue;
            }
            let inhibit = Duration::from_micros(100 * self.get(comm, 3) as u64);
            let timer_ms = self.get(comm, 5) as u64;
            let data = self.tpdo_data(k);
            let i = usize::from(k);
            let due = match &self.tpdo_last[i] {
                None => true,
                Some((t, last)) => {
                    let since = now.duration_since(*t);
                    (since >= inhibit && *last != data)
                        || (timer_ms > 0 && since >= Duration::from_millis(timer_ms))
                }
            };
            if due {
                let cob = self.get(comm, 1) as u32 & 0x7FF;
                out.push((now, frame(cob as u16, &data)));
                self.counters.tpdos += 1;
                self.tpdo_last[i] = Some((now, data));
            }
        }
    }
}

impl Dictionary for Node {
    fn read(&mut self, a: Address, out: &mut [u8]) -> Result<usize, AbortCode> {
        let v = self.sdo_object(a)?;
        if !v.access.readable() {
            return Err(AbortCode::WRITE_ONLY);
        }
        let n = v.bytes.len().min(out.len());
        out[..n].copy_from_slice(&v.bytes[..n]);
        Ok(n)
    }

    fn write(&mut self, a: Address, data: &[u8]) -> Result<(), AbortCode> {
        let v = self.sdo_object(a)?;
        if !v.access.writable() {
            return Err(AbortCode::READ_ONLY);
        }
        if let Some(bits) = v.data_type.bits() {
            let n = bits.div_ceil(8) as usize;
            if data.len() > n {
                return Err(AbortCode::LENGTH_TOO_HIGH);
            }
            if data.len() < n {
                return Err(AbortCode::LENGTH_TOO_LOW);
            }
        }
        self.check_write(a, data)?;
        if let Some(v) = self.od.get_mut(&(a.index, a.sub)) {
            v.bytes = data.to_vec();
        }
        if a.index == 0x1017 {
            self.next_heartbeat = None;
        }
        Ok(())
    }
}

impl Node {
    /// The object an SDO request addresses, or the abort it gets: the injected one first (once),
    /// then a missing object or sub-index.
    fn sdo_object(&mut self, a: Address) -> Result<&Value, AbortCode> {
        if let Some((addr, code)) = self.injected.sdo_abort {
            if addr == a {
                self.injected.sdo_abort = None;
                return Err(code);
            }
        }
        match self.od.get(&(a.index, a.sub)) {
            Some(v) => Ok(v),
            None if self.od.keys().any(|(i, _)| *i == a.index) => Err(AbortCode::NO_SUB_INDEX),
            None => Err(AbortCode::NO_OBJECT),
        }
    }

    /// Writes the drive's units into its factor group — 0x608F, 0x6091, 0x6092 as
    /// `(numerator, denominator)` each — and 0x6076 (mN·m); `None` removes the three factor-group
    /// objects, as on a drive without them (an SDO upload is then aborted with "object does not
    /// exist").
    pub fn set_units(&mut self, factors: Option<[(u32, u32); 3]>, rated_torque_mnm: u32) {
        const GROUP: [u16; 3] = [0x608F, 0x6091, 0x6092];
        match factors {
            Some(f) => {
                for (index, (n, d)) in GROUP.into_iter().zip(f) {
                    self.put_default(index, 1, i64::from(n));
                    self.put_default(index, 2, i64::from(d));
                }
            }
            None => self.od.retain(|(index, _), _| !GROUP.contains(index)),
        }
        self.put_default(0x6076, 0, i64::from(rated_torque_mnm));
    }

    /// Sets an object's value and the value a reset restores.
    fn put_default(&mut self, index: u16, sub: u8, value: i64) {
        self.set(index, sub, value);
        if let Some(v) = self.od.get_mut(&(index, sub)) {
            v.default = v.bytes.clone();
        }
    }

    /// The object's value as an integer (for tests and status).
    pub fn value(&self, index: u16, sub: u8) -> i64 {
        self.get(index, sub)
    }

    /// The drive's position, counts.
    pub fn position(&self) -> i32 {
        self.get(obj::POSITION_ACTUAL.index, 0) as i32
    }
}
