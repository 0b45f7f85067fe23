//! Who was late: the loop, the device (an in-process fake measures its own cycle), or the
//! delivery of the replies. A run that loses replies or misses deadlines on a loaded machine
//! looks like a broken link; the report says which party the time went to, from what each one
//! measured:
//!
//! - **the loop**: how late its thread woke after each deadline (rl-rt's wake-up latency), and
//!   how long the replies it waited for sat in the socket before it read them (the kernel's
//!   receive timestamps: the thread woke late from its wait);
//! - **the device**: an in-process fake's own lateness against its cycle ([`PeerLateness`]); a
//!   real controller has its own CPU and does not report one;
//! - **the delivery**: replies that reached this machine's kernel only after their step's
//!   deadline (found later, with their kernel timestamps).
//!
//! A party counts as late when its worst lateness passed [`LATE_FRACTION`] of its cycle.
//!
//! Where the time of a late party went ([`HostActivity`]): the loop's thread measures how long
//! it waited on its CPU's run queue during the run (schedstat). A wake-up later than that wait
//! was not held up by another thread — the timer's interrupt came late: the host (a
//! hypervisor's steal, the kernel with interrupts off) held the CPU. A wait as long as the
//! lateness was another thread's doing: the other programs' real-time threads are listed. The
//! host's steal and interrupt times over the run back the sentence up.
//!
//! All of this is read after the run; nothing here runs in the loop.

use std::fmt::Write as _;
use std::time::Duration;

use rl_drivers::{Delivery, DeviceError, ErrorKind};
use rl_rt::preflight::rt_threads::RtThread;
use rl_rt::{HostTimes, LoopStats};
use serde_json::json;

use super::control::RunEnd;
use super::supervise::Fault;

/// The share of its cycle a party's worst lateness must pass to count as late (a quarter: a
/// reply or a wake-up that late eats the margin the step's deadline leaves).
pub const LATE_FRACTION: f64 = 0.25;

/// How late the device's side of the link ran, as it measured itself (an in-process fake).
#[derive(Clone, Debug, PartialEq)]
pub struct PeerLateness {
    /// Who it is, for a sentence (e.g. "the fake H7").
    pub who: String,
    /// Its cycle (`None`: it has none of its own; compared with the loop's period).
    pub cycle: Option<Duration>,
    /// Its worst lateness: how long after it meant to its thread came to run.
    pub max: Duration,
    /// Its cycles that came late (`None`: not counted).
    pub late: Option<u64>,
    /// Its cycles in all (`None`: not counted).
    pub cycles: Option<u64>,
}

/// Where the run's time went besides its own work: what the loop's thread waited for its CPU,
/// what the host took, and the other programs at real-time priority.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HostActivity {
    /// How long the loop's thread waited on its run queue, in all, during the loop (`None`:
    /// the kernel has no schedstat).
    pub loop_run_delay: Option<Duration>,
    /// Steal and interrupt time the host took over the run, summed over the CPUs (`None`:
    /// no `/proc/stat`).
    pub host: Option<HostTimes>,
    /// Other programs' threads at real-time priority during the run (kernel threads left out).
    pub other_rt: Vec<OtherRtThread>,
}

/// Another program's thread at real-time priority.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OtherRtThread {
    /// Its process id.
    pub pid: u32,
    /// Its name.
    pub name: String,
    /// Its policy and priority, as `chrt` says it (e.g. `SCHED_FIFO 80`).
    pub scheduling: String,
}

impl HostActivity {
    /// The other programs' (not the kernel's) threads in `threads`, once per thread.
    pub fn other_programs(threads: &[RtThread]) -> Vec<OtherRtThread> {
        let mut out: Vec<OtherRtThread> = Vec::new();
        let mut seen = std::collections::BTreeSet::new();
        for t in threads.iter().filter(|t| !t.kernel) {
            if seen.insert(t.tid) {
                out.push(OtherRtThread {
                    pid: t.pid,
                    name: t.comm.clone(),
                    scheduling: format!("{} {}", t.policy.name(), t.priority),
                });
            }
        }
        out
    }

