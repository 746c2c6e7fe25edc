//! The report of an onboard run in shards: `onboard --shard K/N --partial PART.json`
//! writes the shard's report sums ([`SchemeSums`], exact) with the run's identity, and
//! `onboard --combine PART.json ... [--report PATH]` adds the partials of every shard
//! and writes exactly the report the single run's `--report` writes: the run is set up
//! again from the stored config, seed and schemes, and the sums do not depend on the
//! order of their terms ([`super::report`]).

use std::io::Write;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::Scheme;
use super::identity::{METHOD, source};
use super::native::NativeRun;
use super::report::SchemeSums;
use super::shard::shard_shots;
use crate::error::{Error, Result};
use crate::shard::{Piece, RunIdentity, Shard, check_pieces, read_partial, stored_lidar};

/// `format` of the partials this version writes.
pub const PARTIAL_FORMAT: &str = "lidarsim onboard partial 1";

/// The report sums of one shard of an onboard run, with the run's identity.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct OnboardPartial {
    /// [`PARTIAL_FORMAT`].
    pub format: String,
    /// `lidarsim <version>` that drew it.
    pub source: String,
    /// The run's identity ([`NativeRun::run_id`]).
    pub run_id: String,
    /// The resolved config of the native run (TOML).
    pub config: String,
    /// The config file as named on the command line.
    pub config_file: String,
    /// Seed of the draws.
    pub seed: u64,
    /// Every scheme, as parsed (a scheme file is not read again).
    pub schemes: Vec<Scheme>,
    /// Bits per downlinked count.
    pub word_bits: u32,
    /// Shots of the whole run.
    pub shots: u64,
    /// K.
    pub shard_index: usize,
    /// N.
    pub shard_count: usize,
    /// The shots drawn, `first_shot .. end_shot`.
    pub first_shot: u64,
    /// One past the last shot drawn.
    pub end_shot: u64,
    /// Every scheme's sums over them.
    pub sums: Vec<SchemeSums>,
}

impl OnboardPartial {
    /// The partial of `shots`, shard `shard` of `native`.
    pub fn new(
        native: &NativeRun,
        word_bits: u32,
        shard: Shard,
        shots: Range<u64>,
        sums: Vec<SchemeSums>,
    ) -> Self {
        let loaded = &native.lidar.first().loaded;
        OnboardPartial {
            format: PARTIAL_FORMAT.into(),
            source: source(),
            run_id: native.run_id(word_bits),
            config: loaded.resolved_toml.clone(),
            config_file: loaded.path.display().to_string(),
            seed: native.seed,
            schemes: native.schemes.clone(),
            word_bits,
            shots: native.shots,
            shard_index: shard.index,
            shard_count: shard.count,
            first_shot: shots.start,
            end_shot: shots.end,
            sums,
        }
    }

    /// Writes it as one line of JSON.
    pub fn write(&self, w: &mut dyn Write) -> std::io::Result<()> {
        serde_json::to_writer(&mut *w, self).map_err(std::io::Error::other)?;
        writeln!(w)
    }

    /// It as a piece of its run.
    fn piece<'a>(&self, path: &'a Path) -> Piece<'a> {
        Piece {
            path,
            identity: RunIdentity {
                config: self.config.clone(),
                seed: self.seed,
                method: METHOD.into(),
                shard_count: self.shard_count,
                total: self.shots as usize,
                run_id: self.run_id.clone(),
            },
            shard_index: self.shard_index,
            rows: self.first_shot as usize..self.end_shot as usize,
        }
    }
}

/// Reads a partial; one line naming the file when it is not one, when its shots are not
/// within the run, or when its sums are impossible ([`impossible_sums`]).
pub fn read(path: &Path) -> Result<OnboardPartial> {
    let p: OnboardPartial = read_partial(path, PARTIAL_FORMAT, "onboard --shard K/N --partial")?;
    if p.first_shot > p.end_shot || p.end_shot > p.shots {
        return Err(Error::output(
            path,
            format!(
                "`first_shot` {} and `end_shot` {} are not shots of its run's {} `shots`",
                p.first_shot, p.end_shot, p.shots
            ),
        ));
    }
    if p.sums.len() != p.schemes.len() {
        return Err(Error::output(
            path,
            format!("{} `sums` for {} `schemes`", p.sums.len(), p.schemes.len()),
        ));
    }
    if let Some(why) = impossible_sums(&p.sums) {
        return Err(Error::output(
            path,
            format!("impossible sums (a damaged or edited partial): {why}"),
        ));
    }
    Ok(p)
}

