//! Shared helpers for rl-rt's integration tests.

use rl_rt::{Policy, RtThreadBuilder};

/// Runs `f` on a SCHED_FIFO 50 thread when this process may (fewer spurious late wake-ups on a
/// busy machine), otherwise on a plain thread, saying so on stderr.
pub fn on_loop_thread<F, T>(f: F) -> T
where
    F: FnOnce() -> T + Send + 'static,
    T: Send + 'static,
{
    let builder = RtThreadBuilder::new("test-loop");
    let builder = match rl_rt::preflight::probe_fifo() {
        Ok(()) => builder.policy(Policy::Fifo).priority(50),
        Err(e) => {
            eprintln!("note: loop runs at SCHED_OTHER, SCHED_FIFO is refused: {e}");
            builder
        }
    };
    builder
        .spawn(f)
        .expect("spawn loop thread")
        .join()
        .expect("loop thread panicked")
}
