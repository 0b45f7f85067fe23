//! The Robotiq gripper's `step()` and its setters allocate nothing in steady state, over RTU
//! and over TCP, through a wrong CRC and a late answer (a counting global allocator counts
//! allocations on the test's own thread; the fake gripper's thread is not counted).

#[path = "devices/realtime.rs"]
mod realtime;

use realtime::realtime;
use std::time::Duration;

use rl_drivers::fake::robotiq_gripper::{FakeGripper, FakeGripperConfig};
use rl_drivers::proto::robotiq::Model;
use rl_drivers::robotiq::{Exchange, GripperConfig, RobotiqGripper};
use rl_drivers::{CyclicDevice, Device, Gripper, LinkStatisticsSensor};
use rl_testkit::CountingAllocator;

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn the_counter_sees_allocations() {
    assert!(rl_testkit::allocations(|| drop(std::hint::black_box(vec![1u8; 64]))).0 >= 1);
}

fn steady(g: &mut RobotiqGripper, fake: &FakeGripper) {
    g.open().unwrap();
    g.start().unwrap();
    let _ = g.step();
    let (n, _) = rl_testkit::allocations(|| {
        for k in 0..60 {
            if k == 10 {
                fake.corrupt_answers(1);
            }
            if k == 20 {
                fake.late_answers(1, Duration::from_millis(60));
            }
            let _ = if k % 20 < 10 { g.shut() } else { g.release() };
            let _ = g.set_speed_count((k * 4) as u8);
            let _ = g.set_force(100.0);
            let _ = g.step();
            let _ = g.status();
            let _ = g.opening_m();
            let _ = g.link_statistics();
            std::thread::sleep(Duration::from_millis(2));
        }
    });
    assert_eq!(n, 0, "allocations in 60 steps");
    let m = g.master_counters().unwrap();
    assert!(m.timeouts >= 1, "{m:?}");
    g.stop().unwrap();
    g.close().unwrap();
}

#[test]
fn rtu_steps_allocate_nothing() {
    let fake = FakeGripper::spawn(FakeGripperConfig {
        on_thread_start: Some(realtime),
        activation_time: Duration::from_millis(50),
        ..FakeGripperConfig::serial()
    })
    .unwrap();
    let mut g = RobotiqGripper::rtu(
        GripperConfig::new(Model::TwoF140),
        fake.serial_path().unwrap(),
        115_200,
    )
    .unwrap();
    steady(&mut g, &fake);
    assert!(g.master_counters().is_none(), "closed");
    assert!(fake.status().spoiled >= 2);
}

#[test]
fn tcp_steps_allocate_nothing() {
    let fake = FakeGripper::spawn(FakeGripperConfig {
        on_thread_start: Some(realtime),
        activation_time: Duration::from_millis(50),
        ..FakeGripperConfig::tcp("127.0.0.1:0".parse().unwrap())
    })
    .unwrap();
    let c = GripperConfig {
        exchange: Exchange::Separate,
        ..GripperConfig::new(Model::TwoF85)
    };
    let mut g = RobotiqGripper::tcp(c, fake.tcp_addr().unwrap()).unwrap();
    steady(&mut g, &fake);
}
