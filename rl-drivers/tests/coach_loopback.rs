//! The Coach client against the Coach server on loopback (random ports, bounded waits).
#![allow(clippy::needless_range_loop)]

use std::time::Duration;

use glam::DVec3;
use rl_core::rotation::euler;
use rl_drivers::coach::{Coach, CoachConfig};
use rl_drivers::fake::coach_server::{CoachServer, CoachServerConfig, Delivery};
use rl_drivers::{
    CyclicDevice, Device, DeviceError, ErrorKind, JointPositionActuator, JointPositionSensor,
    JointTorqueActuator, JointVelocityActuator, Pose, ProtocolError, State,
};

const DOF: usize = 6;

fn server(delivery: Delivery) -> CoachServer {
    let config = CoachServerConfig {
        models: vec![(0, vec![0.0; DOF])],
        delivery,
        ..CoachServerConfig::loopback()
    };
    CoachServer::spawn(config).expect("server starts")
}

fn client(server: &CoachServer) -> Coach {
    let mut config = CoachConfig::new(DOF);
    config.server = server.addr();
    config.reply_timeout = Duration::from_secs(1);
    let mut coach = Coach::new(config).unwrap();
    coach.open().unwrap();
    coach.start().unwrap();
    coach
}

fn ramp(k: usize) -> [f64; DOF] {
    core::array::from_fn(|i| 0.001 * k as f64 * (i as f64 - 2.5) + 1e-7 * i as f64)
}

/// Sends `cycles` joint vectors and checks each reply equals the vector to 6 significant digits.
fn exchange(coach: &mut Coach, cycles: usize) {
    let mut got = [0.0; DOF];
    for k in 0..cycles {
        let q = ramp(k);
        coach.set_joint_position(&q).unwrap();
        coach.step().unwrap_or_else(|e| panic!("cycle {k}: {e}"));
        coach.joint_position(&mut got).unwrap();
        for i in 0..DOF {
            let tol = 1e-5 * q[i].abs().max(1e-300);
            assert!(
                (got[i] - q[i]).abs() <= tol,
                "cycle {k} joint {i}: {} vs {}",
                got[i],
                q[i]
            );
        }
    }
}

#[test]
fn a_thousand_cycles_of_joint_positions() {
    let server = server(Delivery::default());
    let mut coach = client(&server);
    exchange(&mut coach, 1000);
    // One request at open (where the robot stands), then a joint line and a request per step.
    let c = coach.counters();
    assert_eq!(
        (c.sent, c.replies, c.timeouts, c.late, c.bad_lines),
        (1001, 1001, 0, 0, 0)
    );
    let s = server.status();
    assert_eq!(
        (s.requests, s.lines, s.bad_lines, s.ignored_lines),
        (1001, 2001, 0, 0)
    );
    let last = ramp(999);
    for (a, b) in s.joints[&0].iter().zip(last) {
        assert!((a - b).abs() <= 1e-5 * b.abs().max(1e-300));
    }
    coach.stop().unwrap();
    coach.close().unwrap();
}

#[test]
fn replies_split_into_pieces_are_reassembled() {
    let server = server(Delivery {
        chunk_bytes: Some(3),
        chunk_pause: Duration::from_micros(300),
        extra_lines: 0,
    });
    let mut coach = client(&server);
    exchange(&mut coach, 50);
    assert_eq!(coach.counters().replies, 51);
}

#[test]
fn several_lines_in_one_read_are_separated() {
    let server = server(Delivery {
        extra_lines: 3,
        ..Delivery::default()
    });
    let mut coach = client(&server);
    exchange(&mut coach, 50);
    let c = coach.counters();
    assert_eq!((c.replies, c.other_lines, c.bad_lines), (51, 153, 0));
}

#[test]
fn every_command_reaches_the_server() {
    let server = server(Delivery::default());
    let mut coach = client(&server);
    let pose = Pose::new(
        euler::from_zyx([0.0, 0.1, 3.0]),
        DVec3::new(0.5, -0.25, 1.0),
    );
    coach.set_body_pose(2, &pose).unwrap();
    coach.set_shape_pose(2, 1, &pose).unwrap();
    coach.set_joint_velocity(&[0.5; DOF]).unwrap();
    coach.set_joint_torque(&[-2.0; DOF]).unwrap();
    coach.step().unwrap();
    let s = server.status();
    let expected = [0.5, -0.25, 1.0, 0.0, 0.1, 3.0];
    for got in [s.bodies[&(0, 2)], s.shapes[&(0, 2, 1)]] {
        for (g, e) in got.iter().zip(expected) {
            assert!((g - e).abs() < 1e-12, "{got:?} != {expected:?}");
        }
    }
    assert_eq!(s.velocities[&0], vec![0.5; DOF]);
    assert_eq!(s.torques[&0], vec![-2.0; DOF]);
}

