//! A fake EtherCAT segment: N fake slave controllers (ESCs) behind one raw socket, each with
//! its register space and process RAM, SII EEPROM generated from a small description, AL state
//! machine, sync managers and FMMUs, working-counter rules, mailbox with a CoE SDO server, a
//! distributed clock and, on a drive, a CiA 402 axis behind its PDOs. Frames from a master pass
//! the devices in order; the last one returns the frame, and it leaves with the locally
//! administered bit set in its source address, as real devices return it.
//!
//! [`Segment`] processes frames without I/O (the capture replay test feeds it directly);
//! [`FakeSegment`] runs it on a thread behind a [`PacketLink`] on a named interface — one end of
//! a veth pair in the tests, or any interface with `rl fake-robot ethercat`.
//!
//! Fault injection ([`Fault`]): lost frames, a wrong working counter, a device falling back to
//! SAFE-OP with an AL status code.
//!
//! The link: when the interface goes down (a cable pulled, `ip link set … down`) or away, the
//! segment keeps its state and waits for it, reopening its socket if the interface was
//! recreated; frames are answered again once it is back. The devices meanwhile do what their
//! firmware does without frames: the process data watchdog drops a device in OP to SAFE-OP.
//!
//! Timing: frames are answered as soon as they are processed (an EtherCAT segment processes on
//! the fly); each device's firmware runs after every frame and every `pdi_tick`, so AL
//! transitions and mailbox answers are ready for the master's next frame unless a description
//! sets a firmware latency. Propagation delays are modelled (`hop_delay_ns` per device) so a
//! master's distributed-clock delay measurement has something to measure.

pub mod axis;
pub mod coe_server;
pub mod description;
pub mod dictionary;
pub mod esc;
pub mod slave;

use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use self::description::DeviceDescription;
use self::esc::PassTimes;
use self::slave::Slave;
use crate::cia402::PowerState;
use crate::proto::ecat::al::{AlState, AlStatusCode};
use crate::proto::ecat::datagram::{DatagramHeader, HEADER_LEN, Span};
use crate::proto::ecat::frame::{
    DATAGRAMS_OFFSET, ETHERTYPE, EthernetHeader, Frame, MAX_FRAME_LEN, MacAddr,
};
use crate::transport::PacketLink;

/// A fault to inject.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// Drop the next `frames` frames (no reply: the master sees them lost).
    LoseFrames {
        /// How many.
        frames: u32,
    },
    /// Decrement the working counter of every logical datagram in the next `frames` frames.
    WrongWorkingCounter {
        /// How many frames.
        frames: u32,
    },
    /// Device `device` (0-based position) drops from OP to SAFE-OP with the error flag and
    /// `code` in its AL status code register.
    FallBackToSafeOp {
        /// Position of the device.
        device: usize,
        /// The AL status code.
        code: AlStatusCode,
    },
}

/// Counts of the segment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SegmentCounters {
    /// EtherCAT frames from a master processed and returned.
    pub frames: u64,
    /// Frames dropped by fault injection.
    pub dropped: u64,
    /// Frames whose working counter was falsified by fault injection.
    pub falsified: u64,
    /// Frames that did not decode (not returned).
    pub malformed: u64,
    /// Frames ignored because they were already processed (the source's forwarded bit set: a
    /// returning frame or our own echo).
    pub ignored: u64,
    /// Times the interface went down or away (the segment waited for it to come back).
    pub link_down: u64,
    /// Times the segment's thread came back from waiting for a frame more than
    /// [`SLIP_US`] µs after its deadline: it was not running (a busy or stalled machine; a
    /// real segment's ESCs answer in hardware), and frames may have waited that long.
    pub slips: u64,
    /// The most its thread came back late, µs.
    pub max_lateness_us: u64,
}

/// A wait that ends this much after its deadline is a slip ([`SegmentCounters::slips`]).
pub const SLIP_US: u64 = 500;

/// What one device looks like from outside, for status lines and tests.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceStatus {
    /// The device's name.
    pub name: String,
    /// Configured station address.
    pub station: u16,
    /// AL state.
    pub state: AlState,
    /// AL status code when the error flag is set.
    pub error: Option<AlStatusCode>,
    /// The drive's power state.
    pub power: Option<PowerState>,
    /// The drive's position in counts.
    pub position: Option<f64>,
    /// Whether the drive runs on SYNC0.
    pub dc_mode: bool,
    /// The last distributed-clock difference the device saw (ns).
    pub dc_difference: i64,
    /// Axis updates so far.
    pub updates: u64,
    /// Mailbox messages answered.
    pub mailbox_requests: u64,
    /// Accesses the ESC refused.
    pub refused_accesses: u64,
}

