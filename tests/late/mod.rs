//! Telling a run the machine made late from one that failed on its own, shared by the tests
//! that run a real-time loop against a fake: on a shared 2-core VM the host holds a CPU (a
//! real-time thread's too) for milliseconds, and a fake on loopback then answers late or the
//! loop wakes late. Such a run is run again, at most three times, then the test is SKIPPED with
//! the reasons. Nothing is loosened: an on-time run is checked in full, and a run that failed
//! or lost replies with nobody measured late is returned to its checks, which fail it.
#![allow(dead_code)]

use rl::controller::RunReport;
use serde_json::Value;

/// How many runs a test makes before it gives up on the machine.
pub const ATTEMPTS: usize = 3;

/// Runs `attempt` (a whole run, from its start) until `late` finds nothing to blame on the
/// machine, at most [`ATTEMPTS`] times; gives back that run to be checked, or prints SKIPPED
/// with the reasons and gives back `None`.
pub fn while_late<T>(
    name: &str,
    mut attempt: impl FnMut() -> T,
    late: impl Fn(&T) -> Option<String>,
) -> Option<T> {
    let mut reasons = Vec::new();
    for n in 1..=ATTEMPTS {
        let outcome = attempt();
        let Some(why) = late(&outcome) else {
            return Some(outcome);
        };
        println!("{name}: attempt {n}: the machine was late: {why}");
        reasons.push(why);
    }
    println!(
        "SKIPPED: {name}: the machine was late in {ATTEMPTS} runs: {}",
        reasons.join("; ")
    );
    None
}

/// A JSON run report (`rl run --json`) that failed on timing (`likely_cause`), lost device
/// replies, overran or missed deadlines while the loop or the device's fake measured itself
/// late (`lateness.culprit`): the reason. `None` for a run without such a shortfall, and for
/// one with a shortfall but nobody late (its checks fail it).
pub fn json_late(report: &Value) -> Option<String> {
    let count = |key: &str| report[key].as_u64().unwrap_or(0);
    let cause = report["likely_cause"].as_str();
    let (lost, overruns, missed) = (
        count("lost_packets"),
        count("overruns"),
        count("missed_deadlines"),
    );
    if cause.is_none() && lost == 0 && overruns == 0 && missed == 0 {
        return None;
    }
    let lateness = &report["lateness"];
    let culprit = lateness["culprit"].as_str().unwrap_or("nobody");
    matches!(culprit, "loop" | "peer" | "loop_and_peer").then(|| {
        format!(
            "{}; {lost} replies lost, {overruns} overruns, {missed} missed deadlines; {culprit} late: {lateness}",
            cause.unwrap_or("no failure")
        )
    })
}

/// A text run report (`rl run` without `--json`) that failed on timing while the loop or the
/// device's side was measured late: its `likely cause:` line. `None` when the report has no
/// such line, or when it names nobody late or only the delivery of the replies (the device or
/// the network: its checks fail it).
pub fn text_late(report: &str) -> Option<String> {
    let cause = report
        .lines()
        .find_map(|l| l.strip_prefix("likely cause: "))?;
    let blames_machine = !cause.starts_with("nobody measured was late")
        && !cause.starts_with("replies arrived late at the kernel");
    blames_machine.then(|| cause.to_owned())
}

/// A run report that failed on timing while somebody was measured late
/// (`RunReport::failed_from_lateness`): the reason.
pub fn failed_late(report: &RunReport) -> Option<String> {
    report
        .failed_from_lateness()
        .then(|| format!("{}\n{report}", report.likely_cause().unwrap_or_default()))
}

/// A run report whose loop overran or missed deadlines, or whose device lost replies (from a
/// fake in this process on loopback: its thread was not scheduled in time): the whole report.
/// For tests whose checks need every reply and every cycle on time.
pub fn any_shortfall(report: &RunReport) -> Option<String> {
    (report.stats.overruns > 0 || report.stats.missed_deadlines > 0 || report.lost_packets > 0)
        .then(|| format!("{report}"))
}
