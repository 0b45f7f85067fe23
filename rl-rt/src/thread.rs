//! Real-time threads: scheduling policy and priority, CPU affinity, stack size and prefault,
//! with a read-back of what the kernel actually granted.
//!
//! ```no_run
//! use std::ops::ControlFlow;
//! use std::time::Duration;
//! use rl_rt::{CyclicLoop, Policy, RtThreadBuilder};
//!
//! let controller = RtThreadBuilder::new("control")
//!     .policy(Policy::Fifo)
//!     .priority(80)
//!     .cpus([1])
//!     .spawn(|| {
//!         CyclicLoop::new(Duration::from_millis(1))?
//!             .max_cycles(1000)
//!             .run(|_cycle| ControlFlow::Continue(()))
//!     })?;
//! println!("running as {}", controller.granted());
//! let report = controller.join().expect("control thread panicked")?;
//! println!("{}", report.stats);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use core::fmt;
use core::time::Duration;
use std::sync::mpsc;
use std::thread::{self, JoinHandle};

use nix::errno::Errno;
use nix::sched::{CpuSet, sched_getaffinity, sched_setaffinity};
use nix::sys::resource::{UsageWho, getrusage};
use nix::unistd::Pid;

use crate::clock::duration_to_nanos;
use crate::memory::{self, MemoryError};
use crate::sys;

/// A Linux scheduling policy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Policy {
    /// `SCHED_OTHER`: the normal time-sharing policy (priority 0).
    #[default]
    Other,
    /// `SCHED_FIFO`: real-time, runs until it blocks or a higher priority wakes (1..=99).
    Fifo,
    /// `SCHED_RR`: like FIFO with a time slice among equal priorities (1..=99).
    RoundRobin,
    /// `SCHED_DEADLINE` (earliest deadline first with admission control): the thread gets
    /// `runtime_ns` of CPU in every `period_ns`, done by `deadline_ns` after the period starts.
    /// Priority 0; the thread's CPU affinity must span its root domain (do not pin it with
    /// [`RtThreadBuilder::cpus`]; use an exclusive cpuset instead). Build with
    /// [`Policy::deadline`].
    Deadline {
        /// CPU time per period, ns (at least 1024).
        runtime_ns: u64,
        /// Relative deadline, ns (runtime ≤ deadline ≤ period).
        deadline_ns: u64,
        /// Period, ns.
        period_ns: u64,
    },
}

impl Policy {
    /// SCHED_DEADLINE with these parameters, or `None` if one does not fit in u64 ns.
    pub fn deadline(runtime: Duration, deadline: Duration, period: Duration) -> Option<Self> {
        Some(Self::Deadline {
            runtime_ns: duration_to_nanos(runtime)?,
            deadline_ns: duration_to_nanos(deadline)?,
            period_ns: duration_to_nanos(period)?,
        })
    }

    fn to_raw(self) -> libc::c_int {
        match self {
            Self::Other => libc::SCHED_OTHER,
            Self::Fifo => libc::SCHED_FIFO,
            Self::RoundRobin => libc::SCHED_RR,
            Self::Deadline { .. } => libc::SCHED_DEADLINE,
        }
    }

    fn from_raw(raw: libc::c_int, deadline: [u64; 3]) -> Option<Self> {
        match raw {
            libc::SCHED_OTHER => Some(Self::Other),
            libc::SCHED_FIFO => Some(Self::Fifo),
            libc::SCHED_RR => Some(Self::RoundRobin),
            libc::SCHED_DEADLINE => Some(Self::Deadline {
                runtime_ns: deadline[0],
                deadline_ns: deadline[1],
                period_ns: deadline[2],
            }),
            _ => None,
        }
    }

    /// The priority range the kernel accepts for this policy, `(min, max)`.
    pub fn priority_range(self) -> Result<(i32, i32), Errno> {
        sys::priority_range(self.to_raw())
    }

    /// Whether this is a real-time policy (FIFO, RR or DEADLINE).
    pub fn is_realtime(self) -> bool {
        !matches!(self, Self::Other)
    }
}

