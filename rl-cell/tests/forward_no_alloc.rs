//! The hand-offs allocate nothing: the loop's push of its per-cycle record into an rl-rt queue
//! (what the real-time thread does, with or without a cell) and `Cell::forward` (what the
//! thread draining that queue does for the cell), measured with rl-testkit's counting
//! allocator over 10,000 cycles in steady state while the bridge publishes.

use std::time::Duration;

use rl_cell::{Cell, CellConfig, JointLimits, Refuse, Sample};
use rl_rt::StopFlag;
use rl_rt::exchange::queue;

#[global_allocator]
static GLOBAL: rl_testkit::CountingAllocator = rl_testkit::CountingAllocator;

#[test]
fn the_loop_side_and_forward_allocate_nothing() {
    let names = (1..=7).map(|k| format!("joint{k}")).collect();
    let mut cell: Cell<7> = Cell::open(
        CellConfig {
            period: Duration::from_millis(1),
            ..CellConfig::default()
        },
        JointLimits::unlimited(names),
        Box::new(Refuse("no inputs")),
        StopFlag::new(),
    )
    .expect("a cell with no endpoints");
    let (mut tx, mut rx) = queue::<Sample<7>>(1024);
    let sample = |cycle: u64| Sample {
        cycle,
        commanded: [cycle as f64 * 1e-3; 7],
        measured: [cycle as f64 * 1e-3; 7],
        effort: [1.0; 7],
    };
    // Warm up: the first samples (the bridge thread's buffers grow on its own thread).
    for cycle in 0..100 {
        tx.try_send(sample(cycle)).expect("room");
        while let Some(s) = rx.try_recv() {
            cell.forward(&s);
        }
    }
    let mut loop_side = 0;
    let mut drain_side = 0;
    for cycle in 100..10_100 {
        let (n, sent) = rl_testkit::allocations(|| tx.try_send(sample(cycle)));
        assert!(sent.is_ok());
        loop_side += n;
        let (n, ()) = rl_testkit::allocations(|| {
            while let Some(s) = rx.try_recv() {
                cell.forward(&s);
            }
        });
        drain_side += n;
        if cycle % 1000 == 0 {
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    assert_eq!(loop_side, 0, "the loop's push allocated");
    assert_eq!(drain_side, 0, "Cell::forward allocated");
    std::thread::sleep(Duration::from_millis(100));
    let report = cell.finish("{}".into(), "{}".into(), None);
    assert_eq!(report.outbound.forwarded, 10_100);
    assert_eq!(report.outbound.handled + report.outbound.dropped, 10_100);
    assert_eq!(report.outbound.joint_states, 2 * report.outbound.handled);
}
