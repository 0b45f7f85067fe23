//! The README's first command (`cargo run --release`: the `rl` tool with no arguments) on a
//! loaded machine: niced, beside busy loops at normal priority. It must succeed, or, if the
//! load made it fail, its report must say who was late — the loop, the fake H7 or the
//! delivery of the replies — rather than leave the newcomer blaming the link. Not a timed test:
//! nothing is asserted about speed.

use std::process::Command;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

mod cli;
use cli::run_bounded;

/// Threads spinning at normal priority while the command runs.
const SPINNERS: usize = 3;

/// What a timing failure's report names as its likely cause: each party there is.
const CAUSES: [&str; 5] = [
    "likely cause: the fake H7 ran up to",
    "likely cause: the loop woke up to",
    "likely cause: both the loop (up to",
    "likely cause: replies arrived late at the kernel",
    "likely cause: nobody measured was late",
];

#[test]
fn the_first_command_succeeds_under_load_or_says_who_was_late() {
    let nice = Command::new("nice").arg("--version").output();
    if nice.is_err() {
        println!("SKIPPED the_first_command_succeeds_under_load: no `nice` on this machine");
        return;
    }
    let stop = Arc::new(AtomicBool::new(false));
    let spinners: Vec<_> = (0..SPINNERS)
        .map(|_| {
            let stop = stop.clone();
            std::thread::spawn(move || {
                let mut n = 0u64;
                while !stop.load(Ordering::Relaxed) {
                    n = std::hint::black_box(n.wrapping_add(1));
                }
                n
            })
        })
        .collect();
    let mut cmd = Command::new("nice");
    cmd.args(["-n", "15", env!("CARGO_BIN_EXE_rl")]);
    let out = run_bounded(cmd, Duration::from_secs(180));
    stop.store(true, Ordering::Relaxed);
    for s in spinners {
        let _ = s.join();
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let context = format!("stdout:\n{stdout}\nstderr:\n{stderr}");
    // Every report says how late each party was at worst.
    assert!(
        stdout.contains("lateness: loop woke up to"),
        "no lateness line\n{context}"
    );
    assert!(
        stdout.contains("the fake H7 up to"),
        "the fake's own lateness is missing\n{context}"
    );
    if out.status.success() {
        assert!(stdout.contains("result: ok"), "{context}");
        println!("the first command succeeded under load:\n{stdout}");
    } else {
        assert_eq!(out.status.code(), Some(1), "{context}");
        assert!(stdout.contains("result: FAILED"), "{context}");
        let named = CAUSES.iter().find(|c| stdout.contains(*c));
        assert!(
            named.is_some(),
            "the run failed without naming who was late\n{context}"
        );
        println!("the first command failed under load and said why:\n{stdout}");
    }
}
