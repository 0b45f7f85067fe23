//! The Franka driver against the fake FR3 on loopback: the session (connect, version, state,
//! URDF), a joint position and a torque-controlled motion, reflexes (a jump, lost commands)
//! and their recovery, refused settings. Each test starts its own fake on a free port.

use std::net::{IpAddr, Ipv4Addr};
use std::time::Duration;

use rl_drivers::fake::franka_controller::{FakeFranka, FakeFrankaConfig, READY, fr3_shaped_urdf};
use rl_drivers::franka::errors::RobotError;
use rl_drivers::franka::message::CollisionBehavior;
use rl_drivers::franka::state::RobotMode;
use rl_drivers::franka::{ControlMode, FrankaArm, FrankaConfig, MotionEnd};
use rl_drivers::{
    CyclicDevice, Device, DeviceError, ErrorKind, JointPositionActuator, JointPositionSensor,
    JointTorqueActuator, JointTorqueSensor, JointVelocityActuator, LinkStatisticsSensor, State,
};

mod support;

use support::stall::emulated;

const LOCALHOST: IpAddr = IpAddr::V4(Ipv4Addr::LOCALHOST);

/// One fake robot at a time: each ticks at 1 kHz at SCHED_FIFO 85 and some tests run a 1 kHz
/// client at SCHED_FIFO 80; run side by side on two CPUs they took each other's cycles (a
/// velocity motion's client skipped states and the fake saw an acceleration discontinuity in a
/// clean-clone CI run).
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner())
}

