//! CiA 402 servo drives on an EtherCAT segment as one joint device ([`EthercatDrives`]): every
//! drive the scan finds (CoE device type 0x1000 with profile 402) is one joint, commanded in
//! cyclic synchronous position (CSP, with the torque offset 0x60B2 as feed-forward), velocity
//! (CSV) or torque (CST) mode through the shared [`cia402`](crate::cia402) module.
//!
//! - `open`: scan, distributed clocks (delays, offsets, drift compensation), INIT → PRE-OP,
//!   find the drives, map their PDOs (our mapping written by SDO, or the drive's own if it
//!   refuses), read their units (0x608F, 0x6091, 0x6092, 0x6076: a drive that cannot give one
//!   the configuration does not give is refused, naming the object) and positions (0x6064), configure sync
//!   managers and FMMUs, start SYNC0 at the period, PRE-OP → SAFE-OP, and exchange process data
//!   once: [`JointDevice::dof`] and [`JointPositionSensor::joint_position`] are valid from here,
//!   before any drive is enabled.
//! - `start`: targets = actual positions, SAFE-OP → OP, then each drive walked to "operation
//!   enabled" (fault reset, shutdown, switch on, enable operation), cycle by cycle.
//! - `step`: one frame (LRW of the image, FRMW of the reference clock, BRD of AL status); the
//!   reply is awaited at most `frame_timeout` (less than a period); lost frames, wrong working
//!   counters, devices out of OP (recovered in the following cycles) and drives that left
//!   "operation enabled" are typed, counted errors.
//! - `stop` (from running or faulted): disable operation, shutdown, disable voltage, then
//!   SAFE-OP and PRE-OP — every step tried and bounded; the first error is returned.
//! - `close`: INIT, socket closed.

use std::time::{Duration, Instant};

use super::dc::DcSetup;
use super::error::{DeviceRef, EcError};
use super::master::{Master, MasterConfig};
use super::process::ProcessData;
use crate::capability::{
    JointDevice, JointLimitSensor, JointPositionActuator, JointPositionSensor, JointTorqueActuator,
    JointTorqueFeedForward, JointTorqueSensor, JointVelocityActuator, JointVelocitySensor,
    LinkStatistics, LinkStatisticsSensor,
};
use crate::cia402::object as obj;
use crate::cia402::state::Goal;
use crate::cia402::{
    AxisUnits, Command as DriveCommand, Controlword, Mode, PowerState, Statusword, UnitsError,
    UnitsOverride,
};
use crate::device::{Driver, Error, FirstError, Lifecycle, Operation, State, impl_cyclic_device};
use crate::proto::canopen::pdo::Entry;
use crate::proto::canopen::sdo::Address;
use crate::proto::ecat::al::AlState;
use crate::proto::ecat::sii::SmUsage;

/// How to run the drives.
#[derive(Clone, Debug, PartialEq)]
pub struct EthercatConfig {
    /// The master's link and bounds.
    pub master: MasterConfig,
    /// The control period (SYNC0 cycle and `update_period`).
    pub period: Duration,
    /// The mode of every drive.
    pub mode: Mode,
    /// Units the user gives per drive, in joint order; what an entry leaves out (and every
    /// unit of a drive without an entry) is read from the drive (0x608F, 0x6091, 0x6092,
    /// 0x6076), and a drive that cannot give it is refused before it is enabled.
    pub units: Vec<UnitsOverride>,
    /// Whether to set up distributed clocks and SYNC0 (drives in CSP usually need it).
    pub distributed_clocks: bool,
    /// SYNC0 shift after the cycle start.
    pub sync0_shift: Duration,
    /// FRMW frames of the static drift compensation in `open`.
    pub dc_static_frames: u32,
    /// Whether to write our PDO mapping by SDO (else use the drive's).
    pub explicit_pdo: bool,
    /// Bound on the reply of one cycle (at most the period).
    pub frame_timeout: Duration,
    /// Bound on enabling the drives in `start`.
    pub enable_timeout: Duration,
    /// Bound on bringing the drives to rest in `stop`.
    pub stop_timeout: Duration,
    /// Failed steps in a row that fault the device.
    pub max_consecutive_failures: u32,
}

impl EthercatConfig {
    /// CSP at 1 ms on `interface`, distributed clocks on, our PDO mapping, replies awaited
    /// half a period, 2 s to enable, 1 s to stop, 10 failed steps to fault.
    pub fn new(interface: &str) -> Self {
        Self {
            master: MasterConfig::new(interface),
            period: Duration::from_millis(1),
            mode: Mode::CyclicPosition,
            units: Vec::new(),
            distributed_clocks: true,
            sync0_shift: Duration::ZERO,
            dc_static_frames: 1000,
            explicit_pdo: true,
            frame_timeout: Duration::from_micros(500),
            enable_timeout: Duration::from_secs(2),
            stop_timeout: Duration::from_secs(1),
            max_consecutive_failures: 10,
        }
    }
}

