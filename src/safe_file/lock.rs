//! The advisory lock of an output target (`.NAME.lock` beside it, `flock`).

use std::fs::{self, File, OpenOptions};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use super::paths::sibling;
use super::registry::{Kind, create_registered, unregister};
use crate::error::describe_io;

/// An advisory lock on an output target: `.NAME.lock` beside it, held with `flock`
/// while the output is written, deleted on release.
///
/// Deleting a lock file races with a second run that opened it before the deletion and
/// locks it after: that run would hold a lock on an unlinked file. So a run that got
/// the lock checks that the path still names the file it locked, and retries if not.
pub(super) struct Lock {
    path: PathBuf,
    _file: File,
}

impl Lock {
    pub(super) fn acquire(target: &Path) -> std::result::Result<Lock, String> {
        let path = sibling(target, "", ".lock");
        for _ in 0..16 {
            let file = match create_registered(&path, Kind::Lock, || {
                OpenOptions::new()
                    .read(true)
                    .write(true)
                    .create(true)
                    .truncate(false)
                    .open(&path)
            }) {
                Ok(f) => f,
                Err(e) => {
                    return Err(format!(
                        "cannot create the lock file {}: {}",
                        path.display(),
                        describe_io(&e)
                    ));
                }
            };
            match file.try_lock() {
                Ok(()) => {}
                Err(fs::TryLockError::WouldBlock) => {
                    unregister(&path);
                    return Err(format!(
                        "another run is writing this file (lock {} is held); wait for it or choose another name",
                        path.display()
                    ));
                }
                Err(fs::TryLockError::Error(e)) => {
                    unregister(&path);
                    return Err(format!(
                        "cannot lock {}: {}",
                        path.display(),
                        describe_io(&e)
                    ));
                }
            }
            let same = match (file.metadata(), fs::metadata(&path)) {
                (Ok(a), Ok(b)) => (a.dev(), a.ino()) == (b.dev(), b.ino()),
                _ => false,
            };
            if same {
                return Ok(Lock { path, _file: file });
            }
        }
        unregister(&path);
        Err(format!("cannot take the lock {}", path.display()))
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        // deleted while still held, so that no other run locks a file about to vanish
        let _ = fs::remove_file(&self.path);
        unregister(&self.path);
    }
}
