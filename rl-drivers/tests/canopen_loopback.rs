//! The CiA 402 master against the fake drives, on the in-process bus and on cannelloni over
//! loopback: open, start, CSP motion, stop; every injected fault becomes a counted, typed
//! error, and a fault reset recovers.

mod support;

use std::time::{Duration, Instant};

use rl_drivers::canopen::{Cia402, Cia402Config};
use rl_drivers::cia402::PowerState;
use rl_drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config, FakeFault};
use rl_drivers::proto::canopen::nmt;
use rl_drivers::transport::can::CanAddress;
use rl_drivers::transport::can::bus::Bus;
use rl_drivers::{
    CyclicDevice, Device, DeviceError, ErrorKind, JointDevice, JointPositionActuator,
    JointPositionSensor, LinkStatisticsSensor, State,
};

/// One fake bus at a time: these tests share two cores with everything else.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Takes the bus, and puts the test's thread — and so the fake drives' threads it spawns,
/// which inherit its policy — at SCHED_FIFO where allowed: real drives have CPUs of their own,
/// and a loaded CI machine delayed a normal-priority fake's answer past the master's 16 ms
/// budget (a drive-fault test failed on its first step in a clean-clone run).
fn serial() -> std::sync::MutexGuard<'static, ()> {
    let guard = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    support::realtime_fake();
    guard
}

/// Fake drives and a master on one in-process bus, 20 ms cycle, 200 ms SDO answers. The
/// fakes' SYNC watchdog allows 10 periods here: these tests check behaviour, not timing, and
/// must hold on a loaded machine (the watchdog itself has its own test; the 2 ms run is the
/// end-to-end test).
fn in_process(nodes: &[u8]) -> (FakeCia402, Cia402) {
    let bus = Bus::new();
    let mut fc = FakeCia402Config::new(nodes).unwrap();
    fc.sync_loss_periods = 10;
    for (k, a) in fc.axes.iter_mut().enumerate() {
        a.initial = 0.1 * (k as f64 + 1.0);
    }
    let fake = FakeCia402::on_transport(fc, Box::new(bus.endpoint())).unwrap();
    let mut config = Cia402Config::new(CanAddress::parse("socketcan://unused").unwrap(), nodes)
        .with_period(Duration::from_millis(20));
    config.sdo_timeout = Duration::from_millis(200);
    let dev = Cia402::with_transport(config, Box::new(bus.endpoint())).unwrap();
    (fake, dev)
}

/// Steps at the device's period for `n` cycles; returns the failed steps.
fn run(dev: &mut Cia402, n: usize, mut command: impl FnMut(&mut Cia402, usize)) -> usize {
    let period = dev.update_period();
    let mut next = Instant::now();
    let mut failed = 0;
    for k in 0..n {
        command(dev, k);
        if let Err(e) = dev.step() {
            eprintln!("step {k}: {e}");
            failed += 1;
        }
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else {
            next = now;
        }
    }
    failed
}

#[test]
fn open_start_move_stop_on_the_in_process_bus() {
    let _serial = serial();
    let (fake, mut dev) = in_process(&[3, 4]);
    dev.open().unwrap();
    assert_eq!(dev.dof(), 2);
    let mut q = [0.0; 2];
    dev.joint_position(&mut q).unwrap();
    let per_count = core::f64::consts::TAU / f64::from(1u32 << 20);
    assert!(
        (q[0] - 0.1).abs() <= per_count && (q[1] - 0.2).abs() <= per_count,
        "{q:?}"
    );
    dev.start().unwrap();
    assert_eq!(dev.state(), State::Running);
    let s = fake.status();
    assert!(
        s.nodes
            .iter()
            .all(|n| n.power == PowerState::OperationEnabled && n.nmt == nmt::State::Operational)
    );
    assert_eq!(s.nodes[0].cycle_period_us, 20_000);
    let start = q;
    let failed = run(&mut dev, 50, |d, k| {
        let t = k as f64 * 0.02;
        let target = [start[0] + 0.05 * t, start[1] - 0.05 * t];
        d.set_joint_position(&target)
            .unwrap_or_else(|e| panic!("{e}: fault {:?}", d.fault()));
    });
    assert_eq!(failed, 0);
    dev.joint_position(&mut q).unwrap();
    // The last command was 0.05 rad/s × 0.98 s; the drive is two cycles behind.
    let expected = start[0] + 0.05 * 0.94;
    assert!((q[0] - expected).abs() < 1e-5, "{q:?} vs {expected}");
    let st = dev.link_statistics();
    assert_eq!((st.lost, st.late, st.corrupt), (0, 0, 0));
    dev.stop().unwrap();
    fake.wait_for(Duration::from_secs(1), |s| {
        s.nodes
            .iter()
            .all(|n| n.power == PowerState::SwitchOnDisabled && n.nmt == nmt::State::PreOperational)
    })
    .unwrap();
    dev.close().unwrap();
}

