//! The H7 driver against the fake controller on loopback (random ports, bounded waits).
#![allow(clippy::needless_range_loop)]

use std::time::{Duration, Instant};

use glam::DVec3;
use rl_core::rotation::euler;
use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config, Fault, FaultPlan};
use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_drivers::proto::h7::{DecodeError, MxtType};
use rl_drivers::{
    CyclicDevice, Device, DeviceError, Error, ErrorKind, Gripper, JointLimitSensor,
    JointPositionActuator, JointPositionSensor, State,
};

const DOF: usize = 6;

fn fake() -> FakeH7 {
    FakeH7::spawn(FakeH7Config::loopback(DOF)).expect("fake controller starts")
}

/// A client whose reply wait is generous (five periods): these tests step back to back, so
/// each packet reaches the fake just after its cycle tick and is answered one cycle later — at
/// the edge of a one-period wait. The one-period default is tested in `h7_faults.rs`.
fn config(fake: &FakeH7) -> MitsubishiH7Config {
    let mut config = MitsubishiH7Config::new(DOF, fake.udp_addr(), fake.r3_addr());
    config.r3_timeout = Duration::from_millis(500);
    config.reply_timeout = 5 * config.reply_timeout;
    config
}

fn device(fake: &FakeH7) -> MitsubishiH7 {
    MitsubishiH7::new(config(fake)).unwrap()
}

fn running(fake: &FakeH7) -> MitsubishiH7 {
    let mut robot = device(fake);
    robot.open().unwrap();
    robot.start().unwrap();
    for _ in 0..3 {
        robot.step().unwrap();
    }
    robot
}

/// The R3 requests RL's `start()` sends, in order (reference, "Session as RL runs it"); the
/// DSTATE polls repeat until the fake reports the servo on (it needs 2 polls).
fn expected_start_log(program: &str) -> Vec<String> {
    [
        "JPOSF",
        "STOP",
        "NEW",
        "LOAD=1432",
        "ECLR",
        &format!("EMDAT{program}"),
        "SAVE",
        "CNTLON",
        "SRVON",
        "CNTLOFF",
        "DSTATE",
        "DSTATE",
        "CNTLON",
        "SLOTINIT",
        "RUN1432;1",
        "CNTLOFF",
    ]
    .map(String::from)
    .to_vec()
}