impl fmt::Display for Policy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Other => "SCHED_OTHER",
            Self::Fifo => "SCHED_FIFO",
            Self::RoundRobin => "SCHED_RR",
            Self::Deadline {
                runtime_ns,
                deadline_ns,
                period_ns,
            } => {
                return write!(
                    f,
                    "SCHED_DEADLINE (runtime {} µs, deadline {} µs, period {} µs)",
                    *runtime_ns as f64 / 1e3,
                    *deadline_ns as f64 / 1e3,
                    *period_ns as f64 / 1e3
                );
            }
        })
    }
}

/// Scheduling of a thread as the kernel reports it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Scheduling {
    /// The policy (`None` for one this crate does not model, e.g. SCHED_BATCH).
    pub policy: Option<Policy>,
    /// The raw policy number.
    pub raw_policy: i32,
    /// The static priority.
    pub priority: i32,
    /// The CPUs the thread may run on.
    pub cpus: Vec<usize>,
}

impl fmt::Display for Scheduling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.policy {
            Some(p) => write!(f, "{p}")?,
            None => write!(f, "policy {}", self.raw_policy)?,
        }
        write!(f, " priority {} on CPUs {:?}", self.priority, self.cpus)
    }
}

/// Reads the calling thread's policy, priority (and SCHED_DEADLINE parameters) and CPU
/// affinity from the kernel (`sched_getattr`, `sched_getaffinity`).
pub fn current_scheduling() -> Result<Scheduling, ThreadError> {
    let (raw_policy, priority, deadline) =
        sys::current_thread_attr().map_err(|errno| ThreadError::Sys {
            call: "sched_getattr",
            errno,
        })?;
    let set = sched_getaffinity(Pid::from_raw(0)).map_err(|errno| ThreadError::Sys {
        call: "sched_getaffinity",
        errno,
    })?;
    let cpus = (0..CpuSet::count())
        .filter(|&c| set.is_set(c).unwrap_or(false))
        .collect();
    Ok(Scheduling {
        policy: Policy::from_raw(raw_policy, deadline),
        raw_policy,
        priority,
        cpus,
    })
}

/// Per-thread counters of what disturbs a real-time loop: page faults (a locked, prefaulted
/// loop has none) and context switches (involuntary ones mean something preempted it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ThreadCounters {
    /// Page faults served without I/O.
    pub minor_faults: u64,
    /// Page faults that needed I/O.
    pub major_faults: u64,
    /// Times the thread gave up the CPU (sleeping, blocking).
    pub voluntary_switches: u64,
    /// Times the thread was preempted.
    pub involuntary_switches: u64,
}

impl ThreadCounters {
    /// The calling thread's counters since it started (`getrusage(RUSAGE_THREAD)`).
    pub fn current() -> Result<Self, Errno> {
        let u = getrusage(UsageWho::RUSAGE_THREAD)?;
        let n = |v: libc::c_long| u64::try_from(v).unwrap_or(0);
        Ok(Self {
            minor_faults: n(u.minor_page_faults()),
            major_faults: n(u.major_page_faults()),
            voluntary_switches: n(u.voluntary_context_switches()),
            involuntary_switches: n(u.involuntary_context_switches()),
        })
    }

    /// The counts from `earlier` to `self`.
    pub fn since(&self, earlier: &Self) -> Self {
        Self {
            minor_faults: self.minor_faults.saturating_sub(earlier.minor_faults),
            major_faults: self.major_faults.saturating_sub(earlier.major_faults),
            voluntary_switches: self
                .voluntary_switches
                .saturating_sub(earlier.voluntary_switches),
            involuntary_switches: self
                .involuntary_switches
                .saturating_sub(earlier.involuntary_switches),
        }
    }
}

impl fmt::Display for ThreadCounters {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "page faults {} minor / {} major, context switches {} voluntary / {} involuntary",
            self.minor_faults,
            self.major_faults,
            self.voluntary_switches,
            self.involuntary_switches
        )
    }
}

/// The outcome of applying a builder's settings to a thread.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Applied {
    /// Policy, priority and CPUs as read back from the kernel.
    pub granted: Scheduling,
    /// What was refused and skipped in best-effort mode.
    pub degraded: Vec<ThreadError>,
}

/// What was asked and what the kernel granted, when they differ.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SchedulingMismatch {
    /// What was asked: policy, priority, CPUs (empty = unchanged).
    pub requested: (Policy, i32, Vec<usize>),
    /// What the read-back showed.
    pub granted: Scheduling,
}