/// A drive that left "operation enabled", as the driver reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DriveFault {
    /// The joint.
    pub axis: usize,
    /// Its device.
    pub device: DeviceRef,
    /// The statusword.
    pub statusword: u16,
    /// The error code (0x603F), when mapped.
    pub error_code: u16,
}

impl core::fmt::Display for DriveFault {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let state = PowerState::from_statusword(self.statusword);
        write!(f, "joint {} ({}): ", self.axis, self.device)?;
        match state {
            Some(s) => write!(f, "{s}")?,
            None => write!(f, "statusword {:#06x}", self.statusword)?,
        }
        if self.error_code != 0 {
            write!(f, ", error code {:#06x}", self.error_code)?;
        }
        Ok(())
    }
}

/// Byte offsets of the objects in one drive's part of the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Offsets {
    controlword: usize,
    target_position: Option<usize>,
    target_velocity: Option<usize>,
    target_torque: Option<usize>,
    torque_offset: Option<usize>,
    mode: Option<usize>,
    statusword: usize,
    position: usize,
    velocity: Option<usize>,
    torque: Option<usize>,
    error_code: Option<usize>,
}

/// One joint.
#[derive(Clone, Debug, PartialEq)]
struct Drive {
    device: usize,
    part: usize,
    units: AxisUnits,
    rx: Vec<Entry>,
    tx: Vec<Entry>,
    at: Offsets,
}

/// Counts beyond the link's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DriveCounters {
    /// Steps that found a drive out of "operation enabled".
    pub drive_faults: u64,
}

/// CiA 402 drives on an EtherCAT segment.
#[derive(Debug)]
pub struct EthercatDrives {
    config: EthercatConfig,
    lifecycle: Lifecycle,
    master: Option<Master>,
    process: Option<ProcessData>,
    drives: Vec<Drive>,
    names: Vec<String>,
    dc: Option<DcSetup>,
    origin: Instant,
    counters: DriveCounters,
    link_before: LinkStatistics,
}

/// Our receive mapping: what every cyclic mode needs.
pub fn rx_mapping() -> [Entry; 6] {
    [
        obj::CONTROLWORD.entry(),
        obj::TARGET_POSITION.entry(),
        obj::TARGET_VELOCITY.entry(),
        obj::TARGET_TORQUE.entry(),
        obj::TORQUE_OFFSET.entry(),
        obj::MODES_OF_OPERATION.entry(),
    ]
}

/// Our transmit mapping.
pub fn tx_mapping() -> [Entry; 6] {
    [
        obj::STATUSWORD.entry(),
        obj::POSITION_ACTUAL.entry(),
        obj::VELOCITY_ACTUAL.entry(),
        obj::TORQUE_ACTUAL.entry(),
        obj::ERROR_CODE.entry(),
        obj::MODES_DISPLAY.entry(),
    ]
}

/// The byte offset of `o` in `entries` (`None` if absent or not byte-aligned).
fn locate(entries: &[Entry], o: obj::Object) -> Option<usize> {
    let mut bit = 0usize;
    for e in entries {
        if e.index == o.index && e.sub == o.sub {
            return (bit % 8 == 0 && usize::from(e.bits) == o.len() * 8).then_some(bit / 8);
        }
        bit += usize::from(e.bits);
    }
    None
}

fn bytes(entries: &[Entry]) -> usize {
    entries
        .iter()
        .map(|e| usize::from(e.bits))
        .sum::<usize>()
        .div_ceil(8)
}

