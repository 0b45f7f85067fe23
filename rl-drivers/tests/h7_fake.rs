//! The fake H7 behaves like the controller, checked with plain sockets rather than our own
//! driver where the point is the fake: one answer per 7.11 ms cycle, real-time packets only
//! while the uploaded program runs and only from its `ENET:` address, the program's mode, R3
//! for several clients with `QeR` for what it does not implement, and pose replies from forward
//! kinematics.

use std::io::{Read, Write};
use std::net::{TcpStream, UdpSocket};
use std::time::{Duration, Instant};

use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;
use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config, ForwardKinematics, Pacing};
use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_drivers::proto::h7::{Command, DataView, Mode, MxtType, PACKET_LEN, Packet};
use rl_drivers::{CartesianPositionSensor, CyclicDevice, Device, JointPositionActuator};

/// An RL-style request asking for joint feedback, with counter `c`.
fn request(c: u32) -> [u8; PACKET_LEN] {
    Packet {
        recv_type: MxtType::JointFeedback,
        c_count: c,
        ..Packet::default()
    }
    .to_bytes()
}

/// Replies received on `socket` until `until`.
fn replies(socket: &UdpSocket, until: Instant) -> Vec<Packet> {
    let mut out = Vec::new();
    let mut buf = [0u8; 512];
    while let Some(left) = until.checked_duration_since(Instant::now()) {
        socket
            .set_read_timeout(Some(left.max(Duration::from_micros(100))))
            .unwrap();
        if let Ok(n) = socket.recv(&mut buf) {
            out.push(Packet::decode(&buf[..n]).unwrap());
        }
    }
    out
}

/// A fake whose program runs, started by our driver (the session's R3 part), and a plain UDP
/// socket on 127.0.0.1 (the program's `ENET:` address).
fn running_fake(config: FakeH7Config) -> (FakeH7, MitsubishiH7, UdpSocket) {
    let fake = FakeH7::spawn(config).unwrap();
    let mut robot =
        MitsubishiH7::new(MitsubishiH7Config::at(fake.udp_addr(), fake.r3_addr())).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket.connect(fake.udp_addr()).unwrap();
    (fake, robot, socket)
}

#[test]
fn it_answers_once_per_cycle_not_as_fast_as_packets_arrive() {
    let (fake, _robot, socket) = running_fake(FakeH7Config::loopback(6));
    let begin = Instant::now();
    for c in 0..20 {
        socket.send(&request(c)).unwrap();
    }
    // In 50 ms the controller has at most 50 / 7.11 + 1 = 8 cycles.
    let early = replies(&socket, begin + Duration::from_millis(50));
    assert!(
        !early.is_empty() && early.len() <= 8,
        "{} replies in 50 ms",
        early.len()
    );
    let rest = replies(&socket, begin + Duration::from_millis(400));
    let all: Vec<u32> = early.iter().chain(&rest).map(|p| p.c_count).collect();
    assert_eq!(
        all,
        (0..20).collect::<Vec<_>>(),
        "every packet answered once, in order"
    );
    assert_eq!(fake.status().cycles, 20);
}

#[test]
fn it_answers_only_while_the_program_runs_and_only_its_enet_address() {
    let fake = FakeH7::spawn(FakeH7Config::loopback(6)).unwrap();
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket.connect(fake.udp_addr()).unwrap();
    socket.send(&request(0)).unwrap();
    let deadline = Instant::now() + Duration::from_millis(60);
    assert!(
        replies(&socket, deadline).is_empty(),
        "no program: no answer"
    );
    assert_eq!(fake.status().packets_outside_program, 1);

    let mut robot =
        MitsubishiH7::new(MitsubishiH7Config::at(fake.udp_addr(), fake.r3_addr())).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    socket.send(&request(1)).unwrap();
    let got = replies(&socket, Instant::now() + Duration::from_millis(60));
    assert_eq!(got.len(), 1);
    // From another address than the program's ENET line: refused.
    let stranger = UdpSocket::bind("127.0.0.2:0").unwrap();
    stranger.connect(fake.udp_addr()).unwrap();
    stranger.send(&request(2)).unwrap();
    assert!(replies(&stranger, Instant::now() + Duration::from_millis(60)).is_empty());
    assert_eq!(fake.status().rejected, 1);

    robot.stop().unwrap();
    socket.send(&request(3)).unwrap();
    assert!(replies(&socket, Instant::now() + Duration::from_millis(60)).is_empty());
    assert_eq!(fake.status().packets_outside_program, 2);
}

