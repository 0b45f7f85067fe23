//! The ATI Net F/T driver against the fake sensor on loopback: the calibration read over TCP,
//! a known wrench in SI units from counts in other units, the sensor's bias and the driver's
//! tare, dropped, reordered and repeated records counted as the fake injected them, garbage and
//! foreign datagrams, a silent sensor (timeouts, then a fault), the sensor's error status, the
//! buffered mode, and the wrench expressed in the flange's and the world's frames through a
//! model.

use std::net::{IpAddr, Ipv4Addr, UdpSocket};
use std::time::{Duration, Instant};

use rl_drivers::ati::{AtiNetFt, NetFtConfig, SensorMount, StreamMode};
use rl_drivers::fake::netft_sensor::{FakeNetFt, FakeNetFtConfig};
use rl_drivers::proto::netft::{Calibration, ForceUnit, TorqueUnit};
use rl_drivers::{CyclicDevice, Device, ErrorKind, SixAxisForceTorqueSensor, State};

const LOCALHOST: IpAddr = IpAddr::V4(Ipv4Addr::LOCALHOST);

fn fake(rate: u32) -> FakeNetFt {
    FakeNetFt::spawn(FakeNetFtConfig {
        rdt_rate_hz: rate,
        http_port: None,
        ..FakeNetFtConfig::loopback().free_ports()
    })
    .expect("fake sensor")
}

fn config_for(fake: &FakeNetFt) -> NetFtConfig {
    let mut c = NetFtConfig::new(LOCALHOST);
    c.rdt_port = fake.rdt_addr().port();
    c.tcp_port = fake.tcp_addr().expect("tcp").port();
    // Generous on a shared machine: the fake's thread may be scheduled late.
    c.stale_after = Duration::from_millis(50);
    c
}

fn started(fake: &FakeNetFt) -> AtiNetFt {
    let mut s = AtiNetFt::new(config_for(fake)).expect("config");
    s.open().expect("open");
    s.start().expect("start");
    s
}

