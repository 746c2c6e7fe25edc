//! `lidarsim onboard`: the run's shots drawn one by one (the shot path, dead time and a
//! changing scene included), summed onboard by every scheme given, the first scheme's
//! product written, and the report of every scheme side by side; or, with `--shard K/N`,
//! the shots of one shard ([`super::shard`]), its product shard and the partial of its
//! report ([`super::partial`]). The native run is `native.rs`, the draw of its shots
//! `draw.rs`, what identifies its product `identity.rs`.

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::draw::{Draw, SchemeRun, draw_shots};
use super::native::NativeRun;
use super::report::{self, SchemeSums};
use super::truth::{ProfileRows, profile_time};
use crate::config::Method;
use crate::error::{Error, Result};
use crate::output::product::ProductWriter;
use crate::safe_file::{OutputId, Outputs, Stream};
use crate::shard::Shard;
use crate::simulate;

/// Options of `lidarsim onboard`.
#[derive(Debug, Clone, Default)]
pub struct OnboardOptions {
    /// `--scheme`, at least one: the first one's product is written.
    pub schemes: Vec<String>,
    /// The product file.
    pub output: PathBuf,
    /// The report CSV (`-` for stdout).
    pub report: Option<PathBuf>,
    /// The native shot-level raw file of the same draw (one shot per profile).
    pub raw: Option<PathBuf>,
    /// Seed (`simulation.seed` when None).
    pub seed: Option<u64>,
    /// Bits per downlinked count, for the data rate.
    pub word_bits: u32,
    /// Draw this shard of the run only (`--shard K/N`).
    pub shard: Option<Shard>,
    /// With `shard`: the partial of the report (`--partial`, JSON).
    pub partial: Option<PathBuf>,
    /// The command line, recorded in the product's `history` (as
    /// [`crate::output::raw_file::content::history_command_omitting`] gives it, with
    /// [`crate::output::raw_file::content::PRODUCT_HISTORY_OMITS`]).
    pub command_line: String,
}

/// Refuses a draw whose memory cannot fit (issue 18: checked before the work): the
/// samplers' tables per channel, per scheme the pending sums (`u64` per native bin and
/// channel) and truth sums (two `f64` per bin) and its report sums, and the batch of
/// drawn shots (4 Mi counts, twice: the batch and its collection).
fn check_memory(native: &NativeRun, schemes: usize) -> Result<()> {
    let first = native.lidar.first();
    let (bins, channels) = (
        first.geometry.n_bins as f64,
        native.lidar.channels.len() as f64,
    );
    let bytes = channels * crate::sampling::table_bytes_bound(first.geometry.n_bins)
        + schemes as f64 * bins * (8.0 * channels + 16.0 + 64.0)
        + 2.0 * 8.0 * (4u64 << 20).max((bins * channels) as u64) as f64;
    let channels = match native.lidar.channels.len() {
        1 => "1 channel".to_string(),
        n => format!("{n} channels"),
    };
    crate::resources::require_memory(
        &format!(
            "the onboard draw of {} bins in {channels}",
            crate::error::compact(bins)
        ),
        bytes,
    )
}

/// Refuses a product whose truth cannot fit: per region, 20 f64 per column, channel and
/// region bin (the truth of every column, built once).
fn check_truth_memory(native: &NativeRun, columns: usize) -> Result<()> {
    let channels = native.lidar.channels.len();
    let bins: usize = native.layouts[0]
        .iter()
        .map(|r| r.bins * r.channel_indices(channels).len())
        .sum();
    crate::resources::require_memory(
        &format!("the product's truth of {columns} columns of {bins} bins"),
        columns as f64 * bins as f64 * 20.0 * 8.0 * 2.0,
    )
}

/// Refuses options that do not go together (one line each).
fn check_options(opts: &OnboardOptions) -> Result<()> {
    let refuse = |why: &str| Err(Error::Unsupported(why.into()));
    if opts.schemes.is_empty() {
        return Err(no_scheme());
    }
    match opts.shard {
        Some(_) if opts.report.is_some() => refuse(
            "--report needs the whole run: with --shard write --partial PART.json, then \
             `lidarsim onboard --combine PART.json ... --report PATH`",
        ),
        Some(_) if opts.raw.is_some() => refuse(
            "--raw is not written with --shard (a product shard cuts at whole frames, not \
             as `simulate --shard`); run `simulate --shard` for the raw shards",
        ),
        None if opts.partial.is_some() => refuse("--partial goes with --shard K/N"),
        _ => Ok(()),
    }
}

