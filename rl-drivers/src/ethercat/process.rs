//! Process data: one logical process image for the whole segment (each device's outputs, then
//! its inputs), the sync managers and FMMUs that map it, and the cyclic exchange — one frame
//! per cycle holding the LRW of the image (its working counter checked against 2 per device
//! with outputs + 1 per device with inputs), the FRMW that distributes the reference clock's
//! time, a BRD of AL status (all devices still in the expected state?) and, when something is
//! wrong, the datagrams of the recovery: read each device's AL status and code, acknowledge
//! its error, request the state again. The exchange allocates nothing.

use std::ops::Range;
use std::time::Instant;

use super::error::{DeviceRef, EcError};
use super::link::Link;
use super::master::{Master, SubDevice};
use crate::proto::ecat::al::{AlControl, AlState, AlStatus, AlStatusCode};
use crate::proto::ecat::command::Command;
use crate::proto::ecat::datagram::{DatagramHeader, physical};
use crate::proto::ecat::fmmu::{self, Fmmu};
use crate::proto::ecat::frame::{DATAGRAMS_OFFSET, Frame};
use crate::proto::ecat::register as reg;
use crate::proto::ecat::sii::SmUsage;
use crate::proto::ecat::sync_manager::{self, Kind, SyncManager};

/// Where one device's data lies in the image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageDevice {
    /// The device (index in the master's list).
    pub device: usize,
    /// Its outputs.
    pub outputs: Range<usize>,
    /// Its inputs.
    pub inputs: Range<usize>,
}

/// The recovery of devices that left the expected state, one step per cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Recovery {
    Idle,
    /// Read every device's AL status and code.
    ReadStatus,
    /// Acknowledge the error of the devices in `mask`.
    Acknowledge(u64),
    /// Request the expected state from the devices in `mask`.
    Request(u64),
}

/// Counts of the cyclic exchange.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CyclicCounters {
    /// Cycles run.
    pub cycles: u64,
    /// Cycles whose reply did not come in time.
    pub timeouts: u64,
    /// Cycles with a wrong process-data working counter.
    pub wkc_errors: u64,
    /// Cycles in which a device was not in the expected state (or reported an error).
    pub state_errors: u64,
    /// Recoveries started.
    pub recoveries: u64,
    /// Devices brought back to the expected state.
    pub recovered: u64,
}

/// The image, its mapping and the cyclic state.
#[derive(Debug)]
pub struct ProcessData {
    /// Logical address of the image's first byte.
    pub logical_start: u32,
    /// What the master sends: the whole image, outputs filled in.
    pub outputs: Vec<u8>,
    /// What came back in the last good cycle.
    pub inputs: Vec<u8>,
    /// The devices' parts.
    pub devices: Vec<ImageDevice>,
    /// The LRW's expected working counter.
    pub expected_wkc: u16,
    /// The state devices must be in.
    pub target: AlState,
    /// The reference clock's station, when distributed clocks run.
    pub dc_reference: Option<u16>,
    /// The reference clock's system time as the last cycle read it.
    pub dc_time: u64,
    /// Counts.
    pub counters: CyclicCounters,
    stations: Vec<u16>,
    status: Vec<(AlStatus, AlStatusCode)>,
    recovery: Recovery,
    last_error: Option<EcError>,
}

