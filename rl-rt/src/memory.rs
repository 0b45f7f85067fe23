//! Keeping a real-time process's memory resident: `mlockall`, stack and heap prefault, and the
//! `RLIMIT_MEMLOCK` check that explains why locking failed.
//!
//! A page fault in a control cycle costs tens of microseconds to milliseconds. Lock everything
//! once at start-up (`MCL_CURRENT | MCL_FUTURE`), then touch the stack and heap the loop will
//! use so their pages exist before the first deadline.

use core::fmt;
use std::hint::black_box;

use nix::errno::Errno;
use nix::sys::mman::{MlockAllFlags, mlockall};
use nix::sys::resource::{RLIM_INFINITY, Resource, getrlimit};

use crate::sys;

/// A resource limit: `None` means unlimited.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limit {
    /// The soft limit, the one in force.
    pub soft: Option<u64>,
    /// The hard limit, the most an unprivileged process may raise the soft one to.
    pub hard: Option<u64>,
}

fn limit(resource: Resource) -> Result<Limit, Errno> {
    let (soft, hard) = getrlimit(resource)?;
    // rlim_t is u32 on 32-bit targets (armv7), u64 on 64-bit ones: the cast is needed there.
    #[allow(clippy::unnecessary_cast)]
    let finite = |v: libc::rlim_t| (v != RLIM_INFINITY).then_some(v as u64);
    Ok(Limit {
        soft: finite(soft),
        hard: finite(hard),
    })
}

/// `RLIMIT_MEMLOCK` in bytes.
pub fn memlock_limit() -> Result<Limit, Errno> {
    limit(Resource::RLIMIT_MEMLOCK)
}

/// `RLIMIT_RTPRIO`: the highest real-time priority an unprivileged thread may take.
pub fn rtprio_limit() -> Result<Limit, Errno> {
    limit(Resource::RLIMIT_RTPRIO)
}

/// Linux capability numbers this crate asks about (from `<linux/capability.h>`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Capability {
    /// `CAP_IPC_LOCK` (14): lock memory beyond `RLIMIT_MEMLOCK`.
    IpcLock = 14,
    /// `CAP_SYS_NICE` (23): real-time priorities beyond `RLIMIT_RTPRIO`, foreign affinity.
    SysNice = 23,
}

/// Whether the process holds `cap` in its effective set (read from `/proc/self/status`);
/// `false` if that cannot be read.
pub fn has_capability(cap: Capability) -> bool {
    let Ok(status) = std::fs::read_to_string("/proc/self/status") else {
        return false;
    };
    status
        .lines()
        .find_map(|l| l.strip_prefix("CapEff:"))
        .and_then(|hex| u64::from_str_radix(hex.trim(), 16).ok())
        .is_some_and(|bits| bits & (1u64 << cap as u32) != 0)
}

/// Why memory could not be locked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryError {
    /// The errno `mlockall` returned.
    pub errno: Errno,
    /// `RLIMIT_MEMLOCK` (soft) in bytes at the time, `None` if unlimited or unreadable.
    pub memlock_limit: Option<u64>,
}

impl fmt::Display for MemoryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "mlockall(MCL_CURRENT | MCL_FUTURE) failed: {}",
            self.errno
        )?;
        match self.memlock_limit {
            Some(bytes) => write!(
                f,
                "; RLIMIT_MEMLOCK is {bytes} bytes. Raise it to unlimited (LimitMEMLOCK=infinity \
                 in a systemd unit, `ulimit -l unlimited`, or `@realtime - memlock unlimited` in \
                 /etc/security/limits.conf) or grant CAP_IPC_LOCK"
            ),
            None => f.write_str(
                "; RLIMIT_MEMLOCK is unlimited, so the system is short of memory to lock \
                 (check free memory and vm.max_map_count)",
            ),
        }
    }
}

impl std::error::Error for MemoryError {}

/// Locks all current and future pages of the process in RAM (`MCL_CURRENT | MCL_FUTURE`).
/// On failure the error carries `RLIMIT_MEMLOCK` and names the fix.
pub fn lock_memory() -> Result<(), MemoryError> {
    mlockall(MlockAllFlags::MCL_CURRENT | MlockAllFlags::MCL_FUTURE).map_err(|errno| MemoryError {
        errno,
        memlock_limit: memlock_limit().ok().and_then(|l| l.soft),
    })
}

/// Size of the stack chunk touched per call of [`prefault_stack`]'s recursion.
const STACK_CHUNK: usize = 16 * 1024;

/// Touches `bytes` of the calling thread's stack below the current frame so those pages are
/// mapped (and, after [`lock_memory`], locked) before the loop needs them. Keep `bytes` well
/// below the thread's stack size: touching past it is a stack overflow.
#[inline(never)]
pub fn prefault_stack(bytes: usize) {
    let mut chunk = [0u8; STACK_CHUNK];
    // black_box makes the compiler materialise and write the whole array.
    black_box(&mut chunk);
    if bytes > STACK_CHUNK {
        prefault_stack(bytes - STACK_CHUNK);
    }
    black_box(&chunk);
}

/// Makes `bytes` of heap resident: asks glibc's malloc to keep freed memory (no trim, no mmap
/// for large blocks), then allocates, touches and frees that much, so later allocations of up
/// to this size reuse mapped pages. Call at start-up, after [`lock_memory`]. Returns whether
/// the malloc tuning applied (false on non-glibc, where the pages may be returned on free).
pub fn prefault_heap(bytes: usize) -> bool {
    let tuned = sys::keep_freed_heap();
    let mut block = vec![0u8; bytes];
    for page in block.chunks_mut(4096) {
        page[0] = 1;
    }
    black_box(&block);
    drop(block);
    tuned
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_names_the_limit_and_the_fix() {
        let e = MemoryError {
            errno: Errno::ENOMEM,
            memlock_limit: Some(8_388_608),
        };
        let text = e.to_string();
        assert!(text.contains("RLIMIT_MEMLOCK is 8388608 bytes"), "{text}");
        assert!(text.contains("LimitMEMLOCK=infinity"), "{text}");
        assert!(text.contains("CAP_IPC_LOCK"), "{text}");
    }

    #[test]
    fn limits_are_readable() {
        let m = memlock_limit().expect("getrlimit(RLIMIT_MEMLOCK)");
        if let (Some(s), Some(h)) = (m.soft, m.hard) {
            assert!(s <= h, "soft {s} above hard {h}");
        }
        rtprio_limit().expect("getrlimit(RLIMIT_RTPRIO)");
    }

    #[test]
    fn prefault_runs_within_a_default_stack() {
        // The test thread has 2 MiB of stack; 256 KiB is well inside it.
        prefault_stack(256 * 1024);
        prefault_heap(1 << 20);
    }
}
