//! `lidarsim merge OUT.h5 SHARD.h5 ...`: the shards of one run into the file the whole
//! run writes, byte for byte when `SOURCE_DATE_EPOCH` is set (docs/scale.md).
//!
//! 1. Each shard's root attributes say which run it belongs to and which profiles it
//!    holds ([`crate::shard::SHARD_ATTRIBUTES`]); shards of different runs, a gap, an
//!    overlap or a file that is not a shard are refused, naming the file.
//! 2. The whole run's [`RawFileSpec`] is built again from the stored config, seed and
//!    method by [`plan`], the very code `simulate` uses, and its [`run_id`] must be the
//!    shards' (else this lidarsim would write another file).
//! 3. Each shard's rows (counts, components, `time`, `n_shots`, `pulse_energy` and every
//!    per-profile variable) are streamed in order into [`RawFileWriter`], in blocks of
//!    at most [`BLOCK_BYTES`]: memory does not grow with the run.

use std::path::{Path, PathBuf};
use std::time::Instant;

use hdf5::Dataset;
use ndarray::{Ix1, Ix2, Ix3, s};

use super::method::ResolvedMethod;
use super::plan::{RunOptions, RunPlan, plan};
use crate::error::describe_hdf5_error;
use crate::error::{Error, Result};
use crate::output::raw_file::check::RecordShape;
use crate::output::raw_file::{
    COMPONENT_NAMES, Dims, PROFILE_COLUMN_NAMES, ProfileRecord, RawFileSpec, RawFileWriter,
};
use crate::safe_file::{OutputId, Outputs};
use crate::scenario::Lidar;
use crate::shard::{
    FileAttributes, MergeSummary, Piece, RunIdentity, Shard, ShardKind, check_pieces, open_shard,
    require_disk_for_merge, run_id, stored_lidar,
};

/// Bytes of rows read from a shard at once (every per-profile variable together).
pub const BLOCK_BYTES: usize = 8 << 20;

/// A shard file and what its root attributes say of it.
struct ShardFile {
    path: PathBuf,
    file: hdf5::File,
    shard: Shard,
    run_profiles: usize,
    run_id: String,
    /// Its first profile in the run, and its profiles.
    first_profile: usize,
    rows: usize,
    seed: u64,
    method: String,
    config: String,
    config_file: String,
    /// `history` without its date: the command line the run recorded.
    command: String,
    threshold: Option<f64>,
    tolerance: Option<f64>,
    components: bool,
}

impl ShardFile {
    /// Opens `path` and reads its identity; one line naming the file when it is not a
    /// shard of `simulate --shard`.
    fn open(path: &Path) -> Result<ShardFile> {
        let fail = |why: &str| Error::output(path, why);
        let (file, kind) = open_shard(path)?;
        if kind != ShardKind::Raw {
            return Err(fail(
                "a product shard (of `onboard --shard`), not a raw shard",
            ));
        }
        let a = FileAttributes { file: &file, path };
        let (history, created) = (a.text("history")?, a.text("date_created")?);
        let command = history
            .strip_prefix(&format!("{created} "))
            .ok_or_else(|| fail("its `history` does not start with its `date_created`"))?
            .to_string();
        // the same checks as every reader of raw files (`curtain`, `export-scc`)
        let header = crate::output::raw_file::read::check(path, &file)?;
        let version = crate::output::raw_file::FORMAT_VERSION;
        if header.format_version != i64::from(version) {
            return Err(Error::output(
                path,
                format!(
                    "a shard of format version {}; this lidarsim writes format {version}: \
                     merge with the lidarsim that wrote the shards",
                    header.format_version
                ),
            ));
        }
        let rows = header.n_profiles;
        Ok(ShardFile {
            shard: a.shard()?,
            run_profiles: a.whole("run_profiles")?,
            run_id: a.text("run_id")?,
            first_profile: a.whole("shard_first_profile")?,
            rows,
            seed: a.number("seed")?,
            method: a.text("method")?,
            config: a.text("config")?,
            config_file: a.text("config_file")?,
            command,
            threshold: a.real("normal_approximation_threshold"),
            tolerance: a.real("tolerance_ks"),
            components: file.dataset(COMPONENT_NAMES[0]).is_ok(),
            path: path.to_path_buf(),
            file,
        })
    }