fn get_i32(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn get_u16(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

/// The generic error of a master error during `operation`.
fn to_error(operation: Operation, e: EcError) -> Error {
    match e {
        EcError::Io { kind, code } => {
            if matches!(code, Some(libc::ENETDOWN | libc::ENXIO | libc::ENODEV)) {
                Error::Disconnected { operation }
            } else {
                Error::Io {
                    operation,
                    kind,
                    os_code: code,
                }
            }
        }
        EcError::Timeout { waited_us, .. } => Error::Timeout {
            operation,
            waited: Duration::from_micros(waited_us),
        },
        EcError::DevicesLost { responding: 0, .. } => Error::Disconnected { operation },
        EcError::AlTransition { .. } | EcError::AlStatus { .. } => {
            Error::device(operation, "AL status", &e)
        }
        EcError::MailboxError { .. } => Error::device(operation, "EtherCAT mailbox", &e),
        EcError::Sdo { .. } if e.is_device_report() => Error::device(operation, "CoE SDO", &e),
        EcError::Sdo { .. } => Error::protocol(operation, "CoE SDO", &e),
        _ => Error::protocol(operation, "EtherCAT datagram", &e),
    }
}

impl EthercatDrives {
    /// A closed device.
    pub fn new(config: EthercatConfig) -> Result<Self, Error> {
        if config.period.is_zero() || config.frame_timeout.is_zero() {
            return Err(Error::InvalidArgument {
                what: "period and frame timeout (µs, at least 1)",
                expected: 1,
                got: 0,
            });
        }
        Ok(Self {
            lifecycle: Lifecycle::with_failure_limit(config.max_consecutive_failures),
            config,
            master: None,
            process: None,
            drives: Vec::new(),
            names: Vec::new(),
            dc: None,
            origin: Instant::now(),
            counters: DriveCounters::default(),
            link_before: LinkStatistics::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &EthercatConfig {
        &self.config
    }

    /// The master (open).
    pub fn master(&self) -> Option<&Master> {
        self.master.as_ref()
    }

    /// The process data (open).
    pub fn process(&self) -> Option<&ProcessData> {
        self.process.as_ref()
    }

    /// The names of the devices found, in position order.
    pub fn device_names(&self) -> &[String] {
        &self.names
    }

    /// The distributed-clock setup, when DC runs.
    pub fn dc(&self) -> Option<&DcSetup> {
        self.dc.as_ref()
    }

    /// The units of each joint.
    pub fn units(&self) -> Vec<AxisUnits> {
        self.drives.iter().map(|d| d.units).collect()
    }

    /// Counts of drive faults.
    pub fn counters(&self) -> DriveCounters {
        self.counters
    }

    /// The statusword of joint `k` from the last cycle.
    pub fn statusword(&self, k: usize) -> Option<Statusword> {
        let p = self.process.as_ref()?;
        let d = self.drives.get(k)?;
        Some(Statusword(get_u16(p.inputs_of(d.part), d.at.statusword)))
    }

    fn master_mut(&mut self, operation: Operation) -> Result<&mut Master, Error> {
        self.master.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })
    }

    fn cycle_paced(&mut self, operation: Operation, next: &mut Instant) -> Result<(), EcError> {
        let now = Instant::now();
        if *next > now {
            std::thread::sleep(*next - now);
        }
        *next += self.config.period;
        let timeout = self.config.frame_timeout.min(self.config.period);
        let (Some(m), Some(p)) = (self.master.as_mut(), self.process.as_mut()) else {
            let _ = operation;
            return Err(EcError::Reply("closed"));
        };
        p.exchange(&mut m.link, Instant::now() + timeout)
    }

    fn drive_fault(&self, k: usize) -> DriveFault {
        let d = &self.drives[k];
        let (sw, code) = match &self.process {
            Some(p) => {
                let i = p.inputs_of(d.part);
                (
                    get_u16(i, d.at.statusword),
                    d.at.error_code.map_or(0, |a| get_u16(i, a)),
                )
            }
            None => (0, 0),
        };
        DriveFault {
            axis: k,
            device: self.master.as_ref().map_or(
                DeviceRef {
                    position: d.device as u16,
                    station: 0,
                },
                |m| m.devices[d.device].reference(),
            ),
            statusword: sw,
            error_code: code,
        }
    }

    /// Sets every drive's controlword to `cw` with targets at the actual values.
    fn hold_outputs(&mut self, cw: u16) {
        for k in 0..self.drives.len() {
            self.hold_axis(k, cw);
        }
    }

    fn hold_axis(&mut self, k: usize, cw: u16) {
        let mode = self.config.mode.code() as u8;
        let Some(p) = self.process.as_mut() else {
            return;
        };
        let d = &self.drives[k];
        let pos = get_i32(p.inputs_of(d.part), d.at.position);
        let out = p.outputs_of(d.part);
        write_u16(out, d.at.controlword, cw);
        for at in [d.at.target_velocity].into_iter().flatten() {
            write_i32(out, at, 0);
        }
        if let Some(at) = d.at.target_position {
            write_i32(out, at, pos);
        }
        for at in [d.at.target_torque, d.at.torque_offset]
            .into_iter()
            .flatten()
        {
            write_u16(out, at, 0);
        }
        if let Some(at) = d.at.mode {
            out[at] = mode;
        }
    }

    fn check_mode(&self, mode: Mode, len: usize) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        if self.config.mode != mode {
            return Err(Error::InvalidArgument {
                what: "command kind does not match the configured CiA 402 mode (code)",
                expected: self.config.mode.code() as usize,
                got: mode.code() as usize,
            });
        }
        Error::check_len("joint vector length", self.drives.len(), len)
    }

    fn read_inputs(
        &self,
        out: &mut [f64],
        f: impl Fn(&Drive, &[u8]) -> Option<f64>,
    ) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", self.drives.len(), out.len())?;
        let p = self.process.as_ref().ok_or(Error::State {
            operation: Operation::Get,
            state: self.lifecycle.state(),
        })?;
        for (o, d) in out.iter_mut().zip(&self.drives) {
            *o = f(d, p.inputs_of(d.part)).ok_or_else(|| {
                Error::protocol(
                    Operation::Get,
                    "EtherCAT process data",
                    &"the quantity is not in the drive's mapping",
                )
            })?;
        }
        Ok(())
    }

    fn write_outputs(
        &mut self,
        values: &[f64],
        f: impl Fn(&Drive, &mut [u8], f64) -> bool,
    ) -> Result<(), Error> {
        let p = self.process.as_mut().ok_or(Error::State {
            operation: Operation::Set,
            state: self.lifecycle.state(),
        })?;
        for (d, &v) in self.drives.iter().zip(values) {
            if !f(d, p.outputs_of(d.part), v) {
                return Err(Error::protocol(
                    Operation::Set,
                    "EtherCAT process data",
                    &"the quantity is not in the drive's mapping",
                ));
            }
        }
        Ok(())
    }
}

fn write_u16(b: &mut [u8], at: usize, v: u16) {
    b[at..at + 2].copy_from_slice(&v.to_le_bytes());
}

fn write_i32(b: &mut [u8], at: usize, v: i32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

fn configure_mailbox(m: &mut Master, k: usize) -> Result<(), EcError> {
    use crate::proto::ecat::register as reg;
    use crate::proto::ecat::sync_manager::{Kind, SyncManager};
    let d = m.devices[k].clone();
    if d.mailbox_out.size == 0 || d.mailbox_in.size == 0 {
        return Ok(());
    }
    for (usage, kind, window, default) in [
        (SmUsage::MailboxOut, Kind::MailboxOut, d.mailbox_out, 0u8),
        (SmUsage::MailboxIn, Kind::MailboxIn, d.mailbox_in, 1u8),
    ] {
        let (n, control) = d
            .sync_manager(usage)
            .map_or((default, SyncManager::control_of(kind)), |(n, s)| {
                (n, s.control)
            });
        let sm = SyncManager {
            control,
            ..SyncManager::new(kind, window.offset, window.size)
        };
        m.fpwr(k, reg::SM0 + 8 * u16::from(n), &sm.encode())?;
    }
    Ok(())
}

/// Writes our mapping by SDO; if the drive refuses, reads its own assignment.
fn map_drive(
    m: &mut Master,
    k: usize,
    explicit: bool,
) -> Result<(Vec<Entry>, Vec<Entry>), EcError> {
    if explicit {
        let written = (|| -> Result<(), EcError> {
            for (assign, pdo, entries) in [
                (0x1C12u16, 0x1600u16, &rx_mapping()[..]),
                (0x1C13, 0x1A00, &tx_mapping()[..]),
            ] {
                m.sdo_download(k, Address::new(assign, 0), &[0], false)?;
                m.sdo_download(k, Address::new(pdo, 0), &[0], false)?;
                for (i, e) in entries.iter().enumerate() {
                    m.sdo_download(
                        k,
                        Address::new(pdo, i as u8 + 1),
                        &e.to_u32().to_le_bytes(),
                        false,
                    )?;
                }
                m.sdo_download(k, Address::new(pdo, 0), &[entries.len() as u8], false)?;
                m.sdo_download(k, Address::new(assign, 1), &pdo.to_le_bytes(), false)?;
                m.sdo_download(k, Address::new(assign, 0), &[1], false)?;
            }
            Ok(())
        })();
        match written {
            Ok(()) => return Ok((rx_mapping().to_vec(), tx_mapping().to_vec())),
            Err(e) if e.is_device_report() => {} // the drive keeps its own mapping
            Err(e) => return Err(e),
        }
    }
    let mut read = |assign: u16| -> Result<Vec<Entry>, EcError> {
        let n = m.sdo_read_u64(k, assign, 0)? as u8;
        let mut entries = Vec::new();
        for i in 1..=n {
            let pdo = m.sdo_read_u64(k, assign, i)? as u16;
            let count = m.sdo_read_u64(k, pdo, 0)? as u8;
            for j in 1..=count {
                entries.push(Entry::from_u32(m.sdo_read_u64(k, pdo, j)? as u32));
            }
        }
        Ok(entries)
    };
    Ok((read(0x1C12)?, read(0x1C13)?))
}

fn offsets(rx: &[Entry], tx: &[Entry]) -> Option<Offsets> {
    Some(Offsets {
        controlword: locate(rx, obj::CONTROLWORD)?,
        target_position: locate(rx, obj::TARGET_POSITION),
        target_velocity: locate(rx, obj::TARGET_VELOCITY),
        target_torque: locate(rx, obj::TARGET_TORQUE),
        torque_offset: locate(rx, obj::TORQUE_OFFSET),
        mode: locate(rx, obj::MODES_OF_OPERATION),
        statusword: locate(tx, obj::STATUSWORD)?,
        position: locate(tx, obj::POSITION_ACTUAL)?,
        velocity: locate(tx, obj::VELOCITY_ACTUAL),
        torque: locate(tx, obj::TORQUE_ACTUAL),
        error_code: locate(tx, obj::ERROR_CODE),
    })
}

/// The drive's units: those `given`, the rest read by CoE SDO from 0x608F (encoder increments
/// per motor revolutions), 0x6091 (motor revolutions per shaft revolutions), 0x6092 (position
/// units per shaft revolutions) and 0x6076 (rated torque, mN·m).
fn read_units(
    m: &mut Master,
    k: usize,
    given: &UnitsOverride,
) -> Result<AxisUnits, UnitsError<EcError>> {
    given.resolve(|o| m.sdo_read_u64(k, o.index, o.sub))
}

/// No device answers on the interface, for the generic error.
struct NoDevicesOn<'a>(&'a str);

impl core::fmt::Display for NoDevicesOn<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "no EtherCAT device answers on `{}`: no frame came back (is a segment's IN port \
             connected to this interface?)",
            self.0
        )
    }
}

