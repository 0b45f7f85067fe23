//! Issue 25: every JSON output of the `rl` tool carries the version key (`"schema":
//! "rl.<command>/<version>"`), and `docs/json.md` names every top-level key each command
//! prints — the commands are run here and their keys compared with the document's tables, so
//! the document cannot drift from the code.
//!
//! The document's grammar (see its opening): a section per output, `## \`rl model eval\``; in
//! it `Schema: \`rl.model.eval/1\`` in its text and a table whose rows start `| \`key\` |` and end
//! with when the key is there (`always`, or the condition). Every key an output prints must be
//! in its table, every `always` key in every output, and every documented key in at least one
//! of the outputs run here (so a key removed from the code is removed from the document).

mod cli;

use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::process::{Command, Stdio};
use std::time::Duration;

use serde_json::Value;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn path(rel: &str) -> String {
    format!("{ROOT}/{rel}")
}

/// One output's documentation.
#[derive(Debug, Default)]
struct Section {
    schema: String,
    /// key → whether it is always there.
    keys: BTreeMap<String, bool>,
}

/// The sections of docs/json.md by title (`rl model eval`).
fn documented() -> BTreeMap<String, Section> {
    let text = std::fs::read_to_string(path("docs/json.md")).expect("docs/json.md");
    let mut out: BTreeMap<String, Section> = BTreeMap::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        if let Some(title) = line.strip_prefix("## `").and_then(|t| t.strip_suffix('`')) {
            assert!(
                out.insert(title.to_string(), Section::default()).is_none(),
                "docs/json.md: section {title} twice"
            );
            current = Some(title.to_string());
            continue;
        }
        if line.starts_with("## ") {
            current = None;
            continue;
        }
        let Some(section) = current.as_ref().and_then(|t| out.get_mut(t)) else {
            continue;
        };
        if let Some((_, rest)) = line.split_once("Schema: `") {
            section.schema = rest.split('`').next().unwrap_or_default().to_string();
        } else if let Some(rest) = line.strip_prefix("| `") {
            let key = rest.split('`').next().unwrap_or_default().to_string();
            let cells: Vec<&str> = line.trim_end_matches('|').split('|').collect();
            let when = cells.last().map(|c| c.trim()).unwrap_or_default();
            assert!(
                section.keys.insert(key.clone(), when == "always").is_none(),
                "docs/json.md: {key} twice"
            );
        }
    }
    out
}

/// Runs `rl args` (within two minutes) and parses every JSON object on standard output: one
/// document, or one per line.
fn outputs(args: &[String], stdin: Option<&str>, wrapper: &[&str]) -> Vec<Value> {
    let (program, pre) = match wrapper.split_first() {
        Some((p, rest)) => (p.to_string(), rest.iter().map(|s| s.to_string()).collect()),
        None => (env!("CARGO_BIN_EXE_rl").to_string(), Vec::new()),
    };
    let mut cmd = Command::new(program);
    cmd.args(pre);
    if !wrapper.is_empty() {
        cmd.arg(env!("CARGO_BIN_EXE_rl"));
    }
    cmd.args(args);
    let out = match stdin {
        None => cli::run_bounded(cmd, Duration::from_secs(120)),
        Some(input) => {
            let mut child = cmd
                .stdin(Stdio::piped())
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .expect("spawn rl");
            child
                .stdin
                .take()
                .expect("stdin")
                .write_all(input.as_bytes())
                .expect("input written");
            child.wait_with_output().expect("rl ends")
        }
    };
    let stdout = String::from_utf8(out.stdout).expect("utf-8");
    if let Ok(v) = serde_json::from_str::<Value>(&stdout) {
        return vec![v];
    }
    stdout
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            serde_json::from_str(l).unwrap_or_else(|e| {
                panic!(
                    "rl {args:?}: not JSON ({e}): {l}\nstderr:\n{}",
                    String::from_utf8_lossy(&out.stderr)
                )
            })
        })
        .collect()
}