/// Why `sums` cannot be sums of downlinked counts, naming the field; `None` when they
/// can be. Of `n` whole counts `c ≥ 0`: `Σc ≤ Σc² ≤ (Σc)²` and (Cauchy–Schwarz: a
/// variance is not negative) `(Σc)² ≤ n·Σc²`; at most `n` biases, their sum finite.
pub fn impossible_sums(sums: &[SchemeSums]) -> Option<String> {
    for (i, scheme) in sums.iter().enumerate() {
        for (k, region) in scheme.regions.iter().enumerate() {
            for (b, s) in region.iter().enumerate() {
                let n = u128::from(s.n);
                let why = if s.squares < s.counts {
                    Some(format!(
                        "`squares` {} is less than `counts` {}",
                        s.squares, s.counts
                    ))
                } else if s
                    .counts
                    .checked_mul(s.counts)
                    .is_some_and(|c2| s.squares > c2)
                {
                    Some(format!(
                        "`squares` {} is more than `counts`² (counts are ≥ 0)",
                        s.squares
                    ))
                } else if match (s.counts.checked_mul(s.counts), n.checked_mul(s.squares)) {
                    (Some(a), Some(b)) => a > b,
                    (None, Some(_)) => true,
                    _ => (s.counts as f64).powi(2) > n as f64 * s.squares as f64,
                } {
                    Some(format!(
                        "`counts` {} and `squares` {} of `n` = {} profiles make a negative \
                         variance",
                        s.counts, s.squares, s.n
                    ))
                } else if s.biased > s.n {
                    Some(format!("`biased` {} is more than `n` {}", s.biased, s.n))
                } else if !s.bias.is_finite() || !s.bias.value().is_finite() {
                    Some("`bias` is not finite".to_string())
                } else {
                    None
                };
                if let Some(why) = why {
                    return Some(format!("`sums[{i}].regions[{k}][{b}]`: {why}"));
                }
            }
        }
    }
    None
}

/// The whole run set up again from a partial: one line naming it when this lidarsim
/// would set it up differently (another version, config path or model).
fn native_of(path: &Path, p: &OnboardPartial) -> Result<NativeRun> {
    let lidar = stored_lidar(&p.config, &p.config_file)?;
    let native = NativeRun::new(lidar, p.seed, p.schemes.clone())?;
    if native.run_id(p.word_bits) != p.run_id || native.shots != p.shots {
        return Err(Error::output(
            path,
            "this lidarsim cannot set its run up again (another version, or a file the \
             config names changed or read from another directory): combine with the \
             lidarsim that drew it, where it ran",
        ));
    }
    Ok(native)
}

/// `onboard --combine PART.json ...`: the whole run and its report sums from the partials
/// of all its shards, each once; and the word size of the report.
pub fn combine(paths: &[PathBuf]) -> Result<(NativeRun, Vec<SchemeSums>, u32)> {
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
    let native = native_of(first_path, first)?;
    let frame = native.frame_shots().unwrap_or(0);
    let rows = |s: Shard| {
        let r = shard_shots(s, first.shots, frame);
        r.start as usize..r.end as usize
    };
    let order = check_pieces(&pieces, "partial", "shots", rows)?;
    let mut sums: Vec<SchemeSums> = native.layouts.iter().map(|l| SchemeSums::new(l)).collect();
    for i in order {
        if sums.len() != parts[i].sums.len() {
            return Err(Error::output(
                &paths[i],
                "its schemes differ from the run's",
            ));
        }
        for (a, b) in sums.iter_mut().zip(&parts[i].sums) {
            a.add(b).map_err(|why| Error::output(&paths[i], why))?;
        }
    }
    Ok((native, sums, first.word_bits))
}
