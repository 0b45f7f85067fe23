//! `rl otg`: the JSONL interface of the online trajectory generator, and the comparison with
//! Ruckig (PyPI `ruckig` 0.19.4, the C++ library's binding, not written here) run live:
//! scripts/test installs it in target/ruckig-venv; without it that test prints SKIPPED.

use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};

use serde_json::Value;

mod cli;

fn rl_otg(args: &[&str], input: &str) -> (i32, Vec<Value>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rl"))
        .arg("otg")
        .args(args)
        .arg("-")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("rl runs");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(input.as_bytes())
        .expect("jobs written");
    let out = child.wait_with_output().expect("rl ends");
    let lines = String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line per job"))
        .collect();
    (out.status.code().unwrap_or(-1), lines)
}

#[test]
fn answers_every_line_and_samples_to_the_end() {
    let jobs = concat!(
        r#"{"current":{"p":[0,0]},"target":{"p":[1,-0.5]},"vmax":[1,1],"amax":[2,2],"jmax":[10,10]}"#,
        "\n",
        r#"{"current":{"p":[0],"v":[0.5],"a":[1]},"target":{"p":[0.3],"v":[0.2]},"vmax":[1],"vmin":[-0.5],"amax":[2],"amin":["-inf"],"jmax":[10],"sync":"phase"}"#,
        "\n",
        r#"{"current":{"p":[0]},"target":{"p":[1],"v":[3]},"vmax":[1],"amax":[2],"jmax":[10]}"#,
        "\n",
        r#"{"current":{"p":[0,0]},"target":{"p":[1,1]},"vmax":[1,1],"amax":[2,2],"jmax":[10,10],"waypoints":[[0.5,0.2],[0.7,0.9]]}"#,
        "\n",
    );
    let (code, out) = rl_otg(&["--samples", "0.25", "--verify"], jobs);
    assert_eq!(code, 0);
    assert_eq!(out.len(), 4);
    // Rest to rest: 1 m at 1 m/s, 2 m/s², 10 m/s³ takes 1/1 + 1/2 + 2/10 = 1.7 s.
    assert_eq!(out[0]["result"], "ok");
    assert!((out[0]["duration_s"].as_f64().expect("duration_s") - 1.7).abs() < 1e-12);
    assert_eq!(out[0]["violation"], Value::Null);
    let samples = &out[0]["samples"];
    let t: Vec<f64> = serde_json::from_value(samples["t"].clone()).expect("times");
    assert_eq!(t.first(), Some(&0.0));
    assert_eq!(t.last(), Some(&1.7));
    assert_eq!(t.len(), 8);
    let p_end = &samples["p"][t.len() - 1];
    assert!((p_end[0].as_f64().expect("p") - 1.0).abs() < 1e-12);
    assert!((p_end[1].as_f64().expect("p") + 0.5).abs() < 1e-12);
    assert_eq!(samples["j"][0].as_array().expect("jerk").len(), 2);
    assert_eq!(out[1]["result"], "ok");
    assert_eq!(out[2]["result"], "error");
    assert_eq!(out[2]["error"], "TargetOutsideLimits");
    assert_eq!(out[2]["axis"], 0);
    assert_eq!(out[3]["result"], "ok");
    assert_eq!(
        out[3]["sections_s"].as_array().expect("sections_s").len(),
        3
    );
    assert_eq!(out[3]["violation"], Value::Null);

    // A line that is not a job is answered as such, the others still are, and the exit status
    // says something was wrong.
    let (code, out) = rl_otg(
        &[],
        "{\"current\":{\"p\":[0]},\"target\":{\"p\":[1]},\"vmax\":[1],\"amax\":[2],\"jmax\":[10],\"vmn\":[1]}\nnot json\n{\"current\":{\"p\":[0]},\"target\":{\"p\":[1]},\"vmax\":[1],\"amax\":[2],\"jmax\":[10]}\n",
    );
    assert_eq!(code, 1);
    assert_eq!(out[0]["result"], "invalid");
    assert!(out[0]["message"].as_str().expect("message").contains("vmn"));
    assert_eq!(out[1]["result"], "invalid");
    assert_eq!(out[2]["result"], "ok");
}

#[test]
fn edge_case_fixtures_agree_through_the_cli() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("rl-core/tests/data/otg/edge_cases.jsonl");
    let text = std::fs::read_to_string(&path).expect("fixture");
    let (code, out) = rl_otg(&["--verify"], &text);
    assert_eq!(code, 0);
    for (line, answer) in text.lines().zip(&out) {
        let job: Value = serde_json::from_str(line).expect("json");
        assert!(answer["violation"].is_null(), "{answer} for {line}");
        if let Some(theirs) = job["ruckig"]["duration"].as_f64() {
            let ours = answer["duration_s"]
                .as_f64()
                .unwrap_or_else(|| panic!("ours failed: {answer} for {line}"));
            // The same duration, or shorter where Ruckig's is not time-optimal (one edge case).
            assert!(
                ours <= theirs * (1.0 + 1e-9) + 1e-12,
                "{ours} vs {theirs}: {line}"
            );
        }
    }
}

#[test]
fn live_comparison_with_ruckig() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    if cli::ruckig_python().is_none() {
        println!(
            "SKIPPED: live_comparison_with_ruckig: no ruckig in target/ruckig-venv (scripts/test installs it)"
        );
        return;
    }
    // 300 fresh random jobs per category (a different seed from the committed fixtures); the
    // disagreeing jobs go to a directory of this test's own, not scripts/otg-vs-ruckig's.
    let record = root.join(format!("target/tmp/otg-cli-live-{}", std::process::id()));
    let out = Command::new(root.join("scripts/otg-vs-ruckig"))
        .args([
            "--jobs", "300", "--chunk", "300", "--seed", "4242", "--show", "5",
        ])
        .arg("--out")
        .arg(&record)
        .env("RL_BIN", env!("CARGO_BIN_EXE_rl"))
        .output()
        .expect("scripts/otg-vs-ruckig runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    let _ = std::fs::remove_dir_all(&record);
    assert!(
        out.status.success(),
        "disagreements with Ruckig:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
