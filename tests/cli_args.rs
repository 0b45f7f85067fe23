//! Flags do what they say or are refused with a message that names them: negative numbers
//! reach the range checks (not clap's "use '-- -5'" tip) in every subcommand, out-of-range
//! values are refused, and an output file that cannot be created is refused before a long
//! measurement starts.

use std::process::Command;
use std::time::{Duration, Instant};

fn rl(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rl"))
        .args(args)
        .output()
        .expect("run rl")
}

/// Exit code 2, every needle in the message, and no clap tip about `--`.
fn refused(args: &[&str], needles: &[&str]) {
    let out = rl(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "rl {args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "rl {args:?}: {n:?} not in\n{err}");
    }
    assert!(
        !err.contains("tip:"),
        "rl {args:?}: clap's tip instead of the check:\n{err}"
    );
}

const PUMA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/rlmdl/unimation-puma560.xml"
);

fn waypoints() -> String {
    let dir = std::env::temp_dir().join(format!("rl-args-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("wp.csv");
    std::fs::write(&path, "a,b\n0,0\n1,-1\n").unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn negative_numbers_reach_the_range_checks() {
    refused(
        &["run", "--rate", "-5"],
        &["--rate -5", "between 0.1 and 20000"],
    );
    refused(&["run", "--speed", "-0.5"], &["-0.5"]);
    let wp = waypoints();
    refused(
        &["traj", &wp, "--profile", "quintic", "--dt", "-0.01"],
        &["--dt must be a positive number", "-0.01"],
    );
    refused(
        &["traj", &wp, "--profile", "quintic", "--vmax", "-1"],
        &["--vmax", "`-1` is not a positive number"],
    );
    refused(
        &["traj", &wp, "--profile", "cubic-natural", "--vmax", "1,-2"],
        &["--vmax", "`-2`"],
    );
    refused(
        &["jitter", "--priority", "-3", "--duration", "1ms"],
        &["-3"],
    );
    // Unsigned flags: clap's own message about the value, not the tip.
    refused(&["model", "bench", PUMA, "--states", "-4"], &["-4"]);
    refused(&["jitter", "--interval-us", "-100"], &["-100"]);
    // A vector with negative entries is a value, too.
    let out = rl(&[
        "model",
        "eval",
        PUMA,
        "--q",
        "-0.1,-0.2,-0.3,-0.4,-0.5,-0.6",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn jitter_refuses_a_zero_or_huge_histogram_range() {
    refused(
        &["jitter", "--histogram-range-us", "0", "--duration", "1ms"],
        &["--histogram-range-us 0", "1 to 1000000"],
    );
    refused(
        &[
            "jitter",
            "--histogram-range-us",
            "100000000",
            "--duration",
            "1ms",
        ],
        &["--histogram-range-us 100000000"],
    );
}

#[test]
fn an_output_file_that_cannot_be_created_is_refused_before_the_work() {
    let start = Instant::now();
    // 30 s of measurement if the file were checked after it.
    refused(
        &[
            "jitter",
            "--duration",
            "30s",
            "--policy",
            "other",
            "--no-mlock",
            "--histogram",
            "/nonexistent-dir/h.txt",
        ],
        &["--histogram", "/nonexistent-dir/h.txt"],
    );
    assert!(start.elapsed() < Duration::from_secs(10));
    // A trajectory of a million rows, refused before the first one.
    let wp = waypoints();
    let start = Instant::now();
    for flag in ["--out", "--plot"] {
        refused(
            &[
                "traj",
                &wp,
                "--profile",
                "jerk-limited",
                "--vmax",
                "0.0001",
                "--amax",
                "1",
                "--jmax",
                "1",
                flag,
                "/nonexistent-dir/x",
            ],
            &[flag, "cannot create /nonexistent-dir/x"],
        );
    }
    assert!(start.elapsed() < Duration::from_secs(10));
}

/// `--obstacle`'s forms that cannot work are refused before anything connects (the device
/// here is a Franka address nothing listens on: reaching it would be a device error, not 2).
#[test]
fn obstacle_flags_that_cannot_work_are_refused_before_the_run() {
    let law = [
        "run",
        "--device",
        "franka://127.0.0.1:9",
        "--law",
        "cartesian-impedance",
    ];
    let with =
        |more: &[&'static str]| -> Vec<&'static str> { law.iter().chain(more).copied().collect() };
    refused(
        &with(&["--obstacle", "/nonexistent-dir/hand.obstacles"]),
        &["--obstacle /nonexistent-dir/hand.obstacles", "No such file"],
    );
    refused(
        &with(&["--obstacle", "zenoh"]),
        &["--obstacle zenoh", "--zenoh ENDPOINT"],
    );
    refused(
        &with(&["--obstacle", "moving-sphere", "--obstacle-radius", "0.1"]),
        &["--obstacle-radius is for --obstacle zenoh"],
    );
    refused(
        &with(&["--obstacle", "udp:notaport"]),
        &["'notaport' is not a port"],
    );
    // Without --law, obstacles have no law to go to.
    refused(&["run", "--obstacle", "-"], &["--law"]);
}
