//! The Coach client against servers that misbehave: a paused server whose queued replies flood
//! the client afterwards, an overlong line, a killed, silent or garbling server; and the Coach
//! server against a client with more values than any fixed buffer holds.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::time::{Duration, Instant};

use rl_drivers::coach::{Coach, CoachConfig};
use rl_drivers::fake::coach_server::{Behaviour, CoachServer, CoachServerConfig};
use rl_drivers::{
    CyclicDevice, Device, DeviceError, ErrorKind, JointPositionActuator, LinkStatisticsSensor,
    State,
};

const DOF: usize = 6;

fn server() -> CoachServer {
    CoachServer::spawn(CoachServerConfig {
        models: vec![(0, vec![0.0; DOF])],
        ..CoachServerConfig::loopback()
    })
    .unwrap()
}

/// A started client that has had one good exchange (a server thread may take a moment to
/// serve a new connection: the first steps may time out, and count so).
fn client(addr: std::net::SocketAddr, failures: u32, timeout: Duration) -> Coach {
    let mut config = CoachConfig::new(DOF);
    config.server = addr;
    config.max_consecutive_failures = failures;
    config.reply_timeout = timeout;
    let mut coach = Coach::new(config).unwrap();
    coach.open().unwrap();
    coach.start().unwrap();
    let begin = Instant::now();
    while coach.step().is_err() {
        assert!(
            coach.state() == State::Running && begin.elapsed() < Duration::from_secs(2),
            "the server never answered"
        );
    }
    coach
}

#[test]
fn replies_queued_behind_a_paused_server_do_not_wedge_the_client() {
    let server = server();
    let mut coach = client(server.addr(), u32::MAX, Duration::from_millis(10));
    server.set_behaviour(Behaviour::Paused);
    // The server thread notices the pause at its next read (within 20 ms).
    std::thread::sleep(Duration::from_millis(30));
    // 150 requests at one period each: the server answers them all when it resumes, about
    // 7 KB of replies — more than the client's 4096-byte line buffer.
    for _ in 0..150 {
        assert_eq!(coach.step().unwrap_err().kind(), ErrorKind::Timeout);
    }
    server.set_behaviour(Behaviour::Normal);
    let begin = Instant::now();
    let mut recovered = false;
    while begin.elapsed() < Duration::from_secs(3) {
        coach.set_joint_position(&[0.5; DOF]).unwrap();
        if coach.step().is_ok() {
            recovered = true;
            break;
        }
    }
    assert!(recovered, "no good step after the server resumed");
    let mut good = 0;
    for _ in 0..20 {
        good += u32::from(coach.step().is_ok());
    }
    assert!(good > 0, "steps go on succeeding");
    let c = coach.counters();
    assert!(c.late >= 140, "{c:?}");
    // Every request is accounted for: answered in time, answered late, or still outstanding.
    assert_eq!(
        c.sent,
        c.replies + c.late + u64::from(c.outstanding),
        "{c:?}"
    );
    assert_eq!(c.bad_lines, 0);
    let l = coach.link_statistics();
    assert_eq!((l.received, l.late), (c.replies, c.late));
}

#[test]
fn a_request_the_server_skips_does_not_make_every_later_reply_late() {
    let server = server();
    let mut coach = client(server.addr(), u32::MAX, Duration::from_millis(30));
    // The server reads these requests but never answers them.
    server.set_behaviour(Behaviour::Silent);
    std::thread::sleep(Duration::from_millis(30));
    for _ in 0..3 {
        assert_eq!(coach.step().unwrap_err().kind(), ErrorKind::Timeout);
    }
    server.set_behaviour(Behaviour::Normal);
    let begin = Instant::now();
    let mut good = 0;
    while good < 10 && begin.elapsed() < Duration::from_secs(3) {
        good += u32::from(coach.step().is_ok());
    }
    assert_eq!(good, 10, "{:?}", coach.counters());
    let c = coach.counters();
    assert_eq!(
        c.sent,
        c.replies + c.late + u64::from(c.outstanding) + c.unanswered
    );
    assert_eq!(c.unanswered, 3, "{c:?}");
}

