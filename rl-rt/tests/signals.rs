//! SIGINT/SIGTERM raise a StopFlag through a sigwait watcher thread (no signal handler).
//! Its own test binary: it blocks both signals in the test thread.

use std::os::unix::thread::JoinHandleExt;

use nix::sys::pthread::pthread_kill;
use nix::sys::signal::Signal;
use rl_rt::StopFlag;

#[test]
fn sigterm_to_the_watcher_raises_the_flag() {
    let flag = StopFlag::new();
    let watcher = flag
        .raise_on_termination_signals()
        .expect("block signals, start watcher");
    assert!(!flag.is_stop_requested());
    // Thread-directed, so no other thread of the test harness can receive it.
    pthread_kill(watcher.as_pthread_t(), Signal::SIGTERM).expect("pthread_kill");
    watcher.join().expect("watcher ends after one signal");
    assert!(flag.is_stop_requested());
}