    /// It as a piece of its run.
    fn piece(&self) -> Piece<'_> {
        Piece {
            path: &self.path,
            identity: RunIdentity {
                config: self.config.clone(),
                seed: self.seed,
                method: self.method.clone(),
                shard_count: self.shard.count,
                total: self.run_profiles,
                run_id: self.run_id.clone(),
            },
            shard_index: self.shard.index,
            rows: self.first_profile..self.first_profile + self.rows,
        }
    }

    /// The options that make `simulate` plan this shard's run again.
    fn run_options(&self, output: &Path) -> Result<(RunOptions, ResolvedMethod)> {
        let method = ResolvedMethod::from_name(&self.method, self.threshold).ok_or_else(|| {
            Error::output(&self.path, format!("unknown method `{}`", self.method))
        })?;
        let opts = RunOptions {
            output: output.to_path_buf(),
            seed: Some(self.seed),
            profiles: Some(self.run_profiles),
            components: Some(self.components),
            tolerance: self.tolerance,
            command_line: self.command.clone(),
            ..Default::default()
        };
        Ok((opts, method))
    }
}

/// A merge checked and planned, ready to write: the shards in the run's order, and the
/// whole run as `simulate` would draw it.
pub struct Merge {
    files: Vec<ShardFile>,
    order: Vec<usize>,
    /// The run's lidar, from the shards' stored config.
    pub lidar: Lidar,
    plan: RunPlan,
    out: PathBuf,
    start: Instant,
}

/// The first half of `lidarsim merge OUT SHARD...`: checks that `shards` are one run's,
/// each once, and rebuilds that run's file layout (nothing written yet).
pub fn prepare(out: &Path, shards: &[PathBuf]) -> Result<Merge> {
    let start = Instant::now();
    let files = shards
        .iter()
        .map(|p| ShardFile::open(p))
        .collect::<Result<Vec<_>>>()?;
    let Some(first) = files.first() else {
        return Err(Error::Unsupported("merge needs at least one shard".into()));
    };
    let pieces: Vec<Piece> = files.iter().map(ShardFile::piece).collect();
    let order = check_pieces(&pieces, "shard", "profiles", |s| s.rows(first.run_profiles))?;
    let lidar = stored_lidar(&first.config, &first.config_file)?;
    let (opts, method) = first.run_options(out)?;
    let plan = plan(&lidar, &opts, Some(method))?;
    let rebuilt = run_id(&plan.spec);
    if rebuilt != first.run_id {
        return Err(Error::output(
            &first.path,
            format!(
                "this lidarsim cannot rebuild its run: the file it would write differs from \
                 the shards' (run_id {rebuilt} vs {}): another lidarsim version, or a file \
                 the config {} names changed or read from another directory; merge with the \
                 lidarsim that wrote the shards, where they ran",
                first.run_id, first.config_file
            ),
        ));
    }
    Ok(Merge {
        files,
        order,
        lidar,
        plan,
        out: out.to_path_buf(),
        start,
    })
}

impl Merge {
    /// Writes the whole run's raw file as output `id` of `outputs` (complete or absent,
    /// through [`crate::safe_file`]), streaming the shards' rows in order.
    pub fn write(self, outputs: Outputs, id: OutputId) -> Result<MergeSummary> {
        require_disk_for_merge(&self.out, self.files.iter().map(|f| f.path.as_path()))?;
        let spec = &self.plan.spec;
        let mut writer = RawFileWriter::create(outputs.temp_path(id)?, &self.out, spec)?;
        match &self.plan.scene {
            None => {
                for &i in &self.order {
                    let f = &self.files[i];
                    copy_rows(f, spec, &mut writer, 0..f.rows)?;
                }
            }
            Some(_) => self.write_scene(spec, &mut writer)?,
        }
        writer.finish()?;
        outputs.commit()?;
        Ok(MergeSummary {
            output: self.out,
            shards: self.files.len(),
            profiles: self.plan.profiles,
            what: "profiles",
            file: "file",
            elapsed: self.start.elapsed(),
        })
    }
}

