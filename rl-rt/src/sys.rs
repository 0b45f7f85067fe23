//! The only place in rl-rt that calls C directly.
//!
//! nix covers most of what the crate needs (affinity, mlockall, rlimits, clock_nanosleep);
//! what it lacks is here: `pthread_setschedparam`/`pthread_getschedparam` (musl's
//! `sched_setscheduler` is ENOSYS, so the pthread calls are the portable way), the priority
//! range of a policy, a panic-free monotonic clock read and glibc's malloc tuning.

use nix::errno::Errno;

/// Sets policy and priority of the calling thread with `pthread_setschedparam`.
pub(crate) fn set_current_thread_scheduling(
    policy: libc::c_int,
    priority: i32,
) -> Result<(), Errno> {
    // SAFETY: sched_param is a plain C struct; zeroing it is a valid value on every libc
    // (glibc and musl have padding/reserved fields that must be zero anyway).
    let mut param: libc::sched_param = unsafe { core::mem::zeroed() };
    param.sched_priority = priority;
    // SAFETY: pthread_self() is always a valid handle for the calling thread, and `param` is a
    // live, initialised sched_param for the duration of the call.
    let rc = unsafe { libc::pthread_setschedparam(libc::pthread_self(), policy, &param) };
    if rc == 0 {
        Ok(())
    } else {
        Err(Errno::from_raw(rc))
    }
}

/// The priority range `(min, max)` the kernel accepts for `policy`.
pub(crate) fn priority_range(policy: libc::c_int) -> Result<(i32, i32), Errno> {
    // SAFETY: both functions take a plain integer and only read it.
    let (min, max) = unsafe {
        (
            libc::sched_get_priority_min(policy),
            libc::sched_get_priority_max(policy),
        )
    };
    if min < 0 || max < 0 {
        Err(Errno::last())
    } else {
        Ok((min, max))
    }
}

/// CLOCK_MONOTONIC in nanoseconds. Cannot fail: the clock id is valid and the out-pointer is
/// live, which are the only failure causes (EINVAL, EFAULT) of clock_gettime; so no Result and
/// no panic on the hot path.
pub(crate) fn monotonic_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a live timespec and CLOCK_MONOTONIC exists on every Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    (ts.tv_sec as u64)
        .wrapping_mul(1_000_000_000)
        .wrapping_add(ts.tv_nsec as u64)
}

/// Sleeps until the absolute CLOCK_MONOTONIC time `ns`, restarting after signals (EINTR) so a
/// signal never shortens a period. Returns the errno of any other failure.
pub(crate) fn sleep_until_monotonic_ns(ns: u64) -> Result<(), Errno> {
    let ts = libc::timespec {
        tv_sec: (ns / 1_000_000_000) as libc::time_t,
        tv_nsec: (ns % 1_000_000_000) as libc::c_long,
    };
    loop {
        // SAFETY: `ts` is a valid, normalised timespec; with TIMER_ABSTIME the remaining-time
        // pointer is unused and may be null.
        let rc = unsafe {
            libc::clock_nanosleep(
                libc::CLOCK_MONOTONIC,
                libc::TIMER_ABSTIME,
                &ts,
                core::ptr::null_mut(),
            )
        };
        match rc {
            0 => return Ok(()),
            libc::EINTR => continue,
            e => return Err(Errno::from_raw(e)),
        }
    }
}

/// Tells glibc's malloc to keep freed memory (no trimming, no mmap for large blocks), so memory
/// prefaulted and locked once stays mapped. Returns false where this is not glibc.
pub(crate) fn keep_freed_heap() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt takes two integers and only changes allocator tuning parameters.
        let trim = unsafe { libc::mallopt(libc::M_TRIM_THRESHOLD, -1) };
        // SAFETY: as above.
        let mmap = unsafe { libc::mallopt(libc::M_MMAP_MAX, 0) };
        trim == 1 && mmap == 1
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}

/// Policy, priority and SCHED_DEADLINE parameters (runtime, deadline, period in ns) of the
/// calling thread, read from the kernel with `sched_getattr` (no library-side caching).
pub(crate) fn current_thread_attr() -> Result<(i32, i32, [u64; 3]), Errno> {
    // SAFETY: sched_attr is a plain C struct of integers; all-zero is a valid value.
    let mut attr: libc::sched_attr = unsafe { core::mem::zeroed() };
    let size = core::mem::size_of::<libc::sched_attr>() as libc::c_uint;
    // SAFETY: pid 0 is the calling thread; `attr` is live and `size` is its exact size, so the
    // kernel writes at most that many bytes; flags must be 0.
    let rc = unsafe {
        libc::syscall(
            libc::SYS_sched_getattr,
            0 as libc::pid_t,
            &mut attr,
            size,
            0 as libc::c_uint,
        )
    };
    if rc != 0 {
        return Err(Errno::last());
    }
    Ok((
        attr.sched_policy as i32,
        attr.sched_priority as i32,
        [attr.sched_runtime, attr.sched_deadline, attr.sched_period],
    ))
}

/// Makes the calling thread SCHED_DEADLINE with these parameters (ns) via `sched_setattr`.
pub(crate) fn set_current_thread_deadline(
    runtime: u64,
    deadline: u64,
    period: u64,
) -> Result<(), Errno> {
    let attr = libc::sched_attr {
        size: core::mem::size_of::<libc::sched_attr>() as u32,
        sched_policy: libc::SCHED_DEADLINE as u32,
        sched_flags: 0,
        sched_nice: 0,
        sched_priority: 0,
        sched_runtime: runtime,
        sched_deadline: deadline,
        sched_period: period,
    };
    // SAFETY: pid 0 is the calling thread; `attr` is a fully initialised sched_attr whose
    // `size` field matches its layout; the kernel only reads it; flags must be 0.
    let rc = unsafe {
        libc::syscall(
            libc::SYS_sched_setattr,
            0 as libc::pid_t,
            &attr,
            0 as libc::c_uint,
        )
    };
    if rc == 0 { Ok(()) } else { Err(Errno::last()) }
}