    /// A few of the other real-time threads, for a sentence: `name (pid, SCHED_FIFO 80), …`.
    fn list(&self) -> String {
        const SHOWN: usize = 4;
        let mut s = self
            .other_rt
            .iter()
            .take(SHOWN)
            .map(|t| format!("{} (pid {}, {})", t.name, t.pid, t.scheduling))
            .collect::<Vec<_>>()
            .join(", ");
        if self.other_rt.len() > SHOWN {
            let _ = write!(s, " and {} more", self.other_rt.len() - SHOWN);
        }
        s
    }

    /// The host's steal and interrupt time, for a sentence.
    fn host_times(&self) -> String {
        match &self.host {
            Some(h) => format!(
                "the host took {:.0} ms of steal, {:.0} ms of interrupts during the run",
                ms(h.steal),
                ms(h.irq + h.softirq)
            ),
            None => "no host times".to_owned(),
        }
    }

    /// Why a thread that woke up to `late` behind its deadline was late: it waited for its CPU
    /// (another thread's doing), or it was held up while not waiting for one (the host's).
    fn why_late(&self, late: Duration) -> String {
        let others = if self.other_rt.is_empty() {
            "no other program runs at real-time priority".to_owned()
        } else {
            format!(
                "other programs' real-time threads: {} — see `rl preflight`",
                self.list()
            )
        };
        match self.loop_run_delay {
            Some(waited) if waited < late => format!(
                "the loop's thread waited only {:.2} ms in all for its CPU, so nothing on this \
                 machine ran in its place: the host held the CPU (a hypervisor running other \
                 work, or the kernel with interrupts off; {}); {others}",
                ms(waited),
                self.host_times()
            ),
            Some(waited) => format!(
                "the loop's thread waited {:.2} ms in all for its CPU, enough to explain it: \
                 something else held its CPU — a thread at its priority or above, or the kernel \
                 working for another task where it does not preempt (without PREEMPT_RT: see \
                 `rl preflight`); {others}",
                ms(waited)
            ),
            None if self.other_rt.is_empty() => format!(
                "{others}: the host or the kernel held the CPUs up ({})",
                self.host_times()
            ),
            None => format!("other real-time work took the CPUs ({others})"),
        }
    }
}

/// Who was late in a run: what the loop, the device's side and the delivery measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Lateness {
    /// The loop's period.
    pub period: Duration,
    /// The loop's worst wake-up lateness.
    pub loop_wakeup_max: Duration,
    /// How far the loop's longest step ran past its period (zero when every step fit): a
    /// thread held up inside its step passes its next deadlines without waking late for them.
    pub loop_step_overrun_max: Duration,
    /// Deadlines the loop passed over without a cycle.
    pub missed_deadlines: u64,
    /// When the replies reached the kernel (empty without receive timestamps).
    pub delivery: Delivery,
    /// The device's side, where it measures itself.
    pub peer: Option<PeerLateness>,
    /// Where the time went besides the run's own work.
    pub host: HostActivity,
}

/// The party a likely cause names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Culprit {
    /// The loop's thread woke late (or read its replies late).
    Loop,
    /// The device's side (an in-process fake) ran late against its own cycle.
    Peer,
    /// Both the loop and the device's side ran late (other real-time work held both up).
    LoopAndPeer,
    /// Replies reached this machine late while neither side measured itself late.
    Delivery,
    /// Nobody measured was late.
    Nobody,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

impl Lateness {
    /// What a run's loop statistics, link and device's side measured.
    pub fn new(
        stats: &LoopStats,
        delivery: Delivery,
        peer: Option<PeerLateness>,
        host: HostActivity,
    ) -> Self {
        Self {
            period: Duration::from_nanos(stats.period_ns),
            loop_wakeup_max: Duration::from_nanos(stats.wakeup.summary().max_ns),
            loop_step_overrun_max: Duration::from_nanos(
                stats.step.summary().max_ns.saturating_sub(stats.period_ns),
            ),
            missed_deadlines: stats.missed_deadlines,
            delivery,
            peer,
            host,
        }
    }

    /// The loop's worst lateness: a late wake-up, a step that ran past its period, or a reply
    /// it read late.
    fn loop_max(&self) -> Duration {
        self.loop_wakeup_max
            .max(self.loop_step_overrun_max)
            .max(self.delivery.max_wait)
    }

    /// `late` as a share of `cycle` (0 for a zero cycle).
    fn share(late: Duration, cycle: Duration) -> f64 {
        if cycle.is_zero() {
            0.0
        } else {
            late.as_secs_f64() / cycle.as_secs_f64()
        }
    }

