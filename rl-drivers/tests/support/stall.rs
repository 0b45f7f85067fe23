//! Telling frames lost to the machine from frames lost by the code: a canary thread that sees
//! how long the machine stalled during a session, and the rule that runs a session again when
//! frames beyond the bound went with such a stall (at most three times, then SKIPPED).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The emulator's name when the test binaries run under one: `RL_EMULATED`, which
/// `scripts/cross` sets to the qemu binary (e.g. `qemu-aarch64`) when it runs them in
/// qemu-user. There the threads of a test, its fakes and its master do not keep real time (code
/// is translated as it first runs), so the tests report their timing bounds instead of
/// asserting them. `None` when `RL_EMULATED` is not set.
pub fn emulated() -> Option<String> {
    std::env::var_os("RL_EMULATED").map(|v| v.to_string_lossy().into_owned())
}

/// A stall at least this long explains lost frames: the masters' frame timeout (900 µs).
pub const STALL: Duration = Duration::from_micros(900);

/// Threads with nothing to do but wake every 500 µs at SCHED_FIFO 90 (above the fake's 80 and
/// the master's 70), one pinned to each CPU, that record how late they woke at worst: the
/// machine's own stalls during a session (on a shared VM the host holds a CPU, real-time
/// threads included, for milliseconds), seen independently of the master and the fake. One per
/// CPU, because a host that holds one virtual CPU (where the fake, the master or the kernel's
/// packet delivery runs) leaves the others on time: a single canary on another CPU saw no stall
/// while a fake's answers came back 17 ms late.
pub struct Canary {
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<Duration>>,
}

impl Canary {
    pub fn start() -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let cpus = std::thread::available_parallelism().map_or(1, usize::from);
        let threads = (0..cpus)
            .map(|cpu| {
                let flag = stop.clone();
                std::thread::spawn(move || {
                    let _ = rl_rt::RtThreadBuilder::new("canary")
                        .policy(rl_rt::Policy::Fifo)
                        .priority(90)
                        .cpus([cpu])
                        .best_effort(true)
                        .apply_to_current();
                    let period = Duration::from_micros(500);
                    let mut next = Instant::now() + period;
                    let mut worst = Duration::ZERO;
                    while !flag.load(Ordering::Relaxed) {
                        let now = Instant::now();
                        if next > now {
                            std::thread::sleep(next - now);
                        }
                        worst = worst.max(Instant::now().saturating_duration_since(next));
                        next += period;
                        // After a stall, the next wake-up is measured from now, not from the
                        // backlog.
                        next = next.max(Instant::now());
                    }
                    worst
                })
            })
            .collect();
        Self { stop, threads }
    }

    /// The worst lateness seen on any CPU.
    pub fn worst(self) -> Duration {
        self.stop.store(true, Ordering::Relaxed);
        self.threads
            .into_iter()
            .map(|t| t.join().unwrap_or(Duration::MAX))
            .max()
            .unwrap_or(Duration::ZERO)
    }
}

/// `failed` of `cycles` beyond the 1 % bound while the `canary` saw the machine stall a thread
/// for [`STALL`] or more: `Err` with the numbers, the session to run again; beyond the bound
/// with no stall seen: `Ok(false)`, for the caller to fail; within it: `Ok(true)`.
pub fn within_bound_or_stall(failed: usize, cycles: usize, canary: Canary) -> Result<bool, String> {
    let stalled = canary.worst();
    if failed * 100 <= cycles {
        return Ok(true);
    }
    if stalled >= STALL {
        return Err(format!(
            "{failed} of {cycles} cycles failed while the machine stalled a thread {stalled:?}"
        ));
    }
    Ok(false)
}

/// Runs `session` again while it returns `Err` (frames lost beyond the bound with the machine
/// stalled), at most three times, then prints SKIPPED with the numbers.
pub fn unless_stalled(name: &str, mut session: impl FnMut() -> Result<(), String>) {
    let mut stalls = Vec::new();
    while stalls.len() < 3 {
        match session() {
            Ok(()) => return,
            Err(stall) => {
                println!("{name}: attempt {}: {stall}", stalls.len() + 1);
                stalls.push(stall);
            }
        }
    }
    println!(
        "SKIPPED {name}: this machine stalled in three sessions: {}",
        stalls.join("; ")
    );
}
