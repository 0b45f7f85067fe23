//! SIGINT/SIGTERM raise a StopFlag through a sigwait watcher thread (no signal handler): the
//! first signal asks to come to rest, the second to stop now, after which the watcher ends.
//! Its own test binary: it blocks both signals in the test thread.

use std::os::unix::thread::JoinHandleExt;
use std::time::{Duration, Instant};

use nix::sys::pthread::pthread_kill;
use nix::sys::signal::Signal;
use rl_rt::{StopFlag, StopLevel};

/// Waits (bounded) until the flag reaches `level`.
fn wait_for(flag: &StopFlag, level: StopLevel) {
    let deadline = Instant::now() + Duration::from_secs(5);
    while flag.level() < level {
        assert!(Instant::now() < deadline, "flag stayed at {}", flag.level());
        std::thread::sleep(Duration::from_millis(1));
    }
}

#[test]
fn two_signals_to_the_watcher_raise_the_flag_twice() {
    let flag = StopFlag::new();
    let watcher = flag
        .raise_on_termination_signals()
        .expect("block signals, start watcher");
    assert!(!flag.is_stop_requested());
    // Thread-directed, so no other thread of the test harness can receive it.
    pthread_kill(watcher.as_pthread_t(), Signal::SIGTERM).expect("pthread_kill");
    wait_for(&flag, StopLevel::Rest);
    assert_eq!(flag.level(), StopLevel::Rest);
    assert!(
        !watcher.is_finished(),
        "the watcher waits for a second signal"
    );
    pthread_kill(watcher.as_pthread_t(), Signal::SIGINT).expect("pthread_kill");
    watcher
        .join()
        .expect("watcher ends after the second signal");
    assert_eq!(flag.level(), StopLevel::Now);
}
