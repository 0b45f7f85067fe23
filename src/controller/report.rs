//! The end-of-run report: loop timing, link health, tracking, feed-forward, supervision, how
//! the run ended and how the device was brought to a safe state, as text for a person and JSON
//! for a script. The loop statistics use rl-rt's one JSON schema ([`LoopStats::to_json`]),
//! shared with `rl jitter`.

use std::fmt::{self, Write as _};

use rl_drivers::LinkStatistics;
use rl_rt::LoopStats;
use serde_json::json;

use super::control::{FaultAt, RunEnd};
use super::input::InputReport;
use super::lateness::{self, HostActivity, Lateness, PeerLateness};
use super::supervise::Fault;
use super::tracking::Violation;

/// How the device was brought to a safe state after the loop.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shutdown {
    /// `stop()` succeeded.
    pub stopped: bool,
    /// What a clean stop means for this device (e.g. "end packet sent, program stopped, servo
    /// off").
    pub description: String,
    /// Why `stop()` or `close()` failed.
    pub error: Option<String>,
    /// The device's own fault before it was stopped, if it had one.
    pub fault_before_stop: Option<String>,
}

/// Everything a run reports.
#[derive(Clone, Debug)]
pub struct RunReport {
    /// Model name and source.
    pub model: String,
    /// Device description.
    pub device: String,
    /// Joint names.
    pub joints: Vec<String>,
    /// Control period, s.
    pub period_s: f64,
    /// The device's cycle, s.
    pub device_period_s: f64,
    /// Scheduling the loop got (e.g. `SCHED_FIFO priority 80 on CPUs [1]`).
    pub scheduling: String,
    /// What the real-time set-up could not get, each with its fix.
    pub warnings: Vec<String>,
    /// Whether memory was locked.
    pub memory_locked: bool,
    /// Planned trajectory duration, s.
    pub plan_duration_s: f64,
    /// Where the trajectory came from: `"tour"`, or the tag of a followed trajectory (e.g.
    /// `"plan"`).
    pub trajectory_source: String,
    /// The trajectory in one line.
    pub trajectory_description: String,
    /// Trajectory time reached, s.
    pub trajectory_time_s: f64,
    /// Wall time of the loop, s.
    pub wall_time_s: f64,
    /// How the run ended (`None`: the loop itself failed, see `failure`).
    pub end: Option<RunEnd>,
    /// When the first fault was found: its cycle and that cycle's time (the telemetry's
    /// `t_s`), which can be well before the run ended.
    pub fault_at: Option<FaultAt>,
    /// Loop timing: wake-up latency, step duration, overruns, missed deadlines.
    pub stats: LoopStats,
    /// The device link's counts (read after the device was closed: nothing is lost).
    pub link: LinkStatistics,
    /// Steps without a usable reply.
    pub lost_packets: u64,
    /// Largest tracking error per joint.
    pub tracking_max: Vec<f64>,
    /// RMS tracking error per joint.
    pub tracking_rms: Vec<f64>,
    /// Tracking error of the last cycle per joint.
    pub tracking_final: Vec<f64>,
    /// The supervisor's tracking bound per joint.
    pub tracking_bound: Vec<f64>,
    /// Largest feed-forward torque per joint.
    pub peak_feed_forward: Vec<f64>,
    /// Largest tracking error of any joint.
    pub tracking_error_max: f64,
    /// RMS tracking error over all joints and cycles.
    pub tracking_error_rms: f64,
    /// Limits crossed by the measured motion.
    pub limit_violations: u64,
    /// The first crossed limit.
    pub first_violation: Option<Violation>,
    /// Whether the supervisor acted on faults.
    pub supervised: bool,
    /// The speed assumed (rad/s or m/s) for joints whose model gives no speed limit, and those
    /// joints.
    pub assumed_speed: Option<(f64, Vec<String>)>,
    /// Cycles whose torque command was clamped to the model's effort limits (a law commanding
    /// torques).
    pub torque_clamped: u64,
    /// What became of the inputs sent to the law (`None` when none were sent and no input
    /// timeout was set).
    pub inputs: Option<InputReport>,
    /// What the law reported at the end ([`ControlLaw::summary`](super::ControlLaw::summary)),
    /// e.g. the targets a [`TargetFollower`](super::TargetFollower) followed.
    pub law: Option<serde_json::Value>,
    /// The law's headline results, merged into the top of the JSON report
    /// ([`LawSummary::headline`](super::LawSummary::headline)).
    pub law_headline: Option<serde_json::Value>,
    /// What the safety chain saw (`None`: the run had none).
    pub safety: Option<super::safety::SafetyReport>,
    /// How the device was stopped.
    pub shutdown: Shutdown,
    /// Telemetry rows written (by the caller).
    pub telemetry_rows: Option<u64>,
    /// Telemetry records dropped because the queue was full.
    pub telemetry_dropped: Option<u64>,
    /// Lines the caller adds (e.g. what a fake device saw).
    pub notes: Vec<String>,
    /// How late the device's side ran, as it measured itself (the caller adds it for an
    /// in-process fake; see [`RunReport::lateness`]).
    pub peer_lateness: Option<PeerLateness>,
    /// Where the run's time went besides its own work: the loop's wait for its CPU, the host's
    /// steal and interrupts, other programs at real-time priority.
    pub host: HostActivity,
    /// Why the run failed, if it did (fault, loop error, stop failed).
    pub failure: Option<String>,
}