/// The devices of a segment and the frame processing, without I/O.
#[derive(Clone, Debug)]
pub struct Segment {
    slaves: Vec<Slave>,
    hop_ns: u64,
    counters: SegmentCounters,
    lose: u32,
    falsify: u32,
}

impl Segment {
    /// Devices in order; device k's clock is offset by a pseudo-random amount (seeded by
    /// `seed`) and drifts `drift_ppb[k]` (missing entries: 0); frames take `hop_ns` from one
    /// device to the next.
    pub fn new(devices: &[DeviceDescription], hop_ns: u64, seed: u64, drift_ppb: &[i64]) -> Self {
        let n = devices.len();
        let mut x = seed | 1;
        let slaves = devices
            .iter()
            .enumerate()
            .map(|(k, d)| {
                // xorshift: clocks that disagree by up to ~16 s, as unsynchronised ESCs do.
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                let offset = (x % 16_000_000_000) as i64;
                let ports = if k + 1 < n { 0b0011 } else { 0b0001 };
                Slave::new(
                    d.clone(),
                    ports,
                    offset,
                    drift_ppb.get(k).copied().unwrap_or(0),
                )
            })
            .collect();
        Self {
            slaves,
            hop_ns,
            counters: SegmentCounters::default(),
            lose: 0,
            falsify: 0,
        }
    }

    /// The devices.
    pub fn slaves(&self) -> &[Slave] {
        &self.slaves
    }

    /// Device `k`.
    pub fn slave_mut(&mut self, k: usize) -> Option<&mut Slave> {
        self.slaves.get_mut(k)
    }

    /// Counts so far.
    pub fn counters(&self) -> SegmentCounters {
        self.counters
    }

    /// Applies a fault.
    pub fn inject(&mut self, fault: Fault) {
        match fault {
            Fault::LoseFrames { frames } => self.lose = self.lose.saturating_add(frames),
            Fault::WrongWorkingCounter { frames } => {
                self.falsify = self.falsify.saturating_add(frames)
            }
            Fault::FallBackToSafeOp { device, code } => {
                if let Some(s) = self.slaves.get_mut(device) {
                    s.fall_back(code);
                }
            }
        }
    }

    /// Processes a frame arriving at fake time `t` (ns) in place. Returns whether to send it
    /// back (`false`: not for the segment, malformed, or dropped by a fault).
    pub fn process(&mut self, frame: &mut [u8], t: u64) -> bool {
        let Ok(eth) = EthernetHeader::decode(frame) else {
            return false;
        };
        if eth.ethertype != ETHERTYPE {
            return false;
        }
        if eth.source.is_forwarded() {
            self.counters.ignored += 1;
            return false;
        }
        let payload_len = match Frame::decode(frame) {
            Ok(f) => f.payload.len(),
            Err(_) => {
                // A real segment would pass a frame it cannot parse with a CRC error; the
                // master sees it lost either way.
                self.counters.malformed += 1;
                return false;
            }
        };
        if self.lose > 0 {
            self.lose -= 1;
            self.counters.dropped += 1;
            return false;
        }
        let payload = &mut frame[DATAGRAMS_OFFSET..DATAGRAMS_OFFSET + payload_len];
        let mut spans = Vec::with_capacity(8);
        let mut pos = 0;
        while pos < payload.len() {
            let Ok(span) = Span::at(payload, pos) else {
                break;
            };
            pos = span.end();
            let more = span.header.more_follows;
            spans.push(span);
            if !more {
                break;
            }
        }
        let n = self.slaves.len() as u64;
        for (k, slave) in self.slaves.iter_mut().enumerate() {
            let k = k as u64;
            let times = PassTimes {
                port0: t + k * self.hop_ns,
                port1: (k + 1 < n).then(|| t + (2 * (n - 1) - k) * self.hop_ns),
            };
            for span in &spans {
                let mut header = DatagramHeader::decode(&payload[span.start..]).expect("span");
                let mut wkc = span.read_wkc(payload);
                slave.process(
                    &mut header,
                    &mut payload[span.data.clone()],
                    &mut wkc,
                    &times,
                );
                let mut h = [0u8; HEADER_LEN];
                header.encode(&mut h);
                payload[span.start..span.start + HEADER_LEN].copy_from_slice(&h);
                span.write_wkc(payload, wkc);
            }
        }
        if self.falsify > 0 {
            self.falsify -= 1;
            self.counters.falsified += 1;
            for span in &spans {
                if span.header.command().is_some_and(|c| c.is_logical()) {
                    let w = span.read_wkc(payload);
                    span.write_wkc(payload, w.wrapping_sub(1));
                }
            }
        }
        let src = eth.source.forwarded();
        frame[6..12].copy_from_slice(&src.0);
        self.counters.frames += 1;
        true
    }