/// A drive refused for its units, as the generic error describes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitsRefused {
    /// The joint.
    pub axis: usize,
    /// Its device.
    pub device: DeviceRef,
    /// Which object, and why.
    pub error: UnitsError<EcError>,
}

impl core::fmt::Display for UnitsRefused {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "joint {} ({}): ", self.axis, self.device)?;
        match self.error {
            // Compact: the object is named once.
            UnitsError::Unreadable {
                object,
                error: EcError::Sdo { error, .. },
            } => write!(
                f,
                "cannot read {:#06x}:{} ({}): {}; give the axis units instead",
                object.index,
                object.sub,
                object.name,
                error.reason()
            ),
            e => write!(f, "{e}"),
        }
    }
}

/// Output and input bytes of a device that is no drive, from its SII PDOs.
fn sii_sizes(d: &super::master::SubDevice) -> (usize, usize) {
    let sum = |pdos: &[super::master::SiiPdo], usage| {
        let sm = d.sync_manager(usage).map(|(n, _)| n);
        pdos.iter()
            .filter(|p| sm.is_none_or(|n| p.sync_manager == n))
            .flat_map(|p| p.entries.iter())
            .map(|e| usize::from(e.2))
            .sum::<usize>()
            .div_ceil(8)
    };
    (
        sum(&d.rx_pdos, SmUsage::Outputs),
        sum(&d.tx_pdos, SmUsage::Inputs),
    )
}

