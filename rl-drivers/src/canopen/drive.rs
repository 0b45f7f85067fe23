//! The [`Cia402`] device: CiA 402 drives on one CANopen bus as one cyclic device.
//!
//! Session:
//! - `open`: connect the bus; per node NMT "enter pre-operational", then by SDO the device
//!   type (0x1000, must be profile 402), the identity (0x1018), the supported drive modes
//!   (0x6502, must include the configured mode), the units — position encoder resolution
//!   (0x608F), gear ratio (0x6091), feed constant (0x6092) and motor rated torque (0x6076),
//!   each unless the configuration gives it; a node that cannot give one is refused with
//!   [`CanopenError::Units`] naming the object — and the position (0x6064): so `dof()` and
//!   `joint_position()` are right, in joint units, before anything is enabled.
//! - `start`: per node by SDO, checked against the EDS when one is configured: all PDOs
//!   disabled; RPDO1 and TPDO1 (and TPDO2 for velocity feedback) mapped and set to
//!   synchronous (transmission type 1), then enabled; the mode (0x6060, confirmed in 0x6061),
//!   the interpolation period (0x60C2) and the communication cycle period (0x1006), the
//!   heartbeat producer time (0x1017). Then NMT start, and SYNC/PDO cycles at the period
//!   walk each drive's power state machine to operation enabled (fault reset on a rising edge
//!   if configured), holding the target at the actual position; each transition bounded by
//!   `transition_timeout` — a drive stuck in a state is [`CanopenError::Stuck`], naming it.
//! - `step`: drain what arrived since the last step (late TPDOs are counted and dropped; EMCY
//!   and heartbeats are taken); send SYNC then each RPDO as one flush (one datagram on
//!   cannelloni UDP); wait until every TPDO of this SYNC is in or `tpdo_timeout` passes. A
//!   drive in fault faults the device at once; lost TPDOs, EMCY, lost heartbeats, following
//!   errors and bad frames are counted and make the step fail, and `max_consecutive_failures`
//!   failed steps in a row fault the device.
//! - `stop` (from running or faulted; every part attempted, each bounded): quick stop, then
//!   disable voltage until each drive is switch on disabled (or in fault: power off either
//!   way), then NMT "enter pre-operational". SDO and power transitions are not real-time and
//!   run only in open, start and stop.
//! - `close`: drop the bus.
//!
//! `step` allocates nothing and waits at most `tpdo_timeout` (plus the send).

use std::time::{Duration, Instant};

use super::config::{Cia402Config, MAX_AXES};
use super::error::CanopenError;
use crate::capability::{
    Delivery, JointDevice, JointLimitSensor, JointPositionActuator, JointPositionSensor,
    JointTorqueActuator, JointTorqueFeedForward, JointTorqueSensor, JointVelocityActuator,
    JointVelocitySensor, LinkStatistics, LinkStatisticsSensor,
};
use crate::cia402::state::Goal;
use crate::cia402::{
    AxisUnits, Command, Controlword, Mode, PowerState, Statusword, UnitsError, object as obj,
};
use crate::device::{Driver, Error, FirstError, Lifecycle, Operation, State, impl_cyclic_device};
use crate::proto::can::Frame;
use crate::proto::canopen::emcy::Emergency;
use crate::proto::canopen::pdo::{self, Direction, Field, Mapping};
use crate::proto::canopen::sdo::{AbortCode, Address};
use crate::proto::canopen::sdo_client::{self, Next, SdoError};
use crate::proto::canopen::{Function, NodeId, heartbeat, nmt, sync};
use crate::transport::can::{CanTransport, TransportCounters};

/// What the device has seen, beyond the generic link statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cia402Counters {
    /// SYNCs sent.
    pub syncs: u64,
    /// RPDOs sent.
    pub rpdos: u64,
    /// TPDOs received in time and used.
    pub tpdos: u64,
    /// TPDOs missing at their cycle's deadline.
    pub tpdos_lost: u64,
    /// TPDOs that came after their cycle's deadline (dropped).
    pub tpdos_late: u64,
    /// Emergency messages with an error code (not counting error resets).
    pub emcy: u64,
    /// Heartbeats lost (each loss counted once until the node is heard again).
    pub heartbeats_lost: u64,
    /// Cycles in which a drive signalled a following error.
    pub following_errors: u64,
    /// Cycles in which a drive set its warning bit.
    pub warnings: u64,
    /// Drive faults seen.
    pub drive_faults: u64,
    /// SDO transfers completed.
    pub sdo_transfers: u64,
    /// SDO transfers aborted (by either side) or timed out.
    pub sdo_failures: u64,
    /// Frames for nobody here (another master's, unknown COB-IDs, unasked SDO answers).
    pub rejected: u64,
    /// Frames of the wrong length or form (TPDO, EMCY, heartbeat).
    pub corrupt: u64,
    /// Commands beyond what the drive units can carry (a torque above ±32 767 ‰ of the rated
    /// torque, a position beyond ±2³¹ counts), sent clamped.
    pub commands_clamped: u64,
}

/// What `open` learned about a node.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodeReport {
    /// The node id.
    pub node: u8,
    /// 0x1000 device type.
    pub device_type: u32,
    /// 0x1018 vendor id, product code, revision, serial number (0 where the node has none).
    pub identity: [u32; 4],
    /// 0x6502 supported drive modes.
    pub supported_modes: u32,
    /// The units in use: read from the node (0x608F, 0x6091, 0x6092, 0x6076) where the
    /// configuration gives none.
    pub units: AxisUnits,
}

#[derive(Clone, Copy, Debug)]
struct Axis {
    node: NodeId,
    statusword: u16,
    state: Option<PowerState>,
    position: i32,
    velocity: i32,
    torque: i16,
    target_position: i32,
    target_velocity: i32,
    target_torque: i16,
    torque_offset: i16,
    controlword: u16,
    fresh1: bool,
    fresh2: bool,
    emcy: Option<Emergency>,
    heartbeat: Option<Instant>,
    heartbeat_lost: bool,
    /// The units in use (known from `open`).
    units: AxisUnits,
    report: NodeReport,
}

