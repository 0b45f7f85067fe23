//! Real-time scheduling as the kernel grants it. Needs CAP_SYS_NICE (or RLIMIT_RTPRIO) and
//! CAP_IPC_LOCK: without them each test prints why and skips; as root (CI) they all run and
//! check the read-back policy, priority and affinity.

use std::ops::ControlFlow;
use std::time::Duration;

use rl_rt::thread::current_scheduling;
use rl_rt::{CyclicLoop, LoopEnd, Policy, RtThreadBuilder};

/// `true` if SCHED_FIFO is permitted; otherwise prints the reason to skip.
fn privileged(test: &str) -> bool {
    match rl_rt::preflight::probe_fifo() {
        Ok(()) => true,
        Err(e) => {
            eprintln!("SKIP {test}: SCHED_FIFO not permitted here: {e}");
            false
        }
    }
}

#[test]
fn fifo_thread_reads_back_policy_and_priority() {
    if !privileged("fifo_thread_reads_back_policy_and_priority") {
        return;
    }
    let t = RtThreadBuilder::new("fifo-42")
        .policy(Policy::Fifo)
        .priority(42)
        .spawn(|| current_scheduling().expect("read back inside"))
        .expect("SCHED_FIFO 42");
    assert_eq!(t.granted().policy, Some(Policy::Fifo));
    assert_eq!(t.granted().priority, 42);
    assert!(t.matches_request());
    assert_eq!(t.thread().name(), Some("fifo-42"));
    let inside = t.join().expect("no panic");
    assert_eq!(
        (inside.policy, inside.priority),
        (Some(Policy::Fifo), 42),
        "still so while running"
    );
}

#[test]
fn round_robin_thread_reads_back_policy_and_priority() {
    if !privileged("round_robin_thread_reads_back_policy_and_priority") {
        return;
    }
    let t = RtThreadBuilder::new("rr-7")
        .policy(Policy::RoundRobin)
        .priority(7)
        .spawn(|| ())
        .expect("SCHED_RR 7");
    assert_eq!(
        (t.granted().policy, t.granted().priority),
        (Some(Policy::RoundRobin), 7)
    );
    t.join().expect("no panic");
}

#[test]
fn affinity_is_applied_and_read_back() {
    if !privileged("affinity_is_applied_and_read_back") {
        return;
    }
    let allowed = current_scheduling().expect("read back").cpus;
    let cpu = *allowed.last().expect("at least one CPU");
    let t = RtThreadBuilder::new("pinned")
        .policy(Policy::Fifo)
        .priority(10)
        .cpus([cpu])
        .spawn(move || current_scheduling().expect("read back inside").cpus)
        .expect("pinned thread");
    assert_eq!(t.granted().cpus, vec![cpu]);
    assert_eq!(t.join().expect("no panic"), vec![cpu]);
}

/// Held while a test starts a process, and by the locked loop while it runs: where a process
/// start is a fork (qemu-user emulates vfork by fork), the parent's private pages turn
/// copy-on-write and the loop's next writes fault, however locked (the armv7 run under qemu-arm
/// counted minor faults in the loop while the preflight test started `chrt`).
static PROCESS_STARTS: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn no_process_starts() -> std::sync::MutexGuard<'static, ()> {
    PROCESS_STARTS.lock().unwrap_or_else(|p| p.into_inner())
}

#[test]
fn memory_locks_and_a_fifo_loop_returns_its_report_through_join() {
    if !privileged("memory_locks_and_a_fifo_loop_returns_its_report_through_join") {
        return;
    }
    let no_forks = no_process_starts();
    let looped = CyclicLoop::new(Duration::from_millis(1))
        .expect("valid")
        .max_cycles(200);
    let t = RtThreadBuilder::new("rt-loop")
        .policy(Policy::Fifo)
        .priority(60)
        .lock_memory(true)
        .spawn(move || looped.run(|_| ControlFlow::Continue(())))
        .expect("locked SCHED_FIFO thread");
    let report = t.join().expect("no panic").expect("loop ran");
    drop(no_forks);
    assert_eq!(report.end, LoopEnd::CycleLimit);
    assert_eq!(report.stats.cycles(), 200);
    let locked = std::fs::read_to_string("/proc/self/status")
        .expect("status")
        .lines()
        .find_map(|l| l.strip_prefix("VmLck:").map(|v| v.trim().to_owned()))
        .expect("VmLck line");
    assert_ne!(locked, "0 kB", "mlockall locked nothing");
    nix::sys::mman::munlockall().expect("unlock again for the other tests");
    let counters = report
        .counters
        .expect("getrusage(RUSAGE_THREAD) works on Linux");
    eprintln!("SCHED_FIFO 60 loop: {}\n{counters}", report.stats);
    assert_eq!(
        counters.major_faults, 0,
        "locked memory must not page in during the loop"
    );
    assert_eq!(
        counters.minor_faults, 0,
        "locked, prefaulted: no page is touched first in the loop"
    );
    assert!(
        counters.voluntary_switches > 0,
        "the loop sleeps between cycles"
    );
}

#[test]
fn other_policy_refuses_a_priority_before_any_syscall() {
    // Needs no privilege: validation happens before the kernel is asked.
    let e = RtThreadBuilder::new("bad")
        .policy(Policy::Other)
        .priority(10)
        .spawn(|| ());
    assert!(
        matches!(e, Err(rl_rt::ThreadError::InvalidPriority { .. })),
        "{e:?}"
    );
}