#[test]
fn commands_of_another_kind_than_the_programs_mode_are_ignored() {
    let fake = FakeH7::spawn(FakeH7Config::loopback(6)).unwrap();
    let mut config = MitsubishiH7Config::at(fake.udp_addr(), fake.r3_addr());
    config.mode = Mode::Pose;
    let mut robot = MitsubishiH7::new(config).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    let s = fake.status();
    assert_eq!(s.program_info.map(|p| p.mode), Some(Mode::Pose));
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket.connect(fake.udp_addr()).unwrap();
    let mut joint_move = Packet {
        command: Command::Move,
        send_type: MxtType::Joint,
        recv_type: MxtType::Joint,
        ..Packet::default()
    };
    joint_move.dat = rl_drivers::proto::h7::Data::from_joints(&[1.0; 8]);
    socket.send(&joint_move.to_bytes()).unwrap();
    let got = replies(&socket, Instant::now() + Duration::from_millis(60));
    assert_eq!(got.len(), 1, "answered");
    assert_eq!(
        got[0].find(MxtType::Joint),
        Some(DataView::Joint([0.0; 8])),
        "not moved"
    );
    assert_eq!(fake.status().wrong_mode, 1);
}

fn r3(stream: &mut TcpStream, request: &str) -> String {
    stream.write_all(request.as_bytes()).unwrap();
    let mut reply = Vec::new();
    let mut buf = [0u8; 256];
    while !reply.ends_with(b"\r") {
        let n = stream.read(&mut buf).unwrap();
        assert!(n > 0, "connection closed");
        reply.extend_from_slice(&buf[..n]);
    }
    String::from_utf8(reply).unwrap()
}

#[test]
fn r3_serves_several_clients_and_answers_what_it_lacks_with_an_error_number() {
    let fake = FakeH7::spawn(FakeH7Config::loopback(6)).unwrap();
    let mut a = TcpStream::connect(fake.r3_addr()).unwrap();
    let mut b = TcpStream::connect(fake.r3_addr()).unwrap();
    for s in [&a, &b] {
        s.set_read_timeout(Some(Duration::from_secs(2))).unwrap();
    }
    // Both connections are open at once and both are answered.
    assert_eq!(r3(&mut b, "1;1;DSTATE"), "QoK80000;0;1\r");
    assert_eq!(r3(&mut a, "1;1;DSTATE"), "QoK80000;0;1\r");
    assert!(r3(&mut a, "1;1;JPOSF").starts_with("QoKJ1;0.00;J2;0.00;"));
    // Not implemented: an error number, and its text on request (RL asks ERRORMES after QeR).
    assert_eq!(r3(&mut b, "1;1;PPOSF"), "QeR9101\r");
    assert_eq!(
        r3(&mut b, "1;1;ERRORMES9101"),
        "QoKcommand not implemented by the fake\r"
    );
    assert_eq!(r3(&mut a, "garbage"), "QeR9100\r");
    let s = fake.status();
    assert_eq!((s.r3_clients, s.r3_not_implemented), (2, 1));
}

#[test]
fn pose_replies_come_from_forward_kinematics() {
    // RL's planar2 example: two unit links turning about z; the tip is frame1 on link2.
    let loaded = rl_core::loader::load_file::<8>(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/rlmdl/planar2.xml"
    ))
    .unwrap();
    let (body, placement) = loaded.frame_placement("frame1").unwrap();
    assert_ne!(body, ROOT);
    let mut config = FakeH7Config::loopback(2);
    config.kinematics = Some(ForwardKinematics::from_model(loaded.model, body, placement));
    // The arm follows its command at once (no servo lag): the pose after three cycles is exact.
    config.servo_time_constant_s = 0.0;
    // The arm's model is under test, not the cycle: replies as packets come (back-to-back steps
    // on the controller's cycle each wait almost a whole period, at the edge of the reply
    // timeout on a slow or emulated machine).
    config.pacing = Pacing::Immediate;
    let (fake, mut robot, _socket) = running_fake(config);
    let q = [0.4, -1.1];
    robot.set_joint_position(&q).unwrap();
    for _ in 0..3 {
        robot.step().unwrap();
    }
    // The closed form: x = cos q1 + cos(q1 + q2), y = sin q1 + sin(q1 + q2), yaw q1 + q2.
    let pose: PlueckerTransform = robot.cartesian_position().unwrap();
    let (c, s) = (q[0] as f32 as f64, q[1] as f32 as f64);
    let x = c.cos() + (c + s).cos();
    let y = c.sin() + (c + s).sin();
    assert!(
        (pose.translation.x - x).abs() < 1e-6,
        "{} vs {x}",
        pose.translation.x
    );
    assert!((pose.translation.y - y).abs() < 1e-6);
    assert!(pose.translation.z.abs() < 1e-6);
    let yaw = rl_core::rotation::euler::to_zyx(&pose.rotation)[2];
    assert!((yaw - (c + s)).abs() < 1e-6, "yaw {yaw}");
    assert!(fake.status().moves >= 1);
}

/// `r3` for robot 1, slot 1, without the carriage return.
fn r3_1(stream: &mut TcpStream, body: &str) -> String {
    r3(stream, &format!("1;1;{body}")).trim_end().to_owned()
}

fn r3_client(fake: &FakeH7) -> TcpStream {
    let s = TcpStream::connect(fake.r3_addr()).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(2))).unwrap();
    s
}

