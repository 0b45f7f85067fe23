//! Linux real time for rl-rs: SCHED_FIFO threads, memory locking, absolute-deadline periodic
//! loops and allocation-free jitter statistics.
//!
//! Not built yet: see issue 5. This crate is a placeholder so the workspace builds.
