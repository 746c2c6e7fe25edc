//! Writers: the `expect` CSV and terminal table, the S/N map, the raw HDF5 file.
//! Every file is written under a temporary name and renamed when complete.

pub mod expect;
pub mod raw_file;
pub mod snr_map;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

/// The temporary name a file is written under before it is renamed to `path`:
/// `.NAME.partial-PID-SEQ` in the same directory (SEQ keeps two writers of one process
/// apart); `None` when `path` names no file.
pub fn partial_path(path: &Path) -> Option<PathBuf> {
    static SEQ: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name()?.to_string_lossy();
    let seq = SEQ.fetch_add(1, Ordering::Relaxed);
    Some(path.with_file_name(format!(".{name}.partial-{}-{seq}", std::process::id())))
}

/// Writes `path` through `fill`, complete or not at all: into a temporary file in the
/// same directory, renamed over `path` only when `fill` succeeded.
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let tmp = partial_path(path).ok_or_else(|| Error::output(path, "not a file name"))?;
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let result = (|| {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        fill(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io_err)
}