fn strings(args: &[&str]) -> Vec<String> {
    args.iter().map(|s| s.to_string()).collect()
}

/// `rl run` without the right to real-time scheduling or locked memory (it warns and runs at
/// SCHED_OTHER), so that this test never runs at real-time priority: `setpriv` drops the
/// capabilities when there is one (root has them), else none are needed to try.
fn without_realtime() -> Vec<&'static str> {
    let has_setpriv = Command::new("setpriv")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if has_setpriv {
        vec![
            "setpriv",
            "--inh-caps=-sys_nice,-ipc_lock",
            "--bounding-set=-sys_nice,-ipc_lock",
            "--",
        ]
    } else {
        Vec::new()
    }
}

/// One command to run: (its section in docs/json.md, its arguments, its standard input, the
/// program that runs it, if any).
type Run<'a> = (&'a str, Vec<String>, Option<&'a str>, Vec<&'a str>);

const OTG_JOBS: &str = concat!(
    r#"{"current":{"p":[0,0]},"target":{"p":[1,-0.5]},"vmax":[1,1],"amax":[2,2],"jmax":[10,10]}"#,
    "\n",
    r#"{"current":{"p":[0]},"target":{"p":[1],"v":[3]},"vmax":[1],"amax":[2],"jmax":[10]}"#,
    "\n",
    r#"{"current":{"p":[0,0]},"target":{"p":[1,1]},"vmax":[1,1],"amax":[2,2],"jmax":[10,10],"waypoints":[[0.5,0.2],[0.7,0.9]]}"#,
    "\n",
    "not a job\n",
);