/// Steps (1 ms apart) until `done` holds, at most `limit`; step errors are ignored here.
fn step_until(s: &mut AtiNetFt, limit: Duration, mut done: impl FnMut(&AtiNetFt) -> bool) -> bool {
    let end = Instant::now() + limit;
    while Instant::now() < end {
        let _ = s.step();
        if done(s) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    false
}

fn close(a: &[f64; 6], b: &[f64; 6], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

#[test]
fn a_known_wrench_arrives_in_si_units_with_the_sensors_calibration() {
    // A calibration in lbf and N·mm, as some sensors are calibrated: the driver reads it over
    // TCP and converts.
    let calibration = Calibration {
        counts_per_force: 1_000_000,
        counts_per_torque: 1_000,
        force_unit: ForceUnit::PoundForce,
        torque_unit: TorqueUnit::NewtonMillimetre,
        scale_factors: [1; 6],
    };
    let f = FakeNetFt::spawn(FakeNetFtConfig {
        calibration,
        rdt_rate_hz: 1000,
        http_port: None,
        ..FakeNetFtConfig::loopback().free_ports()
    })
    .unwrap();
    let mut s = started(&f);
    assert_eq!(s.calibration(), Some(calibration));
    let wrench = [12.5, -3.0, 40.0, 0.25, -0.5, 1.5];
    f.set_wrench(wrench);
    assert!(
        step_until(&mut s, Duration::from_secs(2), |s| {
            close(&s.forces_torques().unwrap(), &wrench, 1e-5)
        }),
        "got {:?}",
        s.forces_torques()
    );
    // The counts on the wire are the calibration's: 1e6 per lbf, 1e3 per N·mm.
    let r = s.record().unwrap();
    assert_eq!(
        r.counts[0],
        (12.5 / 4.448_221_615_260_5 * 1e6_f64).round() as i32
    );
    assert_eq!(r.counts[5], 1_500_000);
    // As a spatial force vector: moment first.
    let w = s.wrench().unwrap();
    assert!((w.moment.z - 1.5).abs() < 1e-9 && (w.force.z - 40.0).abs() < 1e-5);
    assert_eq!(s.counters().status_errors, 0);
    s.stop().unwrap();
    s.close().unwrap();
    // The fake stops streaming on command 0.
    std::thread::sleep(Duration::from_millis(20));
    assert_eq!(f.status().streaming_to, None);
    assert!(f.status().calinfo_requests >= 1);
}

#[test]
fn the_sensors_bias_and_the_drivers_tare_remove_an_offset() {
    let f = fake(1000);
    f.set_offset([1.0, 2.0, -3.0, 0.1, 0.2, 0.3]);
    let mut s = started(&f);
    assert!(step_until(&mut s, Duration::from_secs(2), |s| {
        close(
            &s.forces_torques().unwrap(),
            &[1.0, 2.0, -3.0, 0.1, 0.2, 0.3],
            1e-5,
        )
    }));
    // The sensor's own bias (RDT 0x42), sent by the next step.
    s.bias_sensor().unwrap();
    assert!(step_until(&mut s, Duration::from_secs(2), |s| {
        close(&s.forces_torques().unwrap(), &[0.0; 6], 1e-5)
    }));
    assert_eq!(f.status().biases, 1);
    let load = [0.0, 0.0, -9.81, 0.0, 0.0, 0.0];
    f.set_wrench(load);
    assert!(step_until(&mut s, Duration::from_secs(2), |s| {
        close(&s.forces_torques().unwrap(), &load, 1e-5)
    }));
    // The driver's tare: the sensor untouched, the reading zeroed here.
    s.tare().unwrap();
    assert_eq!(s.forces_torques().unwrap(), [0.0; 6]);
    f.set_wrench([0.0, 0.0, -19.62, 0.0, 0.0, 0.0]);
    assert!(step_until(&mut s, Duration::from_secs(2), |s| {
        close(&s.forces_torques().unwrap(), &load, 1e-5)
    }));
    assert_eq!(f.status().biases, 1, "a tare sends nothing");
    s.stop().unwrap();
}

#[test]
fn dropped_reordered_and_repeated_records_are_counted_as_injected() {
    let f = fake(1000);
    let mut s = started(&f);
    assert!(step_until(&mut s, Duration::from_secs(1), |s| s
        .counters()
        .records
        > 20));
    f.drop_records(5);
    f.reorder_pairs(3);
    f.duplicate_records(2);
    let ok = step_until(&mut s, Duration::from_secs(3), |_| {
        let st = f.status();
        st.dropped == 5 && st.reordered == 3 && st.duplicated == 2
    });
    assert!(ok, "the fake injected {:?}", f.status());
    // Let the last injected datagrams arrive.
    step_until(&mut s, Duration::from_millis(50), |_| false);
    let c = s.counters();
    let st = f.status();
    // A pair sent in swapped order: the later record comes first, so the earlier one is late
    // (dropped as reordered) and was counted missing when the later one came.
    assert_eq!(c.reordered, st.reordered, "{c:?} {st:?}");
    assert_eq!(c.duplicated, st.duplicated, "{c:?} {st:?}");
    assert_eq!(c.dropped, st.dropped + st.reordered, "{c:?} {st:?}");
    let l = rl_drivers::LinkStatisticsSensor::link_statistics(&s);
    assert_eq!(l.late, 5);
    s.stop().unwrap();
}

#[test]
fn garbage_and_strangers_are_counted_not_taken() {
    let f = fake(1000);
    let mut s = started(&f);
    assert!(step_until(&mut s, Duration::from_secs(1), |s| s
        .counters()
        .records
        > 5));
    f.send_garbage(&[0xAB; 35]);
    f.send_garbage(&[]);
    let stranger = UdpSocket::bind("127.0.0.1:0").unwrap();
    let me = s.local_addr().unwrap();
    stranger.send_to(&[0u8; 36], me).unwrap();
    assert!(step_until(&mut s, Duration::from_secs(2), |s| {
        let c = s.counters();
        c.malformed == 2 && c.foreign == 1
    }));
    assert!(s.step().is_ok() || s.state() == State::Running);
    s.stop().unwrap();
}

#[test]
fn a_silent_sensor_times_out_then_faults_and_can_still_be_stopped() {
    let f = fake(1000);
    let mut c = config_for(&f);
    c.stale_after = Duration::from_millis(20);
    c.max_failures = 5;
    let mut s = AtiNetFt::new(c).unwrap();
    s.open().unwrap();
    s.start().unwrap();
    f.silence(Duration::from_secs(10));
    let mut kinds = Vec::new();
    let end = Instant::now() + Duration::from_secs(3);
    while s.state() == State::Running && Instant::now() < end {
        if let Err(e) = s.step() {
            kinds.push(rl_drivers::DeviceError::kind(&e));
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    assert_eq!(s.state(), State::Faulted);
    assert_eq!(kinds.len(), 5, "{kinds:?}");
    assert!(kinds.iter().all(|k| *k == ErrorKind::Timeout));
    assert_eq!(
        rl_drivers::DeviceError::kind(&s.fault().unwrap()),
        ErrorKind::Timeout
    );
    assert_eq!(s.counters().stale_steps, 5);
    s.stop().unwrap();
    s.close().unwrap();
}

#[test]
fn the_sensors_error_status_fails_the_step_as_a_device_error() {
    let f = fake(1000);
    let mut s = started(&f);
    f.set_status_word(0x8000_0002);
    let mut err = None;
    let end = Instant::now() + Duration::from_secs(2);
    while err.is_none() && Instant::now() < end && s.state() == State::Running {
        err = s.step().err();
        std::thread::sleep(Duration::from_millis(1));
    }
    let e = err.expect("an error");
    assert_eq!(rl_drivers::DeviceError::kind(&e), ErrorKind::Device);
    assert!(e.to_string().contains("0x80000002"), "{e}");
    assert!(s.counters().status_errors > 0);
    assert_eq!(s.counters().last_status, 0x8000_0002);
    s.stop().unwrap();
}

#[test]
fn buffered_streaming_takes_the_newest_of_each_datagram() {
    let f = fake(2000);
    let mut c = config_for(&f);
    c.mode = StreamMode::Buffered;
    let mut s = AtiNetFt::new(c).unwrap();
    s.open().unwrap();
    s.start().unwrap();
    f.set_wrench([0.0, 5.0, 0.0, 0.0, 0.0, 0.0]);
    assert!(step_until(&mut s, Duration::from_secs(2), |s| {
        s.counters().records >= 200
            && close(
                &s.forces_torques().unwrap(),
                &[0.0, 5.0, 0.0, 0.0, 0.0, 0.0],
                1e-5,
            )
    }));
    let c = s.counters();
    // Ten records per datagram.
    assert!(c.records >= 9 * c.datagrams, "{c:?}");
    assert_eq!(
        c.dropped + c.reordered + c.duplicated + c.malformed,
        0,
        "{c:?}"
    );
    s.stop().unwrap();
}

#[test]
fn without_a_calibration_server_open_fails_and_a_given_calibration_needs_none() {
    let f = FakeNetFt::spawn(FakeNetFtConfig {
        tcp_port: None,
        http_port: None,
        rdt_rate_hz: 1000,
        ..FakeNetFtConfig::loopback().free_ports()
    })
    .unwrap();
    let mut c = NetFtConfig::new(LOCALHOST);
    c.rdt_port = f.rdt_addr().port();
    // A port nobody listens on.
    c.tcp_port = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        l.local_addr().unwrap().port()
    };
    c.timeout = Duration::from_millis(300);
    let mut s = AtiNetFt::new(c.clone()).unwrap();
    let e = s.open().unwrap_err();
    assert_eq!(s.state(), State::Closed);
    assert!(
        matches!(
            rl_drivers::DeviceError::kind(&e),
            ErrorKind::Io | ErrorKind::Disconnected
        ),
        "{e}"
    );
    c.calibration = Some(Calibration::si(1_000_000, 1_000_000));
    let mut s = AtiNetFt::new(c).unwrap();
    s.open().unwrap();
    s.start().unwrap();
    f.set_wrench([1.0; 6]);
    assert!(step_until(&mut s, Duration::from_secs(2), |s| {
        close(&s.forces_torques().unwrap(), &[1.0; 6], 1e-5)
    }));
    s.stop().unwrap();
}

/// A two-link arm whose flange carries a sensor frame turned 90° about z and 5 cm out along z,
/// and a tool frame 10 cm further.
const ARM: &str = r#"<robot name="arm">
  <link name="base"/>
  <link name="link1"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="flange"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="ft_sensor"/>
  <link name="tool"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/><origin xyz="0 0 0.3"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="flange"/><origin xyz="0.4 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <joint name="mount" type="fixed"><parent link="flange"/><child link="ft_sensor"/><origin xyz="0 0 0.05" rpy="0 0 1.5707963267948966"/></joint>
  <joint name="tcp" type="fixed"><parent link="ft_sensor"/><child link="tool"/><origin xyz="0 0 0.1"/></joint>
</robot>"#;

#[test]
fn the_wrench_in_the_flanges_and_the_worlds_frame_through_the_model() {
    use rl_core::loader::{UrdfOptions, load_urdf_str};
    let loaded = load_urdf_str::<8>(ARM, &UrdfOptions::default()).expect("urdf");
    let mount = SensorMount::from_model(&loaded, "ft_sensor").expect("frame");
    let f = fake(1000);
    let mut s = started(&f);
    // 10 N along the sensor's x, 1 N·m about its z.
    f.set_wrench([10.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    assert!(step_until(&mut s, Duration::from_secs(2), |s| {
        (s.forces_torques().unwrap()[0] - 10.0).abs() < 1e-5
    }));
    // In the flange's frame: the sensor's x is the flange's y (90° about z); the force acts
    // 5 cm out along z, so its moment about the flange's origin is r × f = (0,0,0.05) × (0,10,0)
    // = (-0.5, 0, 0), plus the measured 1 N·m about z.
    let x_flange_sensor = mount.pose_in(&loaded, "flange").expect("same body");
    let w = s.wrench_in(&x_flange_sensor).unwrap();
    assert!(
        (w.force - glam::DVec3::new(0.0, 10.0, 0.0)).length() < 1e-6,
        "{w:?}"
    );
    assert!(
        (w.moment - glam::DVec3::new(-0.5, 0.0, 1.0)).length() < 1e-6,
        "{w:?}"
    );
    // In the tool's frame (10 cm beyond the sensor along its z): the force is the sensor's x,
    // at (0, 0, -0.1) from the tool's origin: moment (0,0,-0.1) × (10,0,0) = (0, -1, 0).
    let x_tool_sensor = mount.pose_in(&loaded, "tool").expect("same body");
    let w = s.wrench_in(&x_tool_sensor).unwrap();
    assert!(
        (w.force - glam::DVec3::new(10.0, 0.0, 0.0)).length() < 1e-6,
        "{w:?}"
    );
    assert!(
        (w.moment - glam::DVec3::new(0.0, -1.0, 1.0)).length() < 1e-6,
        "{w:?}"
    );
    // In the world's frame at q = (π/2, 0): link 1 turned 90° about z, so the flange's y is the
    // world's -x; the sensor sits at (0, 0.4, 0.35).
    let mut data = rl_core::model::Data::<8>::new();
    rl_core::algo::forward_position(
        &loaded.model,
        &mut data,
        &[core::f64::consts::FRAC_PI_2, 0.0],
    )
    .unwrap();
    let w = mount.wrench_in_world(&data, &s.wrench().unwrap());
    let f_world = glam::DVec3::new(-10.0, 0.0, 0.0);
    let p = glam::DVec3::new(0.0, 0.4, 0.35);
    assert!((w.force - f_world).length() < 1e-6, "{w:?}");
    let expected_moment = p.cross(f_world) + glam::DVec3::new(0.0, 0.0, 1.0);
    assert!((w.moment - expected_moment).length() < 1e-6, "{w:?}");
    assert!(mount.pose_in(&loaded, "link1").is_none(), "another body");
    assert!(SensorMount::from_model(&loaded, "nowhere").is_err());
    s.stop().unwrap();
}