/// Opens and starts `dev`, then steps until the run is steady.
fn started(nodes: &[u8]) -> (FakeCia402, Cia402) {
    let (fake, mut dev) = in_process(nodes);
    dev.open().unwrap();
    dev.start().unwrap();
    assert_eq!(run(&mut dev, 3, |_, _| {}), 0);
    (fake, dev)
}

/// Steps until a step fails (at most `n`); returns its error.
fn first_failure(dev: &mut Cia402, n: usize) -> rl_drivers::Error {
    let period = dev.update_period();
    for _ in 0..n {
        if let Err(e) = dev.step() {
            return e;
        }
        std::thread::sleep(period);
    }
    panic!("no step failed in {n} cycles");
}

#[test]
fn a_drive_fault_faults_the_device_with_its_emcy_and_a_fault_reset_recovers() {
    let _serial = serial();
    let (fake, mut dev) = started(&[1, 2]);
    fake.inject(FakeFault::DriveFault {
        node: 2,
        code: 0x2310,
    });
    // The EMCY comes first (a counted step failure), the fault state with the next TPDO.
    let e = first_failure(&mut dev, 20);
    assert_eq!(e.kind(), ErrorKind::Device);
    for _ in 0..3 {
        if dev.state() == State::Faulted {
            break;
        }
        let _ = dev.step();
    }
    assert_eq!(dev.state(), State::Faulted);
    let fault = dev.fault().unwrap();
    assert_eq!(fault.kind(), ErrorKind::Device);
    let text = fault.to_string();
    assert!(
        text.contains("node 2 faulted (EMCY 0x2310 continuous over-current)"),
        "{text}"
    );
    assert_eq!(dev.counters().drive_faults, 1);
    assert!(dev.counters().emcy >= 1);
    // Stop from the fault brings the other drive to a safe state too: power off, by the quick
    // stop and disable voltage, or by its own SYNC watchdog if that came first.
    dev.stop().unwrap();
    fake.wait_for(Duration::from_secs(1), |s| {
        matches!(
            s.nodes[0].power,
            PowerState::SwitchOnDisabled | PowerState::Fault
        ) && s.nodes[1].power == PowerState::Fault
            && s.nodes.iter().all(|n| n.nmt == nmt::State::PreOperational)
    })
    .unwrap();
    // Start again: the fault is reset (rising edge of bit 7) and both drives are enabled.
    dev.start().unwrap();
    assert_eq!(run(&mut dev, 5, |_, _| {}), 0);
    assert!(
        fake.status()
            .nodes
            .iter()
            .all(|n| n.power == PowerState::OperationEnabled)
    );
    assert!(
        dev.emergencies()[1].is_some_and(|e| e.code == 0),
        "the reset EMCY"
    );
    dev.stop().unwrap();
}