/// Why a real-time thread could not be set up as asked.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ThreadError {
    /// The priority is outside the policy's range.
    InvalidPriority {
        /// The policy asked for.
        policy: Policy,
        /// The priority asked for.
        priority: i32,
        /// Lowest priority of the policy.
        min: i32,
        /// Highest priority of the policy.
        max: i32,
    },
    /// The kernel refused the real-time policy (EPERM).
    PermissionDenied {
        /// The policy asked for.
        policy: Policy,
        /// The priority asked for.
        priority: i32,
    },
    /// SCHED_DEADLINE parameters out of order: it needs 1024 ns ≤ runtime ≤ deadline ≤ period.
    InvalidDeadline {
        /// The policy with the parameters asked for.
        policy: Policy,
    },
    /// The kernel refused SCHED_DEADLINE.
    DeadlineRefused {
        /// The policy with the parameters asked for.
        policy: Policy,
        /// The errno (EBUSY: admission control; EPERM: privilege or affinity).
        errno: Errno,
    },
    /// A CPU number is beyond what a CPU set can hold.
    InvalidCpu {
        /// The CPU asked for.
        cpu: usize,
        /// How many CPUs a set can hold.
        limit: usize,
    },
    /// The kernel refused the CPU affinity (EINVAL: none of the CPUs is online or allowed).
    Affinity {
        /// The CPUs asked for.
        cpus: Vec<usize>,
        /// The errno.
        errno: Errno,
    },
    /// Memory locking failed.
    Memory(MemoryError),
    /// The kernel granted something other than what was asked.
    Mismatch(Box<SchedulingMismatch>),
    /// The thread could not be created.
    Spawn(std::io::ErrorKind),
    /// The new thread died before reporting its set-up.
    SetupLost,
    /// Another system call failed.
    Sys {
        /// The call.
        call: &'static str,
        /// The errno.
        errno: Errno,
    },
}

impl fmt::Display for ThreadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::InvalidPriority {
                policy,
                priority,
                min,
                max,
            } => {
                write!(
                    f,
                    "priority {priority} is invalid for {policy}: it takes {min}..={max}"
                )
            }
            Self::PermissionDenied { policy, priority } => write!(
                f,
                "{policy} priority {priority} not permitted (EPERM): needs CAP_SYS_NICE or an \
                 RLIMIT_RTPRIO ≥ {priority} (e.g. LimitRTPRIO={priority} in a systemd unit, \
                 `ulimit -r {priority}`, or `@realtime - rtprio {priority}` in \
                 /etc/security/limits.conf); also check that no cgroup forbids real-time \
                 runtime (cpu.rt_runtime_us)"
            ),
            Self::InvalidDeadline { policy } => write!(
                f,
                "{policy} is invalid: it needs 1024 ns ≤ runtime ≤ deadline ≤ period"
            ),
            Self::DeadlineRefused {
                policy,
                errno: Errno::EBUSY,
            } => write!(
                f,
                "{policy} refused by admission control (EBUSY): the CPUs' deadline bandwidth \
                 (kernel.sched_rt_runtime_us / sched_rt_period_us) is taken; lower the \
                 runtime/period ratio or end other SCHED_DEADLINE tasks"
            ),
            Self::DeadlineRefused {
                policy,
                errno: Errno::EPERM,
            } => write!(
                f,
                "{policy} not permitted (EPERM): needs CAP_SYS_NICE (RLIMIT_RTPRIO does not \
                 cover SCHED_DEADLINE), and the thread's CPU affinity must span its root \
                 domain: do not pin it with cpus(), use an exclusive cpuset"
            ),
            Self::DeadlineRefused { policy, errno } => write!(f, "{policy} refused: {errno}"),
            Self::InvalidCpu { cpu, limit } => {
                write!(
                    f,
                    "CPU {cpu} does not exist here: a CPU set holds CPUs 0..{limit}"
                )
            }
            Self::Affinity { cpus, errno } => write!(
                f,
                "cannot pin the thread to CPUs {cpus:?}: {errno}; check the online CPUs \
                 (/sys/devices/system/cpu/online) and the process's cpuset (taskset -p, cgroup)"
            ),
            Self::Memory(e) => e.fmt(f),
            Self::Mismatch(m) => write!(
                f,
                "asked for {} priority {} on CPUs {:?} but the kernel reports {}",
                m.requested.0, m.requested.1, m.requested.2, m.granted
            ),
            Self::Spawn(kind) => write!(f, "cannot create the thread: {kind}"),
            Self::SetupLost => f.write_str("the new thread ended before reporting its set-up"),
            Self::Sys { call, errno } => write!(f, "{call} failed: {errno}"),
        }
    }
}