fn us(ns: u64) -> f64 {
    ns as f64 / 1e3
}

impl RunReport {
    /// A report for a run whose loop did not come back (the thread panicked).
    pub fn failed_early(model: String, device: String, joints: Vec<String>, why: &str) -> Self {
        let n = joints.len();
        Self {
            model,
            device,
            joints,
            period_s: 0.0,
            device_period_s: 0.0,
            scheduling: String::new(),
            warnings: Vec::new(),
            memory_locked: false,
            plan_duration_s: 0.0,
            trajectory_source: String::new(),
            trajectory_description: String::new(),
            trajectory_time_s: 0.0,
            wall_time_s: 0.0,
            end: None,
            fault_at: None,
            stats: LoopStats::new(1, 1),
            link: LinkStatistics::default(),
            lost_packets: 0,
            tracking_max: vec![0.0; n],
            tracking_rms: vec![0.0; n],
            tracking_final: vec![0.0; n],
            tracking_bound: vec![0.0; n],
            peak_feed_forward: vec![0.0; n],
            tracking_error_max: 0.0,
            tracking_error_rms: 0.0,
            limit_violations: 0,
            first_violation: None,
            supervised: true,
            assumed_speed: None,
            torque_clamped: 0,
            inputs: None,
            law: None,
            law_headline: None,
            safety: None,
            shutdown: Shutdown::default(),
            telemetry_rows: None,
            telemetry_dropped: None,
            notes: Vec::new(),
            peer_lateness: None,
            host: HostActivity::default(),
            failure: Some(why.to_owned()),
        }
    }

    /// Marks the run failed for `why` (the first reason is kept).
    pub fn fail(&mut self, why: impl Into<String>) {
        if self.failure.is_none() {
            self.failure = Some(why.into());
        }
    }

    /// Who was late in this run: the loop, the device's side, the delivery of the replies.
    pub fn lateness(&self) -> Lateness {
        Lateness::new(
            &self.stats,
            self.link.delivery,
            self.peer_lateness.clone(),
            self.host.clone(),
        )
    }

    /// For a run that failed on timing (replies lost, deadlines missed, overruns), the likely
    /// cause in one sentence: who was late.
    pub fn likely_cause(&self) -> Option<String> {
        (self.failure.is_some() && lateness::is_timing_failure(self.end))
            .then(|| self.lateness().likely_cause())
    }

