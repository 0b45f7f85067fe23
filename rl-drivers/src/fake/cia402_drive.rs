//! Fake CiA 402 drives on a CAN bus: N simulated nodes sharing one bus, each with the object
//! dictionary of an EDS (by default the one shipped for this fake, `data/rl-fake-cia402.eds`,
//! with the mandatory CiA 301 and 402 objects), an SDO server, NMT, a heartbeat producer,
//! SYNC-triggered (and event-driven) TPDOs, RPDOs applied at the next SYNC, the power state
//! machine, and a motor that follows its target per mode within the configured limits.
//!
//! It behaves like hardware: TPDOs leave a configurable delay after their SYNC, not at once;
//! an enabled drive faults (EMCY 0x8100) when SYNC stops for two communication cycle periods
//! (0x1006); SDO requests are refused with the abort codes a drive gives (no object, no
//! sub-index, read-only, wrong length, a mapping change on a valid PDO, …); an RPDO shorter
//! than its mapping is an EMCY 0x8210. Faults can be injected ([`FakeFault`]).
//!
//! The fake runs its own thread (it imitates remote hardware); it serves on any
//! [`CanTransport`] — cannelloni UDP or TCP on loopback, SocketCAN, or the in-process bus. On
//! cannelloni UDP it serves one master, the first sender, and ignores (counts) datagrams from
//! other addresses while that master is active, as a gateway with one remote would.

mod motor;
mod node;

use std::io;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

pub use motor::MotorLimits;
pub use node::{EMCY_PDO_LENGTH, EMCY_SYNC_LOST, NodeCounters};

use crate::cia402::{AxisUnits, PowerState};
use crate::proto::can::Frame;
use crate::proto::canopen::eds::Eds;
use crate::proto::canopen::sdo::{AbortCode, Address};
use crate::proto::canopen::{NodeId, nmt};
use crate::transport::can::cannelloni_tcp::{CannelloniTcp, Listener};
use crate::transport::can::cannelloni_udp::CannelloniUdp;
use crate::transport::can::record::{CandumpLog, PcapLog};
use crate::transport::can::socketcan::SocketCan;
use crate::transport::can::{CanAddress, CanTransport};
use crate::transport::timestamp;
use node::{Node, Outbox};

/// The EDS shipped for the fake drive.
pub const FAKE_EDS: &str = include_str!("../../data/rl-fake-cia402.eds");

/// One simulated axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FakeAxis {
    /// Node id.
    pub node: u8,
    /// The drive's units: its encoder, gear, feed constant (position units per joint
    /// revolution) and rated torque, which it reports in 0x608F, 0x6091, 0x6092 and 0x6076 and
    /// which convert its counts to joint units.
    pub units: AxisUnits,
    /// Whether the drive has the factor-group objects 0x608F, 0x6091 and 0x6092 (`false`: an
    /// SDO upload of them is aborted with "object does not exist", as on a drive without them).
    pub unit_objects: bool,
    /// Position at power-up, rad (or m).
    pub initial: f64,
    /// Lowest position, rad.
    pub lower: f64,
    /// Highest position, rad.
    pub upper: f64,
    /// Highest speed, rad/s.
    pub max_velocity: f64,
    /// Highest acceleration, rad/s².
    pub max_acceleration: f64,
}

impl FakeAxis {
    /// Node `node` with default units, ±π, 2π rad/s, 20π rad/s².
    pub fn new(node: u8) -> Self {
        Self {
            node,
            units: AxisUnits::default(),
            unit_objects: true,
            initial: 0.0,
            lower: -core::f64::consts::PI,
            upper: core::f64::consts::PI,
            max_velocity: core::f64::consts::TAU,
            max_acceleration: 10.0 * core::f64::consts::TAU,
        }
    }

