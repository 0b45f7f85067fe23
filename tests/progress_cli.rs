//! Issue 25: long work shows a progress line on a terminal and nothing when standard error is
//! piped (as here). `rl plan` (certification), `rl plan bench`, `rl scene bench` and `rl
//! jitter` are run with standard error piped: no carriage return, no escape sequence and no
//! progress text reaches it. (The line's format and throttling are unit-tested in
//! `src/cli/progress.rs` with a fake clock and writer.)

mod cli;

use std::time::Duration;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn path(rel: &str) -> String {
    format!("{ROOT}/{rel}")
}

/// Runs `rl args` with standard error piped and returns it; the command must succeed.
fn piped_stderr(args: &[&str]) -> String {
    let out = cli::rl_within(args, Duration::from_secs(120));
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "rl {args:?}: {stderr}");
    stderr
}

fn assert_no_progress(args: &[&str], words: &[&str]) {
    let stderr = piped_stderr(args);
    assert!(
        !stderr.contains('\r') && !stderr.contains('\x1b'),
        "rl {args:?} drew a live line into a pipe: {stderr:?}"
    );
    for w in words {
        assert!(
            !stderr.contains(w),
            "rl {args:?} printed progress ({w:?}) into a pipe: {stderr:?}"
        );
    }
}

#[test]
fn piped_long_work_prints_no_progress() {
    let panda = path("tests/data/mbm/panda/panda.urdf");
    let problem = path("tests/data/mbm/panda/problems/table_pick_panda");
    let scene = format!("{problem}/scene0001.yaml");
    let request = format!("{problem}/request0001.yaml");
    // Certification runs on the returned path (the JSON says it did).
    assert_no_progress(
        &[
            "plan",
            &panda,
            "--scene",
            &scene,
            "--request",
            &request,
            "--seed",
            "3",
        ],
        &["certifying"],
    );
    let problems = path("tests/data/mbm/panda/problems");
    assert_no_progress(
        &[
            "plan",
            "bench",
            &problems,
            "--checker",
            "spheres",
            "--raw-spheres",
            "--limit",
            "2",
        ],
        &["solved,"],
    );
    assert_no_progress(
        &[
            "scene",
            "bench",
            &path("tests/data/rlsg/unimation-puma560_boxes.convex.xml"),
            "--kinematics",
            &path("tests/data/rlmdl/unimation-puma560.xml"),
            "--configs",
            "3",
            "--rounds",
            "2",
        ],
        &["rounds of"],
    );
    assert_no_progress(
        &[
            "jitter",
            "--policy",
            "other",
            "--no-mlock",
            "--no-cpu-latency-hint",
            "--cycles",
            "100",
            "--interval-us",
            "500",
        ],
        &["cycles,"],
    );
}
