//! The paths of an output: its temporary stand-in, its siblings, the files it must not
//! be (inputs, by device and inode), its symbolic links followed.

use std::fs;
use std::io;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The temporary name a file is written under before it is renamed to `target`:
/// `.NAME.partial-PID-SEQ` in the same directory (SEQ keeps two writers of one process
/// apart).
pub(super) fn partial_path(target: &Path) -> PathBuf {
    static SEQ: AtomicU64 = AtomicU64::new(0);
    let seq = SEQ.fetch_add(1, Ordering::Relaxed);
    sibling(
        target,
        "",
        &format!(".partial-{}-{seq}", std::process::id()),
    )
}

/// `.NAME<suffix>` beside `target`.
pub(super) fn sibling(target: &Path, prefix: &str, suffix: &str) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    target.with_file_name(format!(".{prefix}{name}{suffix}"))
}

/// (device, inode, path) of each of `inputs` that exists, links followed.
pub(super) fn identify<'a>(inputs: impl IntoIterator<Item = &'a Path>) -> Vec<(u64, u64, PathBuf)> {
    inputs
        .into_iter()
        .filter_map(|p| fs::metadata(p).ok().map(|m| (m.dev(), m.ino(), p.into())))
        .collect()
}

/// Follows symbolic links at the end of `path` (not in its directories, which the OS
/// resolves), up to 40 deep like the kernel; a dangling link gives its target.
pub(super) fn follow_links(path: &Path) -> io::Result<PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let t = fs::read_link(&p)?;
                p = if t.is_absolute() {
                    t
                } else {
                    parent_dir(&p).join(t)
                };
            }
            _ => return Ok(p),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// The directory holding `path` (`.` for a bare file name).
pub fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}
