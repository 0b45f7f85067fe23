//! `rl traj` writes its samples as it computes them: a long trajectory takes little memory
//! (issue 13: 12 axes over 10 000 s took 4.2 GB when the rows were held until the end), and
//! its plot shows what the flags asked for.

use std::process::Command;

fn dir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("rl-traj-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The largest resident set of any child of this process so far, in MB.
fn children_peak_mb() -> f64 {
    let usage = nix::sys::resource::getrusage(nix::sys::resource::UsageWho::RUSAGE_CHILDREN)
        .expect("getrusage");
    usage.max_rss() as f64 / 1024.0 // KiB on Linux
}

#[test]
fn a_million_rows_stream_in_little_memory() {
    let wp = dir().join("long.csv");
    std::fs::write(&wp, "a,b,c,d\n0,0,0,0\n1,-1,2,0.5\n0,0,0,0\n").unwrap();
    // About 1.3 million samples of 4 axes (17 numbers a row): holding them would take well
    // over 150 MB.
    let out = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args([
            "traj",
            wp.to_str().unwrap(),
            "--profile",
            "jerk-limited",
            "--vmax",
            "0.003",
            "--amax",
            "1",
            "--jmax",
            "10",
            "--out",
            "/dev/null",
        ])
        .output()
        .expect("run rl traj");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let peak = children_peak_mb();
    println!("peak resident memory of rl traj: {peak:.1} MB");
    assert!(peak < 40.0, "rl traj took {peak:.1} MB");
}

#[test]
fn the_plot_has_units_limits_and_a_legend_beside_the_curves() {
    let d = dir();
    let wp = d.join("plot.csv");
    std::fs::write(&wp, "t,shoulder,elbow\n0,0,0\n1,1,-0.5\n2,0.2,0.8\n3,0,0\n").unwrap();
    let svg = d.join("plot.svg");
    let out = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args([
            "traj",
            wp.to_str().unwrap(),
            "--profile",
            "cubic-clamped",
            "--vmax",
            "1.5",
            "--amax",
            "4",
            "--unit",
            "m",
            "--out",
            "/dev/null",
            "--plot",
            svg.to_str().unwrap(),
        ])
        .output()
        .expect("run rl traj");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    for label in [
        "position [m]",
        "velocity [m/s]",
        "acceleration [m/s²]",
        "jerk [m/s³]",
        "t [s]",
        "shoulder",
        "elbow",
        "± limit",
        "waypoint",
    ] {
        assert!(text.contains(label), "{label:?} not in the plot");
    }
}
