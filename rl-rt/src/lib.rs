//! Linux real time for rl-rs: threads with real-time scheduling, memory locking,
//! absolute-deadline periodic loops, allocation-free jitter statistics and non-blocking
//! exchange between the real-time thread and the rest of the program.
//!
//! - [`thread`]: [`RtThreadBuilder`] (policy SCHED_FIFO/RR/OTHER/DEADLINE, validated priority, CPU
//!   affinity, stack size and prefault) with a read-back of what the kernel granted.
//! - [`memory`]: `mlockall`, stack and heap prefault, `RLIMIT_MEMLOCK`/`RLIMIT_RTPRIO`.
//! - [`cyclic`]: [`CyclicLoop`] on `clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)`, measuring
//!   wake-up latency and step duration, with an [`OverrunPolicy`].
//! - [`phase`]: a [`PhaseShift`] moves a running loop's deadlines, to phase-lock it to a
//!   device that runs its own cycle.
//! - [`stop`]: the two-level [`StopFlag`] (first request: come to rest; second: stop now),
//!   raised from SIGINT/SIGTERM without a signal handler.
//! - [`stats`]: 1 µs-bin [`Histogram`]s (text, JSON, cyclictest's `-h` format), mergeable.
//! - [`exchange`]: wait-free SPSC [`queue`](exchange::queue) and latest-value
//!   [`mailbox`](exchange::mailbox), drops counted.
//! - [`cpu_latency`]: hold `/dev/cpu_dma_latency` (no deep C-states) while measuring.
//! - [`host_time`]: where a late thread's time went — its own wait for a CPU ([`ThreadWait`],
//!   schedstat) or the host's steal and interrupts ([`HostTimes`]).
//! - [`preflight`]: what stands between this machine and hard real time, with fixes, and the
//!   other programs' threads at real-time priority that can starve a loop.
//!
//! Linux only (std). All `unsafe` lives in one private module (`sys`), each block with its
//! safety argument. Nothing called per cycle allocates (proved by `tests/no_alloc.rs`).
//!
//! A controller thread at SCHED_FIFO 80 running a 1 kHz loop, stopped from outside:
//!
//! ```no_run
//! use std::ops::ControlFlow;
//! use std::time::Duration;
//! use rl_rt::{CyclicLoop, Policy, RtThreadBuilder, StopFlag};
//!
//! rl_rt::memory::lock_memory()?;
//! let stop = StopFlag::new();
//! let looped = CyclicLoop::new(Duration::from_millis(1))?.stop_flag(&stop);
//! let thread = RtThreadBuilder::new("control")
//!     .policy(Policy::Fifo)
//!     .priority(80)
//!     .spawn(move || looped.run(|_cycle| ControlFlow::Continue(())))?;
//! std::thread::sleep(Duration::from_secs(1));
//! stop.request_stop();
//! let report = thread.join().expect("no panic")?;
//! println!("{}", report.stats);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(unsafe_code, missing_docs)]
#![deny(clippy::undocumented_unsafe_blocks, clippy::missing_safety_doc)]

pub mod clock;
pub mod cpu_latency;
pub mod cyclic;
pub mod exchange;
pub mod host_time;
pub mod memory;
pub mod phase;
pub mod preflight;
pub mod stats;
pub mod stop;
#[allow(unsafe_code)]
mod sys;
pub mod thread;

pub use clock::MonoTime;
pub use cyclic::{Cycle, CyclicLoop, LoopEnd, LoopError, LoopReport, OverrunPolicy};
pub use host_time::{HostTimes, ThreadWait};
pub use phase::PhaseShift;
pub use stats::{Histogram, LoopStats, Overrun, Summary};
pub use stop::{StopFlag, StopLevel};
pub use thread::{Policy, RtThread, RtThreadBuilder, Scheduling, ThreadCounters, ThreadError};

/// The crate README's examples, compiled as doc tests so they cannot rot.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
