//! The loop body, the statistics and the exchange allocate nothing: a counting global
//! allocator (per thread, so the test harness's own threads do not interfere) over a
//! steady-state 1 kHz loop.

use std::ops::ControlFlow;
use std::time::Duration;

use rl_rt::exchange::{mailbox, queue};
use rl_rt::{CyclicLoop, Histogram, OverrunPolicy};
use rl_testkit::{CountingAllocator, allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn the_counter_sees_allocations() {
    let (n, v) = allocations(|| std::hint::black_box(vec![1u8; 64]));
    assert!(n > 0, "a Vec must be counted");
    drop(v);
}

#[test]
fn steady_state_loop_with_stats_and_exchange_allocates_nothing() {
    // Everything the loop uses is made up front.
    let looped = CyclicLoop::new(Duration::from_millis(1))
        .expect("valid")
        .max_cycles(400)
        .overrun_policy(OverrunPolicy::Skip);
    let mut stats = looped.new_stats();
    let mut merged = looped.new_stats();
    let mut other = looped.new_stats();
    let mut extra = Histogram::new(1000);
    let (mut cmd_tx, mut cmd_rx) = queue::<[f64; 6]>(8);
    let (mut tel_tx, mut tel_rx) = queue::<(u64, u64)>(4);
    let (mut set_w, mut set_r) = mailbox([0.0f64; 6]);
    for i in 0..8 {
        cmd_tx.try_send([f64::from(i); 6]).expect("room for 8");
    }
    // Warm-up run: first-use initialisation (thread-locals, lazy statics) happens here.
    looped
        .clone()
        .max_cycles(3)
        .run_into(&mut stats, |_| ControlFlow::Continue(()))
        .expect("warm-up");
    stats.clear();

    let mut checksum = 0.0;
    let (allocated, end) = allocations(|| {
        looped.run_into(&mut stats, |c| {
            if let Some(cmd) = cmd_rx.try_recv() {
                checksum += cmd[0];
            }
            // Telemetry nobody drains: the queue fills up and further sends count as drops.
            let _ = tel_tx.try_send((c.index, c.wakeup_latency_ns));
            set_w.publish([c.index as f64; 6]);
            checksum += set_r.read()[0];
            extra.record(c.wakeup_latency_ns);
            if c.index % 100 == 99 {
                let s = extra.summary();
                checksum += s.p99_ns as f64;
                other.record_cycle(c.wakeup_latency_ns, 1_000);
                merged.merge(&other).expect("same shape");
            }
            ControlFlow::Continue(())
        })
    });
    let end = end.expect("loop runs");
    assert_eq!(
        allocated, 0,
        "the steady-state loop allocated {allocated} times"
    );
    assert_eq!(end, rl_rt::LoopEnd::CycleLimit);
    assert_eq!(stats.cycles(), 400);
    assert_eq!(extra.count(), 400);
    assert_eq!(
        tel_tx.dropped(),
        400 - 4,
        "4 fit, the rest are counted drops"
    );
    assert_eq!(tel_rx.try_recv().map(|(index, _)| index), Some(0));
    assert_eq!(
        merged.cycles(),
        1 + 2 + 3 + 4,
        "merged 4 times a growing record"
    );
    assert!(checksum > 0.0);
}