/// Draws `shots` of `native` into the first scheme's product, written as output
/// `product` of `outputs`, and returns every scheme's report sums.
fn write_product(
    native: &NativeRun,
    shots: &Range<u64>,
    opts: &OnboardOptions,
    outputs: &Outputs,
    product: OutputId,
) -> Result<Vec<SchemeSums>> {
    check_memory(native, native.layouts.len())?;
    let draw = Draw::new(native)?;
    let header = native.header(
        opts.shard.map(|s| (s, shots)),
        opts.word_bits,
        &opts.command_line,
    )?;
    let columns = draw.columns(native);
    check_truth_memory(native, columns.len())?;
    let specs = native.region_specs(shots, &columns)?;
    let mut rows = ProfileRows::new(
        native.layouts[0]
            .iter()
            .zip(&specs)
            .map(|(r, s)| (r.clone(), s.truth.slots))
            .collect(),
        native.lidar.channels.len(),
        specs.iter().map(|s| s.first_profile).collect(),
        simulate::orbit_of(&native.lidar)?,
        native.rep_rate_hz,
        native
            .lidar
            .channels
            .iter()
            .map(|c| c.loaded.config.instrument.pulse_energy_j)
            .collect(),
    );
    let fl = native.rep_rate_hz;
    let mut times = |k: usize, rows: Range<usize>| {
        let r = &specs[k];
        Ok(rows
            .map(|i| profile_time(r.first_profile + i, r.shots, fl))
            .collect())
    };
    let path = outputs.temp_path(product)?;
    let mut writer = ProductWriter::create(path, &opts.output, &header, &specs, &mut times)?;
    let mut runs: Vec<SchemeRun> = native
        .layouts
        .iter()
        .map(|l| SchemeRun::new(l, draw.channels, draw.n_bins))
        .collect();
    draw_shots(&draw, shots.clone(), &mut runs, &mut rows, &mut writer)?;
    writer.finish()?;
    Ok(runs.into_iter().map(|r| r.sums).collect())
}

/// Commits `outputs`, with `--raw` (output `raw`) the native raw file of the same draw
/// first (counts depend on the seed and shot only), written as `simulate` writes it:
/// that run commits every output together.
fn commit_with_raw(
    native: &NativeRun,
    outputs: Outputs,
    raw: Option<(OutputId, &Path)>,
) -> Result<()> {
    let Some((id, path)) = raw else {
        return outputs.commit();
    };
    let raw_opts = simulate::RunOptions {
        output: path.to_path_buf(),
        seed: Some(native.seed),
        profiles: Some(native.shots as usize),
        method: Some(Method::Shot),
        command_line: crate::output::raw_file::content::history_command(std::env::args()),
        ..Default::default()
    };
    simulate::run(&native.lidar, &raw_opts, outputs, id).map(|_| ())
}

/// Runs the onboard simulation of `config` (with `opts.shard`, one shard of it).
pub fn run(config: &Path, overrides: &[String], opts: &OnboardOptions) -> Result<()> {
    check_options(opts)?;
    let native = NativeRun::load(config, overrides, opts.seed, &opts.schemes)?;
    let shots = native.shots_of(opts.shard)?;
    let inputs = native.files_read();
    let mut outputs = Outputs::new(inputs.iter().map(PathBuf::as_path));
    let product = outputs.add("-o", &opts.output, Stream::Binary)?;
    let mut add = |option, path: &Option<PathBuf>, stream| {
        let id = path.as_deref().map(|p| outputs.add(option, p, stream));
        id.transpose()
    };
    let raw = add("--raw", &opts.raw, Stream::Binary)?;
    let report = add("--report", &opts.report, Stream::Text)?;
    let partial = add("--partial", &opts.partial, Stream::Text)?;
    let sums = write_product(&native, &shots, opts, &outputs, product)?;
    if let Some(id) = report {
        let input = native.report_input(&sums, opts.word_bits);
        outputs.write(id, |w| report::write_report(w, &input))?;
    }
    if let (Some(id), Some(shard)) = (partial, opts.shard) {
        let p = super::partial::OnboardPartial::new(&native, opts.word_bits, shard, shots, sums);
        outputs.write(id, |w| p.write(w))?;
    }
    commit_with_raw(&native, outputs, raw.zip(opts.raw.as_deref()))?;
    // the native config differs from the user's only in accumulation and profiles
    for w in native.lidar.first().loaded.config.plausibility_warnings() {
        crate::tell!("{w}");
    }
    Ok(())
}

/// A refusal of the onboard command.
pub fn no_scheme() -> Error {
    Error::Unsupported(
        "onboard needs at least one --scheme (none, uniform:N, caliop or a file)".into(),
    )
}
