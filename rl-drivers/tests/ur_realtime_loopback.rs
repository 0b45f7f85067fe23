//! The UR real-time interface's device against the fake controller: the state at 500 Hz
//! (joints, tool pose, the wrench and digital inputs the fake was given, modes), a script
//! sent through 30003 that the controller runs (the joints seen moving), the read-only port
//! that runs nothing, the older layouts (CB3's 1116 bytes: an 8 ms cycle), and the faults,
//! each typed and counted: a frozen controller (lost steps, skipped messages), a client that
//! does not read (the fake skips its messages, counted), a stream that cannot be framed, a
//! closed controller.

#[path = "devices/realtime.rs"]
mod realtime;

use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, TcpListener};
use std::time::{Duration, Instant};

use rl_drivers::fake::ur_controller::{FakeUr, FakeUrConfig, FakeUrStatus};
use rl_drivers::proto::ur_realtime::{MAX_LEN, RealtimeState};
use rl_drivers::ur::{UrRealtime, UrRealtimeConfig};
use rl_drivers::{
    CartesianPositionSensor, CyclicDevice, Device, DeviceError, DigitalInputReader, ErrorKind,
    JointPositionSensor, JointVelocitySensor, LinkStatisticsSensor, SixAxisForceTorqueSensor,
    State,
};

fn fake(length: usize) -> FakeUr {
    FakeUr::spawn(FakeUrConfig {
        realtime_length: length,
        on_thread_start: Some(realtime::realtime),
        ..FakeUrConfig::loopback().free_ports()
    })
    .expect("fake UR")
}

fn device(port: u16) -> UrRealtime {
    let mut c = UrRealtimeConfig::new(IpAddr::V4(Ipv4Addr::LOCALHOST));
    c.port = port;
    // Generous on a shared machine: a step waits up to 20 ms for the controller.
    c.state_wait = Duration::from_millis(20);
    UrRealtime::new(c).unwrap()
}

fn started(f: &FakeUr) -> UrRealtime {
    let mut d = device(f.realtime_addr().unwrap().port());
    d.open().unwrap();
    d.start().unwrap();
    d
}