impl std::error::Error for ThreadError {}

impl From<MemoryError> for ThreadError {
    fn from(e: MemoryError) -> Self {
        Self::Memory(e)
    }
}

/// Builds a thread with real-time scheduling. Defaults: `SCHED_OTHER` priority 0, no affinity
/// change, 1 MiB stack of which 256 KiB are prefaulted, memory not locked, any read-back
/// mismatch is an error.
#[derive(Clone, Debug)]
pub struct RtThreadBuilder {
    name: String,
    policy: Policy,
    priority: i32,
    cpus: Option<Vec<usize>>,
    stack_size: usize,
    prefault_stack: usize,
    lock_memory: bool,
    exact: bool,
    best_effort: bool,
}

impl RtThreadBuilder {
    /// A builder for a thread named `name` (shown by `ps -L`, `top -H`; Linux keeps 15 bytes).
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            policy: Policy::Other,
            priority: 0,
            cpus: None,
            stack_size: 1 << 20,
            prefault_stack: 256 << 10,
            lock_memory: false,
            exact: true,
            best_effort: false,
        }
    }

    /// The scheduling policy.
    pub fn policy(mut self, policy: Policy) -> Self {
        self.policy = policy;
        self
    }

    /// The static priority (1..=99 for FIFO/RR on Linux, 0 for OTHER).
    pub fn priority(mut self, priority: i32) -> Self {
        self.priority = priority;
        self
    }

    /// Pin the thread to these CPUs.
    pub fn cpus(mut self, cpus: impl IntoIterator<Item = usize>) -> Self {
        self.cpus = Some(cpus.into_iter().collect());
        self
    }

    /// The thread's stack size in bytes.
    pub fn stack_size(mut self, bytes: usize) -> Self {
        self.stack_size = bytes;
        self
    }

    /// How much of the stack to touch before running (at most half the stack size is used).
    pub fn prefault_stack(mut self, bytes: usize) -> Self {
        self.prefault_stack = bytes;
        self
    }

    /// Lock all process memory (`mlockall`) from the new thread before it runs.
    pub fn lock_memory(mut self, lock: bool) -> Self {
        self.lock_memory = lock;
        self
    }

    /// Whether a read-back that differs from the request is an error (default) or only
    /// reported in [`RtThread::granted`]'s comparison with [`RtThread::matches_request`].
    pub fn require_exact(mut self, exact: bool) -> Self {
        self.exact = exact;
        self
    }

    /// Run even where real-time scheduling or memory locking is refused for lack of privilege
    /// (EPERM; EBUSY from SCHED_DEADLINE admission): the thread then keeps SCHED_OTHER and
    /// unlocked memory, and [`RtThread::degraded`] lists what was refused with its remedy. For
    /// programs that must also run for an unprivileged user (demos, CI without root).
    pub fn best_effort(mut self, best_effort: bool) -> Self {
        self.best_effort = best_effort;
        self
    }

    /// Checks priority and CPU numbers without touching the kernel's scheduler.
    pub fn validate(&self) -> Result<(), ThreadError> {
        let (min, max) = self
            .policy
            .priority_range()
            .map_err(|errno| ThreadError::Sys {
                call: "sched_get_priority_min/max",
                errno,
            })?;
        if !(min..=max).contains(&self.priority) {
            return Err(ThreadError::InvalidPriority {
                policy: self.policy,
                priority: self.priority,
                min,
                max,
            });
        }
        if let Policy::Deadline {
            runtime_ns,
            deadline_ns,
            period_ns,
        } = self.policy
        {
            if !(1024 <= runtime_ns && runtime_ns <= deadline_ns && deadline_ns <= period_ns) {
                return Err(ThreadError::InvalidDeadline {
                    policy: self.policy,
                });
            }
        }
        if let Some(cpu) = self
            .cpus
            .iter()
            .flatten()
            .copied()
            .find(|&c| c >= CpuSet::count())
        {
            return Err(ThreadError::InvalidCpu {
                cpu,
                limit: CpuSet::count(),
            });
        }
        Ok(())
    }

    fn requested(&self) -> (Policy, i32, Vec<usize>) {
        let mut cpus = self.cpus.clone().unwrap_or_default();
        cpus.sort_unstable();
        cpus.dedup();
        (self.policy, self.priority, cpus)
    }

    /// Applies these settings to the calling thread (affinity, memory lock, policy and
    /// priority, stack prefault) and returns the read-back. Stack size does not apply here.
    /// In [`best_effort`](Self::best_effort) mode, refusals for lack of privilege are listed in
    /// [`Applied::degraded`] instead of failing.
    pub fn apply_to_current(&self) -> Result<Applied, ThreadError> {
        self.validate()?;
        let mut degraded = Vec::new();
        if let Some(cpus) = &self.cpus {
            let mut set = CpuSet::new();
            for &cpu in cpus {
                set.set(cpu).map_err(|_| ThreadError::InvalidCpu {
                    cpu,
                    limit: CpuSet::count(),
                })?;
            }
            sched_setaffinity(Pid::from_raw(0), &set).map_err(|errno| ThreadError::Affinity {
                cpus: cpus.clone(),
                errno,
            })?;
        }
        if self.lock_memory {
            match memory::lock_memory() {
                Ok(()) => {}
                Err(e) if self.best_effort => degraded.push(ThreadError::Memory(e)),
                Err(e) => return Err(e.into()),
            }
        }
        let scheduled = match self.policy {
            Policy::Deadline {
                runtime_ns,
                deadline_ns,
                period_ns,
            } => sys::set_current_thread_deadline(runtime_ns, deadline_ns, period_ns).map_err(
                |errno| ThreadError::DeadlineRefused {
                    policy: self.policy,
                    errno,
                },
            ),
            policy => sys::set_current_thread_scheduling(policy.to_raw(), self.priority).map_err(
                |errno| match errno {
                    Errno::EPERM => ThreadError::PermissionDenied {
                        policy,
                        priority: self.priority,
                    },
                    errno => ThreadError::Sys {
                        call: "pthread_setschedparam",
                        errno,
                    },
                },
            ),
        };
        match scheduled {
            Ok(()) => {}
            Err(
                e @ (ThreadError::PermissionDenied { .. }
                | ThreadError::DeadlineRefused {
                    errno: Errno::EPERM | Errno::EBUSY,
                    ..
                }),
            ) if self.best_effort => degraded.push(e),
            Err(e) => return Err(e),
        }
        memory::prefault_stack(self.prefault_stack.min(self.stack_size / 2));
        let granted = current_scheduling()?;
        let requested = self.requested();
        if self.exact && degraded.is_empty() && !matches_request(&requested, &granted) {
            return Err(ThreadError::Mismatch(Box::new(SchedulingMismatch {
                requested,
                granted,
            })));
        }
        Ok(Applied { granted, degraded })
    }

    /// Starts the thread: it applies the settings to itself, reports the read-back, and only
    /// if that succeeded runs `f`. Returns once the set-up is known, so an error (EPERM, bad
    /// CPU, mismatch) comes back here rather than from inside the thread.
    pub fn spawn<F, T>(self, f: F) -> Result<RtThread<T>, ThreadError>
    where
        F: FnOnce() -> T + Send + 'static,
        T: Send + 'static,
    {
        self.validate()?;
        let (tx, rx) = mpsc::sync_channel(1);
        let settings = self.clone();
        let handle = thread::Builder::new()
            .name(self.name.clone())
            .stack_size(self.stack_size)
            .spawn(move || {
                let setup = settings.apply_to_current();
                let ok = setup.is_ok();
                // The spawner waits on the other end; if it is gone nobody needs the result.
                let _ = tx.send(setup);
                ok.then(f)
            })
            .map_err(|e| ThreadError::Spawn(e.kind()))?;
        match rx.recv() {
            Ok(Ok(Applied { granted, degraded })) => {
                let exact = matches_request(&self.requested(), &granted);
                Ok(RtThread {
                    handle,
                    granted,
                    exact,
                    degraded,
                })
            }
            Ok(Err(e)) => {
                let _ = handle.join();
                Err(e)
            }
            Err(_) => Err(ThreadError::SetupLost),
        }
    }
}