    fn peer_share(&self) -> f64 {
        self.peer
            .as_ref()
            .map_or(0.0, |p| Self::share(p.max, p.cycle.unwrap_or(self.period)))
    }

    /// Who was late: the loop, the device's side or both, where their worst lateness passed
    /// [`LATE_FRACTION`] of their cycles; else the delivery where a reply reached the kernel
    /// after its deadline; else [`Culprit::Nobody`].
    pub fn culprit(&self) -> Culprit {
        let looped = Self::share(self.loop_max(), self.period);
        let peer = self.peer_share();
        if looped >= LATE_FRACTION && peer >= LATE_FRACTION {
            Culprit::LoopAndPeer
        } else if peer >= LATE_FRACTION {
            Culprit::Peer
        } else if looped >= LATE_FRACTION {
            Culprit::Loop
        } else if self.delivery.after_deadline > 0 {
            Culprit::Delivery
        } else {
            Culprit::Nobody
        }
    }

    /// One line for every run: how late each party was at worst.
    pub fn summary(&self) -> String {
        let mut out = format!(
            "lateness: loop woke up to {:.2} ms late against its {:.2} ms period",
            ms(self.loop_wakeup_max),
            ms(self.period)
        );
        if !self.loop_step_overrun_max.is_zero() {
            let _ = write!(
                out,
                ", ran a step {:.2} ms past it",
                ms(self.loop_step_overrun_max)
            );
        }
        if let Some(waited) = self.host.loop_run_delay {
            let _ = write!(
                out,
                " (its thread waited {:.2} ms in all for its CPU)",
                ms(waited)
            );
        }
        if self.delivery.timestamped > 0 {
            let _ = write!(
                out,
                ", read replies up to {:.2} ms (mean {:.3} ms) after the kernel received them",
                ms(self.delivery.max_wait),
                ms(self.delivery.mean_wait())
            );
        }
        if let Some(p) = &self.peer {
            let _ = write!(out, "; {} up to {:.2} ms late", p.who, ms(p.max));
            if let Some(c) = p.cycle {
                let _ = write!(out, " against its {:.2} ms cycle", ms(c));
            }
            if let (Some(late), Some(cycles)) = (p.late, p.cycles) {
                let _ = write!(out, " ({late} of {cycles} cycles late)");
            }
        }
        if self.delivery.after_deadline > 0 {
            let _ = write!(
                out,
                "; {} repl{} reached this machine after the step's deadline, up to {:.2} ms",
                self.delivery.after_deadline,
                if self.delivery.after_deadline == 1 {
                    "y"
                } else {
                    "ies"
                },
                ms(self.delivery.max_after_deadline)
            );
        }
        out
    }