    fn limits(&self) -> MotorLimits {
        let c = 1.0 / self.units.per_count();
        MotorLimits {
            lower: self.lower * c,
            upper: self.upper * c,
            max_velocity: self.max_velocity * c,
            max_acceleration: self.max_acceleration * c,
            // 1000 ‰ accelerate the joint at its acceleration limit.
            acceleration_per_permille: self.max_acceleration * c / 1000.0,
            stiffness_permille_per_count: 1000.0 / (0.01 * c).max(1.0),
        }
    }
}

/// The fake bus's configuration.
#[derive(Clone, Debug)]
pub struct FakeCia402Config {
    /// The axes (one node each).
    pub axes: Vec<FakeAxis>,
    /// The dictionary every node has.
    pub eds: Arc<Eds>,
    /// Delay between a SYNC and the TPDOs it triggers.
    pub tpdo_delay: Duration,
    /// Communication cycle periods (0x1006) without SYNC after which an enabled drive faults
    /// (2, as drives typically do; tests of behaviour rather than timing on a loaded machine
    /// may allow more).
    pub sync_loss_periods: u32,
    /// Record every frame received and sent to this pcap file (SocketCAN link type 227).
    pub pcap: Option<PathBuf>,
    /// Record every frame received and sent to this candump log.
    pub candump: Option<PathBuf>,
}

impl FakeCia402Config {
    /// One drive per joint of `model` (nodes 1, 2, …), with its position and speed limits and
    /// `units`, standing at `start` (clamped to the limits); the shipped EDS.
    pub fn for_model<const N: usize>(
        model: &rl_core::Model<N>,
        start: &[f64],
        units: AxisUnits,
    ) -> io::Result<Self> {
        let dof = model.dof();
        if dof == 0 || dof > crate::canopen::MAX_AXES {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "the model has {dof} joints; the fake drives simulate 1 to {} axes",
                    crate::canopen::MAX_AXES
                ),
            ));
        }
        let nodes: Vec<u8> = (1..=dof as u8).collect();
        let mut c = Self::new(&nodes)?;
        for (k, a) in c.axes.iter_mut().enumerate() {
            let l = model.limits(k);
            if !l.wraparound {
                a.lower = l.lower;
                a.upper = l.upper;
            } else {
                a.lower = f64::NEG_INFINITY;
                a.upper = f64::INFINITY;
            }
            if l.velocity.is_finite() && l.velocity > 0.0 {
                a.max_velocity = l.velocity;
            }
            a.units = units;
            a.initial = start.get(k).map_or(0.0, |&q| l.clamp(q));
        }
        Ok(c)
    }

    /// Nodes `nodes` with the shipped EDS, default axes and a 100 µs TPDO delay.
    pub fn new(nodes: &[u8]) -> io::Result<Self> {
        let eds =
            Eds::parse(FAKE_EDS).map_err(|e| io::Error::other(format!("shipped EDS: {e}")))?;
        Ok(Self {
            axes: nodes.iter().map(|&n| FakeAxis::new(n)).collect(),
            eds: Arc::new(eds),
            tpdo_delay: Duration::from_micros(100),
            sync_loss_periods: 2,
            pcap: None,
            candump: None,
        })
    }
}

fn invalid_input(text: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, text)
}

/// The factor-group objects of an axis: encoder resolution, gear ratio, feed constant.
fn unit_objects(a: &FakeAxis) -> io::Result<Option<[(u32, u32); 3]>> {
    if !a.units.is_valid() {
        return Err(invalid_input(format!(
            "node {}: units must be finite and positive: {:?}",
            a.node, a.units
        )));
    }
    if !a.unit_objects {
        return Ok(None);
    }
    let u = &a.units;
    let mut out = [(0, 0); 3];
    for (slot, (value, object)) in out.iter_mut().zip([
        (u.counts_per_rev, "0x608F (counts per revolution)"),
        (u.gear_ratio, "0x6091 (gear ratio)"),
        (u.units_per_rev(), "0x6092 (feed constant)"),
    ]) {
        *slot = crate::cia402::units::ratio(value).ok_or_else(|| {
            invalid_input(format!(
                "node {}: {value} does not fit {object} as a ratio of 32-bit integers",
                a.node
            ))
        })?;
    }
    Ok(Some(out))
}

