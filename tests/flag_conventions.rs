//! One set of conventions for the `rl` tool's flags (issue 25): one name per idea
//! (`--plan-time`, `--duration`), one default per idea (`--speed`: the library's
//! `DEFAULT_SPEED`), one SRDF rule (the SRDF beside a URDF unless `--srdf`, in every command
//! that checks collision pairs), flags that do not apply refused with exit code 2 and one line
//! naming them, and `--help` that agrees with the library's tables and the README.

mod cli;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use cli::{rl, rl_json};
use rl::controller::runtime::DEFAULT_SPEED;
use rl::devices::{DEVICE_FORMS, RATE_HZ};
use serde_json::Value;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn path(rel: &str) -> String {
    format!("{ROOT}/{rel}")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rl-flags-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn help(args: &[&str]) -> String {
    let o = rl(&[args, &["--help"]].concat());
    assert!(o.status.success(), "{args:?} --help");
    String::from_utf8(o.stdout).unwrap()
}

/// The help of `--flag`: its line and the lines below it up to the next flag or heading (the
/// long help puts its default on a line of its own).
fn help_line(text: &str, flag: &str) -> String {
    let mut lines = text.lines().skip_while(|l| {
        let l = l.trim();
        !(l == flag || l.starts_with(&format!("{flag} ")))
    });
    let first = lines
        .next()
        .unwrap_or_else(|| panic!("no {flag} in\n{text}"));
    let rest = lines.take_while(|l| l.starts_with(' ') && !l.trim_start().starts_with('-'));
    std::iter::once(first)
        .chain(rest)
        .map(str::trim)
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn the_planning_budget_has_one_name_and_the_old_one_still_works() {
    for cmd in [&["plan"][..], &["plan", "bench"], &["run"]] {
        let h = help(cmd);
        assert!(
            help_line(&h, "--plan-time").contains("[default: 1s]"),
            "{cmd:?}"
        );
        assert!(!h.contains("--time "), "{cmd:?} lists --time:\n{h}");
    }
    // `--time` is a hidden alias of `--plan-time`: it sets the scenario's budget (the file's
    // budget otherwise), and the message names the budget that was used.
    let scenario = path("tests/data/rlplan/mitsubishi-rv6sl_boxes_prm.xml");
    for flag in ["--time", "--plan-time"] {
        let o = rl(&["plan", &scenario, flag, "1us", "--no-certify"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{flag}: {err}");
        assert!(
            err.contains("no path found by PRM within 1µs"),
            "{flag}: {err}"
        );
    }
}

#[test]
fn how_long_to_run_is_duration_everywhere() {
    for cmd in [
        &["run"][..],
        &["jitter"],
        &["view"],
        &["fake-robot", "h7"],
        &["fake-robot", "coach"],
        &["fake-robot", "canopen"],
        &["fake-robot", "ethercat"],
        &["fake-robot", "franka"],
        &["fake-robot", "gripper"],
        &["fake-robot", "ft"],
        &["fake-robot", "ur"],
    ] {
        let h = help(cmd);
        help_line(&h, "--duration");
        assert!(!h.contains("--seconds"), "{cmd:?}:\n{h}");
    }
    // The old spelling still parses.
    let o = rl(&[
        "fake-robot",
        "h7",
        "--bind",
        "127.0.0.1:0",
        "--r3-bind",
        "127.0.0.1:0",
        "--seconds",
        "0",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn speed_has_one_default_from_the_library() {
    let default = format!("[default: {DEFAULT_SPEED}]");
    for cmd in ["plan", "run"] {
        let h = help(&[cmd]);
        assert!(help_line(&h, "--speed").contains(&default), "{cmd}:\n{h}");
    }
}

#[test]
fn run_help_lists_every_device_form_and_what_rate_takes() {
    let h = help(&["run"]);
    for f in DEVICE_FORMS {
        assert!(h.contains(f.form), "--device help lacks {}:\n{h}", f.form);
    }
    let rate = help_line(&h, "--rate");
    let (low, high) = RATE_HZ;
    assert!(rate.contains(&format!("from {low} to {high}")), "{rate}");
    for f in DEVICE_FORMS.iter().filter(|f| f.fixed_period) {
        assert!(rate.contains(f.form), "{rate}");
    }
    // What the help says is what is refused.
    let o = rl(&["run", "--device", "h7://127.0.0.1", "--rate", "500"]);
    assert_eq!(o.status.code(), Some(2));
    let o = rl(&["run", "--rate", &format!("{}", high * 2.0)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(&format!("between {low} and {high}")), "{err}");
}

/// An arm of three links whose only non-adjacent pair (base, lower) is far apart, with an SRDF
/// beside it that allows every pair and names a `home` state (j1 at 0.5), or without one.
fn arm(name: &str, with_srdf: bool) -> PathBuf {
    let dir = tmp(name);
    let urdf = dir.join("arm.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="arm">
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="upper"><collision><origin xyz="0 0 0.5"/><geometry><box size="0.05 0.05 0.6"/></geometry></collision></link>
  <link name="lower"><collision><origin xyz="0 0 0.4"/><geometry><box size="0.05 0.05 0.5"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="upper"/><child link="lower"/><origin xyz="0 0 0.9"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"#,
    )
    .unwrap();
    if with_srdf {
        std::fs::write(
            dir.join("arm.srdf"),
            r#"<robot name="arm">
  <group name="arm"><chain base_link="base" tip_link="lower"/></group>
  <group_state name="home" group="arm"><joint name="j1" value="0.5"/><joint name="j2" value="0"/></group_state>
  <disable_collisions link1="base" link2="upper" reason="Adjacent"/>
  <disable_collisions link1="upper" link2="lower" reason="Adjacent"/>
  <disable_collisions link1="base" link2="lower" reason="Never"/>
</robot>"#,
        )
        .unwrap();
    }
    urdf
}

fn self_pairs(urdf: &Path, extra: &[&str]) -> u64 {
    let v = rl_json(
        &[
            &["scene", "check", urdf.to_str().unwrap(), "--q", "0,0"],
            extra,
        ]
        .concat(),
    );
    v["self_pairs_checked"]
        .as_u64()
        .unwrap_or_else(|| panic!("{v}"))
}

#[test]
fn the_srdf_beside_the_urdf_is_used_unless_srdf_is_given() {
    let with = arm("with-srdf", true);
    let without = arm("without-srdf", false);
    // rl scene: the SRDF beside allows the one non-adjacent pair; without it, it is checked.
    assert_eq!(self_pairs(&with, &[]), 0);
    assert_eq!(self_pairs(&without, &[]), 1);
    // --srdf wins over the one beside: this one allows the adjacent pairs only.
    let adjacent = with.with_file_name("adjacent.srdf");
    std::fs::write(
        &adjacent,
        r#"<robot name="arm">
  <disable_collisions link1="base" link2="upper" reason="Adjacent"/>
  <disable_collisions link1="upper" link2="lower" reason="Adjacent"/>
</robot>"#,
    )
    .unwrap();
    assert_eq!(
        self_pairs(&with, &["--srdf", adjacent.to_str().unwrap()]),
        1
    );
    // rl view: the robot starts at the named state of the SRDF beside it.
    assert_eq!(
        view_scene(&with)["models"][0]["initial_source"],
        "srdf:home"
    );
    assert_ne!(
        view_scene(&without)["models"][0]["initial_source"],
        "srdf:home"
    );
    // rl plan and rl run --plan load robots through rl-plan, whose loader takes the same rule
    // (`rl_sg::load::srdf::for_robot`).
    assert_eq!(
        rl::sg::load::srdf::for_robot(&with, None),
        Some(with.with_file_name("arm.srdf"))
    );
    assert_eq!(rl::sg::load::srdf::for_robot(&without, None), None);
    for d in [&with, &without] {
        std::fs::remove_dir_all(d.parent().unwrap()).ok();
    }
}

/// `rl view URDF`'s Scene JSON.
fn view_scene(urdf: &Path) -> Value {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rl"))
        .args([
            "view",
            urdf.to_str().unwrap(),
            "--http",
            "127.0.0.1:0",
            "--no-coach",
        ])
        .args(["--duration", "60"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start rl view");
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let first = lines.next().expect("a line").expect("text");
    let addr = first
        .strip_prefix("rl view: open http://")
        .and_then(|u| u.strip_suffix('/'))
        .unwrap_or_else(|| panic!("{first}"))
        .to_string();
    std::thread::spawn(move || lines.for_each(drop));
    let mut s = TcpStream::connect(&addr).expect("connect to rl view");
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(
        s,
        "GET /api/scene HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut out = Vec::new();
    s.read_to_end(&mut out).unwrap();
    let _ = child.kill();
    let _ = child.wait();
    let end = out.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    serde_json::from_slice(&out[end + 4..]).expect("scene JSON")
}

#[test]
fn flags_that_do_not_apply_are_refused_naming_the_flag() {
    let dir = tmp("refused");
    let wp = dir.join("wp.csv");
    std::fs::write(&wp, "a,b\n0,0\n1,1\n").unwrap();
    let wp = wp.to_str().unwrap();
    let scenario = path("tests/data/rlplan/unimation-puma560_boxes_prm.mdl.xml");
    let panda = path("tests/data/mbm/panda/panda.urdf");
    let problem = path("tests/data/mbm/panda/problems/table_pick_panda");
    let (scene, request) = (
        format!("{problem}/scene0001.yaml"),
        format!("{problem}/request0001.yaml"),
    );
    let urdf_problem = ["plan", &panda, "--scene", &scene, "--request", &request];
    let puma_scene = path("tests/data/rlsg/unimation-puma560_boxes.convex.xml");
    let puma = path("tests/data/rlmdl/unimation-puma560.xml");
    let arm = arm("refused-arm", false);
    let arm = arm.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["plan", &scenario, "--optimizer", "shortcut"],
            "--optimizer",
        ),
        (vec!["plan", &scenario, "--planner", "rrt"], "--planner"),
        (vec!["plan", &scenario, "--checker", "spheres"], "--checker"),
        (vec!["plan", &scenario, "--scene", &scene], "--scene"),
        (vec!["plan", &scenario, "--speed", "0.5"], "--speed"),
        (
            vec!["plan", &scenario, "--no-certify", "--certify-margin", "1"],
            "--certify-margin",
        ),
        (vec!["plan", &panda, "--speed", "0.5"], "--speed"),
        (vec!["plan", &panda, "--dt", "5ms"], "--dt"),
        (
            [&urdf_problem[..], &["--planner", "prm", "--range", "1"]].concat(),
            "--range",
        ),
        (
            [&urdf_problem[..], &["--checker", "exact", "--raw-spheres"]].concat(),
            "--raw-spheres",
        ),
        (
            vec!["run", "--no-supervision", "--tracking-bound", "0.1"],
            "--tracking-bound",
        ),
        (
            vec!["run", "--no-supervision", "--rest-after-lost", "2"],
            "--rest-after-lost",
        ),
        (
            vec!["run", "--srdf", "x.srdf", "--view", "127.0.0.1:0"],
            "--srdf",
        ),
        (
            vec![
                "traj",
                wp,
                "--profile",
                "quintic",
                "--vmax",
                "1",
                "--blend",
                "0.5",
            ],
            "--blend",
        ),
        (
            vec![
                "traj",
                wp,
                "--profile",
                "quintic",
                "--vmax",
                "1",
                "--unit",
                "m",
            ],
            "--unit",
        ),
        (
            vec!["jitter", "--cycles", "10", "--duration", "1s"],
            "--duration",
        ),
        (
            vec!["scene", "check", arm, "--kinematics", &puma, "--q", "0,0"],
            "--kinematics",
        ),
        (
            vec![
                "scene",
                "check",
                &puma_scene,
                "--kinematics",
                &puma,
                "--floating-base",
                "--q",
                "0,0,0,0,0,0",
            ],
            "--floating-base",
        ),
        (
            vec!["fake-robot", "h7", "--model", &puma, "--dof", "3"],
            "--dof",
        ),
        (
            vec![
                "fake-robot",
                "ethercat",
                "--interface",
                "lo",
                "--model",
                &puma,
                "--devices",
                "3",
            ],
            "--devices",
        ),
        (vec!["model", "eval", &puma, "--normalize"], "--normalize"),
        (
            vec![
                "model",
                "bench",
                &puma,
                "--states-file",
                "s.txt",
                "--states",
                "4",
            ],
            "--states",
        ),
    ];
    for (args, flag) in cases {
        let o = rl(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.starts_with(&format!("rl: {flag} does not apply ")),
            "{args:?}: {err}"
        );
        assert!(o.stdout.is_empty(), "{args:?}");
    }
    // The ones that do apply in the same places still run.
    let o = rl(&[
        "plan",
        &scenario,
        "--seed",
        "1",
        "--plan-time",
        "5s",
        "--certify-margin",
        "0.00001",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A listener that is switched off takes no address (clap's conflict, exit code 2).
    let o = rl(&[
        "view",
        "--no-coach",
        "--coach",
        "127.0.0.1:0",
        "--duration",
        "0",
    ]);
    assert_eq!(o.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::remove_dir_all(Path::new(arm).parent().unwrap()).ok();
}

#[test]
fn plan_bench_refuses_an_output_directory_before_any_run() {
    let problems = path("tests/data/mbm/panda/problems");
    for flag in ["--out", "--paths"] {
        let o = rl(&["plan", "bench", &problems, flag, "/dev/null/x"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag}: {err}");
        assert!(err.contains(&format!("{flag} /dev/null/x")), "{err}");
        assert!(o.stdout.is_empty(), "{flag}: the runs went ahead");
    }
    let o = rl(&[
        "plan",
        "bench",
        "/nonexistent",
        "--model",
        &path("tests/data/mbm/panda/panda.urdf"),
    ]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn a_sampling_period_is_written_the_same_way_everywhere() {
    let dir = tmp("dt");
    let wp = dir.join("wp.csv");
    std::fs::write(&wp, "a,b\n0,0\n1,1\n").unwrap();
    let traj = |dt: &str| {
        let o = rl(&[
            "traj",
            wp.to_str().unwrap(),
            "--profile",
            "quintic",
            "--vmax",
            "1",
            "--dt",
            dt,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        o.stdout
    };
    assert_eq!(traj("0.25"), traj("250ms"));
    for cmd in [&["traj"][..], &["plan"]] {
        help_line(&help(cmd), "--dt <DURATION>");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Every flag the README's tool summary gives a subcommand is one that subcommand's `--help`
/// lists (hidden aliases are not: the README uses the one name).
#[test]
fn the_readmes_tool_summary_names_the_flags_help_lists() {
    let readme = std::fs::read_to_string(path("README.md")).unwrap();
    let start = readme.find("## The `rl` tool").expect("the tool section");
    let block = readme[start..]
        .split("```sh")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("the tool summary");
    let mut checked = 0;
    for line in block.lines() {
        let line = line.split('#').next().unwrap_or("");
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.first() != Some(&"rl") || words.len() < 2 {
            continue;
        }
        let mut command = vec![words[1]];
        if let Some(sub) = words.get(2).filter(|w| {
            w.chars().all(|c| c.is_ascii_lowercase() || c == '-')
                && rl(&[words[1], w, "--help"]).status.success()
        }) {
            command.push(sub);
        }
        let text = help(&command);
        for flag in line
            .split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
            .filter(|w| w.starts_with("--") && w.len() > 2)
        {
            let listed = text.match_indices(flag).any(|(i, _)| {
                !text[i + flag.len()..].starts_with(|c: char| c.is_ascii_alphanumeric() || c == '-')
            });
            assert!(
                listed,
                "README: `{}` gives {flag}, its --help does not",
                command.join(" ")
            );
            checked += 1;
        }
    }
    assert!(
        checked > 40,
        "only {checked} flags found in the README's summary"
    );
}