impl Master {
    /// Configures each device's process data sync managers and FMMUs for `sizes[k]` =
    /// (output bytes, input bytes) and returns the image. Call in PRE-OP.
    pub fn configure_process_data(
        &mut self,
        sizes: &[(usize, usize)],
        logical_start: u32,
    ) -> Result<ProcessData, EcError> {
        let mut devices = Vec::new();
        let mut at = 0usize;
        let mut expected = 0u16;
        for (k, &(out, inp)) in sizes.iter().enumerate() {
            let d = self.devices[k].clone();
            let mailbox = d.has_coe();
            let fmmu_no = |usage: u8, default: u8| {
                d.fmmu_usage
                    .iter()
                    .position(|&u| u == usage)
                    .map_or(default, |p| p as u8)
            };
            let mut image = ImageDevice {
                device: k,
                outputs: at..at + out,
                inputs: at + out..at + out + inp,
            };
            for (bytes, usage, kind, fmmu_type, default_sm) in [
                (
                    out,
                    SmUsage::Outputs,
                    Kind::Outputs,
                    fmmu::TYPE_WRITE,
                    if mailbox { 2 } else { 0 },
                ),
                (
                    inp,
                    SmUsage::Inputs,
                    Kind::Inputs,
                    fmmu::TYPE_READ,
                    if mailbox { 3 } else { 1 },
                ),
            ] {
                if bytes == 0 {
                    continue;
                }
                let (n, start, control) = match d.sync_manager(usage) {
                    Some((n, s)) => (n, s.start, s.control),
                    None => (
                        default_sm,
                        if kind == Kind::Outputs {
                            0x1100
                        } else {
                            0x1400
                        },
                        SyncManager::control_of(kind),
                    ),
                };
                let len = u16::try_from(bytes).map_err(|_| EcError::Config {
                    device: Some(d.reference()),
                    what: "process data larger than 64 KiB",
                })?;
                let sm = SyncManager {
                    control,
                    ..SyncManager::new(kind, start, len)
                };
                self.fpwr(k, reg::SM0 + 8 * u16::from(n), &sm.encode())?;
                let f = fmmu_no(
                    if kind == Kind::Outputs { 1 } else { 2 },
                    if kind == Kind::Outputs { 0 } else { 1 },
                );
                let logical = logical_start
                    + if kind == Kind::Outputs {
                        image.outputs.start
                    } else {
                        image.inputs.start
                    } as u32;
                let map = Fmmu::bytes(logical, start, len, fmmu_type);
                self.fpwr(k, reg::FMMU0 + 16 * u16::from(f), &map.encode())?;
                expected += if kind == Kind::Outputs { 2 } else { 1 };
            }
            at = image.inputs.end;
            if out == 0 {
                image.outputs = image.inputs.start..image.inputs.start;
            }
            devices.push(image);
        }
        Ok(ProcessData {
            logical_start,
            outputs: vec![0; at],
            inputs: vec![0; at],
            devices,
            expected_wkc: expected,
            target: AlState::SafeOp,
            dc_reference: None,
            dc_time: 0,
            counters: CyclicCounters::default(),
            stations: self.devices.iter().map(|d| d.station).collect(),
            status: vec![(AlStatus(0), AlStatusCode(0)); self.devices.len()],
            recovery: Recovery::Idle,
            last_error: None,
        })
    }
}

fn bit(mask: u64, k: usize) -> bool {
    k < 64 && mask & (1 << k) != 0
}

impl ProcessData {
    /// The outputs of device part `i`.
    pub fn outputs_of(&mut self, i: usize) -> &mut [u8] {
        let r = self.devices[i].outputs.clone();
        &mut self.outputs[r]
    }

    /// The inputs of device part `i`.
    pub fn inputs_of(&self, i: usize) -> &[u8] {
        &self.inputs[self.devices[i].inputs.clone()]
    }

    /// The AL status and code of device `k` as the recovery last read them.
    pub fn device_status(&self, k: usize) -> (AlStatus, AlStatusCode) {
        self.status[k]
    }

    /// Whether a recovery is under way.
    pub fn recovering(&self) -> bool {
        self.recovery != Recovery::Idle
    }

