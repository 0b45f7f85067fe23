//! Where a late thread's time went: to other work on its CPU, or to the host.
//!
//! A real-time thread that wakes late either waited on its CPU's run queue (another thread at
//! its priority or above ran: other real-time work) or was woken late in the first place (the
//! timer's interrupt came late: the hypervisor ran something else on this virtual CPU, or the
//! kernel held interrupts off). The two leave different traces:
//!
//! - [`ThreadWait`]: the calling thread's time on a CPU and its time runnable but waiting for
//!   one (`/proc/thread-self/schedstat`, nanoseconds; the kernel's `sched_info`). A wake-up
//!   that came `L` late while the thread waited less than `L` in all on its run queue was not
//!   late for another thread's sake.
//! - [`HostTimes`]: what the kernel accounts to no program, summed over the CPUs — steal (the
//!   hypervisor ran something else while this machine's virtual CPU wanted to run), hard and
//!   soft interrupts (`/proc/stat`'s `cpu` line, in the kernel's `USER_HZ` ticks of 10 ms: a
//!   single short stall may not show).
//!
//! [`ThreadWait::current`] reads into a stack buffer: it allocates nothing and can be called
//! on the real-time thread before and after its loop.

use core::time::Duration;
use std::fs::File;
use std::io::Read;

/// `/proc/stat` counts in `USER_HZ` ticks, 100 per second on every Linux architecture (the
/// kernel's exported constant, independent of its internal `HZ`).
const USER_HZ: u64 = 100;

/// The calling thread's scheduler times since it started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ThreadWait {
    /// Time spent on a CPU.
    pub on_cpu: Duration,
    /// Time spent runnable, waiting on a run queue for a CPU.
    pub run_delay: Duration,
    /// Times it was given a CPU.
    pub timeslices: u64,
}

impl ThreadWait {
    /// The calling thread's times (`None` where the kernel has no `schedstat`, built without
    /// `CONFIG_SCHED_INFO`). The kernel brings them up to date when the thread leaves or
    /// takes a CPU (every cycle, for a loop that sleeps to its deadlines). Allocation-free.
    pub fn current() -> Option<Self> {
        let mut buf = [0u8; 96];
        let n = read_into("/proc/thread-self/schedstat", &mut buf)?;
        Self::parse(core::str::from_utf8(&buf[..n]).ok()?)
    }

    /// Parses the three numbers of a `schedstat` file: on-CPU ns, run-queue wait ns, slices.
    pub fn parse(text: &str) -> Option<Self> {
        let mut fields = text.split_ascii_whitespace().map(str::parse::<u64>);
        let on_cpu = fields.next()?.ok()?;
        let run_delay = fields.next()?.ok()?;
        let timeslices = fields.next()?.ok()?;
        Some(Self {
            on_cpu: Duration::from_nanos(on_cpu),
            run_delay: Duration::from_nanos(run_delay),
            timeslices,
        })
    }

    /// The times from `earlier` to `self`.
    pub fn since(&self, earlier: &Self) -> Self {
        Self {
            on_cpu: self.on_cpu.saturating_sub(earlier.on_cpu),
            run_delay: self.run_delay.saturating_sub(earlier.run_delay),
            timeslices: self.timeslices.saturating_sub(earlier.timeslices),
        }
    }
}

/// Time the kernel accounts to no program, summed over every CPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HostTimes {
    /// Steal: the hypervisor ran something else while a virtual CPU of this machine wanted to
    /// run (0 on bare metal).
    pub steal: Duration,
    /// Hard interrupt handlers.
    pub irq: Duration,
    /// Soft interrupts (network receive, timers, RCU, …).
    pub softirq: Duration,
}

impl HostTimes {
    /// The machine's totals since boot (`None` without a readable `/proc/stat`).
    pub fn read() -> Option<Self> {
        let mut buf = [0u8; 512];
        let n = read_into("/proc/stat", &mut buf)?;
        Self::parse(core::str::from_utf8(&buf[..n]).ok()?)
    }

    /// Parses the aggregate `cpu` line of `/proc/stat` (user nice system idle iowait irq
    /// softirq steal …, in `USER_HZ` ticks). `None` when the line or a field is missing.
    pub fn parse(stat: &str) -> Option<Self> {
        let line = stat.lines().find(|l| l.starts_with("cpu "))?;
        let mut fields = line.split_ascii_whitespace().skip(1);
        let mut field = || fields.next()?.parse::<u64>().ok();
        let ticks = |t: u64| Duration::from_millis(t.saturating_mul(1000 / USER_HZ));
        let _user = field()?;
        let _nice = field()?;
        let _system = field()?;
        let _idle = field()?;
        let _iowait = field()?;
        let irq = field()?;
        let softirq = field()?;
        let steal = field()?;
        Some(Self {
            steal: ticks(steal),
            irq: ticks(irq),
            softirq: ticks(softirq),
        })
    }

