//! Test support for rl-rs: the counting global allocator behind every allocation-freedom test.
//!
//! A test binary installs it and measures a section of code:
//!
//! ```ignore
//! #[global_allocator]
//! static GLOBAL: rl_testkit::CountingAllocator = rl_testkit::CountingAllocator;
//!
//! let (n, _) = rl_testkit::allocations(|| step());
//! assert_eq!(n, 0);
//! ```
//!
//! It counts allocations and reallocations on the calling thread only, while a measured
//! section runs: the test harness's threads, fake robots and servers on threads of their own
//! allocate freely and are not counted. Memory comes from the system allocator unchanged.
//!
//! With `RL_ALLOC_TRACE=1` in the environment, each counted allocation also prints its
//! backtrace on standard error (to find where a measured section allocates).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::OnceLock;

/// A global allocator that forwards to [`System`] and counts, per thread, the allocations made
/// inside [`allocations`].
pub struct CountingAllocator;

thread_local! {
    /// Depth of nested measured sections on this thread (0: not counting).
    static DEPTH: Cell<u32> = const { Cell::new(0) };
    static COUNT: Cell<u64> = const { Cell::new(0) };
    /// Inside a backtrace's printing (whose own allocations are not traced).
    static TRACING: Cell<bool> = const { Cell::new(false) };
}

/// `RL_ALLOC_TRACE` is set (read once, outside any measured section).
static TRACE: OnceLock<bool> = OnceLock::new();

fn note() {
    // `try_with`: during thread teardown the thread-locals may be gone.
    let counted = DEPTH.try_with(|depth| depth.get() > 0).unwrap_or(false);
    if !counted || TRACING.try_with(Cell::get).unwrap_or(true) {
        return;
    }
    let _ = COUNT.try_with(|c| c.set(c.get() + 1));
    if TRACE.get().copied().unwrap_or(false) {
        TRACING.set(true);
        // Straight to the process's standard error, not through the test harness's capture
        // of `eprintln!` (shown only for a failed test).
        let trace = format!(
            "allocation in a measured section:\n{}\n",
            std::backtrace::Backtrace::force_capture()
        );
        let _ = std::io::Write::write_all(&mut std::io::stderr(), trace.as_bytes());
        TRACING.set(false);
    }
}

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for CountingAllocator {
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
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Runs `f` and returns the allocations it made on this thread (with [`CountingAllocator`]
/// installed as the global allocator; without it the count is always 0), and its result.
pub fn allocations<R>(f: impl FnOnce() -> R) -> (u64, R) {
    TRACE.get_or_init(|| std::env::var_os("RL_ALLOC_TRACE").is_some_and(|v| v != "0"));
    let before = COUNT.with(Cell::get);
    DEPTH.with(|d| d.set(d.get() + 1));
    let r = f();
    DEPTH.with(|d| d.set(d.get() - 1));
    (COUNT.with(Cell::get) - before, r)
}
