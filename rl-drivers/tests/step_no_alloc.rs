//! `step()` and the getters and setters around it allocate nothing in steady state: a counting
//! global allocator counts allocations made on the test's own thread (the fakes' server threads
//! allocate freely and are not counted).

use std::time::Duration;

use rl_drivers::coach::{Coach, CoachConfig};
use rl_drivers::fake::coach_server::{Behaviour, CoachServer, CoachServerConfig};
use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config, Fault, FaultPlan, Pacing};
use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_drivers::{
    CartesianPositionSensor, CyclicDevice, Device, Gripper, JointLimitSensor,
    JointPositionActuator, JointPositionSensor, LinkStatisticsSensor,
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
    // Unpaced: this test is about allocations, not the controller's timing.
    let fake = FakeH7::spawn(FakeH7Config {
        pacing: Pacing::Immediate,
        ..FakeH7Config::loopback(6)
    })
    .unwrap();
    let mut config = MitsubishiH7Config::new(6, fake.udp_addr(), fake.r3_addr());
    // Generous, so a loaded machine does not fail steady-state steps.
    config.reply_timeout = 5 * config.reply_timeout;
    let mut robot = MitsubishiH7::new(config).unwrap();
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
            let _ = robot.link_statistics();
            let mut reached = [false; 6];
            robot.joint_limit_reached(&mut reached).unwrap();
        }
    });
    assert_eq!(n, 0, "allocations in 300 steady-state H7 cycles");
    assert_eq!(failures, 0);
    // The error paths allocate nothing either: a timeout, a replayed (frozen) reply, a
    // corrupt one, and a late one followed by a good one.
    fake.set_frozen(true);
    assert_eq!(allocations(|| assert!(robot.step().is_err())), 0);
    fake.set_frozen(false);
    for (fault, fails) in [
        (Fault::Replay, true),
        (Fault::Corrupt, true),
        (Fault::Delay(std::time::Duration::from_millis(60)), true),
    ] {
        fake.set_fault(Some(FaultPlan { every: 1, fault }));
        assert_eq!(allocations(|| assert_eq!(robot.step().is_err(), fails)), 0);
        fake.set_fault(None);
        std::thread::sleep(std::time::Duration::from_millis(100));
        assert_eq!(allocations(|| robot.step().unwrap()), 0, "after {fault:?}");
    }
    let c = robot.counters();
    assert!(c.replayed >= 1 && c.corrupt >= 1 && c.late >= 1, "{c:?}");
}

#[test]
fn coach_steps_allocate_nothing() {
    let server = CoachServer::spawn(CoachServerConfig {
        models: vec![(0, vec![0.0; 6])],
        ..CoachServerConfig::loopback()
    })
    .unwrap();
    let mut config = CoachConfig::new(6);
    config.server = server.addr();
    config.reply_timeout = Duration::from_millis(100);
    config.max_consecutive_failures = 100;
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
    // A silent server: every step times out, and the timeout path allocates nothing.
    server.set_behaviour(Behaviour::Silent);
    std::thread::sleep(Duration::from_millis(30));
    let n = allocations(|| {
        for _ in 0..5 {
            assert!(coach.step().is_err());
        }
    });
    assert_eq!(n, 0, "allocations in 5 timed-out Coach steps");
    assert!(coach.counters().timeouts >= 5);
}

#[test]
fn cia402_steps_over_cannelloni_allocate_nothing() {
    use rl_drivers::canopen::{Cia402, Cia402Config};
    use rl_drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config, FakeFault};
    use rl_drivers::transport::can::CanAddress;
    use rl_drivers::{JointTorqueFeedForward, JointTorqueSensor, LinkStatisticsSensor};

    let nodes = [1, 2, 3, 4, 5, 6];
    let mut fc = FakeCia402Config::new(&nodes).unwrap();
    fc.sync_loss_periods = 50;
    let fake = FakeCia402::serve(
        fc,
        &CanAddress::parse("cannelloni+udp://127.0.0.1:0").unwrap(),
    )
    .unwrap();
    let bus =
        CanAddress::parse(&format!("cannelloni+udp://{}", fake.local_addr().unwrap())).unwrap();
    let mut config = Cia402Config::new(bus, &nodes);
    config.sdo_timeout = Duration::from_millis(200);
    config.max_consecutive_failures = 1000;
    let mut dev = Cia402::new(config).unwrap();
    dev.open().unwrap();
    dev.start().unwrap();
    dev.step().unwrap();
    let mut q = [0.0; 6];
    let mut tau = [0.0; 6];
    let mut failures = 0;
    let n = allocations(|| {
        for k in 0..300 {
            dev.joint_position(&mut q).unwrap();
            q[0] = 1e-4 * f64::from(k);
            dev.set_joint_position(&q).unwrap();
            dev.set_joint_torque_feed_forward(&tau).unwrap();
            failures += u32::from(dev.step().is_err());
            dev.joint_torque(&mut tau).unwrap();
            tau = [0.0; 6];
            let _ = dev.link_statistics();
            std::thread::sleep(Duration::from_millis(2));
        }
    });
    assert_eq!(n, 0, "allocations in 300 steady-state CiA 402 cycles");
    // The error paths (a lost TPDO, an EMCY of a drive fault) allocate nothing either.
    fake.inject(FakeFault::DropTpdos { node: 3, count: 1 });
    fake.inject(FakeFault::DriveFault {
        node: 4,
        code: 0x2310,
    });
    std::thread::sleep(Duration::from_millis(5));
    let n = allocations(|| {
        for _ in 0..5 {
            let _ = dev.step();
        }
    });
    assert_eq!(n, 0, "allocations on the error paths");
    assert!(dev.counters().tpdos_lost >= 1 && dev.counters().emcy >= 1);
    println!("steady-state failures: {failures}");
    dev.stop().unwrap();
}