    /// Whether the run failed on timing (replies lost, deadlines missed, cycles overrun, the
    /// link timed out) while somebody was measured late — the loop, the device's side, or the
    /// delivery of its replies: the machine's doing rather than the device's or the code's.
    /// (Tests run such a run again; a timing failure with nobody late stays a failure.)
    pub fn failed_from_lateness(&self) -> bool {
        self.likely_cause().is_some() && self.lateness().culprit() != lateness::Culprit::Nobody
    }

    /// The process exit code: 1 failed, 130 interrupted by a stop request, 0 done.
    pub fn exit_code(&self) -> i32 {
        if self.failure.is_some() {
            1
        } else if self.end.is_some_and(|e| e.is_interrupted()) {
            130
        } else {
            0
        }
    }

    /// The report as JSON: `result` (`ok` or `failed`), `reflexes` (motions the device
    /// stopped on its own — a Franka reflex, a drive's fault: a run ends at the first, so 0 or
    /// 1), `cycles`, `overruns`, `lost_packets`, `latency_us` {min, mean, p99,
    /// p999, max}, `tracking_error_rad` {max, rms, per joint, bound per joint}, `loop` (rl-rt's
    /// loop statistics schema), `link` (the device's counts), `fault`, the law's headline keys
    /// ([`LawSummary::headline`](super::LawSummary::headline)), and the rest.
    pub fn to_json(&self) -> serde_json::Value {
        let w = self.stats.wakeup.summary();
        let s = self.stats.step.summary();
        let loop_stats: serde_json::Value =
            serde_json::from_str(&self.stats.to_json()).unwrap_or(serde_json::Value::Null);
        let fault = match self.end {
            Some(RunEnd::Fault(f)) => Some(f),
            _ => None,
        };
        let mut report = json!({
            "result": if self.failure.is_some() { "failed" } else { "ok" },
            "reflexes": u32::from(matches!(fault, Some(Fault::Device { .. }))),
            "cycles": self.stats.cycles(),
            "overruns": self.stats.overruns,
            "missed_deadlines": self.stats.missed_deadlines,
            "lost_packets": self.lost_packets,
            "late_packets": self.link.late,
            "rejected_packets": self.link.rejected,
            "corrupt_packets": self.link.corrupt,
            "packets_sent": self.link.sent,
            "replies": self.link.received,
            "link": {
                "sent": self.link.sent, "received": self.link.received, "lost": self.link.lost,
                "late": self.link.late, "rejected": self.link.rejected,
                "corrupt": self.link.corrupt, "loss_rate": self.link.loss_rate(),
            },
            "loop": loop_stats,
            "lateness": self.lateness().to_json(),
            "likely_cause": self.likely_cause(),
            "latency_us": {
                "min": us(w.min_ns), "mean": us(w.mean_ns), "p50": us(w.p50_ns),
                "p99": us(w.p99_ns), "p999": us(w.p999_ns), "max": us(w.max_ns),
                "overflow": w.overflow,
            },
            "step_us": {
                "min": us(s.min_ns), "mean": us(s.mean_ns), "p99": us(s.p99_ns),
                "p999": us(s.p999_ns), "max": us(s.max_ns),
            },
            "tracking_error_rad": {
                "max": self.tracking_error_max,
                "rms": self.tracking_error_rms,
                "max_per_joint": self.tracking_max,
                "rms_per_joint": self.tracking_rms,
                "final_per_joint": self.tracking_final,
                "bound_per_joint": self.tracking_bound,
            },
            "peak_feed_forward_torque": self.peak_feed_forward,
            "limit_violations": self.limit_violations,
            "torque_clamped": self.torque_clamped,
            "inputs": self.inputs.as_ref().map(|i| json!({
                "sent": i.sent,
                "targets": i.targets,
                "others": i.others,
                "refused_invalid": i.refused_invalid,
                "first_invalid": i.first_invalid,
                "refused_by_law": i.refused_by_law,
                "first_law_refusal": i.first_law_refusal,
                "dropped_full": i.dropped_full,
                "not_taken": i.not_taken,
                "timeout_s": i.timeout_s,
                "max_age_s": i.max_age_s,
                "stale": i.stale,
                "stale_age_s": i.stale_age_s,
            })),
            "law": self.law,
            "safety": self.safety.map(|s| s.to_json()),
            "supervised": self.supervised,
            "fault": fault.map(|f| f.describe(&self.joints)),
            "fault_cycle": self.fault_at.map(|a| a.cycle),
            "fault_time_s": self.fault_at.map(|a| a.time_s),
            "fault_joint": fault.and_then(|f| f.joint()).and_then(|k| self.joints.get(k)),
            "stopped_at_once": fault.map(|f| f.stops_at_once()),
            "assumed_speed": self.assumed_speed.as_ref().map(|(v, joints)| json!({
                "speed": v, "joints": joints,
            })),
            "joints": self.joints,
            "model": self.model,
            "device": self.device,
            "period_s": self.period_s,
            "device_period_s": self.device_period_s,
            "scheduling": self.scheduling,
            "warnings": self.warnings,
            "memory_locked": self.memory_locked,
            "plan_duration_s": self.plan_duration_s,
            "trajectory_source": self.trajectory_source,
            "trajectory": self.trajectory_description,
            "trajectory_time_s": self.trajectory_time_s,
            "wall_time_s": self.wall_time_s,
            "end": self.end.map(|e| e.describe(&self.joints)),
            "interrupted": self.end.is_some_and(|e| e.is_interrupted()),
            "device_stopped": self.shutdown.stopped,
            "device_stop": self.shutdown.description,
            "device_stop_error": self.shutdown.error,
            "device_fault": self.shutdown.fault_before_stop,
            "telemetry_rows": self.telemetry_rows,
            "telemetry_dropped": self.telemetry_dropped,
            "notes": self.notes,
            "failed": self.failure.is_some(),
            "failure": self.failure,
        });
        if let (Some(serde_json::Value::Object(extra)), Some(top)) =
            (&self.law_headline, report.as_object_mut())
        {
            for (k, v) in extra {
                top.entry(k.clone()).or_insert_with(|| v.clone());
            }
        }
        report
    }
}

