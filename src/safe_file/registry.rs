//! The registry of the files this process deletes if a signal ends it (temporary
//! outputs, locks, scratch files), and the scratch file itself.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::paths::parent_dir;

/// An intermediate file of a command (e.g. the raw file an SCC export is made from):
/// hidden beside an output, deleted when dropped and if a signal ends the process.
pub struct ScratchFile {
    path: PathBuf,
}

impl ScratchFile {
    /// A scratch path `.NAME.SUFFIX-PID` beside `output` (nothing is created).
    pub fn beside(output: &Path, suffix: &str) -> ScratchFile {
        let name = output
            .file_name()
            .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        let path = parent_dir(output).join(format!(".{name}.{suffix}-{}", std::process::id()));
        register(&path, Kind::Scratch);
        ScratchFile { path }
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for ScratchFile {
    fn drop(&mut self) {
        let _ = fs::remove_file(&self.path);
        unregister(&self.path);
    }
}

/// What a file of the registry is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    /// The temporary stand-in of an output not yet committed.
    Temp,
    /// The lock file of an output.
    Lock,
    /// An intermediate file of the command ([`ScratchFile`]).
    Scratch,
}

/// The files this process deletes if a signal ends it (temporary outputs, lock files,
/// scratch files), and whether a commit renamed outputs into place.
///
/// Every creation of a registered file and every commit's renames happen while this
/// state is locked; the signal watcher locks it before it deletes anything and never
/// unlocks it (the process ends). So a signal either comes before a creation or rename
/// (which then never happens) or after it (and sees its result).
pub(super) struct FileState {
    pub(super) files: Vec<(PathBuf, Kind)>,
    pub(super) committed: bool,
}

pub(super) static FILE_STATE: Mutex<FileState> = Mutex::new(FileState {
    files: Vec::new(),
    committed: false,
});

pub(super) fn file_state() -> std::sync::MutexGuard<'static, FileState> {
    FILE_STATE.lock().unwrap_or_else(|e| e.into_inner())
}

pub(super) fn register(path: &Path, kind: Kind) {
    file_state().files.push((path.to_path_buf(), kind));
}

/// Registers `path` and runs `create` (which makes the file) under the registry's lock,
/// so that a signal cannot fall between the two; unregisters it when `create` fails.
pub(super) fn create_registered<T>(
    path: &Path,
    kind: Kind,
    create: impl FnOnce() -> io::Result<T>,
) -> io::Result<T> {
    let mut state = file_state();
    state.files.push((path.to_path_buf(), kind));
    let made = create();
    if made.is_err() {
        state.files.retain(|(p, _)| p != path);
    }
    made
}

pub(super) fn unregister(path: &Path) {
    file_state().files.retain(|(p, _)| p != path);
}

pub(super) fn is_registered(path: &Path) -> bool {
    file_state().files.iter().any(|(p, _)| p == path)
}