    /// The likely cause of a run that failed on timing, in one sentence: who was late, and
    /// what to look at.
    pub fn likely_cause(&self) -> String {
        match self.culprit() {
            Culprit::Peer => {
                let p = self.peer.as_ref();
                let who = p.map_or("the device", |p| p.who.as_str());
                let cycle = p.and_then(|p| p.cycle).unwrap_or(self.period);
                let why = if self.host.other_rt.is_empty() {
                    format!(
                        "no other program runs at real-time priority, so the host, the kernel or \
                         — where it could not run at real-time priority — ordinary load held its \
                         thread up ({})",
                        self.host.host_times()
                    )
                } else {
                    format!(
                        "other real-time work on this machine starved it: {} — see `rl preflight`",
                        self.host.list()
                    )
                };
                format!(
                    "{who} ran up to {:.2} ms late against its {:.2} ms cycle (the loop was at most \
                     {:.2} ms late): {why}",
                    ms(p.map_or(Duration::ZERO, |p| p.max)),
                    ms(cycle),
                    ms(self.loop_max())
                )
            }
            Culprit::Loop => {
                let mut s = format!(
                    "the loop woke up to {:.2} ms late against its {:.2} ms period",
                    ms(self.loop_wakeup_max),
                    ms(self.period)
                );
                if self.loop_step_overrun_max > self.loop_wakeup_max {
                    let _ = write!(
                        s,
                        " and ran a step {:.2} ms past its period",
                        ms(self.loop_step_overrun_max)
                    );
                }
                if self.delivery.max_wait > self.loop_wakeup_max {
                    let _ = write!(
                        s,
                        " and read replies up to {:.2} ms after they had arrived",
                        ms(self.delivery.max_wait)
                    );
                }
                if let Some(p) = &self.peer {
                    let _ = write!(s, " ({} was at most {:.2} ms late)", p.who, ms(p.max));
                }
                let _ = write!(s, ": {}", self.host.why_late(self.loop_max()));
                s
            }
            Culprit::LoopAndPeer => {
                let p = self.peer.as_ref();
                format!(
                    "both the loop (up to {:.2} ms late against its {:.2} ms period) and {} \
                     (up to {:.2} ms late against its {:.2} ms cycle) were held up: {}",
                    ms(self.loop_max()),
                    ms(self.period),
                    p.map_or("the device", |p| p.who.as_str()),
                    ms(p.map_or(Duration::ZERO, |p| p.max)),
                    ms(p.and_then(|p| p.cycle).unwrap_or(self.period)),
                    self.host.why_late(self.loop_max())
                )
            }
            Culprit::Delivery => format!(
                "replies arrived late at the kernel (up to {:.2} ms after their step's deadline) \
                 while the loop was at most {:.2} ms late{}: the device or the network was slow",
                ms(self.delivery.max_after_deadline),
                ms(self.loop_max()),
                self.peer.as_ref().map_or_else(String::new, |p| format!(
                    " and {} at most {:.2} ms",
                    p.who,
                    ms(p.max)
                ))
            ),
            Culprit::Nobody => format!(
                "nobody measured was late (the loop at most {:.2} ms{}{}): the replies were lost \
                 on the way or never sent",
                ms(self.loop_max()),
                self.peer.as_ref().map_or_else(String::new, |p| format!(
                    ", {} at most {:.2} ms",
                    p.who,
                    ms(p.max)
                )),
                if self.delivery.timestamped == 0 {
                    "; no kernel receive timestamps"
                } else {
                    ""
                }
            ),
        }
    }

    /// The measurements as JSON (`lateness` in the run's report).
    pub fn to_json(&self) -> serde_json::Value {
        json!({
            "period_ms": ms(self.period),
            "loop_wakeup_max_ms": ms(self.loop_wakeup_max),
            "loop_step_overrun_max_ms": ms(self.loop_step_overrun_max),
            "missed_deadlines": self.missed_deadlines,
            "replies_timestamped": self.delivery.timestamped,
            "reply_wait_max_ms": ms(self.delivery.max_wait),
            "reply_wait_mean_ms": ms(self.delivery.mean_wait()),
            "replies_after_deadline": self.delivery.after_deadline,
            "reply_after_deadline_max_ms": ms(self.delivery.max_after_deadline),
            "peer": self.peer.as_ref().map(|p| json!({
                "who": p.who,
                "cycle_ms": p.cycle.map(ms),
                "max_ms": ms(p.max),
                "late_cycles": p.late,
                "cycles": p.cycles,
            })),
            "loop_run_delay_ms": self.host.loop_run_delay.map(ms),
            "host_steal_ms": self.host.host.map(|h| ms(h.steal)),
            "host_interrupts_ms": self.host.host.map(|h| ms(h.irq + h.softirq)),
            "other_rt_threads": self.host.other_rt.iter().map(|t| json!({
                "pid": t.pid,
                "name": t.name,
                "scheduling": t.scheduling,
            })).collect::<Vec<_>>(),
            "culprit": match self.culprit() {
                Culprit::Loop => "loop",
                Culprit::Peer => "peer",
                Culprit::LoopAndPeer => "loop_and_peer",
                Culprit::Delivery => "delivery",
                Culprit::Nobody => "nobody",
            },
        })
    }
}

