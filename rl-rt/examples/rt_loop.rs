//! A controller-shaped program on rl-rt: a SCHED_FIFO thread with locked memory (when
//! permitted; SCHED_OTHER otherwise) runs a 1 kHz loop for half a second, reads its setpoint
//! from a mailbox the main thread updates, sends telemetry through a queue the main thread
//! drains, and hands its statistics back through `join`. Needs no hardware: `cargo run -p rl-rt --example rt_loop`.

use std::ops::ControlFlow;
use std::time::Duration;

use rl_rt::exchange::{mailbox, queue};
use rl_rt::{CyclicLoop, OverrunPolicy, Policy, RtThreadBuilder, StopFlag};

/// What the loop reports each cycle.
#[derive(Clone, Copy, Debug)]
struct Telemetry {
    cycle: u64,
    wakeup_latency_ns: u64,
    position: f64,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (mut setpoint_tx, mut setpoint_rx) = mailbox(0.0f64);
    let (mut telemetry_tx, mut telemetry_rx) = queue::<Telemetry>(256);
    let stop = StopFlag::new();
    let looped = CyclicLoop::new(Duration::from_millis(1))?
        .overrun_policy(OverrunPolicy::Skip)
        .max_cycles(500)
        .stop_flag(&stop);

    // Best effort: SCHED_FIFO 80 with locked memory where permitted, SCHED_OTHER otherwise,
    // and the refusals reported rather than fatal (so the example runs for any user).
    let builder = RtThreadBuilder::new("control")
        .policy(Policy::Fifo)
        .priority(80)
        .lock_memory(true)
        .best_effort(true);
    let control = builder.spawn(move || {
        let mut position = 0.0;
        let report = looped.run(|cycle| {
            // A first-order follower of the setpoint: the "controller".
            let target = *setpoint_rx.read();
            position += 0.05 * (target - position);
            // Telemetry that does not fit is counted as dropped, never blocks the loop.
            let _ = telemetry_tx.try_send(Telemetry {
                cycle: cycle.index,
                wakeup_latency_ns: cycle.wakeup_latency_ns,
                position,
            });
            ControlFlow::Continue(())
        });
        (report, telemetry_tx.dropped())
    })?;
    println!("control thread: {}", control.granted());
    for refusal in control.degraded() {
        eprintln!("note: {refusal}");
    }

    let mut received = 0u64;
    let mut worst_latency_ns = 0;
    let mut last = None;
    for step in 0..10 {
        setpoint_tx.publish(f64::from(step) * 0.1);
        std::thread::sleep(Duration::from_millis(50));
        while let Some(t) = telemetry_rx.try_recv() {
            received += 1;
            worst_latency_ns = worst_latency_ns.max(t.wakeup_latency_ns);
            last = Some(t);
        }
    }
    let (report, dropped) = control.join().map_err(|_| "control thread panicked")?;
    let report = report?;
    while telemetry_rx.try_recv().is_some() {
        received += 1;
    }
    println!("{}", report.stats);
    println!(
        "telemetry: {received} received, {dropped} dropped; worst latency seen {} µs",
        worst_latency_ns / 1000
    );
    if let Some(t) = last {
        println!(
            "last telemetry: cycle {} position {:.3}",
            t.cycle, t.position
        );
    }
    println!(
        "setpoints overwritten before the loop read them: {}",
        setpoint_tx.overwritten()
    );
    Ok(())
}
