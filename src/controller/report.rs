//! The end-of-run report: loop timing, link health, tracking, feed-forward, and how the run
//! ended, as text for a person and JSON for a script.

use std::fmt::{self, Write as _};

use rl_rt::LoopStats;
use serde_json::json;

use rl_drivers::LinkStatistics;

use super::control::RunEnd;
use super::tracking::Tracking;

/// How the device was shut down.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shutdown {
    /// `stop()` succeeded (for the H7: end packet sent, program stopped, servo off).
    pub stopped: bool,
    /// What a clean stop meant for this device (shown in the report).
    pub detail: String,
    /// Why `stop()` or `close()` failed.
    pub error: Option<String>,
    /// What the in-process fake controller saw, if there is one: end packets received.
    pub fake_end_packets: Option<u64>,
    /// The fake's servo state after the stop.
    pub fake_servo_on: Option<bool>,
    /// Joint commands the fake had to clamp to its limits.
    pub fake_limit_hits: Option<u64>,
}

/// Everything `rl run` reports.
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
    /// Scheduling the loop got (e.g. `SCHED_FIFO 80 on CPUs [1]`).
    pub scheduling: String,
    /// Whether memory was locked.
    pub memory_locked: bool,
    /// Planned trajectory duration, s.
    pub plan_duration_s: f64,
    /// Trajectory time reached, s.
    pub trajectory_time_s: f64,
    /// How the run ended (`None`: the loop itself failed, see `failure`).
    pub end: Option<RunEnd>,
    /// Loop timing: wake-up latency, step duration, overruns, missed deadlines.
    pub stats: LoopStats,
    /// Packet counts of the link.
    pub link: LinkStatistics,
    /// Steps without a usable reply.
    pub lost_packets: u64,
    /// Tracking and feed-forward statistics.
    pub tracking: Tracking,
    /// Device shutdown.
    pub shutdown: Shutdown,
    /// Telemetry rows written and records dropped (queue full), if telemetry was on.
    pub telemetry: Option<(u64, u64)>,
    /// Why the run failed, if it did (device fault, limits crossed, loop error, stop failed).
    pub failure: Option<String>,
}

fn us(ns: u64) -> f64 {
    ns as f64 / 1e3
}

impl RunReport {
    /// The report as JSON: `cycles`, `overruns`, `lost_packets`, `latency_us` {min, mean, p99,
    /// p999, max}, `tracking_error_rad` {max, rms, per joint}, and the rest.
    pub fn to_json(&self) -> serde_json::Value {
        let w = self.stats.wakeup.summary();
        let s = self.stats.step.summary();
        let rms = self.tracking.rms_per_joint();
        json!({
            "cycles": self.stats.cycles(),
            "overruns": self.stats.overruns,
            "missed_deadlines": self.stats.missed_deadlines,
            "lost_packets": self.lost_packets,
            "late_packets": self.link.late,
            "rejected_packets": self.link.rejected,
            "packets_sent": self.link.sent,
            "replies": self.link.received,
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
                "max": self.tracking.max_error(),
                "rms": self.tracking.rms_error(),
                "max_per_joint": self.tracking.max_per_joint(),
                "rms_per_joint": &rms[..self.tracking.dof()],
                "final_per_joint": self.tracking.last_error(),
            },
            "peak_feed_forward_torque": self.tracking.peak_feed_forward(),
            "limit_violations": self.tracking.violations(),
            "joints": self.joints,
            "model": self.model,
            "device": self.device,
            "period_s": self.period_s,
            "scheduling": self.scheduling,
            "memory_locked": self.memory_locked,
            "plan_duration_s": self.plan_duration_s,
            "trajectory_time_s": self.trajectory_time_s,
            "end": self.end.map(|e| e.to_string()),
            "interrupted": matches!(self.end, Some(RunEnd::Stopped | RunEnd::Aborted)),
            "device_stopped": self.shutdown.stopped,
            "fake_end_packets": self.shutdown.fake_end_packets,
            "fake_servo_on": self.shutdown.fake_servo_on,
            "fake_limit_hits": self.shutdown.fake_limit_hits,
            "telemetry_rows": self.telemetry.map(|t| t.0),
            "telemetry_dropped": self.telemetry.map(|t| t.1),
            "failed": self.failure.is_some(),
            "failure": self.failure,
        })
    }
}

fn row(out: &mut String, label: &str, values: &[f64], scale: f64, precision: usize) {
    let _ = write!(out, "  {label:<24}");
    for v in values {
        let _ = write!(out, " {:>9.*}", precision, v * scale);
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
        let _ = writeln!(
            out,
            "end: {} after {:.2} s of a {:.2} s trajectory",
            self.end
                .map_or_else(|| "loop failed".to_owned(), |e| e.to_string()),
            self.trajectory_time_s,
            self.plan_duration_s
        );
        let _ = writeln!(
            out,
            "cycles {}  overruns {}  missed deadlines {}  lost packets {}  late {}  rejected {}",
            self.stats.cycles(),
            self.stats.overruns,
            self.stats.missed_deadlines,
            self.lost_packets,
            self.link.late,
            self.link.rejected
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
        let _ = write!(out, "  {:<24}", "joint");
        for j in &self.joints {
            let _ = write!(out, " {:>9}", truncate(j, 9));
        }
        out.push('\n');
        let t = &self.tracking;
        row(
            &mut out,
            "tracking error max mrad",
            t.max_per_joint(),
            1e3,
            3,
        );
        row(
            &mut out,
            "tracking error rms mrad",
            &t.rms_per_joint()[..t.dof()],
            1e3,
            3,
        );
        row(
            &mut out,
            "peak feed-forward N·m",
            t.peak_feed_forward(),
            1.0,
            2,
        );
        let _ = writeln!(
            out,
            "tracking error: max {:.3} mrad, rms {:.3} mrad; limit violations {}",
            t.max_error() * 1e3,
            t.rms_error() * 1e3,
            t.violations()
        );
        if let Some(v) = t.first_violation() {
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
        if sd.stopped && !sd.detail.is_empty() {
            let _ = write!(out, " ({})", sd.detail);
        }
        if let Some(e) = &sd.error {
            let _ = write!(out, " ({e})");
        }
        if let Some(n) = sd.fake_end_packets {
            let _ = write!(
                out,
                "; fake H7 saw {n} end packet{}, servo {}, {} limit hits",
                if n == 1 { "" } else { "s" },
                if sd.fake_servo_on == Some(true) {
                    "on"
                } else {
                    "off"
                },
                sd.fake_limit_hits.unwrap_or(0)
            );
        }
        out.push('\n');
        if let Some((rows, dropped)) = self.telemetry {
            let _ = writeln!(out, "telemetry: {rows} rows written, {dropped} dropped");
        }
        match &self.failure {
            Some(why) => {
                let _ = writeln!(out, "result: FAILED: {why}");
            }
            None => {
                let _ = writeln!(out, "result: ok");
            }
        }
        f.write_str(&out)
    }
}

fn truncate(s: &str, n: usize) -> &str {
    match s.char_indices().nth(n) {
        Some((i, _)) => &s[..i],
        None => s,
    }
}
