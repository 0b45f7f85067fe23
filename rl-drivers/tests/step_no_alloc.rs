//! `step()` and the getters and setters around it allocate nothing in steady state: a counting
//! global allocator counts allocations made on the test's own thread (the fakes' server threads
//! allocate freely and are not counted).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::time::Duration;

use rl_drivers::coach::{Coach, CoachConfig};
use rl_drivers::fake::coach_server::{CoachServer, CoachServerConfig};
use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config};
use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_drivers::{
    CartesianPositionSensor, CyclicDevice, Device, Gripper, JointPositionActuator,
    JointPositionSensor,
};

struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn note() {
    if COUNTING.with(Cell::get) {
        ALLOCATIONS.with(|n| n.set(n.get() + 1));
    }
}

// SAFETY: forwards every call unchanged to the system allocator; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made on this thread while running `f`.
fn allocations(f: impl FnOnce()) -> u64 {
    let before = ALLOCATIONS.with(Cell::get);
    COUNTING.with(|c| c.set(true));
    f();
    COUNTING.with(|c| c.set(false));
    ALLOCATIONS.with(Cell::get) - before
}

#[test]
fn the_counter_sees_allocations() {
    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);
}

#[test]
fn h7_steps_allocate_nothing() {
    let fake = FakeH7::spawn(FakeH7Config::loopback(6)).unwrap();
    let mut robot =
        MitsubishiH7::new(MitsubishiH7Config::new(6, fake.udp_addr(), fake.r3_addr())).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    robot.step().unwrap();
    let mut q = [0.0; 6];
    let mut failures = 0;
    let n = allocations(|| {
        for k in 0..300 {
            robot.joint_position(&mut q).unwrap();
            q[0] = 0.001 * f64::from(k);
            robot.set_joint_position(&q).unwrap();
            if k % 50 == 0 {
                robot.shut().unwrap();
            }
            failures += u32::from(robot.step().is_err());
            let _ = robot.cartesian_position();
            let _ = robot.counters();
        }
    });
    assert_eq!(n, 0, "allocations in 300 steady-state H7 cycles");
    assert_eq!(failures, 0);
    // An error path (timeout) allocates nothing either.
    fake.set_frozen(true);
    assert_eq!(allocations(|| assert!(robot.step().is_err())), 0);
    fake.set_frozen(false);
}

#[test]
fn coach_steps_allocate_nothing() {
    let server = CoachServer::spawn(CoachServerConfig {
        models: vec![(0, 6)],
        ..CoachServerConfig::loopback()
    })
    .unwrap();
    let mut config = CoachConfig::new(6);
    config.server = server.addr();
    config.reply_timeout = Duration::from_secs(1);
    let mut coach = Coach::new(config).unwrap();
    coach.open().unwrap();
    coach.start().unwrap();
    coach.step().unwrap();
    let mut q = [0.0; 6];
    let n = allocations(|| {
        for k in 0..300 {
            coach.joint_position(&mut q).unwrap();
            q[1] = 0.01 * f64::from(k);
            coach.set_joint_position(&q).unwrap();
            coach.step().unwrap();
        }
    });
    assert_eq!(n, 0, "allocations in 300 steady-state Coach cycles");
}
