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

use super::report::Report;
use super::run::{Sums, ValidateOptions, Validation};
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

/// Reads a partial; one line naming the file when it is not one, when its realizations
/// are beyond `--realizations`' range or not within the run, or when its sums are
/// impossible ([`impossible_sums`]).
pub fn read(path: &Path) -> Result<Partial> {
    let p: Partial = read_partial(path, PARTIAL_FORMAT, "validate --shard K/N --partial")?;
    let max = crate::limits::MAX_REALIZATIONS;
    if p.realizations as u64 > max || p.first > p.end || p.end > p.realizations {
        return Err(Error::output(
            path,
            format!(
                "`first` {}, `end` {} and `realizations` {} are not realizations first..end \
                 of a run of at most {max}",
                p.first, p.end, p.realizations
            ),
        ));
    }
    if let Some(why) = impossible_sums(&p.sums, p.end - p.first) {
        return Err(Error::output(
            path,
            format!("impossible sums (a damaged or edited partial): {why}"),
        ));
    }
    Ok(p)
}

/// Why `sums` cannot be the sums of `n` realizations, naming the field; `None` when they
/// can be. Of whole counts `c ≥ 0` (and whole `u`): `Σc ≤ Σc² ≤ (Σc)²`, `|Σu| ≤ Σu²`,
/// and (Cauchy–Schwarz: a variance is not negative) `(Σc)² ≤ n·Σc²`, `(Σu)² ≤ n·Σu²`.
/// Of a changing scene, every floating-point sum finite and ≥ 0
/// ([`super::scene::Sums::impossible`]).
pub fn impossible_sums(sums: &Sums, n: usize) -> Option<String> {
    match sums {
        Sums::Identical(bins) => bins.iter().enumerate().find_map(|(b, s)| {
            impossible_bin(s, n as u128).map(|why| format!("`sums.bins[{b}]`: {why}"))
        }),
        Sums::Changing(bins) => bins
            .iter()
            .enumerate()
            .find_map(|(b, s)| s.impossible().map(|why| format!("`sums.bins[{b}]`: {why}"))),
    }
}

/// [`impossible_sums`] of one bin's sums over `n` realizations.
fn impossible_bin(s: &super::bins::BinSums, n: u128) -> Option<String> {
    let square = |x: u128| x.checked_mul(x);
    // (Σx)² ≤ n·Σx²; where a product overflows, in f64 (ample for a refusal)
    let cauchy = |sum: u128, squares: u128| match (square(sum), n.checked_mul(squares)) {
        (Some(a), Some(b)) => a <= b,
        (None, Some(_)) => false,
        _ => (sum as f64).powi(2) <= n as f64 * squares as f64,
    };
    let u_abs = s.u.unsigned_abs();
    if s.squares < s.total {
        Some(format!(
            "`squares` {} is less than `total` {}, but Σc² ≥ Σc for whole counts",
            s.squares, s.total
        ))
    } else if square(s.total).is_some_and(|t2| s.squares > t2) {
        Some(format!(
            "`squares` {} is more than `total`² = {}, but Σc² ≤ (Σc)² for counts ≥ 0",
            s.squares,
            s.total * s.total
        ))
    } else if !cauchy(s.total, s.squares) {
        Some(format!(
            "`total` {} and `squares` {} of {n} realizations make a negative variance",
            s.total, s.squares
        ))
    } else if s.u_squares < u_abs {
        Some(format!(
            "`u_squares` {} is less than |`u`| = {u_abs}, but Σu² ≥ |Σu| for whole u",
            s.u_squares
        ))
    } else if !cauchy(u_abs, s.u_squares) {
        Some(format!(
            "`u` {} and `u_squares` {} of {n} realizations make a negative variance",
            s.u, s.u_squares
        ))
    } else {
        None
    }
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

#[cfg(test)]
mod tests {
    use super::super::bins::BinSums;
    use super::*;

    fn sums_of(counts: &[u64], background: &[u64], n_b: usize) -> BinSums {
        let mut s = BinSums::default();
        counts
            .iter()
            .zip(background)
            .for_each(|(&c, &b)| s.push(c, b, n_b));
        s
    }

    #[test]
    fn sums_of_real_counts_are_possible() {
        let s = sums_of(&[0, 3, 7, 7, 12], &[4, 8, 0, 30, 9], 3);
        assert_eq!(impossible_sums(&Sums::Identical(vec![s; 4]), 5), None);
        // all counts equal: variance exactly 0, on the Cauchy–Schwarz boundary
        let s = sums_of(&[5, 5, 5], &[15, 15, 15], 3);
        assert_eq!(impossible_bin(&s, 3), None);
        assert_eq!(impossible_bin(&BinSums::default(), 0), None);
    }

    #[test]
    fn impossible_sums_are_named() {
        let s = sums_of(&[0, 3, 7, 7, 12], &[4, 8, 0, 30, 9], 3);
        let edit = |f: &dyn Fn(&mut BinSums)| {
            let mut x = s;
            f(&mut x);
            impossible_sums(&Sums::Identical(vec![s, x]), 5).unwrap_or_default()
        };
        // Σc = 29, Σc² = 251: (Σc)² = 841 ≤ 5·251 = 1255; with n = 3, 753 < 841
        assert!(
            impossible_sums(&Sums::Identical(vec![s]), 3)
                .unwrap()
                .contains("negative variance")
        );
        assert!(edit(&|x| x.squares = 28).contains("`sums.bins[1]`: `squares` 28 is less"));
        assert!(edit(&|x| x.squares = 842).contains("more than `total`²"));
        assert!(edit(&|x| x.squares = 168).contains("negative variance"));
        assert!(edit(&|x| x.u_squares = 0).contains("`u_squares` 0"));
        assert_eq!(edit(&|x| x.squares = 169), "");
    }
}
