//! The counter sees what it must and nothing else, so a zero in another test means something.

use rl_testkit::{CountingAllocator, allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn counts_allocations_and_reallocations_on_this_thread() {
    let (n, v) = allocations(|| {
        let mut v = Vec::<u64>::with_capacity(1);
        v.extend(0..100); // grows: reallocations
        v
    });
    assert!(n >= 2, "{n}");
    let (n, ()) = allocations(|| drop(v));
    assert_eq!(n, 0, "freeing is not counted");
}

#[test]
fn other_threads_and_code_outside_are_not_counted() {
    let outside = vec![1u8; 64];
    let (start, done) = (std::sync::Barrier::new(2), std::sync::Barrier::new(2));
    std::thread::scope(|s| {
        s.spawn(|| {
            start.wait();
            drop(std::hint::black_box(vec![0u8; 1024]));
            done.wait();
        });
        // The other thread allocates while this one is measured.
        let (n, ()) = allocations(|| {
            start.wait();
            done.wait();
        });
        assert_eq!(n, 0);
    });
    drop(outside);
}

#[test]
fn nested_sections_count_once() {
    let (outer, inner) = allocations(|| {
        let (inner, _v) = allocations(|| vec![1u8; 8]);
        let _w = std::hint::black_box(vec![2u8; 8]);
        inner
    });
    assert_eq!(inner, 1);
    assert_eq!(outer, 2);
}
