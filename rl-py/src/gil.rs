//! Locks that are held while the GIL is released (a batch of collision queries, a wait for a
//! controller's progress) must not be waited for while holding the GIL: the holder needs the
//! GIL back to finish, the waiter holds it, and both would wait forever. [`lock`] waits with
//! the GIL released.

use std::sync::{Mutex, MutexGuard, TryLockError};
use std::time::Duration;

use pyo3::Python;

/// Locks `m`, releasing the GIL while it is taken by another thread. A poisoned lock (a panic
/// in a holder) is taken over as it is: every user overwrites what it reads.
pub fn lock<'a, T>(py: Python<'_>, m: &'a Mutex<T>) -> MutexGuard<'a, T> {
    loop {
        match m.try_lock() {
            Ok(g) => return g,
            Err(TryLockError::Poisoned(p)) => return p.into_inner(),
            Err(TryLockError::WouldBlock) => {
                py.detach(|| std::thread::sleep(Duration::from_micros(200)));
            }
        }
    }
}