#[test]
fn lost_late_and_corrupt_tpdos_are_counted_and_fail_the_step() {
    let _serial = serial();
    let (fake, mut dev) = started(&[1, 2]);
    fake.inject(FakeFault::DropTpdos { node: 1, count: 1 });
    let e = first_failure(&mut dev, 20);
    assert_eq!(e.kind(), ErrorKind::Timeout, "{e}");
    assert_eq!(dev.link_statistics().lost, 1);
    assert_eq!(run(&mut dev, 3, |_, _| {}), 0, "recovers");
    // A TPDO 25 ms late misses its 16 ms wait and is found at the next step.
    fake.inject(FakeFault::LateTpdos {
        node: 2,
        count: 1,
        delay: Duration::from_millis(25),
    });
    let e = first_failure(&mut dev, 20);
    assert_eq!(e.kind(), ErrorKind::Timeout);
    run(&mut dev, 3, |_, _| {});
    let st = dev.link_statistics();
    assert_eq!((st.lost, st.late), (2, 1), "{st:?}");
    fake.inject(FakeFault::CorruptTpdos { node: 1, count: 1 });
    let e = first_failure(&mut dev, 20);
    assert_eq!(e.kind(), ErrorKind::Protocol, "{e}");
    assert!(
        e.to_string().contains("node 1: TPDO of 7 bytes, 8 mapped"),
        "{e}"
    );
    assert_eq!(dev.link_statistics().corrupt, 1);
    assert_eq!(dev.state(), State::Running, "single failures do not fault");
    // Too many in a row do.
    fake.inject(FakeFault::DropTpdos { node: 2, count: 12 });
    run(&mut dev, 12, |_, _| {});
    assert_eq!(dev.state(), State::Faulted);
    assert_eq!(
        dev.fault().map(|e| e.kind()),
        Some(ErrorKind::Timeout),
        "{:?}",
        dev.fault()
    );
    dev.stop()
        .unwrap_or_else(|e| panic!("stop after lost TPDOs: {e}"));
}

#[test]
fn lost_heartbeats_warnings_and_following_errors_are_reported() {
    let _serial = serial();
    let (fake, mut dev) = started(&[5]);
    // A short loss: 200 ms without heartbeat, 150 ms allowed: a few failed steps, then the
    // node is heard again and the run goes on.
    fake.inject(FakeFault::HeartbeatLoss {
        node: 5,
        duration: Duration::from_millis(200),
    });
    let e = first_failure(&mut dev, 50);
    assert_eq!(e.kind(), ErrorKind::Device);
    assert_eq!(
        e.to_string(),
        "step: the device reported heartbeat: node 5: no heartbeat for 150 ms"
    );
    assert_eq!(dev.counters().heartbeats_lost, 1);
    run(&mut dev, 10, |_, _| {});
    assert_eq!(dev.state(), State::Running);
    assert_eq!(dev.counters().heartbeats_lost, 1, "one loss, counted once");
    // A long one: more than ten failed steps in a row fault the device.
    fake.inject(FakeFault::HeartbeatLoss {
        node: 5,
        duration: Duration::from_millis(600),
    });
    run(&mut dev, 30, |_, _| {});
    assert_eq!(dev.state(), State::Faulted);
    assert_eq!(dev.counters().heartbeats_lost, 2);
    dev.stop().unwrap();
    dev.start().unwrap();
    fake.inject(FakeFault::Warning { node: 5, on: true });
    fake.inject(FakeFault::FollowingError { node: 5, syncs: 1 });
    let e = first_failure(&mut dev, 20);
    assert!(e.to_string().contains("node 5: following error"), "{e}");
    run(&mut dev, 3, |_, _| {});
    assert!(dev.counters().warnings >= 3);
    assert_eq!(dev.counters().following_errors, 1);
    dev.stop().unwrap();
}

#[test]
fn an_sdo_abort_at_start_is_a_typed_error_naming_node_object_and_code() {
    let _serial = serial();
    let (fake, mut dev) = in_process(&[7]);
    dev.open().unwrap();
    fake.inject(FakeFault::SdoAbort {
        node: 7,
        index: 0x6060,
        sub: 0,
        code: 0x0800_0022,
    });
    std::thread::sleep(Duration::from_millis(20));
    let e = dev.start().unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Device);
    assert!(
        e.to_string()
            .starts_with("start: the device reported SDO: node 7: 0x6060:00 aborted 0x08000022"),
        "{e}"
    );
    assert_eq!(dev.counters().sdo_failures, 1);
    dev.stop().unwrap();
    dev.close().unwrap();
}

