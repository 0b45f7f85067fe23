//! A recorded bus replays: `tests/data/can/cia402_session.log` (candump format) holds a whole
//! session of our master with two drives — open, start, 20 CSP cycles, stop. Replayed to a new
//! master, the drives' frames come back in order and every frame the master sends is compared
//! with the recording: the master's behaviour on the wire is pinned, and a capture from a real
//! bus (`candump -l`) replays the same way.
//!
//! Regenerate the recording (against the fake drives) with
//! `RL_RECORD_CAN_FIXTURE=1 cargo test -p rl-drivers --test canopen_replay`.

use std::path::PathBuf;
use std::time::Duration;

use rl_drivers::canopen::{Cia402, Cia402Config};
use rl_drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config};
use rl_drivers::proto::can::Frame;
use rl_drivers::proto::canopen::Function;
use rl_drivers::transport::can::bus::Bus;
use rl_drivers::transport::can::record::{CandumpLog, Recording};
use rl_drivers::transport::can::replay::Replay;
use rl_drivers::transport::can::{CanAddress, CanTransport};
use rl_drivers::{CyclicDevice, Device, JointPositionActuator, JointPositionSensor};

fn fixture() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/can/cia402_session.log")
}

fn config() -> Cia402Config {
    let mut c = Cia402Config::new(CanAddress::parse("socketcan://can0").unwrap(), &[1, 2])
        .with_period(Duration::from_millis(20));
    c.sdo_timeout = Duration::from_millis(200);
    // No heartbeats: their timing is the one thing a replay at full speed does not keep.
    c.heartbeat_ms = 0;
    c
}

/// The session; `step` is added to the first joint's target each cycle. Returns the positions
/// read after the last step.
fn session(link: Box<dyn CanTransport>, step: f64) -> [f64; 2] {
    let mut dev = Cia402::with_transport(config(), link).unwrap();
    dev.open().unwrap();
    dev.start().unwrap();
    let mut q = [0.0; 2];
    dev.joint_position(&mut q).unwrap();
    for _ in 0..20 {
        q[0] += step;
        dev.set_joint_position(&q).unwrap();
        dev.step().unwrap();
    }
    dev.joint_position(&mut q).unwrap();
    dev.stop().unwrap();
    dev.close().unwrap();
    q
}

fn sent_by_master(f: &Frame) -> bool {
    matches!(
        f.standard_id().and_then(Function::from_cob_id),
        Some(Function::Nmt | Function::Sync | Function::Rpdo(..) | Function::SdoRx(_))
    )
}

fn record() {
    let bus = Bus::new();
    let mut fc = FakeCia402Config::new(&[1, 2]).unwrap();
    fc.sync_loss_periods = 10;
    fc.axes[1].initial = -0.5;
    let _fake = FakeCia402::on_transport(fc, Box::new(bus.endpoint())).unwrap();
    let link = Recording::new(
        bus.endpoint(),
        None,
        Some(CandumpLog::create(&fixture(), "can0").unwrap()),
    );
    session(Box::new(link), 1e-3);
}

#[test]
fn a_recorded_session_replays_frame_for_frame() {
    if std::env::var_os("RL_RECORD_CAN_FIXTURE").is_some() {
        record();
    }
    let text = std::fs::read_to_string(fixture()).unwrap();
    let replay = Replay::from_candump(&text, sent_by_master).unwrap();
    let total = replay.len();
    assert!(total > 200, "{total} frames");
    // The replay transport is shared with the check below through a raw view of its state:
    // run the session, then look at where the replay stands.
    let shared = std::sync::Arc::new(std::sync::Mutex::new(replay));
    let q = session(Box::new(Shared(shared.clone())), 1e-3);
    let replay = shared.lock().unwrap();
    assert_eq!(replay.mismatch(), None);
    assert_eq!(replay.position(), total, "the whole recording was used");
    // Node 2 stood at −0.5 rad in the recording; node 1 moved 18 mrad by the last TPDO read.
    let per_count = core::f64::consts::TAU / f64::from(1u32 << 20);
    assert!((q[1] + 0.5).abs() < per_count, "{q:?}");
    assert!((q[0] - 0.018).abs() < per_count, "{q:?}");
}

#[test]
fn a_departure_from_the_recording_is_found_where_it_happens() {
    let text = std::fs::read_to_string(fixture()).unwrap();
    let shared = std::sync::Arc::new(std::sync::Mutex::new(
        Replay::from_candump(&text, sent_by_master).unwrap(),
    ));
    // Another command: the first RPDO of the run carries another target.
    let link = Box::new(Shared(shared.clone()));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| session(link, 2e-3)));
    let replay = shared.lock().unwrap();
    let m = replay.mismatch().expect("a mismatch");
    assert_eq!(m.sent.standard_id(), Some(0x201), "{m:?} ({result:?})");
    assert_eq!(m.expected.and_then(|f| f.standard_id()), Some(0x201));
    assert_ne!(m.sent.bytes(), m.expected.unwrap().bytes());
    let bad = Replay::from_candump("(1.000000) can0 201#0F\n(2.0) can0 080#\n", sent_by_master)
        .unwrap_err();
    assert_eq!(bad.line, 2);
}

/// A transport that forwards to a shared replay (so the test can look at it afterwards).
struct Shared(std::sync::Arc<std::sync::Mutex<Replay>>);

impl CanTransport for Shared {
    fn send(&mut self, frame: &Frame) -> std::io::Result<()> {
        self.0.lock().unwrap().send(frame)
    }
    fn flush(&mut self, deadline: std::time::Instant) -> std::io::Result<()> {
        self.0.lock().unwrap().flush(deadline)
    }
    fn recv(
        &mut self,
        deadline: std::time::Instant,
    ) -> std::io::Result<Option<rl_drivers::transport::can::Received>> {
        self.0.lock().unwrap().recv(deadline)
    }
    fn counters(&self) -> rl_drivers::transport::can::TransportCounters {
        self.0.lock().unwrap().counters()
    }
}
