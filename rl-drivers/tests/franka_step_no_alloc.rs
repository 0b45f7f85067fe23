//! The Franka device's `step()` and the getters and setters around it allocate nothing in
//! steady state (a counting global allocator counts allocations on the test's own thread; the
//! fake robot's thread allocates freely and is not counted): in joint position mode and in
//! torque mode, through a reflex's error path and through lost states.

use std::net::{IpAddr, Ipv4Addr};
use std::time::Duration;

use rl_drivers::fake::franka_controller::{FakeFranka, FakeFrankaConfig, fr3_shaped_urdf};
use rl_drivers::franka::{ControlMode, FrankaArm, FrankaConfig};
use rl_drivers::{
    CartesianPositionSensor, CyclicDevice, Device, JointPositionActuator, JointPositionSensor,
    JointTorqueActuator, JointTorqueSensor, JointVelocitySensor, LinkStatisticsSensor,
};
use rl_testkit::CountingAllocator;

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

fn allocations(f: impl FnOnce()) -> u64 {
    rl_testkit::allocations(f).0
}

fn setup(mode: ControlMode, config: FakeFrankaConfig) -> (FakeFranka, FrankaArm) {
    let fake = FakeFranka::spawn(FakeFrankaConfig {
        command_port: 0,
        ..config
    })
    .unwrap();
    let mut c = FrankaConfig::new(IpAddr::V4(Ipv4Addr::LOCALHOST)).with_mode(mode);
    c.command_port = fake.addr().port();
    c.state_wait = Duration::from_millis(20);
    let mut robot = FrankaArm::new(c).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    let _ = robot.step();
    (fake, robot)
}

#[test]
fn the_counter_sees_allocations() {
    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);
}

#[test]
fn position_steps_and_lost_states_allocate_nothing() {
    let (fake, mut robot) = setup(ControlMode::JointPosition, FakeFrankaConfig::loopback());
    let q0 = robot.robot_state().q_d;
    let mut q = [0.0; 7];
    let n = allocations(|| {
        for k in 0..300 {
            if k == 100 {
                fake.drop_states(3);
            }
            robot.joint_position(&mut q).unwrap();
            let mut dq = [0.0; 7];
            robot.joint_velocity(&mut dq).unwrap();
            robot.set_joint_position(&q0).unwrap();
            let _ = robot.step();
            let _ = robot.cartesian_position();
            let _ = robot.counters();
            let _ = robot.link_statistics();
        }
    });
    assert_eq!(n, 0, "allocations in 300 steps");
    assert!(robot.counters().unanswered >= 3);
    robot.stop().unwrap();
}

#[test]
fn torque_steps_and_a_reflex_allocate_nothing() {
    let (_fake, mut robot) = setup(
        ControlMode::JointTorque,
        FakeFrankaConfig::loopback().with_urdf(fr3_shaped_urdf()),
    );
    let mut tau = [0.0; 7];
    let mut reflex = None;
    let n = allocations(|| {
        for k in 0..300 {
            robot.joint_torque(&mut tau).unwrap();
            // A 5 N·m step at 200: the robot stops with a torque discontinuity.
            let t = if k >= 200 { 5.0 } else { 0.0 };
            if robot
                .set_joint_torque(&[t, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
                .is_err()
            {
                break;
            }
            if let Err(e) = robot.step()
                && robot.state() == rl_drivers::State::Faulted
            {
                reflex = Some(e);
                break;
            }
        }
    });
    assert_eq!(n, 0, "allocations in torque steps and the reflex");
    assert!(reflex.is_some(), "the step reached the reflex");
    robot.stop().unwrap();
}