#[test]
fn an_unknown_model_is_a_protocol_error() {
    let server = CoachServer::spawn(CoachServerConfig {
        learn_models: false,
        ..CoachServerConfig::loopback()
    })
    .unwrap();
    let mut config = CoachConfig::new(DOF);
    config.server = server.addr();
    let mut coach = Coach::new(config).unwrap();
    // The query at open (`6 0`) is answered `6 0` without values: nothing to start from.
    let e = coach.open().unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Protocol);
    assert!(matches!(
        e,
        rl_drivers::Error::Protocol {
            error: ProtocolError {
                source: "Coach line",
                ..
            },
            ..
        }
    ));
    assert!(e.to_string().contains("does not know the model"), "{e}");
    assert_eq!(coach.state(), State::Closed);
}

/// Open asks where the robot stands, so a controller can start from there before the device
/// runs; a viewer that never answers fails the open within its bound.
#[test]
fn open_reads_where_the_robot_stands() {
    let standing = [0.1, -0.25, 1.5, 0.0, 2.0e-3, -3.0];
    let server = CoachServer::spawn(CoachServerConfig {
        models: vec![(0, standing.to_vec())],
        ..CoachServerConfig::loopback()
    })
    .unwrap();
    let mut config = CoachConfig::new(DOF);
    config.server = server.addr();
    let mut coach = Coach::new(config).unwrap();
    coach.open().unwrap();
    let mut q = [9.0; DOF];
    coach.joint_position(&mut q).unwrap();
    for (a, b) in q.iter().zip(standing) {
        assert!((a - b).abs() <= coach.joint_position_resolution(b), "{q:?}");
    }
    // Six significant digits.
    assert!((coach.joint_position_resolution(1.5) - 5e-6).abs() < 1e-12);
    assert!((coach.joint_position_resolution(-3.0e-3) - 5e-9).abs() < 1e-15);

    let silent = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let mut config = CoachConfig::new(DOF);
    config.server = silent.local_addr().unwrap();
    config.connect_timeout = Duration::from_millis(200);
    let mut coach = Coach::new(config).unwrap();
    let begin = std::time::Instant::now();
    let e = coach.open().unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Timeout, "{e}");
    assert!(
        begin.elapsed() < Duration::from_secs(2),
        "{:?}",
        begin.elapsed()
    );
    assert_eq!(coach.state(), State::Closed);
}

#[test]
fn a_slow_reply_times_out_and_is_counted_late() {
    let server = server(Delivery::default());
    let mut config = CoachConfig::new(DOF);
    config.server = server.addr();
    config.reply_timeout = Duration::from_millis(30);
    let mut coach = Coach::new(config).unwrap();
    coach.open().unwrap();
    coach.start().unwrap();
    exchange(&mut coach, 3);
    // The reply comes in 2-byte pieces 5 ms apart: longer than the 30 ms bound.
    server.set_delivery(Delivery {
        chunk_bytes: Some(2),
        chunk_pause: Duration::from_millis(5),
        extra_lines: 0,
    });
    assert_eq!(coach.step().unwrap_err().kind(), ErrorKind::Timeout);
    server.set_delivery(Delivery::default());
    std::thread::sleep(Duration::from_millis(300));
    coach.step().unwrap();
    let c = coach.counters();
    assert_eq!((c.timeouts, c.late), (1, 1));
}

#[test]
fn coach_calls_in_the_wrong_state_are_refused() {
    let server = server(Delivery::default());
    let mut config = CoachConfig::new(DOF);
    config.server = server.addr();
    let mut coach = Coach::new(config).unwrap();
    assert_eq!(coach.step().unwrap_err().kind(), ErrorKind::State);
    assert_eq!(
        coach.set_joint_position(&[0.0; DOF]).unwrap_err().kind(),
        ErrorKind::State
    );
    coach.open().unwrap();
    assert_eq!(coach.step().unwrap_err().kind(), ErrorKind::State);
    assert_eq!(
        coach.set_joint_position(&[0.0; 2]).unwrap_err().kind(),
        ErrorKind::InvalidArgument
    );
    coach.start().unwrap();
    assert_eq!(coach.close().unwrap_err().kind(), ErrorKind::State);
    coach.stop().unwrap();
    coach.close().unwrap();
    assert!(Coach::new(CoachConfig::new(0)).is_err());
}