impl Merge {
    /// A changing scene's file: batch by batch as `simulate` writes it (the same batches,
    /// [`super::draw::run_batch`]), the columns the batch's profiles see first (their
    /// truth built again, as the run built it), then its profiles from the shards; at
    /// the end the columns no profile sees. The same writes in the same order: the same
    /// bytes as the whole run's file.
    fn write_scene(&self, spec: &RawFileSpec, writer: &mut RawFileWriter) -> Result<()> {
        let Some(sc) = &self.plan.scene else {
            return Ok(());
        };
        let (lidar, plan) = (&self.lidar, &self.plan);
        let layout = crate::output::raw_file::content::TruthLayout::of(lidar, true, plan.truth);
        let shots = lidar.first().shots_per_profile();
        let rows_of = |c: &super::scene::BuiltColumn| {
            crate::output::raw_file::content::column_rows(
                lidar,
                &plan.expected,
                &c.expected,
                &sc.aerosol_species,
                shots,
                layout,
            )
        };
        let put = |writer: &mut RawFileWriter, i: usize, c: &super::scene::BuiltColumn| {
            let rows = rows_of(c);
            let rows: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
            writer.write_column(i, &rows)
        };
        let batch = super::draw::run_batch(lidar, plan);
        for a in (0..plan.profiles).step_by(batch) {
            let b = (a + batch).min(plan.profiles);
            for (i, c) in sc.prepare(lidar, a as u64..b as u64)? {
                put(writer, i, &c)?;
            }
            for &k in &self.order {
                let f = &self.files[k];
                let (lo, hi) = (a.max(f.first_profile), b.min(f.first_profile + f.rows));
                if lo < hi {
                    copy_rows(f, spec, writer, lo - f.first_profile..hi - f.first_profile)?;
                }
            }
        }
        sc.for_unseen(lidar, |i, c| put(writer, i, c))
    }
}

/// One shard's datasets of per-profile rows, in the order a [`ProfileRecord`] takes them.
struct RowSources {
    counts: Dataset,
    components: Vec<Dataset>,
    time: Dataset,
    n_shots: Dataset,
    pulse_energy: Dataset,
    /// The spec's per-profile variables, with their dimensions.
    values: Vec<(Dataset, Dims)>,
    /// `profile_column` and `profile_column_weight`, if the run has column slots.
    profile_columns: Option<(Dataset, Dataset)>,
}

impl RowSources {
    /// The datasets of `f` that `spec` writes per profile, checked against its shape.
    fn of(f: &ShardFile, spec: &RawFileSpec) -> Result<RowSources> {
        let get = |name: &str| {
            f.file.dataset(name).map_err(|_| {
                Error::output(&f.path, format!("has no `{name}`: not a shard of this run"))
            })
        };
        let counts = get("counts")?;
        let want = vec![f.rows, spec.channels.len(), spec.n_bins];
        if counts.shape() != want {
            return Err(Error::output(
                &f.path,
                format!(
                    "`counts` is {:?}, the run's shard is {want:?}",
                    counts.shape()
                ),
            ));
        }
        let components = match spec.components {
            true => COMPONENT_NAMES
                .iter()
                .map(|n| get(n))
                .collect::<Result<_>>()?,
            false => vec![],
        };
        let values = spec
            .variables
            .iter()
            .filter(|v| v.dims.per_profile())
            .map(|v| get(&v.name).map(|d| (d, v.dims)))
            .collect::<Result<_>>()?;
        let profile_columns = match spec.column_slots {
            0 => None,
            _ => Some((get(PROFILE_COLUMN_NAMES[0])?, get(PROFILE_COLUMN_NAMES[1])?)),
        };
        Ok(RowSources {
            counts,
            components,
            profile_columns,
            time: get("time")?,
            n_shots: get("n_shots")?,
            pulse_energy: get("pulse_energy")?,
            values,
        })
    }
}