/// The fake's status once `done` holds, or after 2 s.
fn wait_for(
    fake: &FakeH7,
    done: impl Fn(&rl_drivers::fake::h7_controller::FakeH7Status) -> bool,
) -> rl_drivers::fake::h7_controller::FakeH7Status {
    let deadline = Instant::now() + Duration::from_secs(2);
    loop {
        let s = fake.status();
        if done(&s) || Instant::now() > deadline {
            return s;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn a_thousand_cycles_at_the_real_period_follow_a_ramp() {
    // Unpaced (one simulated cycle per packet), so the filter's lag does not depend on how
    // punctually this loop wakes up on a loaded machine; the loop still keeps the real period.
    let fake = FakeH7::spawn(FakeH7Config {
        pacing: rl_drivers::fake::h7_controller::Pacing::Immediate,
        ..FakeH7Config::loopback(DOF)
    })
    .unwrap();
    let mut config = config(&fake);
    // A 14 ms filter: the fake's arm lags a ramp by 14 / 7.11 cycles.
    config.filter = 14;
    let mut robot = MitsubishiH7::new(config).unwrap();
    assert_eq!(robot.update_period(), Duration::from_micros(7110));
    robot.open().unwrap();
    robot.start().unwrap();

    let program = "10 OPEN \"ENET:127.0.0.1\" AS #1\u{b}20 MXT 1,1,14\u{b}30 HLT\u{b}40 END";
    let s = fake.status();
    assert_eq!(s.r3_log, expected_start_log(program));
    assert_eq!(
        (s.program.as_str(), s.program_name.as_str()),
        (program, "1432")
    );
    assert!(s.servo_on && s.program_running);

    const CYCLES: usize = 1000;
    const SLOPE: f64 = 0.0005; // rad per cycle
    let period = robot.update_period();
    let mut q = [0.0; DOF];
    let mut measured = [0.0; DOF];
    let mut next = Instant::now();
    for k in 0..CYCLES {
        if k > 0 {
            robot.joint_position(&mut measured).unwrap();
            for (i, qi) in q.iter_mut().enumerate() {
                *qi = SLOPE * k as f64 * (i + 1) as f64 / DOF as f64;
            }
            robot.set_joint_position(&q).unwrap();
        }
        robot.step().unwrap_or_else(|e| panic!("cycle {k}: {e}"));
        next += period;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    let c = robot.counters();
    assert_eq!((c.sent, c.replies), (CYCLES as u64, CYCLES as u64));
    assert_eq!(
        (c.timeouts, c.late, c.foreign, c.corrupt, c.wrong_length),
        (0, 0, 0, 0, 0)
    );

    let s = fake.status();
    assert_eq!((s.packets, s.moves, s.last_c_count), (1000, 999, 999));
    assert_eq!((s.packets_outside_program, s.limit_hits), (0, 0));
    // A first-order filter of time constant τ lags a ramp by τ / T cycles in steady state.
    let lag_cycles = 14.0 / 7.11;
    for i in 0..DOF {
        let slope = SLOPE * (i + 1) as f64 / DOF as f64;
        assert!(
            (s.commanded_rad[i] - q[i]).abs() < 1e-6,
            "joint {i} commanded"
        );
        let lag = s.commanded_rad[i] - s.actual_rad[i];
        assert!(
            (lag - lag_cycles * slope).abs() < 0.01 * slope,
            "joint {i} lags {lag}, not {lag_cycles} cycles"
        );
    }
    robot.joint_position(&mut measured).unwrap();
    for i in 0..DOF {
        assert!(
            (measured[i] - s.actual_rad[i]).abs() < 1e-6,
            "joint {i} measured"
        );
    }

    robot.stop().unwrap();
    // The fake handles the end packet at its next cycle tick.
    let s = wait_for(&fake, |s| s.ends > 0);
    assert_eq!(s.ends, 1, "stop sends the end packet (command 255)");
    assert_eq!(
        s.r3_log[expected_start_log(program).len()..],
        ["STOP", "DSTATE", "SRVOFF", "DSTATE"]
    );
    assert!(!s.servo_on && !s.program_running);
    assert_eq!(robot.state(), State::Open);
    robot.close().unwrap();
    assert_eq!(robot.state(), State::Closed);
}

#[test]
fn calls_in_the_wrong_state_are_refused() {
    let fake = fake();
    let mut robot = device(&fake);
    let kind = |r: Result<(), Error>| r.unwrap_err().kind();
    assert_eq!(kind(robot.step()), ErrorKind::State);
    assert_eq!(kind(robot.start()), ErrorKind::State);
    assert_eq!(
        kind(robot.set_joint_position(&[0.0; DOF])),
        ErrorKind::State
    );
    robot.open().unwrap();
    assert_eq!(kind(robot.step()), ErrorKind::State);
    assert_eq!(
        kind(robot.set_joint_position(&[0.0; 3])),
        ErrorKind::InvalidArgument
    );
    robot.start().unwrap();
    assert_eq!(kind(robot.close()), ErrorKind::State);
    robot.stop().unwrap();
    robot.close().unwrap();
}

/// Injects `fault` into exactly one reply and checks the step's error and the counters, then
/// that the next steps succeed again.
fn inject_once(fault: Fault, check: impl Fn(&Error, &rl_drivers::mitsubishi_h7::H7Counters)) {
    let fake = fake();
    let mut robot = running(&fake);
    fake.set_fault(Some(FaultPlan { every: 1, fault }));
    let e = robot.step().unwrap_err();
    fake.set_fault(None);
    // Leave time for a delayed reply to arrive before the next step.
    std::thread::sleep(Duration::from_millis(150));
    robot.step().unwrap();
    check(&e, &robot.counters());
    for _ in 0..5 {
        robot.step().unwrap();
    }
    assert_eq!(robot.state(), State::Running);
    assert_eq!(robot.counters().consecutive_failures, 0);
    assert_eq!(fake.status().faults_injected, 1);
    robot.stop().unwrap();
}

#[test]
fn a_dropped_reply_is_a_counted_timeout() {
    inject_once(Fault::Drop, |e, c| {
        assert_eq!(e.kind(), ErrorKind::Timeout);
        assert_eq!((c.timeouts, c.late), (1, 0));
    });
}

#[test]
fn a_delayed_reply_times_out_and_is_counted_late_at_the_next_step() {
    inject_once(Fault::Delay(Duration::from_millis(90)), |e, c| {
        assert_eq!(e.kind(), ErrorKind::Timeout);
        assert_eq!((c.timeouts, c.late), (1, 1));
    });
}

#[test]
fn a_corrupted_reply_is_a_protocol_error() {
    inject_once(Fault::Corrupt, |e, c| {
        assert_eq!(e.kind(), ErrorKind::Protocol);
        assert_eq!(
            *e,
            Error::protocol(
                rl_drivers::Operation::Step,
                "H7 packet",
                &DecodeError::UnknownType {
                    offset: 4,
                    value: 0xFFFF
                }
            )
        );
        assert_eq!((c.corrupt, c.timeouts), (1, 0));
    });
}

#[test]
fn a_truncated_reply_is_a_wrong_length() {
    inject_once(Fault::Truncate, |e, c| {
        assert_eq!(
            *e,
            Error::protocol(
                rl_drivers::Operation::Step,
                "H7 packet",
                &DecodeError::Length { got: 100 }
            )
        );
        assert_eq!((c.wrong_length, c.corrupt), (1, 0));
    });
}

#[test]
fn a_reply_from_another_port_is_dropped_and_counted() {
    inject_once(Fault::ForeignPort, |e, c| {
        assert_eq!(e.kind(), ErrorKind::Timeout);
        assert_eq!((c.foreign, c.timeouts), (1, 1));
    });
}

#[test]
fn too_many_failures_in_a_row_fault_the_device() {
    let fake = fake();
    let mut robot = running(&fake);
    fake.set_fault(Some(FaultPlan {
        every: 1,
        fault: Fault::Drop,
    }));
    for i in 0..9 {
        assert_eq!(
            robot.step().unwrap_err().kind(),
            ErrorKind::Timeout,
            "step {i}"
        );
        assert_eq!(robot.state(), State::Running);
    }
    let last = robot.step().unwrap_err();
    assert_eq!(robot.state(), State::Faulted);
    assert_eq!(robot.fault(), Some(last));
    assert_eq!(robot.counters().consecutive_failures, 10);
    let e = robot.step().unwrap_err();
    assert_eq!(
        e,
        Error::State {
            operation: rl_drivers::Operation::Step,
            state: State::Faulted
        }
    );
    robot.close().unwrap();
    assert_eq!((robot.state(), robot.fault()), (State::Closed, None));
}

#[test]
fn a_hung_controller_makes_start_and_step_time_out() {
    let fake = fake();
    let mut robot = device(&fake);
    robot.open().unwrap();
    fake.set_frozen(true);
    let e = robot.start().unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Timeout, "{e}");
    assert_eq!(robot.state(), State::Faulted);
    robot.close().unwrap();

    fake.set_frozen(false);
    let mut robot = running(&fake);
    fake.set_frozen(true);
    let e = robot.step().unwrap_err();
    assert_eq!(
        e,
        Error::Timeout {
            operation: rl_drivers::Operation::Step,
            waited: robot.config().reply_timeout
        }
    );
}

#[test]
fn a_stopped_controller_makes_step_time_out_and_open_fail() {
    let mut fake = fake();
    let mut robot = running(&fake);
    let (udp, r3) = (fake.udp_addr(), fake.r3_addr());
    fake.shutdown();
    assert_eq!(robot.step().unwrap_err().kind(), ErrorKind::Timeout);
    assert_eq!(robot.counters().timeouts, 1);

    let mut other = MitsubishiH7::new(MitsubishiH7Config::new(DOF, udp, r3)).unwrap();
    let e = other.open().unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Io, "{e}");
    assert_eq!(other.state(), State::Closed);
}

#[test]
fn gripper_and_io_go_through_the_packet() {
    let fake = fake();
    let mut robot = running(&fake);
    robot.shut().unwrap();
    assert_eq!(
        (
            robot.request().bit_top,
            robot.request().bit_mask,
            robot.request().io_data
        ),
        (900, 0xFF, 0xA9)
    );
    robot.step().unwrap();
    assert_eq!(fake.status().outputs.get(&900), Some(&0xA9));
    robot.release().unwrap();
    robot.step().unwrap();
    assert_eq!(fake.status().outputs.get(&900), Some(&0xA6));
    assert_eq!(
        robot.request().io_data,
        0,
        "I/O fields are cleared after each send"
    );
    fake.set_input(16, 0x1234);
    robot.request_input(16).unwrap();
    robot.step().unwrap();
    assert_eq!(robot.io_data().unwrap(), 0x1234);
    robot.stop().unwrap();
}

#[test]
fn rls_reply_types_work_and_pulses_follow_joints() {
    let fake = fake();
    let mut config = config(&fake);
    config.feedback = MitsubishiH7Config::RL_FEEDBACK;
    let mut robot = MitsubishiH7::new(config).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    let q = [0.1, -0.2, 0.3, 0.0, 0.5, -0.6];
    robot.set_joint_position(&q).unwrap();
    robot.step().unwrap();
    let reply = robot.reply().unwrap();
    assert_eq!(reply.recv_type, MxtType::Joint);
    let mut got = [0.0; DOF];
    robot.joint_position(&mut got).unwrap();
    for i in 0..DOF {
        assert!(
            (got[i] - q[i]).abs() < 1e-6,
            "commanded joint {i} echoed as type 2"
        );
    }
    let mut pulses = [0; DOF];
    robot.motor_pulse(&mut pulses).unwrap();
    let per_rad = 2f64.powi(20) / std::f64::consts::TAU;
    for i in 0..DOF {
        assert_eq!(pulses[i], (f64::from(q[i] as f32) * per_rad).round() as i32);
    }
    robot.stop().unwrap();
}

#[test]
fn the_typestate_wrapper_walks_the_life_cycle() {
    use rl_drivers::typestate::Closed;
    let fake = fake();
    let robot = Closed::new(device(&fake)).unwrap();
    let mut robot = robot
        .open()
        .map_err(|(e, _)| e)
        .unwrap()
        .start()
        .map_err(|(e, _)| e)
        .unwrap();
    robot.device_mut().set_joint_position(&[0.1; DOF]).unwrap();
    robot.step().unwrap();
    let robot = robot
        .stop()
        .map_err(|(e, _)| e)
        .unwrap()
        .close()
        .map_err(|(e, _)| e)
        .unwrap();
    assert_eq!(robot.device().state(), State::Closed);
    assert_eq!(fake.status().moves, 1);
}

#[test]
fn speed_limits_bound_the_simulated_motion() {
    let config = FakeH7Config::loopback(DOF)
        .with_speed_limits(&[0.5; DOF])
        .unwrap();
    let fake = FakeH7::spawn(config).unwrap();
    let mut robot = running(&fake);
    robot.set_joint_position(&[1.0; DOF]).unwrap();
    let mut reached = [false; DOF];
    for k in 0..10 {
        robot.step().unwrap();
        robot.joint_limit_reached(&mut reached).unwrap();
        assert_eq!(reached, [true; DOF], "step {k}: the command is clamped");
        // The command goes out once; later steps compare with it until it is reached.
    }
    // The controller's command value moves 0.5 rad/s × 7.11 ms per cycle, and what the
    // driver reads back as the commanded joints (type 2) is exactly that.
    let s = fake.status();
    let per_cycle = 0.5 * 0.00711;
    let cycles = s.command_rad[0] / per_cycle;
    assert!(
        (cycles - cycles.round()).abs() < 1e-6 && cycles.round() >= 10.0,
        "command {} is not a whole number (≥ 10) of speed-limited cycles",
        s.command_rad[0]
    );
    assert!(s.actual_rad[0] <= s.command_rad[0] + 1e-12);
    assert!(s.speed_clamps >= 6 * 10);
    match robot.reply().unwrap().find(MxtType::Joint) {
        Some(rl_drivers::proto::h7::DataView::Joint(j)) => {
            assert_eq!(f64::from(j[0]), f64::from(s.command_rad[0] as f32));
        }
        other => panic!("no joint command in the reply: {other:?}"),
    }
    assert!(
        FakeH7Config::loopback(DOF)
            .with_speed_limits(&[0.5; 2])
            .is_err()
    );
    assert!(
        FakeH7Config::loopback(DOF)
            .with_limits(&[1.0; DOF], &[0.0; DOF])
            .is_err()
    );
}

#[test]
fn joint_limits_clamp_commands_and_are_counted() {
    let config = FakeH7Config::loopback(DOF)
        .with_limits(&[-0.1; DOF], &[0.1; DOF])
        .unwrap();
    let fake = FakeH7::spawn(config).unwrap();
    let mut robot = running(&fake);
    robot
        .set_joint_position(&[0.5, 0.0, 0.0, 0.0, 0.0, -0.05])
        .unwrap();
    robot.step().unwrap();
    let mut reached = [false; DOF];
    robot.joint_limit_reached(&mut reached).unwrap();
    assert_eq!(reached, [true, false, false, false, false, false]);
    for _ in 0..20 {
        robot.step().unwrap();
    }
    let s = fake.status();
    assert_eq!(s.limit_hits, 1);
    assert!((s.actual_rad[0] - 0.1).abs() < 1e-9 && (s.actual_rad[5] + 0.05).abs() < 1e-9);
}

#[test]
fn cartesian_mode_commands_poses_in_mm() {
    use rl_drivers::proto::h7::Mode;
    use rl_drivers::{CartesianPositionActuator, CartesianPositionSensor, Pose};
    let fake = fake();
    let mut config = config(&fake);
    config.mode = Mode::Pose;
    let mut robot = MitsubishiH7::new(config).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    assert!(fake.status().program.contains("MXT 1,0,0"));
    assert_eq!(
        robot.set_joint_position(&[0.0; DOF]).unwrap_err().kind(),
        ErrorKind::InvalidArgument
    );
    let abc = [3.0, 0.1, -1.0];
    let pose = Pose::new(euler::from_zyx(abc), DVec3::new(0.4, -0.1, 0.3));
    robot.set_cartesian_position(&pose).unwrap();
    let sent = robot.request().dat.pose();
    assert_eq!(sent.xyz_mm, [400.0, -100.0, 300.0]);
    for _ in 0..20 {
        robot.step().unwrap();
    }
    let got = robot.cartesian_position().unwrap();
    for k in 0..3 {
        assert!(
            (got.translation[k] - pose.translation[k]).abs() < 1e-6,
            "position {k}"
        );
        let got_abc = euler::to_zyx(&got.rotation);
        assert!((got_abc[k] - abc[k]).abs() < 1e-6, "angle {k}");
    }
    robot.stop().unwrap();
}

#[test]
fn pulse_mode_writes_pulses_to_the_first_data_block() {
    use rl_drivers::proto::h7::{Data, Mode};
    let fake = fake();
    let mut config = config(&fake);
    config.mode = Mode::Pulse;
    let mut robot = MitsubishiH7::new(config).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    let pulses = [1000, -2000, 3000, 0, 5, -6];
    robot.set_motor_pulse(&pulses).unwrap();
    assert_eq!(robot.request().send_type, MxtType::Pulse);
    assert_eq!(robot.request().dat.i32s()[..DOF], pulses);
    assert_eq!(robot.request().dat2, Data::ZERO, "not RL's third block");
    robot.step().unwrap();
    let per_rad = 2f64.powi(20) / std::f64::consts::TAU;
    assert!((fake.status().commanded_rad[1] - (-2000.0 / per_rad)).abs() < 1e-12);
    robot.stop().unwrap();
}

#[test]
fn an_unspecified_local_address_writes_the_routed_address_into_the_program() {
    let fake = fake();
    let mut config = config(&fake);
    config.local = "0.0.0.0:0".parse().unwrap();
    let mut robot = MitsubishiH7::new(config).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    assert!(
        fake.status()
            .program
            .starts_with("10 OPEN \"ENET:127.0.0.1\" AS #1")
    );
    robot.step().unwrap();
    robot.stop().unwrap();
    let remote = MitsubishiH7Config::new(
        DOF,
        "192.0.2.1:10000".parse().unwrap(),
        "192.0.2.1:10001".parse().unwrap(),
    );
    assert!(
        remote.local.ip().is_unspecified(),
        "a remote controller is reached from any address"
    );
}

#[test]
fn devices_and_fakes_can_move_to_another_thread() {
    fn send<T: Send>() {}
    send::<MitsubishiH7>();
    send::<FakeH7>();
    send::<rl_drivers::Coach>();
    send::<rl_drivers::fake::coach_server::CoachServer>();
}

#[test]
fn a_controller_error_during_start_faults_with_its_code() {
    use rl_drivers::proto::r3::R3Error;
    let fake = fake();
    let mut robot = device(&fake);
    robot.open().unwrap();
    fake.set_r3_rejection(Some("SRVON"));
    let e = robot.start().unwrap_err();
    assert_eq!(
        e,
        Error::device(
            rl_drivers::Operation::Start,
            "R3 reply",
            &R3Error::Controller { code: 4100 }
        )
    );
    assert_eq!((robot.state(), robot.fault()), (State::Faulted, Some(e)));
    assert_eq!(
        e.to_string(),
        "start: the device reported R3 reply: controller error QeR4100"
    );
    robot.close().unwrap();
    fake.set_r3_rejection(None);
    robot.open().unwrap();
    robot.start().unwrap();
    robot.step().unwrap();
    robot.stop().unwrap();
}

/// A command the controller does not clamp comes back exactly as it was sent, also on the way
/// to 0, where `last + (target − last)` in floating point misses the target by more than the
/// `f32` resolution the driver checks the echo against (a followed target at a joint's 0 ended
/// a run with "the device reports joint joint2 at a limit").
#[test]
fn unclamped_commands_come_back_exactly_also_near_zero() {
    let fake = FakeH7::spawn(FakeH7Config::loopback(DOF)).unwrap();
    let mut robot = running(&fake);
    let mut reached = [false; DOF];
    // The last samples of a motion that ends at 0 leave residues far below the previous
    // command; the difference of two such values is not exact in f64.
    let commands = [
        0.01, 3e-7, 2.7e-17, 0.003, 1.1e-19, 0.0, -0.02, -4e-18, 1e-30, 0.0,
    ];
    for (k, &q) in commands.iter().enumerate() {
        robot.set_joint_position(&[q; DOF]).unwrap();
        robot.step().unwrap();
        robot.joint_limit_reached(&mut reached).unwrap();
        assert_eq!(reached, [false; DOF], "command {k}: {q}");
    }
    assert_eq!(fake.status().speed_clamps, 0);
    assert_eq!(fake.status().command_rad[0], 0.0);
}