/// The joint table's column widths: each joint's name whole, and at least 9 characters.
fn column_widths(joints: &[String]) -> Vec<usize> {
    joints.iter().map(|j| j.chars().count().max(9)).collect()
}

fn row(
    out: &mut String,
    label: &str,
    widths: &[usize],
    values: &[f64],
    scale: f64,
    precision: usize,
) {
    let _ = write!(out, "  {label:<24}");
    for (v, w) in values.iter().zip(widths) {
        let _ = write!(out, " {:>w$.*}", precision, v * scale);
    }
    out.push('\n');
}

impl fmt::Display for RunReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let w = self.stats.wakeup.summary();
        let s = self.stats.step.summary();
        let mut out = String::new();
        let _ = writeln!(
            out,
            "rl run: {} on {}, {} joints, period {:.2} ms, {}, mlockall {}",
            self.model,
            self.device,
            self.joints.len(),
            self.period_s * 1e3,
            self.scheduling,
            if self.memory_locked { "yes" } else { "no" }
        );
        for warning in &self.warnings {
            let _ = writeln!(out, "warning: {warning}");
        }
        if let Some((v, joints)) = &self.assumed_speed {
            let _ = writeln!(
                out,
                "note: the model gives no speed limit for {}; assumed {v} rad/s (or m/s)",
                joints.join(", ")
            );
        }
        if !self.trajectory_description.is_empty() {
            let _ = writeln!(
                out,
                "trajectory ({}): {}",
                self.trajectory_source, self.trajectory_description
            );
        }
        let ended = self.end.map_or_else(
            || "loop failed".to_owned(),
            |e| match e {
                RunEnd::Fault(fault) => format!(
                    "fault ({}): {}",
                    if fault.stops_at_once() {
                        "stopped at once"
                    } else {
                        "brought to rest"
                    },
                    fault.describe(&self.joints)
                ),
                e => e.to_string(),
            },
        );
        let _ = if self.plan_duration_s > 0.0 {
            writeln!(
                out,
                "end: {ended} after {:.2} s of a {:.2} s trajectory",
                self.trajectory_time_s, self.plan_duration_s
            )
        } else {
            writeln!(out, "end: {ended} after {:.2} s", self.trajectory_time_s)
        };
        if let Some(at) = self.fault_at {
            let _ = writeln!(
                out,
                "fault found at cycle {}, t = {:.3} s (the run ended at {:.3} s)",
                at.cycle, at.time_s, self.trajectory_time_s
            );
        }
        let _ = writeln!(
            out,
            "cycles {}  overruns {}  missed deadlines {}  lost packets {}  late {}  rejected {}  \
             corrupt {}",
            self.stats.cycles(),
            self.stats.overruns,
            self.stats.missed_deadlines,
            self.lost_packets,
            self.link.late,
            self.link.rejected,
            self.link.corrupt
        );
        let _ = writeln!(
            out,
            "wake-up latency µs: min {:.1}  mean {:.1}  p99 {:.1}  p99.9 {:.1}  max {:.1}",
            us(w.min_ns),
            us(w.mean_ns),
            us(w.p99_ns),
            us(w.p999_ns),
            us(w.max_ns)
        );
        let _ = writeln!(
            out,
            "step duration µs:   min {:.1}  mean {:.1}  p99 {:.1}  p99.9 {:.1}  max {:.1}",
            us(s.min_ns),
            us(s.mean_ns),
            us(s.p99_ns),
            us(s.p999_ns),
            us(s.max_ns)
        );
        let _ = writeln!(out, "{}", self.lateness().summary());
        let widths = column_widths(&self.joints);
        let _ = write!(out, "  {:<24}", "joint");
        for (j, w) in self.joints.iter().zip(&widths) {
            let _ = write!(out, " {j:>w$}");
        }
        out.push('\n');
        row(
            &mut out,
            "tracking error max mrad",
            &widths,
            &self.tracking_max,
            1e3,
            3,
        );
        row(
            &mut out,
            "tracking error rms mrad",
            &widths,
            &self.tracking_rms,
            1e3,
            3,
        );
        row(
            &mut out,
            "tracking bound mrad",
            &widths,
            &self.tracking_bound,
            1e3,
            1,
        );
        row(
            &mut out,
            "peak feed-forward N·m",
            &widths,
            &self.peak_feed_forward,
            1.0,
            2,
        );
        let _ = writeln!(
            out,
            "tracking error{}: max {:.3} mrad, rms {:.3} mrad; limit violations {}{}",
            if matches!(self.end, Some(RunEnd::Fault(_))) {
                " up to the fault"
            } else {
                ""
            },
            self.tracking_error_max * 1e3,
            self.tracking_error_rms * 1e3,
            self.limit_violations,
            if self.supervised {
                ""
            } else {
                "; supervision OFF"
            }
        );
        if self.torque_clamped > 0 {
            let _ = writeln!(
                out,
                "torque commands clamped to the effort limits in {} cycles",
                self.torque_clamped
            );
        }
        if let Some(i) = &self.inputs {
            let _ = writeln!(
                out,
                "inputs: {} sent, {} targets and {} others taken, refused {} invalid and {} by \
                 the law, {} dropped (queue full), longest gap {:.3} s{}",
                i.sent,
                i.targets,
                i.others,
                i.refused_invalid,
                i.refused_by_law,
                i.dropped_full,
                i.max_age_s,
                match (i.timeout_s, i.stale_age_s) {
                    (Some(t), Some(age)) => {
                        format!("; stale at {age:.3} s without one (timeout {t:.3} s)")
                    }
                    (Some(t), None) => format!(" (timeout {t:.3} s)"),
                    _ => String::new(),
                }
            );
            if let Some(why) = &i.first_invalid {
                let _ = writeln!(out, "first invalid input: {why}");
            }
            if let Some(why) = i.first_law_refusal {
                let _ = writeln!(out, "first input the law refused: {why}");
            }
        }
        if let Some(v) = self.first_violation {
            let _ = writeln!(
                out,
                "first violation: cycle {}, joint {}, {} {:.5} beyond limit {:.5}",
                v.cycle,
                self.joints.get(v.joint).map_or("?", String::as_str),
                v.quantity,
                v.value,
                v.limit
            );
        }
        let sd = &self.shutdown;
        let _ = write!(
            out,
            "device: {}",
            if sd.stopped {
                "stopped cleanly"
            } else {
                "NOT stopped cleanly"
            }
        );
        if sd.stopped && !sd.description.is_empty() {
            let _ = write!(out, " ({})", sd.description);
        }
        if let Some(e) = &sd.error {
            let _ = write!(out, " ({e})");
        }
        if let Some(fault) = &sd.fault_before_stop {
            let _ = write!(out, "; it had faulted: {fault}");
        }
        out.push('\n');
        if let Some(safety) = &self.safety {
            let _ = writeln!(out, "{}", safety.line());
        }
        for note in &self.notes {
            let _ = writeln!(out, "{note}");
        }
        if let Some(rows) = self.telemetry_rows {
            let _ = writeln!(
                out,
                "telemetry: {rows} rows written, {} dropped",
                self.telemetry_dropped.unwrap_or(0)
            );
        }
        match &self.failure {
            Some(why) => {
                if let Some(cause) = self.likely_cause() {
                    let _ = writeln!(out, "likely cause: {cause}");
                }
                let _ = writeln!(out, "result: FAILED: {why}");
            }
            None => {
                let _ = writeln!(out, "result: ok");
            }
        }
        f.write_str(&out)
    }
}