/// Streams rows `rows` of shard `f` into `writer`, block by block, at their rows of the
/// run.
fn copy_rows(
    f: &ShardFile,
    spec: &RawFileSpec,
    writer: &mut RawFileWriter,
    rows: std::ops::Range<usize>,
) -> Result<()> {
    let src = RowSources::of(f, spec)?;
    let shape = RecordShape::of(spec);
    let n = spec.counts_per_profile();
    let wide = 1 + src.components.len() + src.values.len();
    let block = (BLOCK_BYTES / (8 * n * wide).max(1)).max(1);
    let fail = |e: hdf5::Error| {
        Error::output(
            &f.path,
            format!("cannot read: {}", describe_hdf5_error(&e.to_string())),
        )
    };
    for a in rows.clone().step_by(block) {
        let b = (a + block).min(rows.end);
        let rows3 = |d: &Dataset| d.read_slice::<u64, _, Ix3>(s![a..b, .., ..]);
        let rows3f = |d: &Dataset| d.read_slice::<f64, _, Ix3>(s![a..b, .., ..]);
        let rows1 = |d: &Dataset| d.read_slice::<f64, _, Ix1>(s![a..b]);
        let counts = rows3(&src.counts).map_err(fail)?.into_raw_vec();
        let parts: Vec<Vec<u64>> = src
            .components
            .iter()
            .map(|d| rows3(d).map(|x| x.into_raw_vec()))
            .collect::<hdf5::Result<_>>()
            .map_err(fail)?;
        let time = rows1(&src.time).map_err(fail)?.into_raw_vec();
        let shots = src
            .n_shots
            .read_slice::<u64, _, Ix1>(s![a..b])
            .map_err(fail)?
            .into_raw_vec();
        let energy = src
            .pulse_energy
            .read_slice::<f64, _, Ix2>(s![a..b, ..])
            .map_err(fail)?
            .into_raw_vec();
        let ch = spec.channels.len();
        let values: Vec<(Vec<f64>, usize)> = src
            .values
            .iter()
            .map(|(d, dims)| match dims {
                Dims::Profile => rows1(d).map(|x| (x.into_raw_vec(), 1)),
                Dims::ProfileChannel => d
                    .read_slice::<f64, _, Ix2>(s![a..b, ..])
                    .map(|x| (x.into_raw_vec(), ch)),
                _ => rows3f(d).map(|x| (x.into_raw_vec(), n)),
            })
            .collect::<hdf5::Result<_>>()
            .map_err(fail)?;
        let k = spec.column_slots;
        let (columns, weights) = match &src.profile_columns {
            Some((c, w)) => (
                c.read_slice::<i32, _, Ix2>(s![a..b, ..])
                    .map_err(fail)?
                    .into_raw_vec(),
                w.read_slice::<f64, _, Ix2>(s![a..b, ..])
                    .map_err(fail)?
                    .into_raw_vec(),
            ),
            None => (vec![], vec![]),
        };
        for r in 0..b - a {
            let row_values: Vec<&[f64]> = values.iter().map(|(v, w)| row(v, r, *w)).collect();
            let record = ProfileRecord {
                index: f.first_profile + a + r,
                time_s: time[r],
                n_shots: shots[r],
                pulse_energy_j: row(&energy, r, ch),
                counts: row(&counts, r, n),
                components: match &parts[..] {
                    [s, bg, d] => Some([row(s, r, n), row(bg, r, n), row(d, r, n)]),
                    _ => None,
                },
                values: &row_values,
                columns: row(&columns, r, k),
                column_weights: row(&weights, r, k),
            };
            // a shard's bad row is the shard's fault: named there, not as the output's
            shape
                .check(&record)
                .map_err(|why| Error::output(&f.path, format!("row {}: {why}", a + r)))?;
            writer.write_profile(&record)?;
        }
    }
    Ok(())
}

/// Row `r` of rows of `width` values laid end to end.
fn row<T>(rows: &[T], r: usize, width: usize) -> &[T] {
    &rows[r * width..(r + 1) * width]
}