#[test]
fn every_output_is_versioned_and_documented_key_by_key() {
    let docs = documented();
    let puma = path("tests/data/rlmdl/unimation-puma560.xml");
    let boxes = path("tests/data/rlsg/unimation-puma560_boxes.convex.xml");
    let cage = path("tests/data/moveit/cage_panda_scene0001.yaml");
    let panda = path("tests/data/mbm/panda/panda.urdf");
    let problem = path("tests/data/mbm/panda/problems/table_pick_panda");
    let puma_scene = |cmd: &str, extra: &[&str]| {
        let mut a = strings(&["scene", cmd, &boxes, "--kinematics", &puma]);
        a.extend(strings(extra));
        a
    };
    let no_rt = without_realtime();
    let runs: Vec<Run<'_>> = vec![
        (
            "rl model info",
            strings(&["model", "info", &puma, "--json"]),
            None,
            vec![],
        ),
        (
            "rl model eval",
            strings(&["model", "eval", &puma]),
            None,
            vec![],
        ),
        (
            "rl model eval",
            strings(&["model", "eval", &puma, "--derivatives"]),
            None,
            vec![],
        ),
        (
            "rl model bench",
            strings(&[
                "model", "bench", &puma, "--json", "--states", "4", "--rounds", "3",
            ]),
            None,
            vec![],
        ),
        (
            "rl scene info",
            strings(&["scene", "info", &cage, "--json"]),
            None,
            vec![],
        ),
        (
            "rl scene check",
            puma_scene("check", &["--q", "0,0,0,0,0,0"]),
            None,
            vec![],
        ),
        (
            "rl scene dump",
            puma_scene("dump", &["--random", "2"]),
            None,
            vec![],
        ),
        (
            "rl scene bench",
            puma_scene("bench", &["--configs", "3", "--rounds", "2", "--json"]),
            None,
            vec![],
        ),
        (
            "rl plan",
            strings(&[
                "plan",
                &panda,
                "--scene",
                &format!("{problem}/scene0001.yaml"),
                "--request",
                &format!("{problem}/request0001.yaml"),
                "--seed",
                "3",
            ]),
            None,
            vec![],
        ),
        (
            "rl jitter",
            strings(&[
                "jitter",
                "--policy",
                "other",
                "--no-mlock",
                "--no-cpu-latency-hint",
                "--cycles",
                "100",
                "--interval-us",
                "500",
                "--json",
            ]),
            None,
            vec![],
        ),
        (
            "rl preflight",
            strings(&["preflight", "--json"]),
            None,
            vec![],
        ),
        (
            "rl otg",
            strings(&["otg", "--verify", "--samples", "0.5", "-"]),
            Some(OTG_JOBS),
            vec![],
        ),
        (
            "rl run",
            strings(&["run", "--follow", "-", "--json"]),
            Some("position 0.1 0 0 0 0 0\nstop\n"),
            no_rt.clone(),
        ),
        (
            "rl run",
            strings(&["run", "--duration", "1s", "--json"]),
            None,
            no_rt,
        ),
    ];
    let mut seen: BTreeMap<&str, BTreeSet<String>> = BTreeMap::new();
    for (title, args, stdin, wrapper) in &runs {
        let section = docs
            .get(*title)
            .unwrap_or_else(|| panic!("docs/json.md has no section `{title}`"));
        assert!(
            section.schema.starts_with("rl.") && section.schema.contains('/'),
            "{title}: schema {:?}",
            section.schema
        );
        let values = outputs(args, *stdin, wrapper);
        assert!(!values.is_empty(), "rl {args:?} printed no JSON");
        for v in values {
            let obj = v
                .as_object()
                .unwrap_or_else(|| panic!("rl {args:?}: not an object: {v}"));
            assert_eq!(
                obj.get(rl::json::SCHEMA_KEY).and_then(Value::as_str),
                Some(section.schema.as_str()),
                "rl {args:?}: the version key"
            );
            for k in obj.keys() {
                assert!(
                    section.keys.contains_key(k),
                    "rl {args:?} prints `{k}`, which docs/json.md's `{title}` does not name"
                );
            }
            for (k, always) in &section.keys {
                assert!(
                    !always || obj.contains_key(k),
                    "docs/json.md says `{title}` always prints `{k}`; rl {args:?} did not"
                );
            }
            seen.entry(title).or_default().extend(obj.keys().cloned());
        }
    }
    for (title, section) in &docs {
        let printed = seen
            .get(title.as_str())
            .unwrap_or_else(|| panic!("docs/json.md's `{title}` is not run by this test"));
        for k in section.keys.keys() {
            assert!(
                printed.contains(k)
                    || NOT_EXERCISED.contains(&(title.as_str(), k.as_str()))
                    || (title == "rl run" && CIA402_FAKE.contains(&k.as_str())),
                "docs/json.md's `{title}` names `{k}`, which none of the runs printed"
            );
        }
    }
}

/// Keys documented for conditions the runs above do not meet (a device, a feature, an error),
/// named one by one so that a key dropped from the code is dropped from the document too.
const NOT_EXERCISED: [(&str, &str); 11] = [
    ("rl model eval", "qdd_error"),
    ("rl model bench", "rnea_check"),
    ("rl run", "plan"),
    ("rl run", "zenoh"),
    // `--law cartesian-impedance` needs a torque-controlled device (a Franka arm): its
    // headline keys are checked in tests/task_space.rs against `rl fake-robot franka`.
    ("rl run", "task_error_max_m"),
    ("rl run", "task_error_rms_m"),
    ("rl run", "orientation_error_max_rad"),
    ("rl run", "min_obstacle_distance_m"),
    ("rl run", "torque_rate_max"),
    ("rl run", "compute_us"),
    // `--obstacle FILE` goes with `--law` too: checked in tests/task_space.rs.
    ("rl run", "obstacles"),
];

/// `rl run --device fake-cia402`'s keys.
const CIA402_FAKE: [&str; 6] = [
    "fake_drives",
    "fake_drives_powered",
    "fake_syncs",
    "fake_tpdos",
    "fake_faults",
    "fake_max_lateness_ms",
];