/// Waits (bounded) until `cond` holds for the fake's status.
fn eventually(f: &FakeUr, cond: impl Fn(&FakeUrStatus) -> bool) -> bool {
    let end = Instant::now() + Duration::from_secs(2);
    while Instant::now() < end {
        if cond(&f.status()) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    false
}

/// Steps until `cond` holds for the device (bounded: 2 s).
fn step_until(d: &mut UrRealtime, cond: impl Fn(&RealtimeState) -> bool) -> bool {
    let end = Instant::now() + Duration::from_secs(2);
    while Instant::now() < end {
        let _ = d.step();
        if cond(d.realtime_state()) {
            return true;
        }
    }
    false
}

#[test]
fn the_state_streams_at_500_hz_with_what_the_controller_has() {
    let f = fake(MAX_LEN);
    f.set_tcp_force([1.0, -2.0, 3.5, 0.1, -0.2, 0.3]);
    f.set_digital_inputs(0b10_0000_0000_0000_0101);
    let mut d = started(&f);
    assert_eq!(d.controller_period(), Duration::from_millis(2));
    assert!(step_until(&mut d, |s| s.tcp_force[2] == 3.5));
    let t0 = d.realtime_state().time;
    let start = Instant::now();
    let (mut steps, mut timeouts) = (0, 0);
    while start.elapsed() < Duration::from_millis(500) {
        match d.step() {
            Ok(()) => steps += 1,
            Err(e) if e.kind() == ErrorKind::Timeout => timeouts += 1,
            Err(e) => panic!("{e}"),
        }
    }
    let s = *d.realtime_state();
    // The controller's clock advanced in 2 ms steps with the wall clock, every message taken.
    let periods = (s.time - t0) / 0.002;
    assert!((periods - periods.round()).abs() < 1e-6, "{periods}");
    let c = d.counters();
    let st = f.status();
    println!(
        "{steps} steps, {timeouts} timeouts, {c:?}; fake slipped {} times",
        st.slips
    );
    // Every message came (the controller's time has no gap: the fake skipped none for us).
    assert_eq!(c.skipped, 0, "{c:?}");
    assert_eq!(st.realtime_skipped, 0);
    // A step waits 20 ms at most: one came empty only where the fake's own cycle stalled.
    assert!(timeouts == 0 || st.slips > 0, "{timeouts} timeouts");
    if st.slips == 0 {
        assert!(periods >= 200.0, "{periods} periods in 0.5 s");
    }
    assert_eq!(c.corrupt, 0);
    assert_eq!(s.length, 1220);
    assert_eq!(s.robot_mode, 7);
    assert_eq!(s.safety_mode, 1);
    assert_eq!(s.safety_status, 1);
    assert_eq!(s.joint_modes, [253; 6]);
    assert_eq!(s.program_state, 1);
    assert_eq!(s.v_robot, 48.0);
    assert_eq!(s.q_actual, st.q, "the arm stands still");
    let mut q = [0.0; 6];
    d.joint_position(&mut q).unwrap();
    assert_eq!(q, st.q);
    d.joint_velocity(&mut q).unwrap();
    assert_eq!(q, [0.0; 6]);
    assert_eq!(
        d.forces_torques().unwrap(),
        [1.0, -2.0, 3.5, 0.1, -0.2, 0.3]
    );
    let w = d.wrench().unwrap();
    assert_eq!((w.force.z, w.moment.x), (3.5, 0.1));
    let bits: Vec<usize> = (0..18).filter(|k| d.digital_input(*k).unwrap()).collect();
    assert_eq!(bits, [0, 2, 17]);
    assert_eq!(
        d.digital_input(18).unwrap_err().kind(),
        ErrorKind::InvalidArgument
    );
    // The tool pose: the rotation vector as a matrix, the position as sent.
    let pose = d.cartesian_position().unwrap();
    let p = s.tool_vector_actual;
    assert_eq!(pose.translation.to_array(), [p[0], p[1], p[2]]);
    assert!(p.iter().any(|x| *x != 0.0));
    let stats = d.link_statistics();
    assert_eq!(stats.received, c.messages);
    assert!(f.status().realtime_clients >= 1);
    d.stop().unwrap();
    d.close().unwrap();
}

#[test]
fn a_script_through_30003_moves_the_arm_and_the_read_only_port_runs_nothing() {
    let f = fake(MAX_LEN);
    let q0 = f.status().q;
    let target: Vec<f64> = q0.iter().map(|q| q + 0.05).collect();
    let script = format!(
        "def rl_realtime_test():\n  movej([{}], a=1.4, v=0.5)\nend\n",
        target
            .iter()
            .map(|q| format!("{q:.6}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    // The read-only port: the script is dropped (counted), nothing runs.
    let mut ro = device(f.realtime_read_only_addr().unwrap().port());
    ro.open().unwrap();
    ro.start().unwrap();
    ro.queue_script(&script).unwrap();
    ro.step().unwrap();
    assert_eq!(ro.counters().scripts_sent, 1);
    assert!(eventually(&f, |s| s.read_only_ignored == script.len() as u64));
    assert_eq!(f.status().programs_started, 0);
    // 30003 runs it: the program plays and the joints reach the target.
    let mut d = started(&f);
    d.queue_script(&script).unwrap();
    assert!(step_until(&mut d, |s| s.program_state == 2));
    assert!(step_until(&mut d, |s| s
        .q_actual
        .iter()
        .zip(&target)
        .all(|(q, t)| (q - t).abs() < 1e-6)
        && s.program_state == 1));
    assert_eq!(f.status().programs_started, 1);
    // The read-only client saw the same motion.
    assert!(step_until(&mut ro, |s| (s.q_actual[0] - target[0]).abs() < 1e-6));
    // A script longer than the buffer is refused whole, with the sizes.
    let long = "x".repeat(rl_drivers::ur::SCRIPT_CAPACITY + 1);
    let e = d.queue_script(&long).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidArgument);
    assert!(e.to_string().contains("16385"), "{e}");
}

#[test]
fn cb3_layout_gives_an_8_ms_cycle_and_its_fields() {
    let f = fake(1116);
    let d = {
        let mut d = device(f.realtime_addr().unwrap().port());
        d.open().unwrap();
        d
    };
    let s = d.realtime_state();
    assert_eq!(s.length, 1116);
    assert_eq!(d.controller_period(), Duration::from_millis(8));
    assert_eq!(s.safety_status, 1);
    assert_eq!(s.payload_mass, 0.0);
    // The fake streams at its 500 Hz whatever the layout; the device, told 8 ms, counts the
    // 2 ms steps as no gap.
    assert_eq!(d.counters().skipped, 0);
}

#[test]
fn a_frozen_controller_is_lost_steps_and_skipped_messages() {
    let f = fake(MAX_LEN);
    let mut d = started(&f);
    for _ in 0..20 {
        d.step().unwrap();
    }
    f.freeze(Duration::from_millis(100));
    let mut timeouts = 0;
    let end = Instant::now() + Duration::from_millis(400);
    while Instant::now() < end {
        match d.step() {
            Ok(()) => {}
            Err(e) => {
                assert_eq!(e.kind(), ErrorKind::Timeout, "{e}");
                timeouts += 1;
            }
        }
        if d.state() == State::Faulted {
            break;
        }
    }
    let c = d.counters();
    println!("{timeouts} timeouts, {c:?}");
    assert!(timeouts >= 2 && c.lost == timeouts, "{c:?}");
    // 100 ms without messages: the controller's clock jumped by about 50 periods.
    assert!(c.skipped >= 30, "{c:?}");
    assert_eq!(d.link_statistics().lost, c.lost + c.skipped);
}

#[test]
fn a_client_that_does_not_read_is_skipped_by_the_controller_and_others_go_on() {
    let f = fake(MAX_LEN);
    let addr = f.realtime_addr().unwrap();
    // A client with a small receive buffer that never reads (the kernel's would otherwise
    // take megabytes, seconds of the stream, before the fake's queue fills).
    let idle = socket2::Socket::new(socket2::Domain::IPV4, socket2::Type::STREAM, None).unwrap();
    idle.set_recv_buffer_size(4096).unwrap();
    idle.connect(&addr.into()).unwrap();
    let mut d = started(&f);
    // The fake's 64 KiB queue fills in about 0.1 s once the kernel's buffers are full.
    let t = Instant::now();
    while f.status().realtime_skipped == 0 && t.elapsed() < Duration::from_secs(10) {
        let _ = d.step();
    }
    println!("the fake skipped messages after {:?}", t.elapsed());
    assert!(f.status().realtime_skipped > 0);
    let t = Instant::now();
    let before = d.counters().messages;
    while t.elapsed() < Duration::from_millis(200) {
        let _ = d.step();
    }
    // Our reader went on getting whole messages beside the one that does not read.
    assert!(d.counters().messages > before, "{:?}", d.counters());
    assert_eq!(d.counters().corrupt, 0);
    let st = f.status();
    assert!(st.realtime_sent > st.realtime_skipped, "{st:?}");
    drop(idle);
}

#[test]
fn a_stream_that_cannot_be_framed_is_a_protocol_error_that_says_why() {
    // A server that sends a 1000-byte "message": no known layout.
    let l = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    let port = l.local_addr().unwrap().port();
    let server = std::thread::spawn(move || {
        let (mut s, _) = l.accept().unwrap();
        let mut m = vec![0u8; 1000];
        m[..4].copy_from_slice(&1000u32.to_be_bytes());
        s.write_all(&m).unwrap();
        std::thread::sleep(Duration::from_millis(300));
    });
    let mut d = device(port);
    let e = d.open().unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Protocol, "{e}");
    assert!(e.to_string().contains("1000 bytes: no known layout"), "{e}");
    assert_eq!(d.counters().corrupt, 1);
    server.join().unwrap();
}

#[test]
fn a_closed_controller_disconnects() {
    let mut f = fake(MAX_LEN);
    let mut d = started(&f);
    d.step().unwrap();
    f.shutdown();
    drop(f);
    let end = Instant::now() + Duration::from_secs(2);
    let mut kind = None;
    while Instant::now() < end {
        if let Err(e) = d.step() {
            if e.kind() != ErrorKind::Timeout {
                kind = Some(e.kind());
                break;
            }
        }
    }
    assert_eq!(kind, Some(ErrorKind::Disconnected));
}