impl Driver for EthercatDrives {
    const STOP_DESCRIPTION: &'static str =
        "drives disabled (disable operation, shutdown, disable voltage), segment in PRE-OP";

    // ---- open -------------------------------------------------------------------------------

    fn open_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Open;
        let e = |e| to_error(OP, e);
        self.origin = Instant::now();
        let mut m = Master::open(self.config.master.clone()).map_err(e)?;
        m.scan().map_err(|error| match error {
            EcError::NoDevices => Error::device(
                OP,
                "EtherCAT",
                &NoDevicesOn(self.config.master.interface.as_str()),
            ),
            error => to_error(OP, error),
        })?;
        self.names = m.devices.iter().map(|d| d.name.clone()).collect();
        self.dc = if self.config.distributed_clocks {
            m.dc_setup(self.origin, self.config.dc_static_frames)
                .map_err(e)?
        } else {
            None
        };
        // INIT -> PRE-OP: the mailboxes.
        for k in 0..m.devices.len() {
            configure_mailbox(&mut m, k).map_err(e)?;
        }
        let all: Vec<usize> = (0..m.devices.len()).collect();
        m.request_state(&all, AlState::PreOp, |_| Ok(()))
            .map_err(e)?;
        // The drives and their mapping.
        let mut sizes = vec![(0usize, 0usize); m.devices.len()];
        let mut drives = Vec::new();
        for (k, size) in sizes.iter_mut().enumerate() {
            let is_drive = m.devices[k].has_coe()
                && m.sdo_read_u64(k, 0x1000, 0)
                    .is_ok_and(|t| t & 0xFFFF == 402);
            if is_drive {
                let axis = drives.len();
                let (rx, tx) = map_drive(&mut m, k, self.config.explicit_pdo).map_err(e)?;
                let at = offsets(&rx, &tx).ok_or_else(|| {
                    to_error(
                        OP,
                        EcError::Config {
                            device: Some(m.devices[k].reference()),
                            what: "the drive's mapping lacks the controlword, statusword or position",
                        },
                    )
                })?;
                let given = self
                    .config
                    .units
                    .get(axis)
                    .copied()
                    .unwrap_or(UnitsOverride::NONE);
                let units = read_units(&mut m, k, &given).map_err(|error| {
                    Error::device(
                        OP,
                        "CiA 402 units",
                        &UnitsRefused {
                            axis,
                            device: m.devices[k].reference(),
                            error,
                        },
                    )
                })?;
                if self.dc.is_some() {
                    // DC-synchronous mode where the drive has the object (best effort).
                    let _ = m.sdo_download(k, Address::new(0x1C32, 1), &2u16.to_le_bytes(), false);
                }
                *size = (bytes(&rx), bytes(&tx));
                drives.push(Drive {
                    device: k,
                    part: k,
                    units,
                    rx,
                    tx,
                    at,
                });
            } else {
                *size = sii_sizes(&m.devices[k]);
            }
        }
        let mut p = m.configure_process_data(&sizes, 0).map_err(e)?;
        if let Some(dc) = &mut self.dc {
            p.dc_reference = Some(m.devices[dc.reference].station);
            let cycle = self.config.period;
            for &k in &dc.devices {
                if m.devices[k].dc_assign_activate != 0 || drives.iter().any(|d| d.device == k) {
                    m.dc_start_sync0(k, cycle, Duration::from_millis(20), self.config.sync0_shift)
                        .map_err(e)?;
                }
            }
            dc.sync0_cycle = u32::try_from(cycle.as_nanos()).unwrap_or(u32::MAX);
            // Let the first SYNC0 pulses come before SAFE-OP.
            std::thread::sleep(Duration::from_millis(25));
        }
        // Outputs that hold: power off, targets at the actual positions.
        for d in &drives {
            let pos = m
                .sdo_upload(d.device, Address::new(0x6064, 0), false)
                .ok()
                .and_then(|b| {
                    b.get(..4)
                        .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                })
                .unwrap_or(0);
            let out = p.outputs_of(d.part);
            write_u16(out, d.at.controlword, 0);
            if let Some(t) = d.at.target_position {
                write_i32(out, t, pos);
            }
            if let Some(at) = d.at.mode {
                out[at] = self.config.mode.code() as u8;
            }
        }
        p.target = AlState::SafeOp;
        m.request_state(&all, AlState::SafeOp, |_| Ok(()))
            .map_err(e)?;
        // Fill the inputs (a few tries: a frame may be lost).
        let mut last = Ok(());
        for _ in 0..10 {
            last = p.exchange(
                &mut m.link,
                Instant::now() + self.config.period.max(self.config.frame_timeout),
            );
            if last.is_ok() {
                break;
            }
            std::thread::sleep(self.config.period);
        }
        last.map_err(e)?;
        self.drives = drives;
        self.process = Some(p);
        self.master = Some(m);
        Ok(())
    }

    // ---- start ------------------------------------------------------------------------------

    fn start_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Start;
        // Targets at the actual positions, power stage off, our mode.
        self.hold_outputs(0);
        let mut next = Instant::now();
        // Back to SAFE-OP if a stop left the segment in PRE-OP.
        {
            let m = self.master_mut(OP)?;
            let all: Vec<usize> = (0..m.devices.len()).collect();
            let (s, _) = m.al_status(0).map_err(|e| to_error(OP, e))?;
            if s.state() != Some(AlState::SafeOp) {
                m.request_state(&all, AlState::SafeOp, |_| Ok(()))
                    .map_err(|e| to_error(OP, e))?;
            }
        }
        // Valid outputs before OP.
        for _ in 0..3 {
            let _ = self.cycle_paced(OP, &mut next);
        }
        if let Some(p) = self.process.as_mut() {
            p.target = AlState::Op;
        }
        {
            let m = self.master_mut(OP)?;
            let deadline = Instant::now() + m.config.state_timeout;
            for k in 0..m.devices.len() {
                m.al_control(
                    k,
                    crate::proto::ecat::al::AlControl::request(AlState::Op),
                    deadline,
                )
                .map_err(|e| to_error(OP, e))?;
            }
        }
        let deadline = Instant::now() + self.config.master.state_timeout;
        loop {
            match self.cycle_paced(OP, &mut next) {
                Ok(()) => break,
                Err(e) if Instant::now() >= deadline => return Err(to_error(OP, e)),
                Err(_) => {}
            }
        }
        // Walk every drive to operation enabled.
        let deadline = Instant::now() + self.config.enable_timeout;
        let mut previous = vec![0u16; self.drives.len()];
        loop {
            let mut all = true;
            for (k, prev) in previous.iter_mut().enumerate() {
                let sw = self.statusword(k).map_or(0, |s| s.0);
                let state = PowerState::from_statusword(sw);
                let cw = match state.and_then(|s| s.next_command(Goal::OperationEnabled)) {
                    None if state == Some(PowerState::OperationEnabled) => {
                        Controlword::hold(PowerState::OperationEnabled).0
                    }
                    None => 0,
                    Some(DriveCommand::FaultReset) if *prev & 0x80 != 0 => 0,
                    Some(c) => c.bits(),
                };
                if state != Some(PowerState::OperationEnabled) {
                    all = false;
                }
                *prev = cw;
                self.hold_axis(k, cw);
            }
            if all {
                break;
            }
            if Instant::now() >= deadline {
                let k = (0..self.drives.len())
                    .find(|&k| {
                        self.statusword(k).and_then(|s| s.state())
                            != Some(PowerState::OperationEnabled)
                    })
                    .unwrap_or(0);
                return Err(Error::device(
                    OP,
                    "CiA 402 statusword",
                    &self.drive_fault(k),
                ));
            }
            if let Err(e) = self.cycle_paced(OP, &mut next) {
                if Instant::now() >= deadline {
                    return Err(to_error(OP, e));
                }
            }
        }
        Ok(())
    }

    // ---- step -------------------------------------------------------------------------------

    fn period(&self) -> Duration {
        self.config.period
    }

    fn exchange(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Step;
        let timeout = self.config.frame_timeout.min(self.config.period);
        let (Some(m), Some(p)) = (self.master.as_mut(), self.process.as_mut()) else {
            return Err(Error::State {
                operation: OP,
                state: State::Closed,
            });
        };
        p.exchange(&mut m.link, Instant::now() + timeout)
            .map_err(|e| match e {
                EcError::Timeout { .. } => Error::Timeout {
                    operation: OP,
                    waited: timeout,
                },
                e => to_error(OP, e),
            })?;
        for k in 0..self.drives.len() {
            let d = &self.drives[k];
            let sw = get_u16(p.inputs_of(d.part), d.at.statusword);
            if PowerState::from_statusword(sw) != Some(PowerState::OperationEnabled) {
                self.counters.drive_faults += 1;
                return Err(Error::device(
                    OP,
                    "CiA 402 statusword",
                    &self.drive_fault(k),
                ));
            }
        }
        Ok(())
    }

    // ---- stop -------------------------------------------------------------------------------

    fn stop_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Stop;
        let mut steps = FirstError::default();
        if self.process.is_some() && self.master.is_some() {
            // Drives to rest: disable operation, shutdown, disable voltage; each bounded.
            let mut next = Instant::now();
            for (cw, done) in [
                (DriveCommand::SwitchOn.bits(), PowerState::SwitchedOn),
                (DriveCommand::Shutdown.bits(), PowerState::ReadyToSwitchOn),
                (
                    DriveCommand::DisableVoltage.bits(),
                    PowerState::SwitchOnDisabled,
                ),
            ] {
                let deadline = Instant::now() + self.config.stop_timeout / 3;
                let mut last_error = None;
                loop {
                    for k in 0..self.drives.len() {
                        let s = self.statusword(k).and_then(|s| s.state());
                        // A drive already further down is left alone.
                        let further = matches!(
                            s,
                            Some(
                                PowerState::SwitchOnDisabled
                                    | PowerState::Fault
                                    | PowerState::NotReadyToSwitchOn
                            )
                        ) || (done == PowerState::ReadyToSwitchOn
                            && s == Some(PowerState::ReadyToSwitchOn));
                        self.hold_axis(k, if further { 0 } else { cw });
                    }
                    match self.cycle_paced(OP, &mut next) {
                        Ok(())
                        | Err(EcError::WorkingCounter { .. })
                        | Err(EcError::AlStatus { .. }) => {}
                        Err(e) => last_error = Some(e),
                    }
                    let reached = (0..self.drives.len()).all(|k| {
                        let s = self.statusword(k).and_then(|s| s.state());
                        !s.is_some_and(|s| s.is_powered()) && s != Some(PowerState::SwitchedOn)
                            || s == Some(done)
                    });
                    if reached {
                        break;
                    }
                    if Instant::now() >= deadline {
                        let k = (0..self.drives.len())
                            .find(|&k| self.statusword(k).and_then(|s| s.state()) != Some(done))
                            .unwrap_or(0);
                        steps.keep(Err(match last_error {
                            Some(e) => to_error(OP, e),
                            None => Error::device(OP, "CiA 402 statusword", &self.drive_fault(k)),
                        }));
                        break;
                    }
                }
            }
        }
        if let Some(m) = self.master.as_mut() {
            let all: Vec<usize> = (0..m.devices.len()).collect();
            for target in [AlState::SafeOp, AlState::PreOp] {
                steps.keep(
                    m.request_state(&all, target, |_| Ok(()))
                        .map_err(|e| to_error(OP, e)),
                );
            }
        }
        if let Some(p) = self.process.as_mut() {
            p.target = AlState::PreOp;
        }
        steps.into_result()
    }

    // ---- close ------------------------------------------------------------------------------

    fn close_sequence(&mut self) -> Result<(), Error> {
        let stats = self.link_statistics();
        let r = match self.master.as_mut() {
            Some(m) => {
                let all: Vec<usize> = (0..m.devices.len()).collect();
                m.request_state(&all, AlState::Init, |_| Ok(()))
                    .map_err(|e| to_error(Operation::Close, e))
            }
            None => Ok(()),
        };
        self.link_before = stats;
        self.master = None;
        self.process = None;
        r
    }
}

