//! Helpers shared by integration tests.

use std::sync::{Mutex, MutexGuard};

/// HDF5 opens files without close-on-exec, so a child process spawned while another test of
/// the same binary has a file open inherits its descriptor and with it the file lock; the next
/// open of that file then fails with "unable to lock file" until the child exits. Tests that
/// open HDF5 files or spawn processes hold this guard, so the two never overlap.
pub fn hdf5_or_child() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}