    /// One cycle: sends the frame, waits for it until `deadline`, takes the inputs and checks
    /// the working counters and the devices' state. A failed cycle leaves the previous inputs.
    pub fn exchange(&mut self, link: &mut Link, deadline: Instant) -> Result<(), EcError> {
        self.counters.cycles += 1;
        let n = self.stations.len();
        let index = link.next_index();
        let image_len = self.outputs.len();
        // Build: LRW, FRMW, BRD, then the recovery's datagrams.
        let (len, lrw_at) = {
            let mut b = link.builder()?;
            let mut h = DatagramHeader::new(Command::Lrw, self.logical_start, 0);
            h.index = index;
            let lrw_at = b.push(h, &self.outputs).map_err(EcError::Frame)?;
            if let Some(station) = self.dc_reference {
                let mut h =
                    DatagramHeader::new(Command::Frmw, physical(station, reg::DC_SYSTEM_TIME), 0);
                h.index = index;
                b.push_zeroed(h, 8).map_err(EcError::Frame)?;
            }
            let mut h = DatagramHeader::new(Command::Brd, physical(0, reg::AL_STATUS), 0);
            h.index = index;
            b.push_zeroed(h, 2).map_err(EcError::Frame)?;
            match self.recovery {
                Recovery::Idle => {}
                Recovery::ReadStatus => {
                    for &s in &self.stations {
                        let mut h =
                            DatagramHeader::new(Command::Fprd, physical(s, reg::AL_STATUS), 0);
                        h.index = index;
                        b.push_zeroed(h, 6).map_err(EcError::Frame)?;
                    }
                }
                Recovery::Acknowledge(mask) | Recovery::Request(mask) => {
                    let ack = matches!(self.recovery, Recovery::Acknowledge(_));
                    for k in 0..n {
                        if !bit(mask, k) {
                            continue;
                        }
                        let state = self.status[k].0.state().unwrap_or(AlState::SafeOp);
                        let control = if ack {
                            AlControl::acknowledge(state.min(self.target))
                        } else {
                            AlControl::request(self.target)
                        };
                        let mut h = DatagramHeader::new(
                            Command::Fpwr,
                            physical(self.stations[k], reg::AL_CONTROL),
                            0,
                        );
                        h.index = index;
                        b.push(h, &control.to_u16().to_le_bytes())
                            .map_err(EcError::Frame)?;
                    }
                }
            }
            (b.finish(), lrw_at)
        };
        debug_assert_eq!(lrw_at, DATAGRAMS_OFFSET + 10);
        link.send(len)?;
        if !link.receive(index, deadline)? {
            self.counters.timeouts += 1;
            return Err(EcError::Timeout {
                what: "the cyclic frame",
                waited_us: 0,
            });
        }
        // Parse the reply in the order it was built.
        let frame = Frame::decode(link.reply()).map_err(EcError::Frame)?;
        let mut dg = frame.datagrams();
        let lrw = dg
            .next()
            .and_then(Result::ok)
            .ok_or(EcError::Reply("no LRW"))?;
        if lrw.header.cmd != Command::Lrw.code() || lrw.data.len() != image_len {
            return Err(EcError::Reply(
                "the first datagram is not the LRW of the image",
            ));
        }
        let lrw_wkc = lrw.wkc;
        if lrw_wkc == self.expected_wkc {
            self.inputs.copy_from_slice(lrw.data);
        }
        if self.dc_reference.is_some() {
            let d = dg
                .next()
                .and_then(Result::ok)
                .ok_or(EcError::Reply("no FRMW"))?;
            if d.wkc > 0 && d.data.len() == 8 {
                let mut t = [0u8; 8];
                t.copy_from_slice(d.data);
                self.dc_time = u64::from_le_bytes(t);
            }
        }
        let brd = dg
            .next()
            .and_then(Result::ok)
            .ok_or(EcError::Reply("no BRD"))?;
        let responding = brd.wkc;
        let status_or = u16::from_le_bytes([brd.data[0], brd.data[1]]);
        let mut error = None;
        let phase = self.recovery;
        match phase {
            Recovery::Idle => {}
            Recovery::ReadStatus => {
                let mut bad = 0u64;
                for k in 0..n {
                    let d = dg
                        .next()
                        .and_then(Result::ok)
                        .ok_or(EcError::Reply("no AL status"))?;
                    if d.wkc == 1 {
                        let s = AlStatus(u16::from_le_bytes([d.data[0], d.data[1]]));
                        let c = AlStatusCode(u16::from_le_bytes([d.data[4], d.data[5]]));
                        self.status[k] = (s, c);
                        if s.error() || s.state() != Some(self.target) {
                            if k < 64 {
                                bad |= 1 << k;
                            }
                            if error.is_none() {
                                error = Some(EcError::AlStatus {
                                    device: DeviceRef {
                                        position: k as u16,
                                        station: self.stations[k],
                                    },
                                    status: s,
                                    code: c,
                                });
                            }
                        }
                    }
                }
                let errored = (0..n)
                    .filter(|&k| bit(bad, k) && self.status[k].0.error())
                    .fold(0u64, |m, k| m | 1 << k);
                self.recovery = if bad == 0 {
                    Recovery::Idle
                } else if errored != 0 {
                    Recovery::Acknowledge(errored)
                } else {
                    Recovery::Request(bad)
                };
            }
            Recovery::Acknowledge(mask) => {
                for _ in 0..mask.count_ones() {
                    dg.next();
                }
                self.recovery = Recovery::Request(mask);
            }
            Recovery::Request(mask) => {
                for _ in 0..mask.count_ones() {
                    dg.next();
                }
                self.counters.recovered += u64::from(mask.count_ones());
                self.recovery = Recovery::ReadStatus;
            }
        }
        let state_ok = status_or == u16::from(self.target.code());
        if !state_ok || responding != n as u16 {
            self.counters.state_errors += 1;
            if self.recovery == Recovery::Idle && self.target == AlState::Op {
                self.counters.recoveries += 1;
                self.recovery = Recovery::ReadStatus;
            }
        }
        let result = if responding < n as u16 {
            Err(EcError::DevicesLost {
                expected: n as u16,
                responding,
            })
        } else if let Some(e) = error {
            Err(e)
        } else if lrw_wkc != self.expected_wkc {
            self.counters.wkc_errors += 1;
            Err(EcError::WorkingCounter {
                command: Command::Lrw,
                address: self.logical_start,
                expected: self.expected_wkc,
                received: lrw_wkc,
            })
        } else if !state_ok {
            Err(self.last_error.unwrap_or(EcError::AlStatus {
                device: DeviceRef {
                    position: u16::MAX,
                    station: 0,
                },
                status: AlStatus(status_or),
                code: AlStatusCode(0),
            }))
        } else {
            Ok(())
        };
        if lrw_wkc != self.expected_wkc
            && result.is_err()
            && !matches!(result, Err(EcError::WorkingCounter { .. }))
        {
            self.counters.wkc_errors += 1;
        }
        if let Err(e) = result {
            if matches!(e, EcError::AlStatus { .. }) {
                self.last_error = Some(e);
            }
        } else {
            self.last_error = None;
        }
        result
    }
}

/// The sync manager configuration a device with `d`'s SII gets for `kind` (for tests and
/// diagnostics).
pub fn process_sync_manager(d: &SubDevice, kind: Kind, len: u16) -> SyncManager {
    let usage = if kind == Kind::Outputs {
        SmUsage::Outputs
    } else {
        SmUsage::Inputs
    };
    match d.sync_manager(usage) {
        Some((_, s)) => SyncManager {
            control: s.control,
            ..SyncManager::new(kind, s.start, len)
        },
        None => SyncManager::new(kind, 0x1100, len),
    }
}

/// Whether `s` is an enabled process-data channel.
pub fn is_process_channel(s: &SyncManager) -> bool {
    !s.is_mailbox() && s.activate & sync_manager::ACTIVATE_ENABLE != 0
}
