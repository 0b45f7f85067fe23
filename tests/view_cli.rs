//! `rl view` end to end: with no model it serves the embedded RV-6SL that `rl run` drives and
//! prints the address it listens on (port 0 picks a free one); a non-loopback address is
//! warned about; a model that does not load exits with 2 and names the file.

mod cli;
mod late;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::time::Duration;

use cli::rl;
use serde_json::Value;

fn get(addr: &str, path: &str) -> (String, Vec<u8>) {
    let mut s = TcpStream::connect(addr).expect("connect to rl view");
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(s, "GET {path} HTTP/1.1\r\nHost: {addr}\r\n\r\n").unwrap();
    let mut out = Vec::new();
    s.read_to_end(&mut out).unwrap();
    let end = out.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    (
        String::from_utf8_lossy(&out[..end]).into_owned(),
        out[end + 4..].to_vec(),
    )
}

/// Starts `rl view` with the default robot on free ports; returns the child, the HTTP address
/// and the Coach address it printed.
fn start_view() -> (std::process::Child, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args([
            "view",
            "--http",
            "127.0.0.1:0",
            "--coach",
            "127.0.0.1:0",
            "--duration",
            "120",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start rl view");
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let first = lines.next().expect("a line").expect("text");
    let url = first
        .strip_prefix("rl view: open http://")
        .and_then(|u| u.strip_suffix('/'))
        .unwrap_or_else(|| panic!("{first}"))
        .to_string();
    let second = lines.next().expect("a line").expect("text");
    let coach = second
        .strip_prefix("rl view: Coach listening on ")
        .unwrap_or_else(|| panic!("{second}"))
        .trim()
        .to_string();
    // Keep reading what it prints later, so its stdout never meets a closed pipe.
    std::thread::spawn(move || lines.for_each(drop));
    (child, url, coach)
}

#[test]
fn view_serves_the_default_robot_and_prints_its_address() {
    let (mut child, url, coach) = start_view();
    assert!(
        url.starts_with("127.0.0.1:") && !url.ends_with(":0"),
        "{url}"
    );
    assert!(coach.starts_with("127.0.0.1:"), "{coach}");

    let (head, body) = get(&url, "/");
    assert!(head.starts_with("HTTP/1.1 200"), "{head}");
    assert!(String::from_utf8_lossy(&body).contains("<html"));
    let (head, body) = get(&url, "/api/scene");
    assert!(head.starts_with("HTTP/1.1 200"), "{head}");
    let scene: Value = serde_json::from_slice(&body).unwrap();
    let m = &scene["models"][0];
    assert!(m["name"].as_str().unwrap().contains("RV"), "{}", m["name"]);
    assert_eq!(m["joints"].as_array().unwrap().len(), 6);
    assert!(m["urdf"].is_null());
    let _ = child.kill();
    let _ = child.wait();
}

#[test]
fn view_warns_about_a_page_beyond_loopback() {
    let out = rl(&[
        "view",
        "--http",
        "0.0.0.0:0",
        "--no-coach",
        "--duration",
        "0",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no authentication"), "{err}");
}

#[test]
fn view_refuses_a_model_that_does_not_load() {
    let out = rl(&[
        "view",
        "no-such-robot.urdf",
        "--http",
        "127.0.0.1:0",
        "--no-coach",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no-such-robot.urdf"), "{err}");
}

#[test]
fn view_takes_an_rl_scene_with_its_kinematics_as_rl_coach_mdl_does() {
    let root = env!("CARGO_MANIFEST_DIR");
    let scene = format!("{root}/tests/data/rlsg/unimation-puma560_boxes.convex.xml");
    let kin = format!("{root}/tests/data/rlmdl/unimation-puma560.xml");
    let args = ["--http", "127.0.0.1:0", "--no-coach", "--duration", "0"];
    let out = rl(&[
        &["view", scene.as_str(), "--kinematics", kin.as_str()][..],
        &args[..],
    ]
    .concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("rl view: open http://127.0.0.1:"));
    // --kinematics without a scene, a scene without --kinematics: refused.
    let out = rl(&[
        &["view", kin.as_str(), "--kinematics", kin.as_str()][..],
        &args[..],
    ]
    .concat());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--kinematics goes with"));
    let out = rl(&[&["view", scene.as_str()][..], &args[..]].concat());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--kinematics"));
}

/// `rl run --device coach://…` with `rl view` running: the controller's motion shows in the
/// viewer's state while the run goes (polled over HTTP during the run), from the Coach source,
/// with nothing rejected.
#[test]
fn rl_run_over_coach_moves_the_robot_in_rl_view_as_it_happens() {
    let (mut view, url, coach) = start_view();
    let q_now = |url: &str| -> (Vec<f64>, Value) {
        let (head, body) = get(url, "/api/state");
        assert!(head.starts_with("HTTP/1.1 200"), "{head}");
        let s: Value = serde_json::from_slice(&body).expect("state JSON");
        let q = s["models"][0]["q"]
            .as_array()
            .expect("q")
            .iter()
            .map(|v| v.as_f64().expect("number"))
            .collect();
        (q, s)
    };
    // A run the machine made late runs again by the shared rule (`late::json_late`); each run
    // counts the configurations it moved the viewer to from where the viewer stood before it.
    let Some((status, out, seen)) = late::while_late(
        "a run over Coach",
        || {
            let (q0, _) = q_now(&url);
            let mut run = Command::new(env!("CARGO_BIN_EXE_rl"))
                .args([
                    "run",
                    "--device",
                    &format!("coach://{coach}"),
                    "--duration",
                    "2s",
                    "--json",
                ])
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .expect("start rl run");
            let mut seen: Vec<Vec<f64>> = Vec::new();
            let start = std::time::Instant::now();
            let status = loop {
                if let Some(status) = run.try_wait().expect("wait") {
                    break status;
                }
                assert!(
                    start.elapsed() < Duration::from_secs(60),
                    "rl run did not end"
                );
                let (q, s) = q_now(&url);
                if q != q0 && s["models"][0]["source"] == "coach" && seen.last() != Some(&q) {
                    seen.push(q);
                }
                std::thread::sleep(Duration::from_millis(50));
            };
            let out = run.wait_with_output().expect("output");
            (status, out, seen)
        },
        |(_, out, _)| late::json_late(&serde_json::from_slice(&out.stdout).ok()?),
    ) else {
        let _ = view.kill();
        return;
    };
    assert!(
        status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).expect("run JSON");
    assert!(report["cycles"].as_u64().unwrap() > 0, "{report}");
    // Polled every 50 ms over a 2 s motion: the viewer showed it moving, not just its end.
    assert!(
        seen.len() >= 5,
        "only {} distinct configurations seen during the run: {seen:?}",
        seen.len()
    );
    let (_, s) = q_now(&url);
    assert_eq!(s["coach"]["rejected"], 0, "{}", s["coach"]);
    let _ = view.kill();
    let _ = view.wait();
}

/// `rl view`'s per-robot flags and RL scenarios: what is refused, and why.
#[test]
fn view_takes_per_robot_flags_and_refuses_what_does_not_fit() {
    let root = env!("CARGO_MANIFEST_DIR");
    let ur5 = format!("{root}/tests/data/mbm/ur5/ur5.urdf");
    let srdf = format!("{root}/tests/data/mbm/ur5/ur5.srdf");
    let scenario = format!("{root}/tests/data/rlplan/unimation-puma560_boxes_rrtConCon.xml");
    let args = ["--http", "127.0.0.1:0", "--no-coach", "--duration", "0"];
    let run = |extra: &[&str]| rl(&[&["view"][..], extra, &args[..]].concat());
    // Two ur5s, the second placed and given the SRDF: loads.
    let out = run(&[
        &ur5,
        &ur5,
        "--place",
        "1=0,1,0,0,0,90",
        "--srdf",
        &format!("1={srdf}"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let refused = |extra: &[&str], why: &str| {
        let out = run(extra);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(why), "{extra:?}: {err}");
    };
    refused(
        &[&ur5, "--place", "2=0,0,0"],
        "options for 3 robots given, 1 robots loaded",
    );
    refused(&[&ur5, "--place", "0,0"], "--place: 2 values given");
    refused(
        &[&ur5, "--place", "0,0,0", "--place", "0=1,1,1"],
        "model 0 given twice",
    );
    refused(
        &[&scenario, "--place", "0=0,0,0"],
        "comes from an RL scenario",
    );
    refused(&[&scenario, &ur5], "an RL scenario is shown alone");
    // A scenario alone loads (RL's visual Puma, placed by its <world>).
    let out = run(&[&scenario]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