impl Axis {
    fn new(node: NodeId) -> Self {
        Self {
            node,
            statusword: 0,
            state: None,
            position: 0,
            velocity: 0,
            torque: 0,
            target_position: 0,
            target_velocity: 0,
            target_torque: 0,
            torque_offset: 0,
            controlword: 0,
            fresh1: false,
            fresh2: false,
            emcy: None,
            heartbeat: None,
            heartbeat_lost: false,
            units: AxisUnits::default(),
            report: NodeReport {
                node: node.get(),
                ..NodeReport::default()
            },
        }
    }
}

/// Where each mapped object lands in the PDOs.
#[derive(Clone, Copy, Debug)]
struct Layout {
    rpdo: Mapping,
    tpdo1: Mapping,
    tpdo2: Option<Mapping>,
    controlword: Option<Field>,
    target: Option<Field>,
    torque_offset: Option<Field>,
    statusword: Option<Field>,
    position: Option<Field>,
    torque: Option<Field>,
    velocity: Option<Field>,
}

impl Layout {
    fn new(c: &Cia402Config) -> Self {
        let rpdo = c.rpdo_mapping();
        let tpdo1 = c.tpdo1_mapping();
        let tpdo2 = c.tpdo2_mapping();
        let target = match c.mode {
            Mode::CyclicVelocity => obj::TARGET_VELOCITY,
            Mode::CyclicTorque => obj::TARGET_TORQUE,
            _ => obj::TARGET_POSITION,
        };
        let at = |m: &Mapping, o: obj::Object| m.locate(o.index, o.sub);
        Self {
            controlword: at(&rpdo, obj::CONTROLWORD),
            target: at(&rpdo, target),
            torque_offset: at(&rpdo, obj::TORQUE_OFFSET),
            statusword: at(&tpdo1, obj::STATUSWORD),
            position: at(&tpdo1, obj::POSITION_ACTUAL),
            torque: at(&tpdo1, obj::TORQUE_ACTUAL),
            velocity: tpdo2.and_then(|m| at(&m, obj::VELOCITY_ACTUAL)),
            rpdo,
            tpdo1,
            tpdo2,
        }
    }
}

/// CiA 402 drives on one CANopen bus, as one cyclic device with joint position, velocity and
/// torque sensors and actuators.
pub struct Cia402 {
    config: Cia402Config,
    lifecycle: Lifecycle,
    link: Option<Box<dyn CanTransport>>,
    axes: [Axis; MAX_AXES],
    dof: usize,
    layout: Layout,
    sdo: sdo_client::Client,
    counters: Cia402Counters,
    /// Transport counts of links closed since (the counts survive `close`).
    transport_before: TransportCounters,
    /// The first problem the frames of this cycle reported.
    pending: Option<(&'static str, CanopenError)>,
    sync_sent: Instant,
}

impl std::fmt::Debug for Cia402 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cia402")
            .field("bus", &self.config.bus)
            .field("dof", &self.dof)
            .field("state", &self.lifecycle.state())
            .finish_non_exhaustive()
    }
}

fn invalid(what: &'static str, expected: usize, got: usize) -> Error {
    Error::InvalidArgument {
        what,
        expected,
        got,
    }
}

impl Cia402 {
    /// A closed device; checks the configuration and that the cycle fits the bus.
    pub fn new(config: Cia402Config) -> Result<Self, Error> {
        let n = config.axes.len();
        if n == 0 || n > MAX_AXES {
            return Err(invalid("axes (1..=8)", MAX_AXES, n));
        }
        let mut axes = [Axis::new(NODE_1); MAX_AXES];
        for (k, a) in config.axes.iter().enumerate() {
            let node = NodeId::new(a.node).ok_or(invalid(
                "node id (1..=127)",
                127,
                usize::from(a.node),
            ))?;
            if config.axes[..k].iter().any(|b| b.node == a.node) {
                return Err(invalid(
                    "node ids must differ (duplicate id)",
                    0,
                    usize::from(a.node),
                ));
            }
            let u = a.units;
            let given = [
                u.counts_per_rev,
                u.gear_ratio,
                u.feed,
                u.rated_torque_nm,
                u.lead_m,
            ];
            if given
                .into_iter()
                .flatten()
                .any(|v| !(v.is_finite() && v > 0.0))
            {
                return Err(invalid("axis units given (positive, finite; axis)", k, k));
            }
            axes[k] = Axis::new(node);
        }
        if !matches!(
            config.mode,
            Mode::CyclicPosition | Mode::CyclicVelocity | Mode::CyclicTorque
        ) {
            return Err(invalid(
                "mode (8 CSP, 9 CSV or 10 CST)",
                8,
                config.mode.code() as usize,
            ));
        }
        let load = config.bus_load();
        if !load.fits(config.period) {
            return Err(Error::protocol(
                Operation::Open,
                "CAN bus budget",
                &BudgetError {
                    load,
                    period: config.period,
                },
            ));
        }
        Ok(Self {
            layout: Layout::new(&config),
            lifecycle: Lifecycle::with_failure_limit(config.max_consecutive_failures),
            config,
            link: None,
            axes,
            dof: n,
            sdo: sdo_client::Client::new(),
            counters: Cia402Counters::default(),
            transport_before: TransportCounters::default(),
            pending: None,
            sync_sent: Instant::now(),
        })
    }

    /// A closed device that will use `link` instead of opening its configured address (an
    /// in-process bus in tests, or a recording wrapper). It is used by the next `open`.
    pub fn with_transport(
        config: Cia402Config,
        link: Box<dyn CanTransport>,
    ) -> Result<Self, Error> {
        let mut d = Self::new(config)?;
        d.link = Some(link);
        Ok(d)
    }

    /// The configuration.
    pub fn config(&self) -> &Cia402Config {
        &self.config
    }

    /// The counts so far.
    pub fn counters(&self) -> Cia402Counters {
        self.counters
    }