impl_cyclic_device!(EthercatDrives, lifecycle);

impl LinkStatisticsSensor for EthercatDrives {
    fn link_statistics(&self) -> LinkStatistics {
        let mut s = self.link_before;
        if let Some(m) = &self.master {
            let c = m.link.counters();
            s.sent = s.sent.max(self.link_before.sent) + c.sent;
            s.received += c.received;
            s.lost += c.lost;
            s.late += c.late;
            s.rejected += c.echo + c.foreign + c.unmatched;
            s.corrupt += c.corrupt;
        }
        if let Some(p) = &self.process {
            s.corrupt += p.counters.wkc_errors;
        }
        s.consecutive_failures = self.lifecycle.consecutive_failures();
        s
    }
}

impl JointDevice for EthercatDrives {
    fn dof(&self) -> usize {
        self.drives.len()
    }

    fn torque_feed_forward(&mut self) -> Option<&mut dyn JointTorqueFeedForward<Error = Error>> {
        (self.drives.iter().all(|d| d.at.torque_offset.is_some())
            && matches!(
                self.config.mode,
                Mode::CyclicPosition | Mode::CyclicVelocity
            ))
        .then_some(self as &mut dyn JointTorqueFeedForward<Error = Error>)
    }

    fn joint_limit_sensor(&self) -> Option<&dyn JointLimitSensor<Error = Error>> {
        Some(self)
    }
}