/// A hostile peer: answers each `6 0` request with `first` and then a good reply.
fn hostile(first: Vec<u8>) -> std::net::SocketAddr {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    std::thread::spawn(move || {
        let (stream, _) = listener.accept().unwrap();
        stream.set_nodelay(true).unwrap();
        let mut w = stream.try_clone().unwrap();
        let mut answer = first;
        answer.extend_from_slice(b"6 0 1 2 3 4 5 6\n");
        for line in BufReader::new(stream).lines() {
            let Ok(line) = line else { return };
            if line.trim() == "6 0" {
                let _ = w.write_all(&answer);
            }
        }
    });
    addr
}

#[test]
fn an_overlong_line_is_dropped_and_reading_resumes_at_the_next_newline() {
    let mut junk = vec![b'x'; 5000];
    junk.push(b'\n');
    let mut coach = client(hostile(junk), 10, Duration::from_millis(200));
    for _ in 0..3 {
        coach.step().unwrap();
    }
    // The query at open, the first step in `client`, three more: each answered after junk.
    let c = coach.counters();
    assert_eq!((c.replies, c.bad_lines), (5, 5), "{c:?}");
}

#[test]
fn a_killed_server_faults_the_device_at_once() {
    let server = server();
    let mut coach = client(server.addr(), 10, Duration::from_millis(10));
    server.disconnect_clients();
    let begin = Instant::now();
    let mut e = coach.step();
    while e.is_ok() && begin.elapsed() < Duration::from_secs(2) {
        e = coach.step();
    }
    let e = e.unwrap_err();
    assert!(e.kind().is_link_loss(), "{e}");
    assert_eq!(coach.state(), State::Faulted);
}

#[test]
fn a_silent_or_garbling_server_faults_the_device_within_the_bound() {
    for behaviour in [Behaviour::Silent, Behaviour::Garbage] {
        let server = server();
        let timeout = Duration::from_millis(40);
        let mut coach = client(server.addr(), 10, timeout);
        server.set_behaviour(behaviour);
        let begin = Instant::now();
        let mut steps = 0;
        while coach.state() == State::Running {
            assert!(coach.step().is_err(), "{behaviour:?}");
            steps += 1;
        }
        // Ten failed steps of at most one period (10 ms) each, not ten 100 ms waits.
        assert_eq!(steps, 10, "{behaviour:?}");
        assert!(
            begin.elapsed() < Duration::from_millis(500),
            "{behaviour:?}: {:?}",
            begin.elapsed()
        );
        let expected = if behaviour == Behaviour::Silent {
            ErrorKind::Timeout
        } else {
            ErrorKind::Protocol
        };
        assert_eq!(coach.fault().map(|e| e.kind()), Some(expected));
    }
}

#[test]
fn the_server_keeps_any_number_of_values_and_reports_an_overlong_line() {
    let server = CoachServer::spawn(CoachServerConfig {
        max_line_bytes: 2000,
        ..CoachServerConfig::loopback()
    })
    .unwrap();
    let mut stream = TcpStream::connect(server.addr()).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(2)))
        .unwrap();
    // 100 joints: more than the client's 32, and more than RL's biggest example (17).
    let values: Vec<String> = (0..100).map(|i| format!("{}", i as f64 * 0.5)).collect();
    let line = format!("2 7 {}\n6 7\n", values.join(" "));
    stream.write_all(line.as_bytes()).unwrap();
    let mut reply = String::new();
    let mut buf = [0u8; 4096];
    while !reply.ends_with('\n') {
        let n = stream.read(&mut buf).unwrap();
        reply.push_str(std::str::from_utf8(&buf[..n]).unwrap());
    }
    assert_eq!(reply.split_whitespace().count(), 102, "6 7 and 100 values");
    assert_eq!(server.status().joints[&7].len(), 100);
    // A line beyond the bound: dropped, counted and described.
    stream
        .write_all(format!("2 7 {}\n", "1 ".repeat(2000)).as_bytes())
        .unwrap();
    let begin = Instant::now();
    while server.status().overlong_lines == 0 && begin.elapsed() < Duration::from_secs(2) {
        std::thread::sleep(Duration::from_millis(5));
    }
    let s = server.status();
    assert_eq!(s.overlong_lines, 1);
    assert!(
        s.last_error
            .as_deref()
            .is_some_and(|e| e.contains("longer than 2000 bytes")),
        "{:?}",
        s.last_error
    );
    assert_eq!(s.joints[&7].len(), 100, "the model is unchanged");
}