    /// What `open` read from each node.
    pub fn node_reports(&self) -> impl Iterator<Item = NodeReport> + '_ {
        self.axes[..self.dof].iter().map(|a| a.report)
    }

    /// Each drive's last power state (`None` before a statusword arrived).
    pub fn power_states(&self) -> [Option<PowerState>; MAX_AXES] {
        let mut s = [None; MAX_AXES];
        for (d, a) in s.iter_mut().zip(&self.axes[..self.dof]) {
            *d = a.state;
        }
        s
    }

    /// Each drive's last statusword.
    pub fn statuswords(&self) -> [u16; MAX_AXES] {
        let mut s = [0; MAX_AXES];
        for (d, a) in s.iter_mut().zip(&self.axes[..self.dof]) {
            *d = a.statusword;
        }
        s
    }

    /// The last emergency message of each node.
    pub fn emergencies(&self) -> [Option<Emergency>; MAX_AXES] {
        let mut s = [None; MAX_AXES];
        for (d, a) in s.iter_mut().zip(&self.axes[..self.dof]) {
            *d = a.emcy;
        }
        s
    }

    /// The transport's counts (this link's and those of links closed since).
    pub fn transport_counters(&self) -> TransportCounters {
        let mut c = self.transport_before;
        if let Some(l) = &self.link {
            c += l.counters();
        }
        c
    }

    // ---- frames ----------------------------------------------------------------------------

    fn link(&mut self, op: Operation) -> Result<&mut Box<dyn CanTransport>, Error> {
        self.link.as_mut().ok_or(Error::State {
            operation: op,
            state: State::Closed,
        })
    }

    fn send(&mut self, op: Operation, frame: &Frame) -> Result<(), Error> {
        self.link(op)?.send(frame).map_err(|e| Error::io(op, &e))
    }

    fn flush(&mut self, op: Operation) -> Result<(), Error> {
        let deadline = Instant::now() + self.config.period / 2;
        self.link(op)?
            .flush(deadline)
            .map_err(|e| Error::io(op, &e))
    }

    fn axis_of(&self, node: NodeId) -> Option<usize> {
        self.axes[..self.dof].iter().position(|a| a.node == node)
    }

    /// The axis of `node`; `None` for a node not on our list, whose frame is counted rejected.
    fn axis_or_reject(&mut self, node: NodeId) -> Option<usize> {
        let i = self.axis_of(node);
        if i.is_none() {
            self.counters.rejected += 1;
        }
        i
    }

    fn note(&mut self, source: &'static str, e: CanopenError) {
        if self.pending.is_none() {
            self.pending = Some((source, e));
        }
    }

    /// Takes one received frame. `in_cycle`: TPDOs are this cycle's (else they are late).
    /// Returns the SDO answer if it is from `sdo_node`.
    fn dispatch(
        &mut self,
        frame: &Frame,
        in_cycle: bool,
        sdo_node: Option<NodeId>,
    ) -> Option<[u8; 8]> {
        let Some(id) = frame.standard_id() else {
            self.counters.rejected += 1;
            return None;
        };
        let data = frame.bytes();
        match Function::from_cob_id(id) {
            Some(Function::Tpdo(k @ (1 | 2), node)) => {
                let i = self.axis_or_reject(node)?;
                let mapping = if k == 1 {
                    Some(self.layout.tpdo1)
                } else {
                    self.layout.tpdo2
                };
                let Some(mapping) = mapping else {
                    self.counters.rejected += 1;
                    return None;
                };
                if data.len() != mapping.len() {
                    self.counters.corrupt += 1;
                    self.note(
                        "PDO",
                        CanopenError::TpdoLength {
                            node: node.get(),
                            len: data.len(),
                            expected: mapping.len(),
                        },
                    );
                    return None;
                }
                let axis = &mut self.axes[i];
                let fresh = if k == 1 {
                    &mut axis.fresh1
                } else {
                    &mut axis.fresh2
                };
                if !in_cycle || *fresh {
                    self.counters.tpdos_late += 1;
                    return None;
                }
                *fresh = true;
                self.counters.tpdos += 1;
                let l = &self.layout;
                if k == 1 {
                    if let Some(v) = l.statusword.and_then(|f| f.get_unsigned(data)) {
                        axis.statusword = v as u16;
                        axis.state = PowerState::from_statusword(axis.statusword);
                    }
                    if let Some(v) = l.position.and_then(|f| f.get_signed(data)) {
                        axis.position = v as i32;
                    }
                    if let Some(v) = l.torque.and_then(|f| f.get_signed(data)) {
                        axis.torque = v as i16;
                    }
                } else if let Some(v) = l.velocity.and_then(|f| f.get_signed(data)) {
                    axis.velocity = v as i32;
                }
            }
            Some(Function::Emcy(node)) => {
                let i = self.axis_or_reject(node)?;
                match Emergency::decode(data) {
                    Ok(e) => {
                        self.axes[i].emcy = Some(e);
                        if !e.is_reset() {
                            self.counters.emcy += 1;
                            self.note(
                                "EMCY",
                                CanopenError::Emergency {
                                    node: node.get(),
                                    emcy: e,
                                },
                            );
                        }
                    }
                    Err(_) => self.counters.corrupt += 1,
                }
            }
            Some(Function::Heartbeat(node)) => {
                let i = self.axis_or_reject(node)?;
                match heartbeat::decode(data) {
                    Some(state) => {
                        let a = &mut self.axes[i];
                        a.heartbeat = Some(Instant::now());
                        a.heartbeat_lost = false;
                        if state == nmt::State::BootUp && self.lifecycle.state() == State::Running {
                            self.note(
                                "NMT",
                                CanopenError::NmtState {
                                    node: node.get(),
                                    state,
                                },
                            );
                        }
                    }
                    None => self.counters.corrupt += 1,
                }
            }
            Some(Function::SdoTx(node)) if Some(node) == sdo_node => {
                let mut b = [0u8; 8];
                if data.len() == 8 {
                    b.copy_from_slice(data);
                    return Some(b);
                }
                self.counters.corrupt += 1;
            }
            _ => self.counters.rejected += 1,
        }
        None
    }

    /// Takes everything already received, without waiting.
    fn drain(&mut self, op: Operation) -> Result<(), Error> {
        let now = Instant::now();
        while let Some(r) = self.link(op)?.recv(now).map_err(|e| Error::io(op, &e))? {
            self.dispatch(&r.frame, false, None);
        }
        Ok(())
    }

    /// One SYNC cycle: drain, SYNC + RPDOs in one flush, TPDOs until all are in or the
    /// deadline. Returns the TPDOs missing.
    fn cycle(&mut self, op: Operation) -> Result<u32, Error> {
        self.drain(op)?;
        for a in &mut self.axes[..self.dof] {
            a.fresh1 = false;
            a.fresh2 = false;
        }
        self.send(op, &sync::frame(None))?;
        self.counters.syncs += 1;
        let l = self.layout;
        let mode = self.config.mode;
        for k in 0..self.dof {
            let a = &self.axes[k];
            let mut data = [0u8; 8];
            if let Some(f) = l.controlword {
                f.put(&mut data, i64::from(a.controlword));
            }
            if let Some(f) = l.target {
                f.put(
                    &mut data,
                    match mode {
                        Mode::CyclicVelocity => i64::from(a.target_velocity),
                        Mode::CyclicTorque => i64::from(a.target_torque),
                        _ => i64::from(a.target_position),
                    },
                );
            }
            if let Some(f) = l.torque_offset {
                f.put(&mut data, i64::from(a.torque_offset));
            }
            let id = Function::Rpdo(1, a.node).cob_id();
            let frame =
                Frame::standard(id, &data[..l.rpdo.len()]).unwrap_or_else(|| sync::frame(None));
            self.send(op, &frame)?;
            self.counters.rpdos += 1;
        }
        self.flush(op)?;
        self.sync_sent = Instant::now();
        let deadline = self.sync_sent + self.tpdo_wait();
        let want2 = l.tpdo2.is_some();
        loop {
            let done = self.axes[..self.dof]
                .iter()
                .all(|a| a.fresh1 && (a.fresh2 || !want2));
            if done {
                return Ok(0);
            }
            match self
                .link(op)?
                .recv(deadline)
                .map_err(|e| Error::io(op, &e))?
            {
                Some(r) => {
                    self.dispatch(&r.frame, true, None);
                }
                None => break,
            }
        }
        let mut missing = 0;
        let mut first = None;
        for a in &self.axes[..self.dof] {
            let m = u32::from(!a.fresh1) + u32::from(want2 && !a.fresh2);
            if m > 0 && first.is_none() {
                first = Some(a.node.get());
            }
            missing += m;
        }
        self.counters.tpdos_lost += u64::from(missing);
        if let Some(node) = first {
            self.note(
                "PDO",
                CanopenError::TpdoLost {
                    count: missing,
                    node,
                },
            );
        }
        Ok(missing)
    }

    // ---- SDO -------------------------------------------------------------------------------

    /// Runs one SDO transfer with axis `k`'s node: `Err` for a transport failure, `Ok(Err)`
    /// for a failed transfer (aborted by either side, or timed out).
    fn sdo_run(
        &mut self,
        op: Operation,
        k: usize,
        first: [u8; 8],
    ) -> Result<Result<(), SdoError>, Error> {
        let node = self.axes[k].node;
        let rx = Function::SdoRx(node).cob_id();
        let mut message = first;
        loop {
            self.send(op, &sdo_frame(rx, message))?;
            self.flush(op)?;
            let deadline = Instant::now() + self.config.sdo_timeout;
            let answer = loop {
                match self
                    .link(op)?
                    .recv(deadline)
                    .map_err(|e| Error::io(op, &e))?
                {
                    Some(r) => {
                        if let Some(b) = self.dispatch(&r.frame, false, Some(node)) {
                            break Some(b);
                        }
                    }
                    None => break None,
                }
            };
            let outcome = match answer {
                Some(b) => self.sdo.on_response(&b),
                None => Err(self.sdo.timeout()),
            };
            match outcome {
                Ok(Next::Send(m)) => message = m,
                Ok(Next::Done) => {
                    self.counters.sdo_transfers += 1;
                    return Ok(Ok(()));
                }
                Err(f) => {
                    self.counters.sdo_failures += 1;
                    if let Some(abort) = f.send {
                        self.send(op, &sdo_frame(rx, abort))?;
                        self.flush(op)?;
                    }
                    return Ok(Err(f.error));
                }
            }
        }
    }

    fn sdo_error(&self, op: Operation, k: usize, error: SdoError) -> Error {
        Error::device(
            op,
            "SDO",
            &CanopenError::Sdo {
                node: self.axes[k].node.get(),
                error,
            },
        )
    }

    fn eds_check(
        &self,
        op: Operation,
        k: usize,
        check: impl FnOnce(
            &crate::proto::canopen::eds::Eds,
        ) -> Result<(), crate::proto::canopen::eds::CheckError>,
    ) -> Result<(), Error> {
        if let Some(eds) = &self.config.eds {
            check(eds).map_err(|error| {
                Error::protocol(
                    op,
                    "EDS",
                    &CanopenError::Eds {
                        node: self.axes[k].node.get(),
                        error,
                    },
                )
            })?;
        }
        Ok(())
    }

    /// Reads `index:sub` of axis `k` (at most 8 bytes, zero-extended, little-endian).
    fn sdo_read(&mut self, op: Operation, k: usize, index: u16, sub: u8) -> Result<u64, Error> {
        self.eds_check(op, k, |e| e.check_read(index, sub))?;
        let first = self.sdo.upload(Address::new(index, sub));
        self.sdo_run(op, k, first)?
            .map_err(|e| self.sdo_error(op, k, e))?;
        let d = self.sdo.data();
        let mut b = [0u8; 8];
        let n = d.len().min(8);
        b[..n].copy_from_slice(&d[..n]);
        Ok(u64::from_le_bytes(b))
    }

    /// Reads `index:sub` of axis `k` without the EDS check: `Ok(Err)` when the node refuses
    /// or does not answer.
    fn sdo_read_raw(
        &mut self,
        op: Operation,
        k: usize,
        index: u16,
        sub: u8,
    ) -> Result<Result<u64, SdoError>, Error> {
        let first = self.sdo.upload(Address::new(index, sub));
        if let Err(e) = self.sdo_run(op, k, first)? {
            return Ok(Err(e));
        }
        let d = self.sdo.data();
        let mut b = [0u8; 8];
        let n = d.len().min(8);
        b[..n].copy_from_slice(&d[..n]);
        Ok(Ok(u64::from_le_bytes(b)))
    }

    /// Axis `k`'s units: those the configuration gives, the rest read from the node (the node
    /// itself says whether it has the objects: the EDS is not asked). A node that cannot give
    /// one is refused, naming the object.
    fn read_units(&mut self, op: Operation, k: usize) -> Result<AxisUnits, Error> {
        let given = self.config.axes[k].units;
        let mut read = [None; 8];
        for (slot, o) in read.iter_mut().zip(given.objects_to_read()) {
            let r = self.sdo_read_raw(op, k, o.index, o.sub)?;
            let failed = r.is_err();
            *slot = Some((o, r));
            if failed {
                break;
            }
        }
        given
            .resolve(|o| {
                read.iter()
                    .flatten()
                    .find(|(r, _)| *r == o)
                    .map_or(Err(SdoError::Idle), |(_, r)| *r)
            })
            .map_err(|error: UnitsError<SdoError>| {
                Error::device(
                    op,
                    "CiA 402 units",
                    &CanopenError::Units {
                        node: self.axes[k].node.get(),
                        error,
                    },
                )
            })
    }

    fn sdo_write_raw(
        &mut self,
        op: Operation,
        k: usize,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<Result<(), SdoError>, Error> {
        let first = match self.sdo.download(Address::new(index, sub), data) {
            Ok(first) => first,
            Err(e) => return Ok(Err(e)),
        };
        self.sdo_run(op, k, first)
    }

    fn sdo_write(
        &mut self,
        op: Operation,
        k: usize,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), Error> {
        self.eds_check(op, k, |e| e.check_write(index, sub, data.len()))?;
        self.sdo_write_raw(op, k, index, sub, data)?
            .map_err(|e| self.sdo_error(op, k, e))
    }

    /// Writes an object a drive may lack: without an EDS to tell, a node that answers "no such
    /// object" or "no such sub-index" is fine.
    fn sdo_write_optional(
        &mut self,
        op: Operation,
        k: usize,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), Error> {
        if let Some(eds) = &self.config.eds {
            if eds.sub(index, sub).is_err() {
                return Ok(());
            }
            return self.sdo_write(op, k, index, sub, data);
        }
        match self.sdo_write_raw(op, k, index, sub, data)? {
            Ok(()) => Ok(()),
            Err(SdoError::Aborted { code, .. })
                if code == AbortCode::NO_OBJECT || code == AbortCode::NO_SUB_INDEX =>
            {
                Ok(())
            }
            Err(e) => Err(self.sdo_error(op, k, e)),
        }
    }

    // ---- open / start / stop ---------------------------------------------------------------

    fn nmt(&mut self, op: Operation, command: nmt::Command) -> Result<(), Error> {
        for k in 0..self.dof {
            let node = self.axes[k].node;
            self.send(op, &command.frame(Some(node)))?;
        }
        self.flush(op)
    }

    fn configure_pdo(
        &mut self,
        op: Operation,
        k: usize,
        direction: Direction,
        number: u16,
        mapping: Option<Mapping>,
    ) -> Result<(), Error> {
        let node = self.axes[k].node;
        let cob = match direction {
            Direction::Rpdo => Function::Rpdo(number as u8, node).cob_id(),
            Direction::Tpdo => Function::Tpdo(number as u8, node).cob_id(),
        };
        let comm = direction.comm_index(number);
        let map = direction.mapping_index(number);
        let disabled = (u32::from(cob) | pdo::COB_ID_INVALID).to_le_bytes();
        let Some(mapping) = mapping else {
            // Unused: disabled (an optional PDO the node lacks is fine).
            return self.sdo_write_optional(op, k, comm, 1, &disabled);
        };
        for e in mapping.entries() {
            self.eds_check(op, k, |eds| eds.check_mapping(direction, *e))?;
        }
        self.sdo_write(op, k, comm, 1, &disabled)?;
        self.sdo_write(op, k, comm, 2, &[pdo::TRANSMISSION_SYNC])?;
        self.sdo_write(op, k, map, 0, &[0])?;
        for (s, e) in mapping.entries().iter().enumerate() {
            self.sdo_write(op, k, map, s as u8 + 1, &e.to_u32().to_le_bytes())?;
        }
        self.sdo_write(op, k, map, 0, &[mapping.entries().len() as u8])?;
        self.sdo_write(op, k, comm, 1, &u32::from(cob).to_le_bytes())
    }

    fn configure(&mut self, op: Operation) -> Result<(), Error> {
        let period_us = u32::try_from(self.config.period.as_micros()).unwrap_or(u32::MAX);
        let mode = self.config.mode;
        let l = self.layout;
        for k in 0..self.dof {
            self.configure_pdo(op, k, Direction::Rpdo, 1, Some(l.rpdo))?;
            for n in 2..=4 {
                self.configure_pdo(op, k, Direction::Rpdo, n, None)?;
            }
            self.configure_pdo(op, k, Direction::Tpdo, 1, Some(l.tpdo1))?;
            self.configure_pdo(op, k, Direction::Tpdo, 2, l.tpdo2)?;
            for n in 3..=4 {
                self.configure_pdo(op, k, Direction::Tpdo, n, None)?;
            }
            self.sdo_write(
                op,
                k,
                obj::MODES_OF_OPERATION.index,
                0,
                &[mode.code() as u8],
            )?;
            if let Some((value, index)) = obj::interpolation_period(period_us) {
                self.sdo_write_optional(op, k, 0x60C2, 1, &[value])?;
                self.sdo_write_optional(op, k, 0x60C2, 2, &[index as u8])?;
            }
            self.sdo_write_optional(op, k, 0x1006, 0, &period_us.to_le_bytes())?;
            self.sdo_write(op, k, 0x1017, 0, &self.config.heartbeat_ms.to_le_bytes())?;
            // The drive confirms the mode in 0x6061 (possibly after a moment).
            let start = Instant::now();
            loop {
                let display = self.sdo_read(op, k, obj::MODES_DISPLAY.index, 0)? as u8 as i8;
                if display == mode.code() {
                    break;
                }
                if start.elapsed() > self.config.transition_timeout {
                    return Err(Error::device(
                        op,
                        "CiA 402",
                        &CanopenError::ModeNotTaken {
                            node: self.axes[k].node.get(),
                            mode,
                            display,
                        },
                    ));
                }
                std::thread::sleep(self.config.period);
            }
        }
        Ok(())
    }

    /// Runs SYNC cycles at the period, commanding each drive toward `goal`, until every drive
    /// is there (`done`) or one is stuck longer than the transition timeout.
    fn drive_power(
        &mut self,
        op: Operation,
        goal: Goal,
        done: fn(Option<PowerState>) -> bool,
        goal_name: &'static str,
    ) -> Result<(), Error> {
        let timeout = self.config.transition_timeout;
        let start = Instant::now();
        let mut entered = [start; MAX_AXES];
        let mut last = [None; MAX_AXES];
        for (l, a) in last.iter_mut().zip(&self.axes[..self.dof]) {
            *l = a.state;
        }
        let mut next = Instant::now();
        loop {
            for k in 0..self.dof {
                let a = &mut self.axes[k];
                let previous = a.controlword;
                let next = a
                    .state
                    .filter(|s| !done(Some(*s)))
                    .and_then(|s| s.next_command(goal));
                a.controlword = match next {
                    // The edge: bit 7 low for a cycle, then high.
                    Some(Command::FaultReset) if previous & 0x80 != 0 => 0,
                    Some(Command::FaultReset)
                        if !self.config.reset_faults_on_start && goal == Goal::OperationEnabled =>
                    {
                        return Err(Error::device(
                            op,
                            "CiA 402",
                            &CanopenError::DriveFault {
                                node: a.node.get(),
                                state: PowerState::Fault,
                                emcy: a.emcy,
                            },
                        ));
                    }
                    Some(c) => c.bits(),
                    None => a.state.map_or(0, |s| Controlword::hold(s).0),
                };
                // Hold still while the power comes on or goes off.
                a.target_position = a.position;
                a.target_velocity = 0;
                a.target_torque = 0;
                a.torque_offset = 0;
            }
            self.pending = None;
            self.cycle(op)?;
            self.pending = None;
            let now = Instant::now();
            let mut all = true;
            for k in 0..self.dof {
                let a = &self.axes[k];
                if a.state != last[k] {
                    last[k] = a.state;
                    entered[k] = now;
                }
                if done(a.state) {
                    continue;
                }
                all = false;
                if now.duration_since(entered[k]) > timeout {
                    return Err(Error::device(
                        op,
                        "CiA 402",
                        &CanopenError::Stuck {
                            node: a.node.get(),
                            state: a.state,
                            waited: timeout,
                            goal: goal_name,
                        },
                    ));
                }
            }
            if all {
                return Ok(());
            }
            next += self.config.period;
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            } else {
                next = now;
            }
        }
    }

    /// How long this step waits for its TPDOs: `tpdo_timeout`, or less if the caller said so.
    fn tpdo_wait(&self) -> Duration {
        self.lifecycle
            .step_budget()
            .map_or(self.config.tpdo_timeout, |b| {
                b.min(self.config.tpdo_timeout)
            })
    }

    fn check_mode(&self, mode: Mode, len: usize) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        if self.config.mode != mode {
            return Err(invalid(
                "command kind does not match the configured mode (code)",
                self.config.mode.code() as usize,
                mode.code() as usize,
            ));
        }
        Error::check_len("joint vector length", self.dof, len)
    }

    /// Buffers one torque per axis (in thousandths of its rated torque) into `slot`, counting
    /// the values beyond what the command holds (they are clamped).
    fn set_torques(&mut self, tau: &[f64], slot: fn(&mut Axis) -> &mut i16) {
        for (k, v) in tau.iter().enumerate() {
            let u = &self.axes[k].units;
            if (v / u.per_permille()).abs() > f64::from(i16::MAX) {
                self.counters.commands_clamped += 1;
            }
            *slot(&mut self.axes[k]) = u.torque_permille(*v);
        }
    }

    fn read_each(
        &self,
        out: &mut [f64],
        f: impl Fn(&Axis, &crate::cia402::AxisUnits) -> f64,
    ) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", self.dof, out.len())?;
        for (k, o) in out.iter_mut().enumerate() {
            let a = &self.axes[k];
            *o = f(a, &a.units);
        }
        Ok(())
    }
}