#[test]
fn a_cycle_the_bus_cannot_carry_is_refused_with_the_arithmetic() {
    let _serial = serial();
    let nodes = [1, 2, 3, 4, 5, 6];
    let bus = CanAddress::parse("cannelloni+udp://127.0.0.1:9").unwrap();
    let c = Cia402Config::new(bus.clone(), &nodes).with_period(Duration::from_millis(1));
    let e = Cia402::new(c).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Protocol);
    let text = e.to_string();
    assert_eq!(
        text,
        "open: CAN bus budget: 1000 µs cycle < 1810 µs: 13 frames at 1000 kbit/s"
    );
    assert!(
        Cia402::new(Cia402Config::new(bus, &nodes)).is_ok(),
        "2 ms carries six axes"
    );
}

#[test]
fn an_enabled_drive_faults_when_sync_stops_for_two_periods() {
    let _serial = serial();
    let bus = Bus::new();
    let fake = FakeCia402::on_transport(
        FakeCia402Config::new(&[9]).unwrap(),
        Box::new(bus.endpoint()),
    )
    .unwrap();
    let config = Cia402Config::new(CanAddress::parse("socketcan://unused").unwrap(), &[9])
        .with_period(Duration::from_millis(10));
    let mut config = config;
    config.sdo_timeout = Duration::from_millis(200);
    let mut dev = Cia402::with_transport(config, Box::new(bus.endpoint())).unwrap();
    dev.open().unwrap();
    dev.start().unwrap();
    // No step for 50 ms: more than two 10 ms periods without SYNC.
    let s = fake
        .wait_for(Duration::from_secs(1), |s| {
            s.nodes[0].power == PowerState::Fault
        })
        .unwrap();
    assert_eq!(s.nodes[0].counters.sync_timeouts, 1);
    let e = first_failure(&mut dev, 5);
    assert!(e.to_string().contains("EMCY 0x8100"), "{e}");
    assert_eq!(dev.state(), State::Faulted);
    dev.stop().unwrap();
    dev.close().unwrap();
    // The same drive, taken by the next master: it stopped the fault and left the drive
    // pre-operational; the SYNC of the first session is no reason to fault the second.
    let config = Cia402Config::new(CanAddress::parse("socketcan://unused").unwrap(), &[9])
        .with_period(Duration::from_millis(10));
    let mut config = config;
    config.sdo_timeout = Duration::from_millis(200);
    let mut dev = Cia402::with_transport(config, Box::new(bus.endpoint())).unwrap();
    dev.open().unwrap();
    dev.start().unwrap();
    let mut q = [0.0; 1];
    dev.joint_position(&mut q).unwrap();
    let failed = run(&mut dev, 10, |d, _| d.set_joint_position(&q).unwrap());
    assert_eq!(failed, 0);
    assert_eq!(fake.status().nodes[0].counters.sync_timeouts, 1);
    dev.stop().unwrap();
}

/// The same session over cannelloni on loopback: UDP datagrams or the TCP stream.
fn over_cannelloni(address: &str) {
    let fake_addr = CanAddress::parse(address).unwrap();
    let mut fc = FakeCia402Config::new(&[1, 2, 3]).unwrap();
    fc.sync_loss_periods = 10;
    let fake = FakeCia402::serve(fc, &fake_addr).unwrap();
    let bound = fake.local_addr().unwrap();
    let scheme = address.split("://").next().unwrap();
    let bus = CanAddress::parse(&format!("{scheme}://{bound}")).unwrap();
    let mut config = Cia402Config::new(bus, &[1, 2, 3]).with_period(Duration::from_millis(20));
    config.sdo_timeout = Duration::from_millis(200);
    let mut dev = Cia402::new(config).unwrap();
    dev.open().unwrap();
    dev.start().unwrap();
    let mut q = [0.0; 3];
    dev.joint_position(&mut q).unwrap();
    let start = q;
    let failed = run(&mut dev, 25, |d, k| {
        let target = start.map(|s| s + 0.001 * k as f64);
        d.set_joint_position(&target).unwrap();
    });
    assert_eq!(failed, 0);
    dev.stop().unwrap();
    dev.close().unwrap();
    // The last command was 0.024 rad; the quick stop at the end brakes within a millirad.
    let s = fake.status();
    assert!(
        s.nodes.iter().all(|n| (n.position - 0.024).abs() < 1e-3),
        "{s:?}"
    );
    assert_eq!(dev.link_statistics().lost, 0);
}

