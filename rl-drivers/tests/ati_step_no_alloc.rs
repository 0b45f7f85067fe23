//! The Net F/T device's `step()` and its getters allocate nothing in steady state, through
//! dropped, reordered and repeated records and the bias request (a counting global allocator
//! counts allocations on the test's own thread; the fake sensor's thread is not counted).

use std::net::{IpAddr, Ipv4Addr};
use std::time::Duration;

use rl_drivers::ati::{AtiNetFt, NetFtConfig};
use rl_drivers::fake::netft_sensor::{FakeNetFt, FakeNetFtConfig};
use rl_drivers::{CyclicDevice, Device, LinkStatisticsSensor, SixAxisForceTorqueSensor};
use rl_testkit::CountingAllocator;

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn the_counter_sees_allocations() {
    assert!(rl_testkit::allocations(|| drop(std::hint::black_box(vec![1u8; 64]))).0 >= 1);
}

#[test]
fn steps_allocate_nothing() {
    let fake = FakeNetFt::spawn(FakeNetFtConfig {
        rdt_rate_hz: 2000,
        http_port: None,
        ..FakeNetFtConfig::loopback().free_ports()
    })
    .unwrap();
    let mut c = NetFtConfig::new(IpAddr::V4(Ipv4Addr::LOCALHOST));
    c.rdt_port = fake.rdt_addr().port();
    c.tcp_port = fake.tcp_addr().unwrap().port();
    c.stale_after = Duration::from_millis(100);
    let mut s = AtiNetFt::new(c).unwrap();
    s.open().unwrap();
    s.start().unwrap();
    for _ in 0..50 {
        let _ = s.step();
        std::thread::sleep(Duration::from_millis(1));
    }
    fake.drop_records(3);
    fake.reorder_pairs(2);
    fake.duplicate_records(2);
    fake.set_wrench([1.0, 2.0, 3.0, 0.1, 0.2, 0.3]);
    let (n, _) = rl_testkit::allocations(|| {
        for k in 0..500 {
            if k == 100 {
                s.bias_sensor().unwrap();
            }
            let _ = s.step();
            let _ = s.forces_torques();
            let _ = s.wrench();
            let _ = s.link_statistics();
            let _ = s.counters();
            std::thread::sleep(Duration::from_millis(1));
        }
    });
    assert_eq!(n, 0, "allocations in 500 steps");
    let c = s.counters();
    assert!(
        c.dropped >= 3 && c.reordered >= 2 && c.duplicated >= 2,
        "{c:?}"
    );
    s.stop().unwrap();
}
