//! Every pair of processes the README shows — `rl fake-robot X` in one terminal, `rl run
//! --device X` in another — run as two processes: the fake's commands and the run's as the
//! README has them (the CANopen pair exactly, port 20000 included; the H7 and Coach pairs on
//! ports of their own, so that tests beside them do not collide; the EtherCAT pair on a veth
//! pair in a network namespace of its own, as root). Each run must end `result: ok`, and the
//! fake must stop cleanly on Ctrl-C (SIGINT).
//!
//! On a shared machine a run can fail because the machine, not the code, was late: a run that
//! failed while its loop overran, missed deadlines or woke more than half a period late, or
//! lost replies in a row, is run again (three times at most, then SKIPPED with the reports); any
//! other failure fails the test.

mod netns;
mod pairs;

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use netns::{Netns, is_root};
use pairs::run_until_on_time;

const README: &str = include_str!("../README.md");

/// One pair at a time: each runs a real-time loop and a fake beside it on a 2-core machine.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|p| p.into_inner())
}

/// The README's section of pairs.
fn pairs_section() -> &'static str {
    let heading = "### Two processes: a fake robot and `rl run`";
    let at = README.find(heading).expect("the README's section of pairs");
    let rest = &README[at + heading.len()..];
    &rest[..rest.find("\n### ").unwrap_or(rest.len())]
}

/// The line of the README's section of pairs that starts with `start`, as words; fails if
/// there is no such line, so that the commands tested are the README's.
fn readme_command(start: &str) -> Vec<String> {
    let line = pairs_section()
        .lines()
        .find(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("the README shows no command starting `{start}`"));
    let command = line.split('#').next().unwrap_or(line);
    // Shell words: whitespace-separated, single quotes removed.
    command
        .split_whitespace()
        .map(|w| w.trim_matches('\'').to_owned())
        .collect()
}

/// `rl` with the arguments after the README's `rl`.
fn rl_command(words: &[String]) -> Command {
    assert_eq!(words[0], "rl", "{words:?}");
    let mut c = Command::new(env!("CARGO_BIN_EXE_rl"));
    c.args(&words[1..]);
    c
}

/// Starts a fake and waits for its first line (it is serving then).
fn start_fake(mut command: Command) -> Child {
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the fake");
    let mut first = String::new();
    BufReader::new(child.stdout.as_mut().expect("stdout"))
        .read_line(&mut first)
        .expect("the fake's first line");
    assert!(!first.is_empty(), "the fake ended before serving");
    println!("fake: {}", first.trim());
    child
}

/// Ctrl-C to the fake; it must end cleanly within 5 s.
fn stop_fake(mut child: Child) {
    let pid = child.id().to_string();
    assert!(
        Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .is_ok_and(|s| s.success())
    );
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        if let Some(status) = child.try_wait().expect("wait for the fake") {
            let out = child.wait_with_output().expect("fake output");
            assert!(
                status.success(),
                "the fake ended with {status}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            return;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("the fake did not stop on SIGINT within 5 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

#[test]
fn the_canopen_pair_exactly_as_the_readme_shows_it() {
    let _serial = serial();
    let fake = readme_command("rl fake-robot canopen --bus cannelloni+udp://127.0.0.1:20000");
    let run = readme_command("rl run --device 'cannelloni+udp://127.0.0.1:20000?nodes=1-6'");
    assert_eq!(
        fake,
        [
            "rl",
            "fake-robot",
            "canopen",
            "--bus",
            "cannelloni+udp://127.0.0.1:20000",
            "--nodes",
            "1-6"
        ]
    );
    let child = start_fake(rl_command(&fake));
    run_until_on_time("canopen pair", 1000.0, || {
        rl_command(&run).output().expect("rl run")
    });
    stop_fake(child);
}

#[test]
fn the_h7_pair() {
    let _serial = serial();
    let fake = readme_command("rl fake-robot h7 ");
    let run = readme_command("rl run --device h7://127.0.0.1 ");
    assert_eq!(fake, ["rl", "fake-robot", "h7"]);
    // The README's commands on ports of their own.
    let (udp, r3) = (free_port(), free_port());
    let mut f = rl_command(&fake);
    f.args(["--bind", &format!("127.0.0.1:{udp}")])
        .args(["--r3-bind", &format!("127.0.0.1:{r3}")]);
    let child = start_fake(f);
    let device = format!("h7://127.0.0.1:{udp}?r3={r3}");
    run_until_on_time("h7 pair", 3555.0, || {
        let mut words = run.clone();
        words[3] = device.clone();
        rl_command(&words).output().expect("rl run")
    });
    stop_fake(child);
}

#[test]
fn the_coach_pair() {
    let _serial = serial();
    let fake = readme_command("rl fake-robot coach --model");
    let run = readme_command("rl run --device coach://127.0.0.1 ");
    let port = free_port();
    let mut f = rl_command(&fake);
    f.current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["--bind", &format!("127.0.0.1:{port}")]);
    let child = start_fake(f);
    run_until_on_time("coach pair", 5000.0, || {
        let mut words = run.clone();
        words[3] = format!("coach://127.0.0.1:{port}");
        rl_command(&words).output().expect("rl run")
    });
    stop_fake(child);
}

#[test]
fn the_ethercat_pair_in_a_namespace() {
    let _serial = serial();
    if !is_root() {
        println!("SKIPPED: the_ethercat_pair_in_a_namespace: needs root (raw Ethernet, netns)");
        return;
    }
    let setup = readme_command("ip link add rl-ecat0 type veth peer name rl-ecat1");
    let fake = readme_command("rl fake-robot ethercat --interface rl-ecat1");
    let run = readme_command("rl run --device ethercat://rl-ecat0");
    assert!(setup.contains(&"rl-ecat1".to_owned()));
    // The README's pair in a namespace of this test's own (the interface names are its).
    let ns = Netns::with_veth("rlpair", "rl-ecat0", "rl-ecat1");
    let in_ns = |words: &[String]| {
        let mut c = ns.command(env!("CARGO_BIN_EXE_rl"));
        c.args(&words[1..]);
        c
    };
    let child = start_fake(in_ns(&fake));
    run_until_on_time("ethercat pair", 500.0, || {
        in_ns(&run).output().expect("rl run")
    });
    stop_fake(child);
}