fn matches_request(requested: &(Policy, i32, Vec<usize>), granted: &Scheduling) -> bool {
    granted.policy == Some(requested.0)
        && granted.priority == requested.1
        && (requested.2.is_empty() || requested.2 == granted.cpus)
}

/// A running real-time thread: its join handle and what the kernel granted it.
#[derive(Debug)]
pub struct RtThread<T> {
    handle: JoinHandle<Option<T>>,
    granted: Scheduling,
    exact: bool,
    degraded: Vec<ThreadError>,
}

impl<T> RtThread<T> {
    /// Policy, priority and CPUs as read back inside the thread before it ran.
    pub fn granted(&self) -> &Scheduling {
        &self.granted
    }

    /// What was refused in [`best_effort`](RtThreadBuilder::best_effort) mode (real-time
    /// policy, memory lock), each with its remedy; empty when everything was granted.
    pub fn degraded(&self) -> &[ThreadError] {
        &self.degraded
    }

    /// Whether the grant equals the request (always true unless `require_exact(false)` or
    /// `best_effort(true)`).
    pub fn matches_request(&self) -> bool {
        self.exact
    }

    /// The underlying thread (name, id, unpark).
    pub fn thread(&self) -> &thread::Thread {
        self.handle.thread()
    }

    /// Whether the thread has finished.
    pub fn is_finished(&self) -> bool {
        self.handle.is_finished()
    }