impl JointPositionSensor for EthercatDrives {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        self.read_inputs(q, |d, i| Some(d.units.position(get_i32(i, d.at.position))))
    }

    /// Half an encoder count at the joint.
    fn joint_position_resolution(&self, _q: f64) -> f64 {
        self.drives
            .iter()
            .map(|d| d.units.position_resolution())
            .fold(0.0, f64::max)
    }
}

impl JointPositionActuator for EthercatDrives {
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Error> {
        self.check_mode(Mode::CyclicPosition, q.len())?;
        self.write_outputs(q, |d, out, v| match d.at.target_position {
            Some(at) => {
                write_i32(out, at, d.units.position_counts(v));
                true
            }
            None => false,
        })
    }
}

impl JointVelocitySensor for EthercatDrives {
    fn joint_velocity(&self, qd: &mut [f64]) -> Result<(), Error> {
        self.read_inputs(qd, |d, i| {
            d.at.velocity.map(|at| d.units.velocity(get_i32(i, at)))
        })
    }
}

impl JointVelocityActuator for EthercatDrives {
    fn set_joint_velocity(&mut self, qd: &[f64]) -> Result<(), Error> {
        self.check_mode(Mode::CyclicVelocity, qd.len())?;
        self.write_outputs(qd, |d, out, v| match d.at.target_velocity {
            Some(at) => {
                write_i32(out, at, d.units.velocity_counts(v));
                true
            }
            None => false,
        })
    }
}