#[test]
fn deadline_thread_reads_back_its_parameters_and_runs_a_loop() {
    if !privileged("deadline_thread_reads_back_its_parameters_and_runs_a_loop") {
        return;
    }
    let policy = Policy::deadline(
        Duration::from_micros(200),
        Duration::from_micros(900),
        Duration::from_millis(1),
    )
    .expect("fits in ns");
    let looped = CyclicLoop::new(Duration::from_millis(1))
        .expect("valid")
        .max_cycles(100);
    let t = match RtThreadBuilder::new("edf").policy(policy).spawn(move || {
        let inside = current_scheduling().expect("read back inside");
        (inside, looped.run(|_| ControlFlow::Continue(())))
    }) {
        Ok(t) => t,
        Err(rl_rt::ThreadError::DeadlineRefused { errno, .. }) => {
            // e.g. a cgroup without deadline bandwidth, or a kernel without SCHED_DEADLINE.
            eprintln!("SKIP deadline_thread_reads_back_its_parameters_and_runs_a_loop: {errno}");
            return;
        }
        Err(e) => panic!("unexpected error: {e}"),
    };
    assert_eq!(t.granted().policy, Some(policy));
    assert_eq!(t.granted().priority, 0);
    let (inside, report) = t.join().expect("no panic");
    assert_eq!(inside.policy, Some(policy));
    let report = report.expect("loop ran");
    assert_eq!(report.stats.cycles(), 100);
    eprintln!("{policy} loop: {}", report.stats);
}

#[test]
fn deadline_parameters_out_of_order_are_refused_before_any_syscall() {
    let bad = Policy::deadline(
        Duration::from_millis(2),
        Duration::from_millis(1),
        Duration::from_millis(1),
    )
    .expect("fits in ns");
    let e = RtThreadBuilder::new("bad-edf").policy(bad).spawn(|| ());
    assert!(
        matches!(e, Err(rl_rt::ThreadError::InvalidDeadline { .. })),
        "{e:?}"
    );
}

#[test]
fn best_effort_runs_at_sched_other_and_reports_what_was_refused() {
    // SCHED_DEADLINE on a thread pinned to one CPU of several is refused (EPERM: its affinity
    // must span the root domain) even for root; without privilege it is refused anyway.
    let edf = Policy::deadline(
        Duration::from_micros(100),
        Duration::from_millis(1),
        Duration::from_millis(1),
    )
    .expect("fits in ns");
    let pinned = || RtThreadBuilder::new("pinned-edf").policy(edf).cpus([0]);
    match pinned().spawn(|| ()) {
        Err(rl_rt::ThreadError::DeadlineRefused { .. }) => {}
        Ok(_) => {
            eprintln!("SKIP best_effort_...: pinned SCHED_DEADLINE admitted (one-CPU machine?)");
            return;
        }
        Err(e) => panic!("unexpected error: {e}"),
    }
    let t = pinned()
        .best_effort(true)
        .spawn(|| current_scheduling().expect("read back").policy)
        .expect("best effort runs anyway");
    assert_eq!(t.granted().policy, Some(Policy::Other));
    assert_eq!(t.granted().cpus, vec![0], "what was allowed still applies");
    assert!(!t.matches_request());
    assert_eq!(t.degraded().len(), 1);
    let refusal = t.degraded()[0].to_string();
    assert!(refusal.contains("SCHED_DEADLINE"), "{refusal}");
    assert_eq!(t.join().expect("no panic"), Some(Policy::Other));
}

/// `rl preflight` lists another program's thread at real-time priority, with its pid, name,
/// policy and priority (here `sleep` started by `chrt -f 7`).
#[test]
fn preflight_lists_another_programs_real_time_thread() {
    use rl_rt::preflight::{self, rt_threads};
    if !privileged("preflight_lists_another_programs_real_time_thread") {
        return;
    }
    let child = {
        let _no_locked_loop = no_process_starts();
        std::process::Command::new("chrt")
            .args(["-f", "7", "sleep", "30"])
            .spawn()
    };
    let mut child = match child {
        Ok(c) => c,
        Err(e) => {
            println!("SKIPPED preflight_lists_another_programs_real_time_thread: no chrt ({e})");
            return;
        }
    };
    let pid = child.id();
    // `chrt` sets the policy and then executes `sleep` in the same process.
    let deadline = std::time::Instant::now() + Duration::from_secs(5);
    let found = loop {
        let found = rt_threads::other_rt_threads()
            .into_iter()
            .find(|t| t.pid == pid && t.comm == "sleep");
        if found.is_some() || std::time::Instant::now() > deadline {
            break found;
        }
        if let Ok(Some(status)) = child.try_wait() {
            println!(
                "SKIPPED preflight_lists_another_programs_real_time_thread: chrt ended ({status})"
            );
            return;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let report = preflight::check();
    let _ = child.kill();
    let _ = child.wait();
    let t = found.expect("the chrt'd sleep is listed");
    assert_eq!(
        (t.tid, t.policy, t.priority, t.kernel),
        (pid, rt_threads::RtPolicy::Fifo, 7, false)
    );
    let summary = report
        .items
        .iter()
        .find(|i| i.name == "other real-time threads")
        .expect("summary item");
    assert_eq!(summary.status, preflight::Status::Warn, "{report}");
    // Listed if it is among the highest ones shown (other programs' threads may be above it).
    let line = format!("pid {pid} tid {pid} `sleep` SCHED_FIFO priority 7");
    let listed = report.items.iter().any(|i| i.found == line);
    let shown = report
        .items
        .iter()
        .filter(|i| i.name == "real-time thread")
        .count();
    assert!(
        listed || shown == preflight::MAX_RT_THREADS_LISTED,
        "{line} not in\n{report}"
    );
}
