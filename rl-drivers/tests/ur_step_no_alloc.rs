//! The UR device's `step()` and its getters and setters allocate nothing in steady state,
//! through a frozen controller (lost and skipped packages) and digital output writes (a
//! counting global allocator counts allocations on the test's own thread; the fake
//! controller's thread is not counted).

use std::net::{IpAddr, Ipv4Addr};
use std::time::Duration;

use rl_drivers::fake::ur_controller::{FakeUr, FakeUrConfig};
use rl_drivers::ur::{UniversalRobot, UrConfig, UrRealtime, UrRealtimeConfig};
use rl_drivers::{
    CartesianPositionSensor, CyclicDevice, Device, DigitalInputReader, DigitalOutputWriter,
    JointPositionActuator, JointPositionSensor, JointVelocitySensor, LinkStatisticsSensor,
    SixAxisForceTorqueSensor,
};
use rl_testkit::CountingAllocator;

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn the_counter_sees_allocations() {
    assert!(rl_testkit::allocations(|| drop(std::hint::black_box(vec![1u8; 64]))).0 >= 1);
}

/// Allocations made by 300 calls of `step(k)`, the fake's controller frozen for 30 ms at the
/// 100th (lost steps, skipped messages).
fn allocations_in_300_steps(fake: &FakeUr, mut step: impl FnMut(usize)) -> u64 {
    rl_testkit::allocations(|| {
        for k in 0..300 {
            if k == 100 {
                fake.freeze(Duration::from_millis(30));
            }
            step(k);
        }
    })
    .0
}

#[test]
fn steps_allocate_nothing() {
    let fake = FakeUr::spawn(FakeUrConfig::loopback().free_ports()).unwrap();
    let mut c = UrConfig::new(IpAddr::V4(Ipv4Addr::LOCALHOST));
    c.rtde_port = fake.rtde_addr().port();
    c.dashboard_port = fake.dashboard_addr().map(|a| a.port());
    c.script_port = fake.script_addrs()[0].port();
    c.state_wait = Duration::from_millis(20);
    let mut r = UniversalRobot::new(c).unwrap();
    r.open().unwrap();
    r.start().unwrap();
    let mut q = [0.0; 6];
    r.joint_position(&mut q).unwrap();
    for _ in 0..20 {
        let _ = r.step();
    }
    let n = allocations_in_300_steps(&fake, |k| {
        if k % 50 == 0 {
            r.set_digital_output(k / 50, true).unwrap();
        }
        let mut m = [0.0; 6];
        r.joint_position(&mut m).unwrap();
        r.joint_velocity(&mut m).unwrap();
        r.set_joint_position(&q).unwrap();
        let _ = r.step();
        let _ = r.cartesian_position();
        let _ = r.link_statistics();
    });
    assert_eq!(n, 0, "allocations in 300 steps");
    let c = r.counters();
    assert!(c.lost >= 1 && c.skipped >= 5, "{c:?}");
    r.stop().unwrap();
}

#[test]
fn real_time_interface_steps_allocate_nothing() {
    // The real-time interface's reader: messages, a frozen controller (lost steps, skipped
    // messages), scripts queued and sent.
    let fake = FakeUr::spawn(FakeUrConfig::loopback().free_ports()).unwrap();
    let mut c = UrRealtimeConfig::new(IpAddr::V4(Ipv4Addr::LOCALHOST));
    c.port = fake.realtime_addr().unwrap().port();
    c.state_wait = Duration::from_millis(20);
    let mut r = UrRealtime::new(c).unwrap();
    r.open().unwrap();
    r.start().unwrap();
    for _ in 0..20 {
        let _ = r.step();
    }
    let n = allocations_in_300_steps(&fake, |k| {
        if k % 100 == 50 {
            r.queue_script("textmsg(\"rl\")\n").unwrap();
        }
        let mut m = [0.0; 6];
        r.joint_position(&mut m).unwrap();
        r.joint_velocity(&mut m).unwrap();
        let _ = r.step();
        let _ = r.cartesian_position();
        let _ = r.forces_torques();
        let _ = r.digital_input(3);
        let _ = r.link_statistics();
    });
    assert_eq!(n, 0, "allocations in 300 steps");
    let c = r.counters();
    assert!(
        c.lost >= 1 && c.skipped >= 5 && c.scripts_sent == 3,
        "{c:?}"
    );
    r.stop().unwrap();
}