#[cfg(test)]
mod tests {
    use super::RunReport;

    /// The joint table shows every name whole (a UR's and a Panda's were cut to nine
    /// characters: `shoulder_ shoulder_`, `panda_joi` ×7), its rows lined up under them.
    #[test]
    fn the_joint_table_never_cuts_a_name() {
        let joints: Vec<String> = ["shoulder_pan_joint", "shoulder_lift_joint", "j3"]
            .map(String::from)
            .to_vec();
        let mut report = RunReport::failed_early("ur".into(), "d".into(), joints.clone(), "x");
        report.tracking_bound = vec![0.1, 0.25, 1.5];
        let text = report.to_string();
        let header = text
            .lines()
            .find(|l| l.trim_start().starts_with("joint "))
            .expect("header");
        for j in &joints {
            assert!(header.contains(&format!(" {j}")), "{header}");
        }
        // Every row ends where the header ends, and each value ends under its name.
        for label in ["tracking error max mrad", "tracking bound mrad"] {
            let row = text
                .lines()
                .find(|l| l.trim_start().starts_with(label))
                .expect(label);
            assert_eq!(
                row.chars().count(),
                header.chars().count(),
                "{row}\n{header}"
            );
        }
        let bound = text
            .lines()
            .find(|l| l.trim_start().starts_with("tracking bound mrad"))
            .expect("bound row");
        let end_of = |line: &str, needle: &str| line.find(needle).expect(needle) + needle.len();
        assert_eq!(end_of(bound, "100.0"), end_of(header, "shoulder_pan_joint"));
        assert_eq!(
            end_of(bound, "250.0"),
            end_of(header, "shoulder_lift_joint")
        );
    }
}