    /// Runs every device's firmware at fake time `t`.
    pub fn pdi_step(&mut self, t: u64) {
        for s in &mut self.slaves {
            s.pdi_step(t);
        }
    }

    /// The devices' status.
    pub fn status(&self) -> Vec<DeviceStatus> {
        self.slaves
            .iter()
            .map(|s| DeviceStatus {
                name: s.description().name.clone(),
                station: s.esc().station_address(),
                state: s.al_state(),
                error: s.al_error(),
                power: s.axis().map(|a| a.state()),
                position: s.axis().map(|a| a.position()),
                dc_mode: s.dc_mode(),
                dc_difference: s.esc().time_difference(),
                updates: s.axis().map_or(0, |a| a.updates()),
                mailbox_requests: s.mailbox_requests(),
                refused_accesses: s.esc().refused(),
            })
            .collect()
    }
}

/// How to run a fake segment.
#[derive(Clone, Debug)]
pub struct FakeSegmentConfig {
    /// The interface to answer on (one end of a veth pair).
    pub interface: String,
    /// The devices, in order from the master.
    pub devices: Vec<DeviceDescription>,
    /// Time a frame takes from one device to the next (ns).
    pub hop_delay_ns: u64,
    /// How often the firmware runs when no frame comes.
    pub pdi_tick: Duration,
    /// Seed of the devices' clock offsets.
    pub seed: u64,
    /// Clock drift of each device in parts per billion.
    pub drift_ppb: Vec<i64>,
    /// Called first on the segment's thread: real devices are hardware that no other program
    /// delays, so a test or benchmark can give the fake's thread a real-time priority here
    /// (rl-drivers starts no scheduler policy itself; rl-rt does that).
    pub on_thread_start: Option<fn()>,
}

impl FakeSegmentConfig {
    /// `drives` CiA 402 drives on `interface`, standing at 0, 0.1, 0.2 … revolutions.
    pub fn drives(interface: &str, drives: usize) -> Self {
        let devices = (0..drives)
            .map(|k| DeviceDescription::cia402_drive(k as u32, (k as i32) * ((1 << 20) / 10)))
            .collect();
        Self {
            interface: interface.into(),
            devices,
            hop_delay_ns: 500,
            pdi_tick: Duration::from_micros(250),
            seed: 0x5EED,
            drift_ppb: Vec::new(),
            on_thread_start: None,
        }
    }
}

/// The shared state between the segment thread and its owner.
#[derive(Debug, Default)]
struct Shared {
    status: Vec<DeviceStatus>,
    counters: SegmentCounters,
    faults: Vec<Fault>,
}

/// A fake segment answering on a network interface from its own thread.
#[derive(Debug)]
pub struct FakeSegment {
    stop: Arc<AtomicBool>,
    shared: Arc<Mutex<Shared>>,
    thread: Option<JoinHandle<io::Result<()>>>,
    interface: String,
}

impl FakeSegment {
    /// Opens the raw socket on the configured interface (in the caller's network namespace)
    /// and starts the segment's thread.
    pub fn spawn(config: FakeSegmentConfig) -> io::Result<Self> {
        for (k, d) in config.devices.iter().enumerate() {
            if let description::Profile::Cia402 { motor, .. } = &d.profile {
                let u = &motor.units;
                let fits = [u.counts_per_rev, u.gear_ratio, u.units_per_rev()]
                    .into_iter()
                    .all(|v| crate::cia402::units::ratio(v).is_some());
                if !(u.is_valid() && fits) {
                    return Err(io::Error::new(
                        io::ErrorKind::InvalidInput,
                        format!(
                            "device {k}: units {u:?} do not fit 0x608F, 0x6091 and 0x6092 \
                             (ratios of 32-bit integers)"
                        ),
                    ));
                }
            }
        }
        let link = PacketLink::open(&config.interface, ETHERTYPE)?;
        let interface = config.interface.clone();
        let mut segment = Segment::new(
            &config.devices,
            config.hop_delay_ns,
            config.seed,
            &config.drift_ppb,
        );
        let stop = Arc::new(AtomicBool::new(false));
        let shared = Arc::new(Mutex::new(Shared {
            status: segment.status(),
            ..Shared::default()
        }));
        let (s, sh) = (stop.clone(), shared.clone());
        let tick = config.pdi_tick.max(Duration::from_micros(50));
        let hook = config.on_thread_start;
        let thread = std::thread::Builder::new()
            .name("fake-ecat".into())
            .spawn(move || {
                if let Some(f) = hook {
                    f();
                }
                run(link, &interface, &mut segment, &s, &sh, tick)
            })?;
        Ok(Self {
            stop,
            shared,
            thread: Some(thread),
            interface: config.interface,
        })
    }

