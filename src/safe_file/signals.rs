//! SIGINT, SIGTERM and SIGHUP: delete every registered file and end the process with
//! one line and status 128 + signal.

use std::fs;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

use super::registry::{FILE_STATE, Kind, file_state};
use crate::error::{Error, Result};

/// Set by the signal watcher as it starts ending the process.
pub(super) static SIGNALLED: AtomicBool = AtomicBool::new(false);

/// Blocks for good when a signal is ending the process: its watcher deletes the
/// temporary files, so an error from one (a reopen that finds it gone) is no error of
/// the run, and a writer about to open one by path must not recreate it.
pub(super) fn wait_if_signalled() {
    if SIGNALLED.load(Ordering::SeqCst) {
        loop {
            std::thread::park();
        }
    }
}

/// How the process ends: what its outputs are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Ending {
    /// Temporary outputs were deleted: every old output is as it was.
    PartialRemoved,
    /// A commit renamed the outputs into place and none is pending: they are complete.
    Complete,
    /// No output was under way.
    NoOutput,
}

/// Deletes every registered file and keeps the registry locked for good (no file is
/// created or renamed after); for a process about to end. `wait`: wait for the
/// registry (a commit's renames), else give up (`None`, nothing deleted) when it is
/// busy. `paths` receives the deleted paths (for a second pass: a writer that opened
/// its file by path, as HDF5 does, may recreate it before the process ends).
pub(super) fn clean_for_exit(wait: bool, paths: Option<&mut Vec<PathBuf>>) -> Option<Ending> {
    let state = if wait {
        file_state()
    } else {
        match FILE_STATE.try_lock() {
            Ok(s) => s,
            Err(std::sync::TryLockError::Poisoned(e)) => e.into_inner(),
            Err(std::sync::TryLockError::WouldBlock) => return None,
        }
    };
    for (f, _) in &state.files {
        let _ = fs::remove_file(f);
    }
    if let Some(paths) = paths {
        paths.extend(state.files.iter().map(|(p, _)| p.clone()));
    }
    let ending = if state.files.iter().any(|(_, k)| *k == Kind::Temp) {
        Ending::PartialRemoved
    } else if state.committed {
        Ending::Complete
    } else {
        Ending::NoOutput
    };
    std::mem::forget(state);
    Some(ending)
}

/// For a run ending on an allocation failure (the `NoAbortAllocator` of `resources`):
/// deletes every temporary, lock and scratch file of the process, unless the registry
/// is busy; `true` when a partial output was among them.
pub fn remove_files_for_exit() -> bool {
    clean_for_exit(false, None) == Some(Ending::PartialRemoved)
}

/// Installs handlers for SIGINT, SIGTERM and SIGHUP: a watcher thread waits for a commit
/// in progress to finish its renames, deletes every registered temporary and lock file,
/// prints one line saying what the outputs are and ends the process at once with status
/// 128 + signal (130, 143, 129), without running exit handlers (HDF5's could block on a
/// file another thread is writing). The line is "interrupted by SIGINT; partial output
/// removed" (every old output intact), "interrupted by SIGINT after its outputs were
/// written; they are complete", or "interrupted by SIGINT" (no output under way).
/// Call once, from `main`.
pub fn install_signal_handlers() -> Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])
        .map_err(|e| Error::Unsupported(format!("cannot install signal handlers: {e}")))?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            if let Some(sig) = signals.forever().next() {
                SIGNALLED.store(true, Ordering::SeqCst);
                let mut files = Vec::new();
                let ending = clean_for_exit(true, Some(&mut files)).unwrap_or(Ending::NoOutput);
                let name = match sig {
                    SIGINT => "SIGINT",
                    SIGTERM => "SIGTERM",
                    _ => "SIGHUP",
                };
                let what = match ending {
                    Ending::PartialRemoved => "; partial output removed",
                    Ending::Complete => " after its outputs were written; they are complete",
                    Ending::NoOutput => "",
                };
                crate::tell!("\nlidarsim: interrupted by {name}{what}");
                for f in &files {
                    let _ = fs::remove_file(f);
                }
                signal_hook::low_level::exit(128 + sig);
            }
        })
        .map_err(|e| Error::Unsupported(format!("cannot start the signal thread: {e}")))?;
    Ok(())
}