fn sdo_frame(cob: u16, message: [u8; 8]) -> Frame {
    // A COB-ID below 0x800 with 8 bytes is always a valid frame; the fallback is never taken.
    Frame::standard(cob, &message).unwrap_or_else(|| sync::frame(None))
}

const NODE_1: NodeId = match NodeId::new(1) {
    Some(n) => n,
    None => panic!("1 is a node id"),
};

/// The refusal of a cycle the bus cannot carry, with the arithmetic.
#[derive(Clone, Copy, Debug)]
struct BudgetError {
    load: super::BusLoad,
    period: Duration,
}

impl std::fmt::Display for BudgetError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // Compact; `BusLoad`'s own text says it in full, with the bits.
        let l = &self.load;
        write!(
            f,
            "{} µs cycle < {:.0} µs: {} frames at {} kbit/s",
            self.period.as_micros(),
            l.min_period().as_secs_f64() * 1e6,
            l.frames,
            l.bitrate / 1000
        )
    }
}

impl Driver for Cia402 {
    const STOP_DESCRIPTION: &'static str =
        "quick stop, power stage off (switch on disabled), NMT pre-operational";

    fn open_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Open;
        if self.link.is_none() {
            let link = self
                .config
                .bus
                .open(self.config.connect_timeout)
                .map_err(|e| Error::io(OP, &e))?;
            self.link = Some(link);
        }
        self.pending = None;
        self.nmt(OP, nmt::Command::EnterPreOperational)?;
        let mode = self.config.mode;
        for k in 0..self.dof {
            let node = self.axes[k].node.get();
            let device_type = self.sdo_read(OP, k, 0x1000, 0)? as u32;
            if device_type & 0xFFFF != 402 {
                return Err(Error::device(
                    OP,
                    "CiA 402",
                    &CanopenError::NotADrive { node, device_type },
                ));
            }
            let mut identity = [0u32; 4];
            for (s, v) in identity.iter_mut().enumerate() {
                // The vendor id is mandatory; the rest may be absent.
                match self.sdo_read(OP, k, 0x1018, s as u8 + 1) {
                    Ok(x) => *v = x as u32,
                    Err(e) if s == 0 => return Err(e),
                    Err(_) => {}
                }
            }
            let supported = self.sdo_read(OP, k, obj::SUPPORTED_DRIVE_MODES.index, 0)? as u32;
            if !mode.is_supported_by(supported) {
                return Err(Error::device(
                    OP,
                    "CiA 402",
                    &CanopenError::ModeUnsupported {
                        node,
                        mode,
                        supported,
                    },
                ));
            }
            let units = self.read_units(OP, k)?;
            let position = self.sdo_read(OP, k, obj::POSITION_ACTUAL.index, 0)? as u32 as i32;
            let sw = self.sdo_read(OP, k, obj::STATUSWORD.index, 0)? as u16;
            let a = &mut self.axes[k];
            a.units = units;
            a.report.units = units;
            a.report.device_type = device_type;
            a.report.identity = identity;
            a.report.supported_modes = supported;
            a.position = position;
            a.target_position = position;
            a.statusword = sw;
            a.state = PowerState::from_statusword(sw);
            a.velocity = 0;
            a.torque = 0;
        }
        Ok(())
    }

    fn start_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Start;
        self.pending = None;
        self.nmt(OP, nmt::Command::EnterPreOperational)?;
        self.configure(OP)?;
        self.nmt(OP, nmt::Command::Start)?;
        let now = Instant::now();
        for a in &mut self.axes[..self.dof] {
            a.heartbeat = Some(now);
            a.heartbeat_lost = false;
            a.controlword = 0;
        }
        self.drive_power(
            OP,
            Goal::OperationEnabled,
            |s| s == Some(PowerState::OperationEnabled),
            "operation enabled",
        )?;
        for a in &mut self.axes[..self.dof] {
            a.target_position = a.position;
            a.controlword = Controlword::hold(PowerState::OperationEnabled).0;
        }
        self.pending = None;
        Ok(())
    }

    fn stop_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Stop;
        let mut steps = FirstError::default();
        // Decelerate with the drives' quick stop ramp; a drive already off or in fault is safe.
        let r = self.drive_power(
            OP,
            Goal::QuickStop,
            |s| !matches!(s, Some(PowerState::OperationEnabled)),
            "quick stop",
        );
        steps.keep(r);
        let r = self.drive_power(
            OP,
            Goal::SwitchOnDisabled,
            |s| {
                matches!(
                    s,
                    Some(
                        PowerState::SwitchOnDisabled
                            | PowerState::Fault
                            | PowerState::NotReadyToSwitchOn
                    )
                )
            },
            "switch on disabled",
        );
        steps.keep(r);
        let r = self.nmt(OP, nmt::Command::EnterPreOperational);
        steps.keep(r);
        steps.into_result()
    }

    fn close_sequence(&mut self) -> Result<(), Error> {
        if let Some(l) = self.link.take() {
            self.transport_before += l.counters();
        }
        Ok(())
    }

    fn period(&self) -> Duration {
        self.config.period
    }

    /// One control cycle with the error policy.
    fn exchange(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Step;
        self.pending = None;
        self.cycle(OP)?;
        let tpdo_problem = self.pending.take();
        // Heartbeats (all received so far are taken): a node silent longer than the consumer
        // time is lost.
        let now = Instant::now();
        if self.config.heartbeat_ms > 0 {
            for k in 0..self.dof {
                let timeout = self.config.axes[k]
                    .heartbeat_timeout
                    .unwrap_or(self.config.heartbeat_timeout);
                let a = &mut self.axes[k];
                let silent = a.heartbeat.is_none_or(|t| now.duration_since(t) > timeout);
                if silent {
                    if !a.heartbeat_lost {
                        a.heartbeat_lost = true;
                        self.counters.heartbeats_lost += 1;
                    }
                    let node = a.node.get();
                    self.note("heartbeat", CanopenError::HeartbeatLost { node, timeout });
                }
            }
        }
        let heartbeat_problem = self.pending.take();
        // What the frames of this cycle reported (EMCY, lost or bad TPDOs) comes back.
        self.pending = tpdo_problem;
        // A drive in fault, or one that left operation enabled, ends the run at once.
        for k in 0..self.dof {
            let a = self.axes[k];
            let sw = Statusword(a.statusword);
            if a.fresh1 && sw.warning() {
                self.counters.warnings += 1;
            }
            match a.state {
                Some(s @ (PowerState::Fault | PowerState::FaultReactionActive)) if a.fresh1 => {
                    self.counters.drive_faults += 1;
                    let e = Error::device(
                        OP,
                        "CiA 402",
                        &CanopenError::DriveFault {
                            node: a.node.get(),
                            state: s,
                            emcy: a.emcy,
                        },
                    );
                    return Err(self.lifecycle.fail(e));
                }
                Some(s) if a.fresh1 && s != PowerState::OperationEnabled => {
                    let e = Error::device(
                        OP,
                        "CiA 402",
                        &CanopenError::Disabled {
                            node: a.node.get(),
                            state: s,
                        },
                    );
                    return Err(self.lifecycle.fail(e));
                }
                _ => {}
            }
            if a.fresh1 && sw.following_error() && self.config.mode == Mode::CyclicPosition {
                self.counters.following_errors += 1;
                self.note(
                    "CiA 402",
                    CanopenError::FollowingError { node: a.node.get() },
                );
            }
        }
        let problem = heartbeat_problem.or(self.pending.take());
        match problem {
            None => Ok(()),
            Some((_, CanopenError::TpdoLost { .. })) if heartbeat_problem.is_none() => {
                Err(Error::Timeout {
                    operation: OP,
                    waited: self.tpdo_wait(),
                })
            }
            Some((source @ ("PDO" | "NMT"), e)) => Err(Error::protocol(OP, source, &e)),
            Some((source, e)) => Err(Error::device(OP, source, &e)),
        }
    }
}