    /// The interface it answers on.
    pub fn interface(&self) -> &str {
        &self.interface
    }

    /// Injects a fault (applied before the next frame).
    pub fn inject(&self, fault: Fault) {
        if let Ok(mut s) = self.shared.lock() {
            s.faults.push(fault);
        }
    }

    /// The devices' status (as of the last frame or firmware tick).
    pub fn status(&self) -> Vec<DeviceStatus> {
        self.shared
            .lock()
            .map(|s| s.status.clone())
            .unwrap_or_default()
    }

    /// The segment's counts.
    pub fn counters(&self) -> SegmentCounters {
        self.shared.lock().map(|s| s.counters).unwrap_or_default()
    }

    /// Stops the thread; returns its error, if it failed.
    pub fn shutdown(mut self) -> io::Result<()> {
        self.stop_thread()
    }

    fn stop_thread(&mut self) -> io::Result<()> {
        self.stop.store(true, Ordering::Relaxed);
        match self.thread.take() {
            Some(t) => t
                .join()
                .unwrap_or_else(|_| Err(io::Error::other("the fake segment's thread panicked"))),
            None => Ok(()),
        }
    }
}

impl Drop for FakeSegment {
    fn drop(&mut self) {
        let _ = self.stop_thread();
    }
}

/// Whether a socket error means the interface is down or gone (the segment waits for it).
fn link_gone(e: &io::Error) -> bool {
    matches!(
        e.raw_os_error(),
        Some(libc::ENETDOWN | libc::ENXIO | libc::ENODEV | libc::ENETUNREACH)
    )
}

/// How often a segment whose interface went away tries to open it again.
const REOPEN_EVERY: Duration = Duration::from_millis(100);

fn run(
    mut link: PacketLink,
    interface: &str,
    segment: &mut Segment,
    stop: &AtomicBool,
    shared: &Mutex<Shared>,
    tick: Duration,
) -> io::Result<()> {
    let start = Instant::now();
    let now = || start.elapsed().as_nanos() as u64;
    let mut buf = [0u8; MAX_FRAME_LEN + 64];
    let mut next_tick = Instant::now() + tick;
    let mut last_publish = Instant::now();
    // Since when the link has been down, if it is.
    let mut down: Option<Instant> = None;
    while !stop.load(Ordering::Relaxed) {
        if let Ok(mut s) = shared.try_lock() {
            for f in s.faults.drain(..) {
                segment.inject(f);
            }
        }
        if let Some(since) = down {
            // Wait a tick; an interface that was deleted and made again has a new index, so
            // the socket is opened again after a while.
            std::thread::sleep(tick);
            if since.elapsed() >= REOPEN_EVERY {
                if let Ok(l) = PacketLink::open(interface, ETHERTYPE) {
                    link = l;
                }
                down = Some(Instant::now());
            }
        }
        let waited_until = next_tick;
        let got = match link.recv_until(&mut buf, next_tick) {
            Ok(got) => {
                if got.is_some() {
                    down = None;
                }
                got
            }
            Err(e) if link_gone(&e) => {
                if down.is_none() {
                    segment.counters.link_down += 1;
                    down = Some(Instant::now());
                }
                None
            }
            Err(e) => return Err(e),
        };
        let late = u64::try_from(
            Instant::now()
                .saturating_duration_since(waited_until)
                .as_micros(),
        )
        .unwrap_or(u64::MAX);
        // (While the link is down the loop sleeps on purpose.)
        if down.is_none() {
            segment.counters.max_lateness_us = segment.counters.max_lateness_us.max(late);
            if late > SLIP_US {
                segment.counters.slips += 1;
            }
        }
        if let Some(n) = got {
            let n = n.min(MAX_FRAME_LEN);
            if segment.process(&mut buf[..n], now()) {
                match link.send(&buf[..n]) {
                    Ok(()) => {}
                    Err(e) if link_gone(&e) => {
                        if down.is_none() {
                            segment.counters.link_down += 1;
                            down = Some(Instant::now());
                        }
                    }
                    Err(e) => return Err(e),
                }
            }
        }
        segment.pdi_step(now());
        let at = Instant::now();
        if at >= next_tick {
            next_tick = at + tick;
        }
        if got.is_some() || at.duration_since(last_publish) >= Duration::from_millis(20) {
            if let Ok(mut s) = shared.try_lock() {
                s.status = segment.status();
                s.counters = segment.counters();
                last_publish = at;
            }
        }
    }
    if let Ok(mut s) = shared.lock() {
        s.status = segment.status();
        s.counters = segment.counters();
    }
    Ok(())
}

/// The source address frames from our master carry (for tests that talk to a segment
/// directly).
pub const MASTER_MAC: MacAddr = MacAddr::MASTER;
