//! Writers: the `expect` CSV and terminal table, the S/N map, the raw HDF5 file.
//! Every output goes through [`safe_file`]: one rule for temporary names, renames,
//! locks, special files, standard output and signals.

pub mod expect;
pub mod raw_file;
pub mod safe_file;
pub mod snr_map;

use std::path::{Path, PathBuf};

/// The temporary name a raw file is written under (kept until the raw-file writer takes
/// its path from [`safe_file`]).
pub fn partial_path(path: &Path) -> Option<PathBuf> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static SEQ: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name()?.to_string_lossy();
    let seq = SEQ.fetch_add(1, Ordering::Relaxed);
    Some(path.with_file_name(format!(".{name}.partial-{}-{seq}", std::process::id())))
}