    /// The times from `earlier` to `self`.
    pub fn since(&self, earlier: &Self) -> Self {
        Self {
            steal: self.steal.saturating_sub(earlier.steal),
            irq: self.irq.saturating_sub(earlier.irq),
            softirq: self.softirq.saturating_sub(earlier.softirq),
        }
    }
}

/// Reads the start of a small file into `buf` (no allocation: the path goes through std's
/// on-stack C string for short paths). `None` when it cannot be opened or read.
fn read_into(path: &str, buf: &mut [u8]) -> Option<usize> {
    let mut file = File::open(path).ok()?;
    let mut n = 0;
    while n < buf.len() {
        match file.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(_) => return None,
        }
    }
    Some(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedstat_and_proc_stat_parse() {
        let w = ThreadWait::parse("1234567 89012 34\n").expect("parses");
        assert_eq!(w.on_cpu, Duration::from_nanos(1_234_567));
        assert_eq!(w.run_delay, Duration::from_nanos(89_012));
        assert_eq!(w.timeslices, 34);
        assert_eq!(ThreadWait::parse("12 x 3"), None);
        assert_eq!(ThreadWait::parse("12 34"), None);

        let stat = "cpu  1325051 6886 108382 529485 5497 7 2219 293 0 0\n\
                    cpu0 639792 3426 50830 292709 1266 0 764 145 0 0\n";
        let h = HostTimes::parse(stat).expect("parses");
        assert_eq!(h.irq, Duration::from_millis(70));
        assert_eq!(h.softirq, Duration::from_millis(22_190));
        assert_eq!(h.steal, Duration::from_millis(2_930));
        // The per-CPU lines are not the aggregate; a short line is refused.
        assert_eq!(HostTimes::parse("cpu0 1 2 3 4 5 6 7 8\n"), None);
        assert_eq!(HostTimes::parse("cpu  1 2 3 4 5 6 7\n"), None);
        let later = HostTimes {
            steal: h.steal + Duration::from_millis(30),
            ..h
        };
        assert_eq!(later.since(&h).steal, Duration::from_millis(30));
        assert_eq!(h.since(&later).steal, Duration::ZERO);
    }

    #[test]
    fn this_machine_gives_both() {
        // Linux with procfs (every machine rl-rt runs on). The kernel brings a running
        // thread's times up to date when it leaves its CPU: 20 ms of work, then a sleep.
        let a = ThreadWait::current().expect("schedstat");
        let end = std::time::Instant::now() + Duration::from_millis(20);
        while std::time::Instant::now() < end {
            std::hint::spin_loop();
        }
        std::thread::sleep(Duration::from_millis(1));
        let b = ThreadWait::current().expect("schedstat");
        assert!(b.on_cpu > a.on_cpu, "{a:?} {b:?}");
        assert!(b.since(&a).on_cpu > Duration::ZERO);
        assert!(HostTimes::read().is_some());
    }

    #[test]
    fn a_wait_for_the_cpu_is_counted() {
        // Two busy threads on one CPU (SCHED_OTHER: nothing real-time runs here) take turns;
        // each waits on the run queue while the other runs, for a good part of 300 ms.
        let cpu = 0;
        let busy = move || {
            crate::thread::RtThreadBuilder::new("busy")
                .policy(crate::thread::Policy::Other)
                .cpus([cpu])
                .spawn(|| {
                    let a = ThreadWait::current().expect("schedstat");
                    let end = std::time::Instant::now() + Duration::from_millis(300);
                    while std::time::Instant::now() < end {
                        std::hint::spin_loop();
                    }
                    ThreadWait::current().expect("schedstat").since(&a)
                })
                .expect("spawn")
        };
        let (a, b) = (busy(), busy());
        let (a, b) = (a.join().expect("a"), b.join().expect("b"));
        let waited = a.run_delay + b.run_delay;
        assert!(
            waited > Duration::from_millis(100),
            "two threads on CPU {cpu} waited {waited:?} in all: {a:?} {b:?}"
        );
    }
}