#[test]
fn frames_from_another_sender_do_not_reach_the_fake_drives() {
    let _serial = serial();
    let mut fc = FakeCia402Config::new(&[1, 2]).unwrap();
    fc.sync_loss_periods = 10;
    let fake = FakeCia402::serve(
        fc,
        &CanAddress::parse("cannelloni+udp://127.0.0.1:0").unwrap(),
    )
    .unwrap();
    let addr = fake.local_addr().unwrap();
    let bus = CanAddress::parse(&format!("cannelloni+udp://{addr}")).unwrap();
    let mut config = Cia402Config::new(bus, &[1, 2]).with_period(Duration::from_millis(20));
    config.sdo_timeout = Duration::from_millis(200);
    let mut dev = Cia402::new(config).unwrap();
    dev.open().unwrap();
    dev.start().unwrap();
    let mut q = [0.0; 2];
    dev.joint_position(&mut q).unwrap();
    // Another program sends, in valid cannelloni datagrams: NMT "stop" to every node, and an
    // RPDO with controlword 0 (disable voltage) to node 1.
    let stranger = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let nmt_stop = [2, 0, 0, 0, 1, 0, 0, 0, 0x00, 2, 0x02, 0x00];
    let disable = [2, 0, 1, 0, 1, 0, 0, 0x02, 0x01, 8, 0, 0, 0, 0, 0, 0, 0, 0];
    let failed = run(&mut dev, 30, |d, k| {
        if k % 5 == 2 {
            stranger.send_to(&nmt_stop, addr).unwrap();
            stranger.send_to(&disable, addr).unwrap();
        }
        d.set_joint_position(&q).unwrap();
    });
    assert_eq!(failed, 0);
    let s = fake.status();
    assert!(
        s.nodes
            .iter()
            .all(|n| n.nmt == nmt::State::Operational && n.power == PowerState::OperationEnabled),
        "{s:?}"
    );
    assert!(
        s.rejected >= 12,
        "the stranger's datagrams are counted: {}",
        s.rejected
    );
    dev.stop().unwrap();
    dev.close().unwrap();
}

#[test]
fn a_session_over_cannelloni_udp() {
    let _serial = serial();
    over_cannelloni("cannelloni+udp://127.0.0.1:0");
}

#[test]
fn a_session_over_cannelloni_tcp() {
    let _serial = serial();
    over_cannelloni("cannelloni+tcp://127.0.0.1:0");
}

/// A started device in `mode` on the in-process bus.
fn started_in(mode: rl_drivers::cia402::Mode, velocity_feedback: bool) -> (FakeCia402, Cia402) {
    let bus = Bus::new();
    let mut fc = FakeCia402Config::new(&[1]).unwrap();
    fc.sync_loss_periods = 10;
    let fake = FakeCia402::on_transport(fc, Box::new(bus.endpoint())).unwrap();
    let mut config = Cia402Config::new(CanAddress::parse("socketcan://unused").unwrap(), &[1])
        .with_period(Duration::from_millis(20));
    config.sdo_timeout = Duration::from_millis(200);
    config.mode = mode;
    config.velocity_feedback = velocity_feedback;
    let mut dev = Cia402::with_transport(config, Box::new(bus.endpoint())).unwrap();
    dev.open().unwrap();
    dev.start().unwrap();
    (fake, dev)
}

#[test]
fn cyclic_synchronous_velocity_moves_at_the_commanded_speed() {
    use rl_drivers::{JointVelocityActuator, JointVelocitySensor};
    let _serial = serial();
    let (fake, mut dev) = started_in(rl_drivers::cia402::Mode::CyclicVelocity, true);
    assert_eq!(fake.status().nodes[0].mode, 9);
    // A position command is refused in CSV, with the mode in the message.
    let e = dev.set_joint_position(&[0.0]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidArgument);
    let mut q0 = [0.0];
    dev.joint_position(&mut q0).unwrap();
    assert_eq!(
        run(&mut dev, 30, |d, _| d.set_joint_velocity(&[0.5]).unwrap()),
        0
    );
    let mut qd = [0.0];
    dev.joint_velocity(&mut qd).unwrap();
    assert!((qd[0] - 0.5).abs() < 1e-3, "{qd:?}");
    let mut q = [0.0];
    dev.joint_position(&mut q).unwrap();
    // About 27 cycles of 20 ms at 0.5 rad/s (the start ramps at 20π rad/s²).
    assert!(
        q[0] - q0[0] > 0.2 && q[0] - q0[0] < 0.3,
        "{q:?} from {q0:?}"
    );
    dev.stop().unwrap();
}

