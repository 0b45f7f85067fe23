//! A 1 kHz, 7-joint real-time loop (SCHED_FIFO 80 with locked memory where permitted) that
//! hands a record per cycle to a queue, as `ControlRun`'s loop hands its telemetry; the main
//! thread drains it every 2 ms and, with `--bridge`, forwards every record to a cell that
//! publishes it as ROS 2 joint states. Without `--bridge` the records are drained and dropped:
//! the same loop, the same hand-off, no Zenoh. Prints one JSON line: the loop's statistics
//! (rl-rt's schema), the loop thread's id, and the cell's counts. scripts/bench-cell runs it
//! both ways, alternating.
//!
//! `cargo run --release -p rl-cell --example cell_loop -- [--bridge] [--seconds S]
//!  [--connect EP | --listen EP] [--cpu N] [--pause-before S]`

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use rl_cell::{Cell, CellConfig, JointLimits, Refuse, Sample};
use rl_rt::exchange::queue;
use rl_rt::{CyclicLoop, OverrunPolicy, Policy, RtThreadBuilder, StopFlag};

const J: usize = 7;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mut bridge = false;
    let mut seconds = 10.0f64;
    let mut connect = Vec::new();
    let mut listen = Vec::new();
    let mut cpu = None;
    let mut pause = 0.0f64;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--bridge" => bridge = true,
            "--seconds" => seconds = args.next().ok_or("--seconds S")?.parse()?,
            "--connect" => connect.push(args.next().ok_or("--connect EP")?),
            "--listen" => listen.push(args.next().ok_or("--listen EP")?),
            "--cpu" => cpu = Some(args.next().ok_or("--cpu N")?.parse::<usize>()?),
            "--pause-before" => pause = args.next().ok_or("--pause-before S")?.parse()?,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    let period = Duration::from_millis(1);
    let stop = StopFlag::new();
    let mut cell = if bridge {
        let names = (1..=J).map(|k| format!("joint{k}")).collect();
        Some(Cell::<J>::open(
            CellConfig {
                connect,
                listen,
                period,
                ..CellConfig::default()
            },
            JointLimits::unlimited(names),
            Box::new(Refuse("no inputs")),
            stop.clone(),
        )?)
    } else {
        None
    };
    // Let peers connect before the measured loop starts.
    std::thread::sleep(Duration::from_secs_f64(pause));
    let cycles = (seconds * 1e3).round() as u64;
    let (mut tx, mut rx) = queue::<Sample<J>>(1 << 16);
    let looped = CyclicLoop::new(period)?
        .overrun_policy(OverrunPolicy::Skip)
        .max_cycles(cycles);
    let mut builder = RtThreadBuilder::new("rl-control")
        .policy(Policy::Fifo)
        .priority(80)
        .lock_memory(true)
        .best_effort(true);
    if let Some(c) = cpu {
        builder = builder.cpus([c]);
    }
    let (tid_tx, tid_rx) = std::sync::mpsc::channel();
    let thread = builder.spawn(move || {
        let tid = std::fs::read_link("/proc/thread-self")
            .ok()
            .and_then(|p| p.file_name()?.to_str()?.parse::<u64>().ok())
            .unwrap_or(0);
        let _ = tid_tx.send(tid);
        let mut stats = looped.new_stats();
        let mut q = [0.0; J];
        let result = looped.run_into(&mut stats, |cycle| {
            let t = cycle.index as f64 * 1e-3;
            for (k, q) in q.iter_mut().enumerate() {
                *q = 0.5 * (t * (1.0 + k as f64 * 0.1)).sin();
            }
            let _ = tx.try_send(Sample {
                cycle: cycle.index,
                commanded: q,
                measured: q,
                effort: [0.0; J],
            });
            ControlFlow::Continue(())
        });
        (stats, result.is_ok(), tx.dropped())
    })?;
    let tid = tid_rx.recv().unwrap_or(0);
    eprintln!("loop thread {tid}: {}", thread.granted());
    let started = Instant::now();
    let mut drained = 0u64;
    while !thread.is_finished() {
        std::thread::sleep(Duration::from_millis(2));
        while let Some(s) = rx.try_recv() {
            drained += 1;
            if let Some(c) = &mut cell {
                c.forward(&s);
            }
        }
    }
    let (stats, ok, dropped) = thread.join().map_err(|_| "the loop panicked")?;
    while let Some(s) = rx.try_recv() {
        drained += 1;
        if let Some(c) = &mut cell {
            c.forward(&s);
        }
    }
    let report = cell.map(|c| c.finish("{\"state\":\"ended\"}".into(), "{}".into(), None));
    println!(
        "{{\"bridge\":{bridge},\"seconds\":{:.3},\"tid\":{tid},\"ok\":{ok},\"drained\":{drained},\
         \"loop_dropped\":{dropped},\"cell\":{},\"stats\":{}}}",
        started.elapsed().as_secs_f64(),
        report.map_or("null".to_owned(), |r| r.to_json().to_string()),
        stats.to_json()
    );
    Ok(())
}