/// Whether a run that ended so failed on timing: replies lost (in a row, at a rate, or until
/// the device gave up on the link with a timeout), deadlines missed, cycles overrun (a cause
/// in lateness is worth naming).
pub fn is_timing_failure(end: Option<RunEnd>) -> bool {
    match end {
        Some(RunEnd::Fault(
            Fault::LinkInterrupted { .. }
            | Fault::ConsecutiveLost { .. }
            | Fault::LossRate { .. }
            | Fault::MissedDeadlines { .. }
            | Fault::Overruns { .. },
        )) => true,
        Some(RunEnd::Fault(Fault::LinkLost { error } | Fault::Device { error })) => {
            error.kind() == ErrorKind::Timeout
        }
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PERIOD: Duration = Duration::from_micros(7110);

    fn lateness(loop_ms: f64, peer_ms: Option<f64>, delivery: Delivery) -> Lateness {
        Lateness {
            period: PERIOD,
            loop_wakeup_max: Duration::from_secs_f64(loop_ms / 1e3),
            loop_step_overrun_max: Duration::ZERO,
            missed_deadlines: 0,
            delivery,
            peer: peer_ms.map(|m| PeerLateness {
                who: "the fake H7".into(),
                cycle: Some(PERIOD),
                max: Duration::from_secs_f64(m / 1e3),
                late: Some(12),
                cycles: Some(900),
            }),
            host: HostActivity::default(),
        }
    }

    fn other_rt() -> Vec<OtherRtThread> {
        vec![OtherRtThread {
            pid: 4242,
            name: "cyclictest".into(),
            scheduling: "SCHED_FIFO 95".into(),
        }]
    }

    #[test]
    fn a_starved_fake_is_named_not_the_link() {
        let l = lateness(0.3, Some(14.0), Delivery::default());
        assert_eq!(l.culprit(), Culprit::Peer);
        let why = l.likely_cause();
        assert!(
            why.starts_with("the fake H7 ran up to 14.00 ms late against its 7.11 ms cycle"),
            "{why}"
        );
        // Nobody else at real-time priority: not "other real-time work".
        assert!(
            why.contains("no other program runs at real-time priority"),
            "{why}"
        );
        assert!(!why.contains("starved"), "{why}");
        assert!(
            l.summary().contains("(12 of 900 cycles late)"),
            "{}",
            l.summary()
        );
        // Another program's real-time thread is named, with `rl preflight`.
        let mut l = l;
        l.host.other_rt = other_rt();
        let why = l.likely_cause();
        assert!(
            why.contains(
                "other real-time work on this machine starved it: cyclictest (pid 4242, \
                 SCHED_FIFO 95) — see `rl preflight`"
            ),
            "{why}"
        );
    }

    #[test]
    fn a_late_wake_up_without_a_wait_for_the_cpu_is_the_hosts() {
        // The loop woke 3.2 ms and the fake 3.6 ms late; the loop's thread waited 0.05 ms in
        // all on its run queue: nothing ran in its place, the wake-up came late.
        let mut l = lateness(3.2, Some(3.6), Delivery::default());
        l.host.loop_run_delay = Some(Duration::from_micros(50));
        l.host.host = Some(HostTimes {
            steal: Duration::from_millis(20),
            irq: Duration::ZERO,
            softirq: Duration::from_millis(10),
        });
        let why = l.likely_cause();
        assert!(
            why.contains(
                "the loop's thread waited only 0.05 ms in all for its CPU, so nothing on this \
                 machine ran in its place: the host held the CPU"
            ),
            "{why}"
        );
        assert!(
            why.contains("the host took 20 ms of steal, 10 ms of interrupts"),
            "{why}"
        );
        assert!(
            why.ends_with("no other program runs at real-time priority"),
            "{why}"
        );
        // A wait as long as the lateness: another thread ran in its place.
        l.host.loop_run_delay = Some(Duration::from_millis(5));
        l.host.other_rt = other_rt();
        let why = l.likely_cause();
        assert!(
            why.contains(
                "the loop's thread waited 5.00 ms in all for its CPU, enough to explain it: \
                 something else held its CPU — a thread at its priority or above, or the kernel \
                 working for another task where it does not preempt (without PREEMPT_RT: see \
                 `rl preflight`); other programs' real-time threads: cyclictest (pid 4242, \
                 SCHED_FIFO 95)"
            ),
            "{why}"
        );
        let json = l.to_json();
        assert_eq!(json["loop_run_delay_ms"], 5.0);
        assert_eq!(json["host_steal_ms"], 20.0);
        assert_eq!(json["other_rt_threads"][0]["name"], "cyclictest");
    }

    #[test]
    fn a_step_held_past_its_period_is_the_loops_lateness() {
        // Held inside its step, the loop woke on time for every deadline it did not pass.
        let mut l = lateness(0.07, Some(150.2), Delivery::default());
        l.loop_step_overrun_max = Duration::from_millis(148);
        l.host.loop_run_delay = Some(Duration::from_micros(500));
        assert_eq!(l.culprit(), Culprit::LoopAndPeer);
        let why = l.likely_cause();
        assert!(
            why.starts_with("both the loop (up to 148.00 ms late against its 7.11 ms period)"),
            "{why}"
        );
        assert!(
            why.contains("nothing on this machine ran in its place"),
            "{why}"
        );
        assert!(
            l.summary().contains(", ran a step 148.00 ms past it"),
            "{}",
            l.summary()
        );
        assert_eq!(l.to_json()["loop_step_overrun_max_ms"], 148.0);
    }

    #[test]
    fn other_programs_leave_out_kernel_threads_and_repeats() {
        use rl_rt::preflight::rt_threads::RtPolicy;
        let t = |tid, kernel| RtThread {
            pid: 7,
            tid,
            comm: format!("t{tid}"),
            policy: RtPolicy::Fifo,
            priority: 50,
            kernel,
        };
        let found = HostActivity::other_programs(&[t(1, false), t(2, true), t(1, false)]);
        assert_eq!(
            found,
            vec![OtherRtThread {
                pid: 7,
                name: "t1".into(),
                scheduling: "SCHED_FIFO 50".into()
            }]
        );
    }

    #[test]
    fn a_late_loop_is_named_also_when_it_read_its_replies_late() {
        let l = lateness(4.0, Some(0.5), Delivery::default());
        assert_eq!(l.culprit(), Culprit::Loop);
        assert!(
            l.likely_cause()
                .starts_with("the loop woke up to 4.00 ms late")
        );
        // Woke on time from the deadline, but read a reply late: the loop still.
        let mut d = Delivery::default();
        d.note_wait(Duration::from_millis(5));
        let l = lateness(0.1, Some(0.5), d);
        assert_eq!(l.culprit(), Culprit::Loop);
        assert!(
            l.likely_cause()
                .contains("read replies up to 5.00 ms after they had arrived"),
            "{}",
            l.likely_cause()
        );
    }

    #[test]
    fn a_loop_and_a_fake_both_starved_are_both_named() {
        let l = lateness(29.9, Some(30.2), Delivery::default());
        assert_eq!(l.culprit(), Culprit::LoopAndPeer);
        assert!(
            l.likely_cause().starts_with(
                "both the loop (up to 29.90 ms late against its 7.11 ms period) and the \
                 fake H7 (up to 30.20 ms late against its 7.11 ms cycle) were held up"
            ),
            "{}",
            l.likely_cause()
        );
    }

    #[test]
    fn replies_late_at_the_kernel_with_everyone_on_time_blame_the_delivery() {
        let mut d = Delivery::default();
        d.note_wait(Duration::from_micros(50));
        d.note_after_deadline(Duration::from_millis(3));
        let l = lateness(0.2, Some(0.4), d);
        assert_eq!(l.culprit(), Culprit::Delivery);
        assert!(
            l.likely_cause()
                .starts_with("replies arrived late at the kernel (up to 3.00 ms"),
            "{}",
            l.likely_cause()
        );
        let l = lateness(0.2, None, Delivery::default());
        assert_eq!(l.culprit(), Culprit::Nobody);
        assert!(l.likely_cause().contains("no kernel receive timestamps"));
    }

    #[test]
    fn only_timing_faults_ask_for_a_cause() {
        let lost = RunEnd::Fault(Fault::ConsecutiveLost {
            count: 10,
            bound: 10,
        });
        let missed = RunEnd::Fault(Fault::MissedDeadlines {
            count: 13,
            bound: 3,
        });
        assert!(is_timing_failure(Some(lost)));
        assert!(is_timing_failure(Some(missed)));
        assert!(!is_timing_failure(Some(RunEnd::Completed)));
        assert!(!is_timing_failure(Some(RunEnd::Fault(Fault::Frozen {
            cycles: 5
        }))));
        assert!(!is_timing_failure(None));
        let timed_out = rl_drivers::Error::Timeout {
            operation: rl_drivers::Operation::Step,
            waited: PERIOD,
        };
        assert!(is_timing_failure(Some(RunEnd::Fault(Fault::LinkLost {
            error: timed_out
        }))));
        let refused = rl_drivers::Error::State {
            operation: rl_drivers::Operation::Step,
            state: rl_drivers::State::Closed,
        };
        assert!(!is_timing_failure(Some(RunEnd::Fault(Fault::Device {
            error: refused
        }))));
    }
}
