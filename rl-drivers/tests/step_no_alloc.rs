//! `step()` and the getters and setters around it allocate nothing in steady state: a counting
//! global allocator counts allocations made on the test's own thread (the fakes' server threads
//! allocate freely and are not counted).

use std::time::Duration;

use rl_drivers::coach::{Coach, CoachConfig};
use rl_drivers::fake::coach_server::{CoachServer, CoachServerConfig};
use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config};
use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_drivers::{
    CartesianPositionSensor, CyclicDevice, Device, Gripper, JointPositionActuator,
    JointPositionSensor,
};
use rl_testkit::CountingAllocator;

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// Allocations made on this thread while running `f`.
fn allocations(f: impl FnOnce()) -> u64 {
    rl_testkit::allocations(f).0
}

#[test]
fn the_counter_sees_allocations() {
    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);
}

#[test]
fn h7_steps_allocate_nothing() {
    let fake = FakeH7::spawn(FakeH7Config::loopback(6)).unwrap();
    let mut robot =
        MitsubishiH7::new(MitsubishiH7Config::new(6, fake.udp_addr(), fake.r3_addr())).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    robot.step().unwrap();
    let mut q = [0.0; 6];
    let mut failures = 0;
    let n = allocations(|| {
        for k in 0..300 {
            robot.joint_position(&mut q).unwrap();
            q[0] = 0.001 * f64::from(k);
            robot.set_joint_position(&q).unwrap();
            if k % 50 == 0 {
                robot.shut().unwrap();
            }
            failures += u32::from(robot.step().is_err());
            let _ = robot.cartesian_position();
            let _ = robot.counters();
        }
    });
    assert_eq!(n, 0, "allocations in 300 steady-state H7 cycles");
    assert_eq!(failures, 0);
    // An error path (timeout) allocates nothing either.
    fake.set_frozen(true);
    assert_eq!(allocations(|| assert!(robot.step().is_err())), 0);
    fake.set_frozen(false);
}

#[test]
fn coach_steps_allocate_nothing() {
    let server = CoachServer::spawn(CoachServerConfig {
        models: vec![(0, 6)],
        ..CoachServerConfig::loopback()
    })
    .unwrap();
    let mut config = CoachConfig::new(6);
    config.server = server.addr();
    config.reply_timeout = Duration::from_secs(1);
    let mut coach = Coach::new(config).unwrap();
    coach.open().unwrap();
    coach.start().unwrap();
    coach.step().unwrap();
    let mut q = [0.0; 6];
    let n = allocations(|| {
        for k in 0..300 {
            coach.joint_position(&mut q).unwrap();
            q[1] = 0.01 * f64::from(k);
            coach.set_joint_position(&q).unwrap();
            coach.step().unwrap();
        }
    });
    assert_eq!(n, 0, "allocations in 300 steady-state Coach cycles");
}
