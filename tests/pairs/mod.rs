//! What the two-process tests (`rl fake-robot …` beside `rl run`) share: telling a run that
//! failed because the machine was late from one that failed on its own.
#![allow(dead_code)]

use std::process::Output;

/// The number after `label` in a text report (`overruns 0`, `missed deadlines 3`).
fn number_after(report: &str, label: &str) -> Option<f64> {
    let at = report.find(label)? + label.len();
    report[at..].split_whitespace().next()?.parse().ok()
}

/// Whether a failed run's text report shows the machine late: the loop overran or missed
/// deadlines or woke more than `half_period_us` late, or replies were lost in a row (on
/// loopback, with the fake at a real-time priority, the machine's doing).
pub fn machine_late(report: &str, half_period_us: f64) -> bool {
    let loop_late = number_after(report, "overruns ").is_some_and(|n| n > 0.0)
        || number_after(report, "missed deadlines ").is_some_and(|n| n > 0.0)
        || report
            .lines()
            .find(|l| l.starts_with("wake-up latency"))
            .and_then(|l| number_after(l, " max "))
            .is_some_and(|us| us > half_period_us);
    loop_late || report.contains("replies lost in a row")
}

/// Runs `run` up to three times while it fails with the machine late; asserts that the last
/// run ended `result: ok` at its duration, or prints SKIPPED with the reasons if every run
/// failed with the machine late. A failure with the machine on time fails at once.
pub fn run_until_on_time(name: &str, half_period_us: f64, mut run: impl FnMut() -> Output) {
    let mut late = Vec::new();
    for attempt in 1..=3 {
        let out = run();
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        if out.status.success() {
            assert!(stdout.contains("result: ok"), "{name}:\n{stdout}");
            assert!(
                stdout.contains("end: duration reached"),
                "{name}:\n{stdout}"
            );
            println!("{name}: attempt {attempt}:\n{stdout}");
            return;
        }
        let report = format!("{stdout}\n{stderr}");
        assert!(
            machine_late(&report, half_period_us),
            "{name} failed (exit {:?}) with the machine on time:\n{report}",
            out.status.code()
        );
        println!("{name}: attempt {attempt} failed with the machine late:\n{report}");
        // A fake on cannelloni UDP takes the next master after a quarter second of silence.
        std::thread::sleep(std::time::Duration::from_millis(300));
        late.push(
            report
                .lines()
                .find(|l| l.starts_with("end:"))
                .unwrap_or("")
                .to_owned(),
        );
    }
    println!(
        "SKIPPED: {name}: this machine was late in three runs ({})",
        late.join("; ")
    );
}

#[test]
fn lateness_is_read_from_the_report() {
    let on_time = "cycles 1500  overruns 0  missed deadlines 0  lost packets 2\n\
                   wake-up latency µs: min 19.9  mean 55.0  p99 76.0  p99.9 118.0  max 167.1\n\
                   end: fault (stopped at once): the device faulted";
    assert!(!machine_late(on_time, 1000.0));
    assert!(machine_late(
        &on_time.replace("missed deadlines 0", "missed deadlines 3"),
        1000.0
    ));
    assert!(machine_late(
        &on_time.replace("overruns 0", "overruns 1"),
        1000.0
    ));
    assert!(
        machine_late(on_time, 100.0),
        "woke 167 µs late, half a period is 100"
    );
    assert!(machine_late(
        &format!("{on_time}: 10 replies lost in a row"),
        1000.0
    ));
}