#[test]
fn operation_rights_belong_to_the_connection_that_took_them_and_end_with_it() {
    let fake = FakeH7::spawn(FakeH7Config::loopback(6)).unwrap();
    let mut a = r3_client(&fake);
    let mut b = r3_client(&fake);
    assert_eq!(r3_1(&mut a, "CNTLON"), "QoK");
    // The other connection gets neither the rights nor the servo.
    assert_eq!(r3_1(&mut b, "CNTLON"), "QeR4002");
    assert_eq!(r3_1(&mut b, "SRVON"), "QeR4000");
    assert_eq!(
        r3_1(&mut b, "ERRORMES4002"),
        "QoKanother connection holds the operation rights"
    );
    // The holder closes its connection without CNTLOFF: the rights end with it.
    drop(a);
    let deadline = Instant::now() + Duration::from_secs(2);
    let mut answer = r3_1(&mut b, "CNTLON");
    while answer != "QoK" && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        answer = r3_1(&mut b, "CNTLON");
    }
    assert_eq!(answer, "QoK");
    assert_eq!(r3_1(&mut b, "SRVON"), "QoK");
    assert_eq!(r3_1(&mut b, "CNTLOFF"), "QoK");
    // Given back, another connection may take them.
    let mut c = r3_client(&fake);
    assert_eq!(r3_1(&mut c, "CNTLON"), "QoK");
    assert_eq!(r3_1(&mut b, "SRVOFF"), "QoK");
}

extern "C" fn ignore_signal(_: libc::c_int) {}

#[test]
fn the_r3_responder_survives_signals_instead_of_dropping_the_connection() {
    use nix::sys::signal::{SaFlags, SigAction, SigHandler, SigSet, Signal, sigaction};
    let fake = FakeH7::spawn(FakeH7Config::loopback(6)).unwrap();
    let mut robot =
        MitsubishiH7::new(MitsubishiH7Config::at(fake.udp_addr(), fake.r3_addr())).unwrap();
    robot.open().unwrap();
    // A handler without SA_RESTART: a blocked socket read with a timeout returns EINTR.
    let action = SigAction::new(
        SigHandler::Handler(ignore_signal),
        SaFlags::empty(),
        SigSet::empty(),
    );
    // SAFETY: the handler does nothing (async-signal-safe); no other handler of SIGUSR1 is
    // replaced in this test binary.
    unsafe { sigaction(Signal::SIGUSR1, &action) }.unwrap();
    // The thread serving our connection, by name (comm holds 15 bytes).
    let task = std::fs::read_dir("/proc/self/task")
        .unwrap()
        .filter_map(Result::ok)
        .find(|t| {
            std::fs::read_to_string(t.path().join("comm"))
                .is_ok_and(|c| c.trim() == "fake-h7-r3-clie")
        })
        .expect("the R3 client thread");
    let tid: libc::pid_t = task.file_name().to_string_lossy().parse().unwrap();
    for _ in 0..50 {
        // SAFETY: tgkill with this process's id, a thread id read from /proc and a signal
        // whose handler is installed above.
        unsafe {
            libc::syscall(
                libc::SYS_tgkill,
                std::process::id() as libc::pid_t,
                tid,
                libc::SIGUSR1,
            )
        };
        std::thread::sleep(Duration::from_millis(2));
    }
    // The connection is still there: the whole start sequence runs over it.
    robot
        .start()
        .unwrap_or_else(|e| panic!("start after the signals: {e}"));
    assert_eq!(
        fake.status().r3_clients,
        1,
        "no second connection was needed"
    );
    robot.stop().unwrap();
    robot.close().unwrap();
}

/// The fake measures its own lateness against its cycle: a tick held up (here by forward
/// kinematics that take three cycles, as a thread starved by other real-time work would be)
/// is counted late, by at least the time it was held; a run's report names it from this.
#[test]
fn the_fake_counts_the_ticks_it_ran_late() {
    const HELD: Duration = Duration::from_millis(3 * 7110 / 1000);
    let mut config = FakeH7Config::loopback(2);
    // Without R3 it answers real-time packets from anyone.
    config.r3_bind = None;
    config.kinematics = Some(ForwardKinematics::new(|_| {
        std::thread::sleep(HELD);
        None
    }));
    let fake = FakeH7::spawn(config).unwrap();
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket.connect(fake.udp_addr()).unwrap();
    let before = fake.status();
    assert_eq!(
        (before.late_ticks, before.max_tick_lateness),
        (0, Duration::ZERO)
    );
    for c in 0..3 {
        let pose = Packet {
            recv_type: MxtType::Pose,
            c_count: c,
            ..Packet::default()
        };
        socket.send(&pose.to_bytes()).unwrap();
    }
    let got = replies(&socket, Instant::now() + Duration::from_secs(2));
    assert_eq!(got.len(), 3, "every packet answered");
    let s = fake.status();
    assert_eq!(s.cycles, 3);
    assert_eq!(s.late_ticks, 3, "each tick was held {HELD:?}: {s:?}");
    assert!(s.max_tick_lateness >= HELD, "{:?}", s.max_tick_lateness);
}