impl_cyclic_device!(Cia402, lifecycle);

impl LinkStatisticsSensor for Cia402 {
    fn link_statistics(&self) -> LinkStatistics {
        let c = self.counters;
        let t = self.transport_counters();
        LinkStatistics {
            sent: c.syncs + c.rpdos,
            received: c.tpdos,
            lost: c.tpdos_lost,
            late: c.tpdos_late,
            rejected: c.rejected + t.rejected,
            corrupt: c.corrupt + t.corrupt,
            consecutive_failures: self.lifecycle.consecutive_failures(),
            delivery: Delivery::default(),
        }
    }
}

impl JointDevice for Cia402 {
    fn dof(&self) -> usize {
        self.dof
    }

    fn torque_feed_forward(&mut self) -> Option<&mut dyn JointTorqueFeedForward<Error = Error>> {
        if self.layout.torque_offset.is_some() {
            Some(self)
        } else {
            None
        }
    }

    fn joint_limit_sensor(&self) -> Option<&dyn JointLimitSensor<Error = Error>> {
        Some(self)
    }

    fn joint_velocity_actuator(&mut self) -> Option<&mut dyn JointVelocityActuator<Error = Error>> {
        (self.config.mode == Mode::CyclicVelocity).then_some(self as _)
    }

    fn joint_torque_actuator(&mut self) -> Option<&mut dyn JointTorqueActuator<Error = Error>> {
        (self.config.mode == Mode::CyclicTorque).then_some(self as _)
    }