    /// Waits for the thread and returns its result; `Err` carries a panic's payload.
    pub fn join(self) -> thread::Result<T> {
        match self.handle.join()? {
            Some(value) => Ok(value),
            // Not reachable: an RtThread exists only after a successful set-up, after which
            // the closure always runs. Reported as a panic payload rather than panicking here.
            None => Err(Box::new("real-time thread set-up failed; closure not run")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn priority_is_validated_against_the_policy() {
        let e = RtThreadBuilder::new("t")
            .policy(Policy::Fifo)
            .priority(0)
            .validate();
        assert_eq!(
            e,
            Err(ThreadError::InvalidPriority {
                policy: Policy::Fifo,
                priority: 0,
                min: 1,
                max: 99
            })
        );
        let e = RtThreadBuilder::new("t")
            .policy(Policy::Other)
            .priority(5)
            .validate();
        assert!(
            matches!(e, Err(ThreadError::InvalidPriority { min: 0, max: 0, .. })),
            "{e:?}"
        );
        assert!(
            RtThreadBuilder::new("t")
                .policy(Policy::RoundRobin)
                .priority(99)
                .validate()
                .is_ok()
        );
    }

    #[test]
    fn impossible_cpu_is_refused_before_spawning() {
        let e = RtThreadBuilder::new("t")
            .cpus([CpuSet::count()])
            .spawn(|| ());
        assert!(matches!(e, Err(ThreadError::InvalidCpu { .. })), "{e:?}");
    }

    #[test]
    fn eperm_error_names_the_remedy() {
        let text = ThreadError::PermissionDenied {
            policy: Policy::Fifo,
            priority: 90,
        }
        .to_string();
        assert!(text.contains("SCHED_FIFO priority 90"), "{text}");
        assert!(text.contains("CAP_SYS_NICE"), "{text}");
        assert!(text.contains("RLIMIT_RTPRIO ≥ 90"), "{text}");
        assert!(text.contains("LimitRTPRIO=90"), "{text}");
    }

    #[test]
    fn other_policy_thread_reads_back_and_returns_its_value() {
        let t = RtThreadBuilder::new("plain")
            .spawn(|| 41 + 1)
            .expect("SCHED_OTHER is always allowed");
        assert_eq!(t.granted().policy, Some(Policy::Other));
        assert_eq!(t.granted().priority, 0);
        assert!(t.matches_request());
        assert_eq!(t.join().expect("no panic"), 42);
    }
}