impl JointTorqueSensor for EthercatDrives {
    fn joint_torque(&self, tau: &mut [f64]) -> Result<(), Error> {
        self.read_inputs(tau, |d, i| {
            d.at.torque.map(|at| d.units.torque(get_u16(i, at) as i16))
        })
    }
}

impl JointTorqueActuator for EthercatDrives {
    fn set_joint_torque(&mut self, tau: &[f64]) -> Result<(), Error> {
        self.check_mode(Mode::CyclicTorque, tau.len())?;
        self.write_outputs(tau, |d, out, v| match d.at.target_torque {
            Some(at) => {
                write_u16(out, at, d.units.torque_permille(v) as u16);
                true
            }
            None => false,
        })
    }
}

impl JointTorqueFeedForward for EthercatDrives {
    fn set_joint_torque_feed_forward(&mut self, tau: &[f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        Error::check_len("joint vector length", self.drives.len(), tau.len())?;
        self.write_outputs(tau, |d, out, v| match d.at.torque_offset {
            Some(at) => {
                write_u16(out, at, d.units.torque_permille(v) as u16);
                true
            }
            None => false,
        })
    }
}

impl JointLimitSensor for EthercatDrives {
    fn joint_limit_reached(&self, reached: &mut [bool]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", self.drives.len(), reached.len())?;
        for (k, r) in reached.iter_mut().enumerate() {
            *r = self.statusword(k).is_some_and(|s| s.internal_limit());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn objects_are_located_in_a_mapping() {
        let rx = rx_mapping();
        assert_eq!(locate(&rx, obj::CONTROLWORD), Some(0));
        assert_eq!(locate(&rx, obj::TARGET_POSITION), Some(2));
        assert_eq!(locate(&rx, obj::MODES_OF_OPERATION), Some(14));
        assert_eq!(bytes(&rx), 15);
        // Not byte-aligned: refused.
        let odd = [Entry::new(0x7000, 1, 1), obj::STATUSWORD.entry()];
        assert_eq!(locate(&odd, obj::STATUSWORD), None);
        let at = offsets(&rx, &tx_mapping()).unwrap();
        assert_eq!(
            (at.statusword, at.position, at.error_code),
            (0, 2, Some(12))
        );
        assert!(offsets(&rx[1..], &tx_mapping()).is_none());
    }
}