/// 0x6076 of an axis, mN·m.
fn rated_torque_mnm(a: &FakeAxis) -> io::Result<u32> {
    let mnm = (a.units.rated_torque_nm * 1000.0).round();
    if mnm >= 1.0 && mnm <= f64::from(u32::MAX) {
        Ok(mnm as u32)
    } else {
        Err(invalid_input(format!(
            "node {}: rated torque {} N·m does not fit 0x6076 (mN·m)",
            a.node, a.units.rated_torque_nm
        )))
    }
}

/// A fault to inject.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FakeFault {
    /// The drive faults with an EMCY of `code` (e.g. 0x2310 over-current).
    DriveFault {
        /// Node.
        node: u8,
        /// EMCY error code.
        code: u16,
    },
    /// The node sends no heartbeat for `duration`.
    HeartbeatLoss {
        /// Node.
        node: u8,
        /// How long.
        duration: Duration,
    },
    /// The next SDO access to `index:sub` is aborted with `code`.
    SdoAbort {
        /// Node.
        node: u8,
        /// Object.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Abort code.
        code: u32,
    },
    /// The next `count` TPDOs are not sent.
    DropTpdos {
        /// Node.
        node: u8,
        /// How many.
        count: u32,
    },
    /// The next `count` TPDOs leave `delay` later than usual.
    LateTpdos {
        /// Node.
        node: u8,
        /// How many.
        count: u32,
        /// Extra delay.
        delay: Duration,
    },
    /// The next `count` TPDOs are sent one byte short (a corrupted frame).
    CorruptTpdos {
        /// Node.
        node: u8,
        /// How many.
        count: u32,
    },
    /// The warning bit (statusword bit 7) on or off.
    Warning {
        /// Node.
        node: u8,
        /// On.
        on: bool,
    },
    /// Statusword bit 13 (following error) for `syncs` SYNCs.
    FollowingError {
        /// Node.
        node: u8,
        /// How many SYNCs.
        syncs: u32,
    },
}

impl FakeFault {
    fn node(&self) -> u8 {
        match *self {
            FakeFault::DriveFault { node, .. }
            | FakeFault::HeartbeatLoss { node, .. }
            | FakeFault::SdoAbort { node, .. }
            | FakeFault::DropTpdos { node, .. }
            | FakeFault::LateTpdos { node, .. }
            | FakeFault::CorruptTpdos { node, .. }
            | FakeFault::Warning { node, .. }
            | FakeFault::FollowingError { node, .. } => node,
        }
    }
}

/// One node as the fake sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FakeNodeStatus {
    /// Node id.
    pub node: u8,
    /// NMT state.
    pub nmt: nmt::State,
    /// Power state.
    pub power: PowerState,
    /// Modes of operation (0x6060).
    pub mode: i8,
    /// Position, rad.
    pub position: f64,
    /// Position, counts.
    pub position_counts: i32,
    /// Target position (0x607A), counts.
    pub target_counts: i32,
    /// Velocity, rad/s.
    pub velocity: f64,
    /// Torque actual, ‰.
    pub torque_permille: i16,
    /// Torque offset (0x60B2), ‰.
    pub torque_offset_permille: i16,
    /// Communication cycle period (0x1006), µs.
    pub cycle_period_us: u32,
    /// Heartbeat producer time (0x1017), ms.
    pub heartbeat_ms: u16,
    /// What the node did.
    pub counters: NodeCounters,
}

/// The fake bus's status.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FakeStatus {
    /// The nodes.
    pub nodes: Vec<FakeNodeStatus>,
    /// Frames received.
    pub frames_received: u64,
    /// Frames sent.
    pub frames_sent: u64,
    /// Master connections accepted (TCP).
    pub connections: u64,
    /// Frames or datagrams the transport refused: from another sender than the master it
    /// serves (a bus would not deliver them), or malformed.
    pub rejected: u64,
    /// The longest the fake's own thread woke after it meant to (a wait's deadline, a frame's
    /// due time, a received frame's kernel timestamp where the transport has one): real drives have their own CPU; a fake that shares one may be held up, and
    /// a test can tell that apart from a defect of the master.
    pub max_lateness: Duration,
    /// The last transport error (a dropped TCP peer, …).
    pub last_error: Option<String>,
}