/// Waits (at most a second) until the fake's status, published after each of its ticks,
/// shows `condition`.
fn eventually(condition: impl Fn() -> bool) {
    let deadline = std::time::Instant::now() + Duration::from_secs(1);
    while !condition() {
        assert!(
            std::time::Instant::now() < deadline,
            "condition not met within 1 s"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// The fake's status once the tick that answered the client's last request has published it.
fn settled(fake: &FakeFranka) -> rl_drivers::fake::franka_controller::FakeFrankaStatus {
    std::thread::sleep(Duration::from_millis(10));
    fake.status()
}

/// SCHED_FIFO for the calling thread where the process may (root, as in CI), as a robot's
/// controller and a client's control loop run; else as it is.
fn real_time(priority: i32) {
    let _ = rl_rt::RtThreadBuilder::new("franka-test")
        .policy(rl_rt::Policy::Fifo)
        .priority(priority)
        .best_effort(true)
        .apply_to_current();
}

fn fake_thread() {
    real_time(85);
}

fn fake(config: FakeFrankaConfig) -> FakeFranka {
    FakeFranka::spawn(FakeFrankaConfig {
        command_port: 0,
        on_thread_start: Some(fake_thread),
        ..config
    })
    .expect("fake robot")
}

fn arm(fake: &FakeFranka, mode: ControlMode) -> FrankaArm {
    let mut config = FrankaConfig::new(LOCALHOST).with_mode(mode);
    config.command_port = fake.addr().port();
    // A loaded test machine: wait up to 20 ms for a state rather than 2.
    config.state_wait = Duration::from_millis(20);
    FrankaArm::new(config).unwrap()
}

#[test]
fn open_reads_the_version_the_first_state_and_the_urdf() {
    let _one = one_at_a_time();
    let fake = fake(FakeFrankaConfig::loopback());
    let mut robot = arm(&fake, ControlMode::JointPosition);
    robot.open().unwrap();
    assert_eq!(robot.server_version(), Some(10));
    let urdf = robot.robot_model_urdf().expect("urdf");
    assert!(urdf.contains("position_based_velocity_limits"), "{urdf}");
    let mut q = [0.0; 7];
    robot.joint_position(&mut q).unwrap();
    for (a, b) in q.iter().zip(READY) {
        assert!((a - b).abs() < 1e-6, "{q:?}");
    }
    assert_eq!(robot.robot_state().robot_mode, RobotMode::Idle);
    assert!(robot.robot_udp_addr().is_some());
    robot.close().unwrap();
}

#[test]
fn another_version_is_refused_and_the_message_names_both() {
    let _one = one_at_a_time();
    let fake = fake(FakeFrankaConfig {
        version: 9,
        ..FakeFrankaConfig::loopback()
    });
    let mut robot = arm(&fake, ControlMode::JointPosition);
    let e = robot.open().unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Device);
    assert!(
        e.to_string()
            .contains("incompatible version: robot 9, client 10"),
        "{e}"
    );
    assert_eq!(robot.state(), State::Closed);
    eventually(|| fake.status().version_refusals == 1);
}

/// A smooth joint-4 excursion, `0.2 (1 − cos πt)` rad for 2 s (accelerations ≤ 2 rad/s²).
fn excursion(k: usize) -> f64 {
    let t = k as f64 * 1e-3;
    0.2 * (1.0 - (std::f64::consts::PI * t).cos())
}

#[test]
fn a_joint_position_motion_runs_without_reflex_and_finishes() {
    let _one = one_at_a_time();
    real_time(80);
    let fake = fake(FakeFrankaConfig::loopback());
    let mut robot = arm(&fake, ControlMode::JointPosition);
    robot.open().unwrap();
    robot.start().unwrap();
    let mut q0 = [0.0; 7];
    robot.joint_position(&mut q0).unwrap();
    let q0 = robot.robot_state().q_d;
    let mut timeouts = 0;
    // The trajectory follows the robot's clock (its state ids), as libfranka's does: a cycle
    // this client misses does not put it behind the robot.
    let id0 = robot.robot_state().message_id;
    loop {
        let k = (robot.robot_state().message_id - id0) as usize;
        if k > 2000 {
            break;
        }
        let mut q = q0;
        q[3] = q0[3] + excursion(k.min(2000));
        robot.set_joint_position(&q).unwrap();
        if let Err(e) = robot.step() {
            // Under an emulator, as at the stop below: a command that missed its cycle made the
            // next one jump (a clean-clone CI run under qemu-aarch64: the fake slipped 9 ms,
            // 4 commands lost, an acceleration discontinuity at the 3rd cycle).
            if let Some(emulator) = emulated()
                && e.to_string().contains("discontinuity")
            {
                println!(
                    "SKIPPED the reflex-free motion under {emulator}: {e} at {k} (client {:?}, \
                     {timeouts} step timeouts; fake {:?})",
                    robot.counters(),
                    fake.status()
                );
                return;
            }
            assert_eq!(
                e.kind(),
                ErrorKind::Timeout,
                "{e} at {k}: {:?} {:?} {:?}",
                robot.motion_end(),
                robot.counters(),
                fake.status()
            );
            timeouts += 1;
        }
    }
    if let Err(e) = robot.stop() {
        // Under an emulator neither side keeps the 1 kHz cycle: a command that misses its cycle
        // makes the next one jump, which the robot rightly calls a discontinuity. The timing is
        // reported there, not asserted.
        if let Some(emulator) = emulated()
            && e.to_string().contains("discontinuity")
        {
            println!(
                "SKIPPED the reflex-free motion under {emulator}: {e} (client {:?}, {timeouts} \
                 step timeouts; fake {:?})",
                robot.counters(),
                fake.status()
            );
            return;
        }
        panic!("stop: {e}");
    }
    assert_eq!(robot.motion_end(), Some(MotionEnd::Finished));
    let s = settled(&fake);
    assert_eq!((s.reflexes, s.finished, s.motions), (0, 1, 1), "{s:?}");
    let mut q = [0.0; 7];
    robot.joint_position(&mut q).unwrap();
    assert!((q[3] - (q0[3] + excursion(2000))).abs() < 1e-4, "{q:?}");
    let c = robot.counters();
    assert!(c.states >= 1900, "{c:?}");
    assert_eq!(c.reflexes, 0);
    // Both ends agree on what was lost: the fake counts a cycle without its command, the
    // client a state it did not answer (or a step that waited in vain).
    println!(
        "client {c:?} timeouts {timeouts}; fake lost {} late {}",
        s.lost, s.late
    );
    assert!(
        s.lost <= c.unanswered + c.timeouts + s.late + 2,
        "{s:?} {c:?}"
    );
    robot.close().unwrap();
}

#[test]
fn a_jump_is_a_velocity_discontinuity_and_recovery_clears_it() {
    let _one = one_at_a_time();
    let fake = fake(FakeFrankaConfig::loopback());
    let mut robot = arm(&fake, ControlMode::JointPosition);
    robot.open().unwrap();
    robot.start().unwrap();
    let mut q = robot.robot_state().q_d;
    robot.set_joint_position(&q).unwrap();
    robot.step().unwrap();
    q[0] += 0.01;
    robot.set_joint_position(&q).unwrap();
    let mut error = None;
    for _ in 0..50 {
        if let Err(e) = robot.step() {
            if e.kind() == ErrorKind::Device {
                error = Some(e);
                break;
            }
        }
    }
    let e = error.expect("a reflex");
    assert!(e.to_string().contains("Franka reflex"), "{e}");
    assert_eq!(robot.state(), State::Faulted);
    let Some(MotionEnd::Reflex(reasons)) = robot.motion_end() else {
        panic!("{:?}", robot.motion_end())
    };
    assert!(reasons.contains(RobotError::JointMotionGeneratorVelocityDiscontinuity));
    assert_eq!(robot.counters().reflexes, 1);
    assert!(
        robot
            .reflex_counts()
            .count(RobotError::JointMotionGeneratorVelocityDiscontinuity)
            >= 1
    );
    robot.stop().unwrap();
    // The robot refuses a new motion until its errors are recovered.
    assert!(robot.start().is_err());
    robot.stop().unwrap();
    robot.automatic_error_recovery().unwrap();
    robot.start().unwrap();
    for _ in 0..20 {
        let _ = robot.step();
    }
    robot.stop().unwrap();
    let s = settled(&fake);
    assert_eq!((s.reflexes, s.recoveries, s.finished), (1, 1, 1), "{s:?}");
}

#[test]
fn lost_states_are_counted_and_twenty_in_a_row_stop_the_motion() {
    let _one = one_at_a_time();
    let fake = fake(FakeFrankaConfig::loopback());
    let mut robot = arm(&fake, ControlMode::JointPosition);
    robot.open().unwrap();
    robot.start().unwrap();
    let q = robot.robot_state().q_d;
    robot.set_joint_position(&q).unwrap();
    for _ in 0..50 {
        let _ = robot.step();
    }
    let before = robot.counters().unanswered;
    // Five states lost on the way: five commands the robot never gets.
    fake.drop_states(5);
    for _ in 0..100 {
        robot
            .step()
            .or_else(|e| {
                if e.kind() == ErrorKind::Timeout {
                    Ok(())
                } else {
                    Err(e)
                }
            })
            .unwrap();
    }
    let c = robot.counters();
    assert!(c.unanswered - before >= 5, "{c:?}");
    assert!(c.max_unanswered_in_a_row >= 5, "{c:?}");
    assert_eq!(settled(&fake).reflexes, 0);
    // Twenty-five in a row: the robot stops with communication_constraints_violation.
    fake.drop_states(25);
    let mut error = None;
    for _ in 0..200 {
        match robot.step() {
            Err(e) if e.kind() == ErrorKind::Device => {
                error = Some(e);
                break;
            }
            _ => {}
        }
    }
    let e = error.expect("a reflex");
    assert!(
        e.to_string()
            .contains("communication_constraints_violation"),
        "{e}"
    );
    assert!(robot.counters().max_unanswered_in_a_row >= 20);
    let s = settled(&fake);
    assert!(s.max_lost_in_a_row >= 20, "{s:?}");
    assert!(
        s.raised
            .iter()
            .any(|(e, _)| *e == RobotError::CommunicationConstraintsViolation)
    );
    assert!(robot.link_statistics().lost >= 30);
}

#[test]
fn torques_move_the_simulated_arm_and_zero_torque_holds_it_against_gravity() {
    let _one = one_at_a_time();
    real_time(80);
    let fake = fake(FakeFrankaConfig::loopback().with_urdf(fr3_shaped_urdf()));
    let mut robot = arm(&fake, ControlMode::JointTorque);
    robot.open().unwrap();
    robot.start().unwrap();
    let q0 = robot.robot_state().q;
    // Zero torque for 0.5 s: the robot compensates gravity, nothing moves.
    for _ in 0..500 {
        robot.set_joint_torque(&[0.0; 7]).unwrap();
        if let Err(e) = robot.step() {
            assert_eq!(e.kind(), ErrorKind::Timeout, "{e} {:?}", robot.motion_end());
        }
    }
    let mut q = [0.0; 7];
    robot.joint_position(&mut q).unwrap();
    for i in 0..7 {
        assert!((q[i] - q0[i]).abs() < 1e-5, "joint {i}: {q:?} vs {q0:?}");
    }
    let mut tau = [0.0; 7];
    robot.joint_torque(&mut tau).unwrap();
    assert!(
        tau[1].abs() > 1.0,
        "gravity on joint 2 is measured: {tau:?}"
    );
    // A torque of 0.5 N·m on joint 1 for 0.15 s turns it positive.
    for _ in 0..150 {
        let mut t = [0.0; 7];
        t[0] = 0.5;
        robot.set_joint_torque(&t).unwrap();
        if let Err(e) = robot.step() {
            assert_eq!(e.kind(), ErrorKind::Timeout, "{e} {:?}", robot.motion_end());
        }
    }
    robot.joint_position(&mut q).unwrap();
    assert!(q[0] - q0[0] > 0.01, "{q:?}");
    // Back to zero and end.
    robot.set_joint_torque(&[0.0; 7]).unwrap();
    let _ = robot.step();
    robot.stop().unwrap();
    let s = settled(&fake);
    assert_eq!((s.reflexes, s.finished), (0, 1), "{s:?}");
    assert!(s.dynamics);
}

#[test]
fn a_torque_step_is_a_torque_discontinuity() {
    let _one = one_at_a_time();
    let fake = fake(FakeFrankaConfig::loopback().with_urdf(fr3_shaped_urdf()));
    let mut robot = arm(&fake, ControlMode::JointTorque);
    robot.open().unwrap();
    robot.start().unwrap();
    let mut t = [0.0; 7];
    t[2] = 5.0;
    robot.set_joint_torque(&t).unwrap();
    let e = (0..50)
        .find_map(|_| robot.step().err().filter(|e| e.kind() == ErrorKind::Device))
        .expect("a reflex");
    assert!(
        e.to_string().contains("controller_torque_discontinuity"),
        "{e}"
    );
    robot.stop().unwrap();
}

#[test]
fn settings_are_refused_while_moving_and_when_out_of_range() {
    let _one = one_at_a_time();
    let fake = fake(FakeFrankaConfig::loopback());
    let mut robot = arm(&fake, ControlMode::JointPosition);
    robot.open().unwrap();
    robot
        .set_collision_behavior(&CollisionBehavior::uniform(20.0, 30.0))
        .unwrap();
    let e = robot
        .set_collision_behavior(&CollisionBehavior::uniform(-1.0, 30.0))
        .unwrap_err();
    assert!(e.to_string().contains("invalid argument"), "{e}");
    let mut not_a_transform = [0.0; 16];
    not_a_transform[15] = 1.0;
    assert!(robot.set_ee(&not_a_transform).is_err());
    let mut shifted = rl_drivers::franka::state::IDENTITY;
    shifted[14] = 0.1;
    robot.set_ee(&shifted).unwrap();
    robot.set_joint_impedance(&[3000.0; 7]).unwrap();
    robot.start().unwrap();
    // A setting while the motion runs is refused by the device before the robot sees it.
    assert_eq!(
        robot.set_joint_impedance(&[3000.0; 7]).unwrap_err().kind(),
        ErrorKind::State
    );
    assert!(robot.set_joint_torque(&[0.0; 7]).is_err(), "wrong mode");
    robot.stop().unwrap();
    // NE_T_EE took effect: the state reports it.
    assert_eq!(robot.robot_state().NE_T_EE[14], f64::from(0.1f32));
    assert_eq!(settled(&fake).refused_requests, 2);
}

#[test]
fn a_joint_velocity_motion_moves_the_joint_by_the_integral() {
    let _one = one_at_a_time();
    real_time(80);
    let fake = fake(FakeFrankaConfig::loopback());
    let mut robot = arm(&fake, ControlMode::JointVelocity);
    robot.open().unwrap();
    robot.start().unwrap();
    let q0 = robot.robot_state().q;
    let id0 = robot.robot_state().message_id;
    // Joint 1: 2 rad/s² for 0.1 s, 0.2 rad/s for 0.3 s, −2 rad/s² for 0.1 s: 0.08 rad in all.
    let velocity = |t: f64| {
        if t < 0.1 {
            2.0 * t
        } else if t < 0.4 {
            0.2
        } else {
            (0.2 - 2.0 * (t - 0.4)).max(0.0)
        }
    };
    loop {
        let k = robot.robot_state().message_id - id0;
        if k > 600 {
            break;
        }
        let mut dq = [0.0; 7];
        dq[0] = velocity(k as f64 * 1e-3);
        robot.set_joint_velocity(&dq).unwrap();
        if let Err(e) = robot.step() {
            assert_eq!(e.kind(), ErrorKind::Timeout, "{e} {:?}", robot.motion_end());
        }
    }
    robot.stop().unwrap();
    let moved = robot.robot_state().q[0] - q0[0];
    assert!((moved - 0.08).abs() < 2e-3, "{moved}");
    let s = settled(&fake);
    assert_eq!((s.reflexes, s.finished), (0, 1), "{s:?}");
}