#[test]
fn cyclic_synchronous_torque_accelerates_and_reports_torque() {
    use rl_drivers::{JointTorqueActuator, JointTorqueSensor};
    let _serial = serial();
    let (fake, mut dev) = started_in(rl_drivers::cia402::Mode::CyclicTorque, false);
    assert_eq!(fake.status().nodes[0].mode, 10);
    // The torque offset is not mapped in CST: no feed-forward input.
    assert!(JointDevice::torque_feed_forward(&mut dev).is_none());
    let mut q0 = [0.0];
    dev.joint_position(&mut q0).unwrap();
    assert_eq!(
        run(&mut dev, 10, |d, _| d.set_joint_torque(&[0.1]).unwrap()),
        0
    );
    let mut tau = [0.0];
    dev.joint_torque(&mut tau).unwrap();
    assert!(
        (tau[0] - 0.1).abs() < 1e-9,
        "100 ‰ of the 1 N·m rated torque: {tau:?}"
    );
    let mut q = [0.0];
    dev.joint_position(&mut q).unwrap();
    assert!(q[0] > q0[0] + 1e-3, "it moved: {q:?} from {q0:?}");
    dev.stop().unwrap();
}

#[test]
fn each_node_has_its_own_heartbeat_consumer_time() {
    let _serial = serial();
    let bus = Bus::new();
    let mut fc = FakeCia402Config::new(&[1, 2]).unwrap();
    fc.sync_loss_periods = 10;
    let fake = FakeCia402::on_transport(fc, Box::new(bus.endpoint())).unwrap();
    let mut config = Cia402Config::new(CanAddress::parse("socketcan://unused").unwrap(), &[1, 2])
        .with_period(Duration::from_millis(20));
    config.sdo_timeout = Duration::from_millis(200);
    config.axes[1].heartbeat_timeout = Some(Duration::from_secs(1));
    let mut dev = Cia402::with_transport(config, Box::new(bus.endpoint())).unwrap();
    dev.open().unwrap();
    dev.start().unwrap();
    // 300 ms without node 2's heartbeat: within its 1 s, no error.
    fake.inject(FakeFault::HeartbeatLoss {
        node: 2,
        duration: Duration::from_millis(300),
    });
    assert_eq!(run(&mut dev, 25, |_, _| {}), 0);
    assert_eq!(dev.counters().heartbeats_lost, 0);
    // The same for node 1 (150 ms): lost, and said so.
    fake.inject(FakeFault::HeartbeatLoss {
        node: 1,
        duration: Duration::from_millis(300),
    });
    let e = first_failure(&mut dev, 25);
    assert!(
        e.to_string().contains("node 1: no heartbeat for 150 ms"),
        "{e}"
    );
    dev.stop().unwrap();
}

#[test]
fn a_feed_forward_torque_the_units_cannot_carry_is_sent_clamped_and_counted() {
    use rl_drivers::JointTorqueFeedForward;
    let _serial = serial();
    let (fake, mut dev) = started(&[1]);
    // Default units: 1 N·m rated, no gear: ±32.767 N·m.
    dev.set_joint_torque_feed_forward(&[10.0]).unwrap();
    assert_eq!(dev.counters().commands_clamped, 0);
    run(&mut dev, 3, |_, _| {});
    assert_eq!(fake.status().nodes[0].torque_offset_permille, 10_000);
    dev.set_joint_torque_feed_forward(&[50.0]).unwrap();
    assert_eq!(dev.counters().commands_clamped, 1);
    run(&mut dev, 3, |_, _| {});
    assert_eq!(fake.status().nodes[0].torque_offset_permille, i16::MAX);
    dev.stop().unwrap();
}
