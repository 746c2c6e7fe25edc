//! Shard files as `merge` reads them: their root attributes, the kind of shard each is,
//! the lidar of their stored config, the disk their merge needs and what a merge did.

use std::path::{Path, PathBuf};
use std::time::Duration;

use super::cut::Shard;
use crate::error::{Error, Result};
use crate::output::raw_file::content::PRODUCT_ATTRIBUTE;
use crate::scenario::Lidar;

/// The lidar of a config stored in a file (`config`: the resolved TOML; `config_file`:
/// the config's path as the run named it, against which the files it names resolve).
pub fn stored_lidar(config: &str, config_file: &str) -> Result<Lidar> {
    let loaded = crate::loaded::load_str(config, Path::new(config_file), &[])?;
    Lidar::from_loaded(loaded)
}

/// The root attributes of an HDF5 shard file, read with one-line errors naming it.
pub struct FileAttributes<'a> {
    /// The open file.
    pub file: &'a hdf5::File,
    /// Its path, for messages.
    pub path: &'a Path,
}

impl FileAttributes<'_> {
    fn fail(&self, why: String) -> Error {
        Error::output(self.path, why)
    }

    /// A text attribute.
    pub fn text(&self, name: &str) -> Result<String> {
        self.file
            .attr(name)
            .and_then(|a| a.read_scalar::<hdf5::types::VarLenUnicode>())
            .map(|v| v.as_str().to_string())
            .map_err(|_| self.fail(format!("has no text attribute `{name}`")))
    }

    /// A whole-number attribute.
    pub fn number(&self, name: &str) -> Result<u64> {
        self.file
            .attr(name)
            .and_then(|a| a.read_scalar::<u64>())
            .map_err(|_| self.fail(format!("has no whole-number attribute `{name}`")))
    }

    /// A whole-number attribute as a size.
    pub fn whole(&self, name: &str) -> Result<usize> {
        usize::try_from(self.number(name)?).map_err(|_| self.fail(format!("`{name}` too large")))
    }

    /// A real attribute, if present.
    pub fn real(&self, name: &str) -> Option<f64> {
        self.file
            .attr(name)
            .and_then(|a| a.read_scalar::<f64>())
            .ok()
    }

    /// Its shard (`shard_index` of `shard_count`).
    pub fn shard(&self) -> Result<Shard> {
        Shard::new(self.whole("shard_index")?, self.whole("shard_count")?)
            .map_err(|why| self.fail(format!("shard_index/shard_count: {why}")))
    }
}

/// What a shard file is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShardKind {
    /// A raw file of `simulate --shard`.
    Raw,
    /// An onboard product of `onboard --shard`.
    Product,
}

impl ShardKind {
    fn describe(self) -> &'static str {
        match self {
            ShardKind::Raw => "a raw shard (of `simulate --shard`)",
            ShardKind::Product => "a product shard (of `onboard --shard`)",
        }
    }
}

/// Opens the shard file at `path` and says what it is; one line naming the file when it
/// is not HDF5 or not a shard.
pub fn open_shard(path: &Path) -> Result<(hdf5::File, ShardKind)> {
    let fail = |why: &str| Error::output(path, why);
    crate::input_file::check("SHARD.h5", path)?;
    let file = hdf5::File::open(path)
        .map_err(|_| fail("not a lidarsim raw file or product (not HDF5, or unreadable)"))?;
    if file.attr("shard_index").is_err() {
        return Err(fail(
            "not a shard (no `shard_index` attribute): merge takes the files of \
             `simulate --shard K/N` or of `onboard --shard K/N`",
        ));
    }
    let kind = match file.attr(PRODUCT_ATTRIBUTE) {
        Ok(_) => ShardKind::Product,
        Err(_) => ShardKind::Raw,
    };
    Ok((file, kind))
}

/// What the shards given to `merge` are: all raw or all product shards; refuses a file
/// that is no shard, and a mix, naming the file.
pub fn kind_of_shards(paths: &[std::path::PathBuf]) -> Result<ShardKind> {
    let mut first: Option<(&Path, ShardKind)> = None;
    for path in paths {
        let kind = open_shard(path)?.1;
        match first {
            Some((p, k)) if k != kind => {
                return Err(Error::output(
                    path,
                    format!(
                        "{}, but {} is {}: merge raw shards and product shards apart",
                        kind.describe(),
                        p.display(),
                        k.describe()
                    ),
                ));
            }
            None => first = Some((path, kind)),
            _ => {}
        }
    }
    first
        .map(|(_, k)| k)
        .ok_or_else(|| Error::Unsupported("merge needs at least one shard".into()))
}

/// Refuses a merge into `out` where the free space is below the shards' size.
pub fn require_disk_for_merge<'a>(
    out: &Path,
    shards: impl IntoIterator<Item = &'a Path>,
) -> Result<()> {
    let bytes: u64 = shards
        .into_iter()
        .filter_map(|p| std::fs::metadata(p).ok())
        .map(|m| m.len())
        .sum();
    crate::resources::require_disk("OUT.h5", out, bytes as f64)
}

/// What a merge did, for its closing line.
#[derive(Debug, Clone)]
pub struct MergeSummary {
    /// The file written.
    pub output: PathBuf,
    /// Shards merged.
    pub shards: usize,
    /// Profiles (or shots) of the run.
    pub profiles: usize,
    /// What `profiles` counts: `profiles` (raw shards) or `shots` (product shards).
    pub what: &'static str,
    /// What was written: `file` (raw) or `product`.
    pub file: &'static str,
    /// Wall time.
    pub elapsed: Duration,
}

impl std::fmt::Display for MergeSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Merged {} shards into {}: {} {}, the {} of the whole run; {:.3} s.",
            self.shards,
            self.output.display(),
            self.profiles,
            self.what,
            self.file,
            self.elapsed.as_secs_f64()
        )
    }
}