    fn joint_velocity_sensor(&self) -> Option<&dyn JointVelocitySensor<Error = Error>> {
        self.layout.velocity.is_some().then_some(self as _)
    }

    fn joint_torque_sensor(&self) -> Option<&dyn JointTorqueSensor<Error = Error>> {
        self.layout.torque.is_some().then_some(self as _)
    }
}

impl JointPositionSensor for Cia402 {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        self.read_each(q, |a, u| u.position(a.position))
    }

    /// The coarsest axis's resolution (half a position unit or half an encoder increment).
    fn joint_position_resolution(&self, _q: f64) -> f64 {
        self.axes[..self.dof]
            .iter()
            .map(|a| a.units.position_resolution())
            .fold(0.0, f64::max)
    }
}

impl JointPositionActuator for Cia402 {
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Error> {
        self.check_mode(Mode::CyclicPosition, q.len())?;
        for (k, v) in q.iter().enumerate() {
            let u = &self.axes[k].units;
            if (v / u.per_count()).abs() > f64::from(i32::MAX) {
                self.counters.commands_clamped += 1;
            }
            self.axes[k].target_position = u.position_counts(*v);
        }
        Ok(())
    }
}

impl JointVelocitySensor for Cia402 {
    fn joint_velocity(&self, qd: &mut [f64]) -> Result<(), Error> {
        if self.layout.velocity.is_none() {
            return Err(invalid(
                "velocity feedback is not mapped (set Cia402Config::velocity_feedback)",
                1,
                0,
            ));
        }
        self.read_each(qd, |a, u| u.velocity(a.velocity))
    }
}

