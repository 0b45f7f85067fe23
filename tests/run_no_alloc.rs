//! The controller's steady-state cycle allocates nothing: read, trajectory, RNEA, command,
//! device step against the fake H7, telemetry queue and progress mailbox, counted by a global
//! allocator that counts only on the thread under test (the fake runs its own threads).

mod common;

use rl::controller::{Controller, CycleRecord, rv6sl};
use rl::drivers::Device;
use rl::drivers::mitsubishi_h7::MitsubishiH7;
use rl::rt::exchange::{mailbox, queue};
use rl_testkit::CountingAllocator;

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// Allocations made by `f` on this thread.
fn allocations(f: impl FnOnce()) -> u64 {
    rl_testkit::allocations(f).0
}

#[test]
fn steady_state_control_cycle_allocates_nothing() {
    // The counter sees allocations (so a zero below means something).
    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);

    let dof = rv6sl().expect("embedded model").model.dof();
    let fake = common::immediate_fake(dof);
    let mut control = Box::new(common::demo_controller(&fake));
    let (mut telemetry, mut sink) = queue::<CycleRecord>(1024);
    let (mut progress, _reader) = mailbox((0u64, 0.0f64));

    let mut cycle = |control: &mut Controller<MitsubishiH7>| {
        let out = control.cycle();
        let _ = telemetry.try_send(out.record);
        progress.publish((out.record.cycle, control.tracking().max_error()));
        out.finished
    };
    // Warm-up: first cycles, lazily initialised statics, the socket's first receives.
    for _ in 0..50 {
        assert!(!cycle(&mut control));
    }
    while sink.try_recv().is_some() {}
    let mut finished = false;
    let counted = allocations(|| {
        for _ in 0..400 {
            finished |= cycle(&mut control);
        }
    });
    assert!(!finished, "the plan is longer than 450 cycles");
    assert_eq!(counted, 0, "allocations in 400 steady-state control cycles");
    assert_eq!(control.failed_steps(), 0);
    assert!(control.tracking().max_error() > 0.0, "the arm moved");

    let mut robot = control.into_robot();
    robot.stop().expect("stop");
    robot.close().expect("close");
}
