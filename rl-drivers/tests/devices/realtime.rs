//! A fake device's thread at a real-time priority where the process may (root, as in CI): a
//! device's firmware answers in its own time, whatever else the host runs.

/// Gives the calling thread SCHED_FIFO 80, or leaves it as it is where that is not allowed.
pub fn realtime() {
    let _ = rl_rt::RtThreadBuilder::new("fake-device")
        .policy(rl_rt::Policy::Fifo)
        .priority(80)
        .best_effort(true)
        .apply_to_current();
}
