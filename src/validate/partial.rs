//! `validate` at scale: `validate --shard K/N --partial PART.json` draws shard K's
//! realizations (`⌊K·R/N⌋ … ⌊(K+1)·R/N⌋ − 1` of R, [`crate::shard::Shard::rows`]) and
//! writes their sufficient statistics; `validate --combine PART.json ...` adds the
//! partials of every shard and judges them: exactly the single run's report, because
//! the sums are exact ([`super::exact`]) and the run is set up again from the stored
//! config by the same [`Validation::new`].
//!
//! The partial (JSON) holds the run's identity (`run_id`, a hash of the resolved config,
//! its file name, seed, method, realizations and lidarsim version; and each of them),
//! the shard and its realizations, and the per-bin sums.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{Report, Sums, ValidateOptions, Validation};
use crate::config::Method;
use crate::error::{Error, Result};
use crate::scenario::Lidar;
use crate::shard::{
    Piece, RunIdentity, Shard, check_pieces, fingerprint, read_partial, stored_lidar,
};

/// `format` of the partials this version writes.
pub const PARTIAL_FORMAT: &str = "lidarsim validate partial 1";

/// The sufficient statistics of one shard of a validation, with the run's identity.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Partial {
    /// [`PARTIAL_FORMAT`].
    pub format: String,
    /// `lidarsim <version>` that drew it.
    pub source: String,
    /// The run's identity ([`run_id`]).
    pub run_id: String,
    /// The resolved config (TOML, after every `--set`).
    pub config: String,
    /// The config file as named on the command line.
    pub config_file: String,
    /// Seed of the draws.
    pub seed: u64,
    /// `--method` as given (`None`: the config's `simulation.method`).
    pub method_option: Option<Method>,
    /// The method used.
    pub method: String,
    /// Realizations of the whole run.
    pub realizations: usize,
    /// K.
    pub shard_index: usize,
    /// N.
    pub shard_count: usize,
    /// The realizations drawn, `first .. end`.
    pub first: usize,
    /// One past the last realization drawn.
    pub end: usize,
    /// Their sums.
    pub sums: Sums,
}

/// The identity of a validation run.
pub fn run_id(v: &Validation, lidar: &Lidar) -> String {
    let loaded = &lidar.first().loaded;
    fingerprint(&[
        &source(),
        &loaded.resolved_toml,
        &loaded.path.display().to_string(),
        &v.seed.to_string(),
        v.method.name(),
        &v.realizations.to_string(),
    ])
}

fn source() -> String {
    format!("lidarsim {}", env!("CARGO_PKG_VERSION"))
}

/// Draws shard `shard` of the validation of `lidar` and returns its partial.
pub fn partial(lidar: &Lidar, opts: &ValidateOptions, shard: Shard) -> Result<Partial> {
    let v = Validation::new(lidar, opts)?;
    let rows = shard.rows_of(opts.realizations, "realizations")?;
    v.check_sizes(rows.len())?;
    let sums = v.draw(rows.clone());
    let loaded = &lidar.first().loaded;
    Ok(Partial {
        format: PARTIAL_FORMAT.into(),
        source: source(),
        run_id: run_id(&v, lidar),
        config: loaded.resolved_toml.clone(),
        config_file: loaded.path.display().to_string(),
        seed: v.seed,
        method_option: opts.method,
        method: v.method.name().into(),
        realizations: opts.realizations,
        shard_index: shard.index,
        shard_count: shard.count,
        first: rows.start,
        end: rows.end,
        sums,
    })
}

/// Reads a partial; one line naming the file when it is not one.
pub fn read(path: &Path) -> Result<Partial> {
    read_partial(path, PARTIAL_FORMAT, "validate --shard K/N --partial")
}

impl Partial {
    /// It as a piece of its run.
    fn piece<'a>(&self, path: &'a Path) -> Piece<'a> {
        Piece {
            path,
            identity: RunIdentity {
                config: self.config.clone(),
                seed: self.seed,
                method: self.method.clone(),
                shard_count: self.shard_count,
                total: self.realizations,
                run_id: self.run_id.clone(),
            },
            shard_index: self.shard_index,
            rows: self.first..self.end,
        }
    }
}

/// `validate --combine PART.json ...`: the report of the whole run from the partials of
/// all its shards, each once; and the files its stored config read (inputs no output may
/// replace).
pub fn combine(paths: &[PathBuf]) -> Result<(Report, Vec<PathBuf>)> {
    let parts = paths.iter().map(|p| read(p)).collect::<Result<Vec<_>>>()?;
    let (Some(first_path), Some(first)) = (paths.first(), parts.first()) else {
        return Err(Error::Unsupported(
            "--combine needs at least one partial".into(),
        ));
    };
    let pieces: Vec<Piece> = paths
        .iter()
        .zip(&parts)
        .map(|(path, p)| p.piece(path))
        .collect();
    let order = check_pieces(&pieces, "partial", "realizations", |s| {
        s.rows(first.realizations)
    })?;
    let lidar = stored_lidar(&first.config, &first.config_file)?;
    let opts = ValidateOptions {
        realizations: first.realizations,
        method: first.method_option,
        seed: Some(first.seed),
        json: None,
    };
    let v = Validation::new(&lidar, &opts)?;
    if run_id(&v, &lidar) != first.run_id {
        return Err(Error::output(
            first_path,
            "this lidarsim cannot set its run up again (another version, or another config \
             path or method resolution): combine with the lidarsim that drew it",
        ));
    }
    let mut sums = parts[order[0]].sums.clone();
    for &i in &order[1..] {
        sums.add(&parts[i].sums)
            .map_err(|why| Error::output(&paths[i], why))?;
    }
    Ok((v.report(&sums)?, lidar.first().loaded.files_read()))
}