impl JointVelocityActuator for Cia402 {
    fn set_joint_velocity(&mut self, qd: &[f64]) -> Result<(), Error> {
        self.check_mode(Mode::CyclicVelocity, qd.len())?;
        for (k, v) in qd.iter().enumerate() {
            self.axes[k].target_velocity = self.axes[k].units.velocity_counts(*v);
        }
        Ok(())
    }
}

impl JointTorqueSensor for Cia402 {
    fn joint_torque(&self, tau: &mut [f64]) -> Result<(), Error> {
        self.read_each(tau, |a, u| u.torque(a.torque))
    }
}

impl JointTorqueActuator for Cia402 {
    fn set_joint_torque(&mut self, tau: &[f64]) -> Result<(), Error> {
        self.check_mode(Mode::CyclicTorque, tau.len())?;
        self.set_torques(tau, |a| &mut a.target_torque);
        Ok(())
    }
}

impl JointTorqueFeedForward for Cia402 {
    fn set_joint_torque_feed_forward(&mut self, tau: &[f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        Error::check_len("joint vector length", self.dof, tau.len())?;
        if self.layout.torque_offset.is_none() {
            return Err(invalid(
                "torque offset (0x60B2) is not mapped in this mode",
                1,
                0,
            ));
        }
        self.set_torques(tau, |a| &mut a.torque_offset);
        Ok(())
    }
}

impl JointLimitSensor for Cia402 {
    fn joint_limit_reached(&self, reached: &mut [bool]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", self.dof, reached.len())?;
        for (k, r) in reached.iter_mut().enumerate() {
            *r = Statusword(self.axes[k].statusword).internal_limit();
        }
        Ok(())
    }
}