#[derive(Debug, Default)]
struct Shared {
    status: FakeStatus,
    faults: Vec<FakeFault>,
}

fn lock(m: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Where the fake is reached.
enum Link {
    Transport(Box<dyn CanTransport>),
    Tcp {
        listener: Listener,
        peer: Option<Box<CannelloniTcp>>,
    },
}

/// Running fake drives; the thread stops when this is dropped.
#[derive(Debug)]
pub struct FakeCia402 {
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    local: Option<SocketAddr>,
}

impl FakeCia402 {
    /// Serves on `address`: cannelloni UDP binds its address and answers whoever sends;
    /// cannelloni TCP listens there (one master at a time); SocketCAN opens the interface.
    pub fn serve(config: FakeCia402Config, address: &CanAddress) -> io::Result<Self> {
        let (link, local) = match address {
            CanAddress::CannelloniUdp { remote, .. } => {
                let udp = CannelloniUdp::serve(*remote)?;
                let local = udp.local_addr()?;
                (Link::Transport(Box::new(udp)), Some(local))
            }
            CanAddress::CannelloniTcp { addr, .. } => {
                let listener = Listener::bind(*addr)?;
                let local = listener.local_addr()?;
                (
                    Link::Tcp {
                        listener,
                        peer: None,
                    },
                    Some(local),
                )
            }
            CanAddress::SocketCan { interface } => (
                Link::Transport(Box::new(SocketCan::open(interface, &[], false)?)),
                None,
            ),
        };
        Self::spawn(config, link, local)
    }

    /// Serves on `transport` (an in-process bus endpoint, say).
    pub fn on_transport(
        config: FakeCia402Config,
        transport: Box<dyn CanTransport>,
    ) -> io::Result<Self> {
        Self::spawn(config, Link::Transport(transport), None)
    }

    fn spawn(config: FakeCia402Config, link: Link, local: Option<SocketAddr>) -> io::Result<Self> {
        let now = Instant::now();
        let mut nodes = Vec::new();
        for a in &config.axes {
            let id = NodeId::new(a.node).ok_or_else(|| {
                io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!("node id {} outside 1..=127", a.node),
                )
            })?;
            if nodes.iter().any(|n: &Node| n.id == id) {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!("node id {} twice", a.node),
                ));
            }
            let position = a.initial / a.units.per_count();
            let mut node = Node::new(
                id,
                &config.eds,
                position,
                a.limits(),
                (config.tpdo_delay, config.sync_loss_periods),
                now,
            );
            node.set_units(unit_objects(a)?, rated_torque_mnm(a)?);
            nodes.push(node);
        }
        let pcap = config.pcap.as_deref().map(PcapLog::create).transpose()?;
        let candump = config
            .candump
            .as_deref()
            .map(|p| CandumpLog::create(p, "can0"))
            .transpose()?;
        let shared = Arc::new(Mutex::new(Shared::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let mut worker = Worker {
            pcap,
            candump,
            nodes,
            axes: config.axes,
            link,
            shared: shared.clone(),
            stop: stop.clone(),
            outbox: Vec::with_capacity(256),
            frames_received: 0,
            frames_sent: 0,
            connections: 0,
            max_lateness: Duration::ZERO,
            last_error: None,
        };
        worker.boot(now);
        worker.publish();
        let thread = std::thread::Builder::new()
            .name("fake-cia402".into())
            .spawn(move || worker.run())?;
        Ok(Self {
            shared,
            stop,
            thread: Some(thread),
            local,
        })
    }

    /// The bound address (cannelloni UDP or TCP).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.local
    }

    /// A snapshot of the nodes (as of the fake's last turn, at most a millisecond old).
    pub fn status(&self) -> FakeStatus {
        lock(&self.shared).status.clone()
    }

    /// Waits at most `timeout` for the status to satisfy `condition` (the fake is remote
    /// hardware: what was sent last may not be processed yet); returns the last status.
    pub fn wait_for(
        &self,
        timeout: Duration,
        condition: impl Fn(&FakeStatus) -> bool,
    ) -> Result<FakeStatus, FakeStatus> {
        let deadline = Instant::now() + timeout;
        loop {
            let s = self.status();
            if condition(&s) {
                return Ok(s);
            }
            if Instant::now() >= deadline {
                return Err(s);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Injects a fault (taken at the fake's next turn, within a millisecond).
    pub fn inject(&self, fault: FakeFault) {
        lock(&self.shared).faults.push(fault);
    }

    /// Stops the thread.
    pub fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for FakeCia402 {
    fn drop(&mut self) {
        self.shutdown();
    }
}

struct Worker {
    pcap: Option<PcapLog>,
    candump: Option<CandumpLog>,
    nodes: Vec<Node>,
    axes: Vec<FakeAxis>,
    link: Link,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    outbox: Outbox,
    frames_received: u64,
    frames_sent: u64,
    connections: u64,
    max_lateness: Duration,
    last_error: Option<String>,
}

const TURN: Duration = Duration::from_millis(1);

impl Worker {
    fn boot(&mut self, now: Instant) {
        for n in &self.nodes {
            self.outbox.push((now, n.boot_up()));
        }
    }

    fn transport(&mut self, deadline: Instant) -> Option<&mut dyn CanTransport> {
        match &mut self.link {
            Link::Transport(t) => Some(t.as_mut()),
            Link::Tcp { listener, peer } => {
                if peer.is_none() {
                    match listener.accept(deadline) {
                        Ok(p) => {
                            *peer = Some(Box::new(p));
                            self.connections += 1;
                        }
                        Err(e) if e.kind() == io::ErrorKind::TimedOut => {}
                        Err(e) => self.last_error = Some(e.to_string()),
                    }
                }
                peer.as_deref_mut().map(|p| p as &mut dyn CanTransport)
            }
        }
    }

    fn drop_peer(&mut self, e: &io::Error) {
        self.last_error = Some(e.to_string());
        if let Link::Tcp { peer, .. } = &mut self.link {
            *peer = None;
        }
    }

    fn run(&mut self) {
        while !self.stop.load(Ordering::Relaxed) {
            let now = Instant::now();
            // Wake for the earliest scheduled frame, or after a turn.
            let next_due = self.outbox.iter().map(|(t, _)| *t).min();
            let deadline = next_due.map_or(now + TURN, |t| t.min(now + TURN));
            let received = match self.transport(deadline) {
                Some(t) => t.recv(deadline),
                None => Ok(None),
            };
            match received {
                Ok(Some(r)) => {
                    self.frames_received += 1;
                    // How long the frame waited in the socket for this thread to take it.
                    if let Some(at) = r.timestamp {
                        let late = timestamp::since_epoch().saturating_sub(at);
                        self.max_lateness = self.max_lateness.max(late);
                    }
                    self.record(&r.frame);
                    let now = Instant::now();
                    for n in &mut self.nodes {
                        n.on_frame(&r.frame, now, &mut self.outbox);
                    }
                }
                Ok(None) => {
                    let late = Instant::now().saturating_duration_since(deadline);
                    self.max_lateness = self.max_lateness.max(late);
                }
                Err(e) => self.drop_peer(&e),
            }
            let now = Instant::now();
            self.take_faults(now);
            for n in &mut self.nodes {
                n.tick(now, &mut self.outbox);
            }
            self.send_due(now);
            self.publish();
        }
        if let Some(p) = &mut self.pcap {
            let _ = p.flush();
        }
        if let Some(c) = &mut self.candump {
            let _ = c.flush();
        }
        self.publish();
    }

    fn send_due(&mut self, now: Instant) {
        if !self.outbox.iter().any(|(t, _)| *t <= now) {
            return;
        }
        self.outbox.sort_by_key(|(t, _)| *t);
        if let Some((due, _)) = self.outbox.first() {
            self.max_lateness = self.max_lateness.max(now.saturating_duration_since(*due));
        }
        let split = self.outbox.partition_point(|(t, _)| *t <= now);
        let due: Vec<Frame> = self.outbox.drain(..split).map(|(_, f)| f).collect();
        let deadline = now + Duration::from_millis(5);
        let Some(t) = self.transport(now) else { return };
        let mut r = Ok(());
        for f in &due {
            r = t.send(f);
            if r.is_err() {
                break;
            }
        }
        let r = r.and_then(|()| t.flush(deadline));
        match r {
            Ok(()) => {
                self.frames_sent += due.len() as u64;
                for f in &due {
                    self.record(f);
                }
            }
            Err(e) => self.drop_peer(&e),
        }
    }

    fn record(&mut self, frame: &Frame) {
        if self.pcap.is_none() && self.candump.is_none() {
            return;
        }
        let t = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        let mut r = Ok(());
        if let Some(p) = &mut self.pcap {
            r = r.and(p.write(t, frame));
        }
        if let Some(c) = &mut self.candump {
            r = r.and(c.write(t, frame));
        }
        if let Err(e) = r {
            self.last_error = Some(format!("recording: {e}"));
        }
    }

    fn take_faults(&mut self, now: Instant) {
        let faults = std::mem::take(&mut lock(&self.shared).faults);
        for f in faults {
            let Some(n) = self.nodes.iter_mut().find(|n| n.id.get() == f.node()) else {
                continue;
            };
            let i = &mut n.injected;
            match f {
                FakeFault::DriveFault { code, .. } => n.fault(code, 0x02, now, &mut self.outbox),
                FakeFault::HeartbeatLoss { duration, .. } => {
                    i.heartbeat_silent_until = Some(now + duration)
                }
                FakeFault::SdoAbort {
                    index, sub, code, ..
                } => i.sdo_abort = Some((Address::new(index, sub), AbortCode(code))),
                FakeFault::DropTpdos { count, .. } => i.drop_tpdos += count,
                FakeFault::LateTpdos { count, delay, .. } => {
                    i.late_tpdos += count;
                    i.late_by = delay;
                }
                FakeFault::CorruptTpdos { count, .. } => i.corrupt_tpdos += count,
                FakeFault::Warning { on, .. } => i.warning = on,
                FakeFault::FollowingError { syncs, .. } => i.following_error_syncs += syncs,
            }
        }
    }

    fn publish(&mut self) {
        let nodes = self
            .nodes
            .iter()
            .zip(&self.axes)
            .map(|(n, a)| FakeNodeStatus {
                node: n.id.get(),
                nmt: n.nmt,
                power: n.power,
                mode: n.value(0x6060, 0) as i8,
                position: n.motor.position * a.units.per_count(),
                position_counts: n.position(),
                target_counts: n.value(0x607A, 0) as i32,
                velocity: n.motor.velocity * a.units.per_count(),
                torque_permille: n.value(0x6077, 0) as i16,
                torque_offset_permille: n.value(0x60B2, 0) as i16,
                cycle_period_us: n.value(0x1006, 0) as u32,
                heartbeat_ms: n.value(0x1017, 0) as u16,
                counters: n.counters,
            })
            .collect();
        let rejected = match &self.link {
            Link::Transport(t) => {
                let c = t.counters();
                c.rejected + c.corrupt
            }
            Link::Tcp { peer, .. } => peer.as_ref().map_or(0, |p| {
                let c = p.counters();
                c.rejected + c.corrupt
            }),
        };
        let mut s = lock(&self.shared);
        s.status = FakeStatus {
            nodes,
            frames_received: self.frames_received,
            frames_sent: self.frames_sent,
            connections: self.connections,
            rejected,
            max_lateness: self.max_lateness,
            last_error: self.last_error.clone(),
        };
    }
}
