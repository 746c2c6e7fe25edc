//! The subcommands' work, called by the thin `lidarsim` binary.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::config::PlatformKind;
use crate::error::{Error, Result};
use crate::figures::snr_map;
use crate::output::{expect, scc};
use crate::resources;
use crate::safe_file::{Outputs, ScratchFile, Stream};
use crate::scenario::{ExpectedProfile, Lidar, Scenario};
use crate::simulate;
use crate::snr;
use crate::validate;

/// Bytes per bin of the `expect` CSV (measured: 576 MB for 2.7e6 bins).
const EXPECT_CSV_BYTES_PER_BIN: f64 = 220.0;
/// Bytes per row of the `snr-map` CSV (measured: 9.25 GB for 1.65e8 rows, 56 B; rows
/// reach 60 B).
const SNR_MAP_CSV_BYTES_PER_ROW: f64 = 60.0;
/// Seconds per row of the `snr-map` CSV (measured: ~77 s for 1.65e8 rows, one core).
const SNR_MAP_CSV_S_PER_ROW: f64 = 0.5e-6;

/// Accumulation times of the S/N map, s: 1 to 1000, log-spaced (the paper's Figs. 2–3).
pub fn snr_map_times_s() -> Vec<f64> {
    (0..=60).map(|k| 10f64.powf(k as f64 / 20.0)).collect()
}

/// Writes to stdout; a closed pipe (`| head`) is not an error.
fn to_stdout(fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<()> {
    let stdout = std::io::stdout();
    let mut lock = stdout.lock();
    match fill(&mut lock).and_then(|_| lock.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(Error::Io {
            path: "<stdout>".into(),
            source: e,
        }),
        _ => Ok(()),
    }
}

/// The files a scenario reads (its config and every file it names,
/// [`crate::loaded::LoadedConfig::files_read`]): no output may replace them.
pub fn input_files(sc: &Scenario) -> Vec<PathBuf> {
    sc.loaded.files_read()
}

/// One channel of a config: the one named `channel`, or the first (with a note on
/// stderr when there are several).
pub fn load_channel(
    config: &Path,
    overrides: &[String],
    channel: Option<&str>,
) -> Result<Scenario> {
    let lidar = Lidar::load(config, overrides)?;
    let names = lidar.channel_names();
    let k = match channel {
        Some(name) => channel_index(&lidar, config, name)?,
        None => {
            if names.len() > 1 {
                crate::tell!(
                    "lidarsim: channel {} of {} ({}); --channel NAME for another",
                    names[0],
                    names.len(),
                    names.join(", ")
                );
            }
            0
        }
    };
    Ok(lidar
        .channels
        .into_iter()
        .nth(k)
        .unwrap_or_else(|| unreachable!()))
}

/// The index of the channel named `name` of `lidar` (loaded from `config`), or the
/// error `--channel` gives for a name the config has not.
pub fn channel_index(lidar: &Lidar, config: &Path, name: &str) -> Result<usize> {
    let names = lidar.channel_names();
    names.iter().position(|n| n == name).ok_or_else(|| {
        Error::config(
            config.display().to_string(),
            "instrument.channels",
            format!("has no channel `{name}` (channels: {})", names.join(", ")),
        )
    })
}

/// The output set of a command on `sc`, with the scenario's inputs protected.
pub fn outputs_for(sc: &Scenario) -> Outputs {
    let inputs = input_files(sc);
    Outputs::new(inputs.iter().map(PathBuf::as_path))
}

/// `lidarsim expect`: the CSV (to a file or `-` for stdout) or the terminal table.
pub fn expect(
    config: &Path,
    overrides: &[String],
    csv: Option<&Path>,
    channel: Option<&str>,
) -> Result<()> {
    let mut sc = load_channel(config, overrides, channel)?;
    let mut outputs = outputs_for(&sc);
    let csv_path = csv.filter(|p| *p != Path::new("-"));
    let csv = csv
        .map(|p| outputs.add("--csv", p, Stream::Text))
        .transpose()?;
    if let Some(p) = csv_path {
        let bytes = sc.geometry.n_bins as f64 * EXPECT_CSV_BYTES_PER_BIN;
        resources::require_disk("--csv", p, bytes)?;
    }
    let e = sc.expected()?;
    // nothing below reads the beam path: it goes before the CSV's columns come
    sc.path.release();
    let shots = sc.instrument.rep_rate_hz * sc.accumulation_time_s();
    match csv {
        Some(id) => {
            outputs.write(id, |w| expect::write_csv(w, &e, shots))?;
            outputs.commit()?;
        }
        None => to_stdout(|w| expect::write_table(w, &sc, &e))?,
    }
    for w in sc.loaded.config.plausibility_warnings() {
        crate::tell!("{w}");
    }
    if let Some(note) = sc.atmosphere.molecules.continuation_note() {
        crate::tell!("{note}");
    }
    if let Some(w) = sc.linear_range_warning(&e) {
        crate::tell!("{w}");
    }
    Ok(())
}

/// Most altitude rows drawn in the S/N map PNG: more than its pixel rows, so a
/// window of millions of bins is drawn from every k-th bin (the CSV has them all).
pub const MAX_MAP_ROWS: usize = 4 * snr_map::HEIGHT as usize;

/// The bins drawn in the map: all of them, or every k-th where there are more than
/// [`MAX_MAP_ROWS`].
fn map_rows(n_bins: usize) -> impl Iterator<Item = usize> {
    (0..n_bins).step_by(n_bins.div_ceil(MAX_MAP_ROWS).max(1))
}

/// The S/N map of a scenario: Eq. 4 against altitude and accumulation time.
pub fn build_snr_map(sc: &Scenario, e: &ExpectedProfile) -> snr_map::SnrMap {
    let cfg = &sc.loaded.config;
    let i = &cfg.instrument;
    let times = snr_map_times_s();
    let rows: Vec<usize> = map_rows(e.n_bins()).collect();
    let snr = rows
        .iter()
        .map(|&b| {
            times
                .iter()
                .map(|tc| snr::eq4(e.signal[b], e.background, e.dark, i.rep_rate_hz * tc))
                .collect()
        })
        .collect();
    snr_map::SnrMap {
        altitude_km: rows.iter().map(|&b| e.altitude_m[b] / 1e3).collect(),
        accumulation_time_s: times,
        snr,
        title: format!("{} — S/N (Eq. 4)", cfg.name),
        subtitle: format!(
            "E0 = {} J, fL = {} Hz, A = {} m², {} nm, FOV {} µrad, Lλ = {:.1e}, platform {} km",
            i.pulse_energy_j,
            i.rep_rate_hz,
            i.telescope_area_m2,
            i.wavelength_nm,
            i.fov_rad * 1e6,
            cfg.background.radiance.unwrap_or(0.0),
            cfg.platform.altitude_km
        ),
    }
}

/// `lidarsim snr-map`: the PNG and optionally the long-format CSV
/// (`altitude_m,accumulation_time_s,snr`).
pub fn snr_map(
    config: &Path,
    overrides: &[String],
    png: &Path,
    csv: Option<&Path>,
    channel: Option<&str>,
) -> Result<()> {
    let sc = load_channel(config, overrides, channel)?;
    let mut outputs = outputs_for(&sc);
    let png = outputs.add("--png", png, Stream::Binary)?;
    let csv_path = csv.filter(|p| *p != Path::new("-"));
    let csv = csv
        .map(|p| outputs.add("--csv", p, Stream::Text))
        .transpose()?;
    if csv.is_some() {
        let rows = (sc.geometry.n_bins * snr_map_times_s().len()) as f64;
        if let Some(p) = csv_path {
            resources::require_disk("--csv", p, rows * SNR_MAP_CSV_BYTES_PER_ROW)?;
        }
        resources::announce_duration("the S/N map CSV", rows * SNR_MAP_CSV_S_PER_ROW);
    }
    let e = sc.expected()?;
    let map = build_snr_map(&sc, &e);
    if let Some(id) = csv {
        let fl = sc.instrument.rep_rate_hz;
        outputs.write(id, |w| {
            writeln!(w, "altitude_m,accumulation_time_s,snr")?;
            for (z, &s) in e.altitude_m.iter().zip(&e.signal) {
                for tc in &map.accumulation_time_s {
                    let snr = snr::eq4(s, e.background, e.dark, fl * tc);
                    writeln!(w, "{z},{tc},{snr:e}")?;
                }
            }
            Ok(())
        })?;
    }
    let bytes = snr_map::png_bytes(&map).map_err(|r| Error::output(outputs.shown_path(png), r))?;
    outputs.write(png, |w| w.write_all(&bytes))?;
    outputs.commit()
}

/// The file `simulate` writes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum OutputFormat {
    /// The raw lidar file (HDF5, netCDF-4 readable; `docs/file-format.md`).
    #[default]
    Raw,
    /// The EARLINET Single Calculus Chain raw NetCDF (`docs/scc.md`), ground runs.
    Scc,
}

/// `lidarsim simulate`: the Monte Carlo run, then a one-paragraph summary on stderr.
pub fn simulate(
    config: &Path,
    overrides: &[String],
    opts: &simulate::RunOptions,
    threads: Option<usize>,
) -> Result<()> {
    simulate_as(config, overrides, opts, threads, OutputFormat::Raw)
}

/// `lidarsim simulate --format F`: as [`fn@simulate`], writing `format`. For SCC the raw
/// file is an intermediate scratch file beside the output, exported then deleted.
pub fn simulate_as(
    config: &Path,
    overrides: &[String],
    opts: &simulate::RunOptions,
    threads: Option<usize>,
    format: OutputFormat,
) -> Result<()> {
    let summary = simulate_quietly(config, overrides, opts, threads, format)?;
    crate::tell!("{summary}");
    if let Some(w) = &summary.warning {
        crate::tell!("{w}");
    }
    Ok(())
}

/// A Δ90 depolarization calibration run (`simulate --calibration plus45|minus45`,
/// docs/simulation.md "Calibration runs"): the run of `config` with the receiver's
/// polarization plane rotated by `rotation_deg` (±45°), its noise drawn from
/// [`calibration_seed`] of the run's seed (`--seed`, else `simulation.seed`) and the
/// rotation, so that the two runs and the measurement do not share their noise;
/// `same_noise` (`--same-noise`) draws with the seed itself. Refused, before anything is
/// written, for an instrument without a parallel or perpendicular channel.
pub fn simulate_calibration(
    config: &Path,
    overrides: &[String],
    opts: &simulate::RunOptions,
    threads: Option<usize>,
    format: OutputFormat,
    rotation_deg: f64,
    same_noise: bool,
) -> Result<()> {
    let lidar = Lidar::load(config, overrides)?;
    let first = &lidar.first().loaded;
    let polarized = lidar
        .channels
        .iter()
        .any(|c| c.loaded.config.instrument.channel != crate::config::Channel::Total);
    if !polarized {
        return Err(Error::config(
            first.file_label(),
            "instrument.polarization",
            "--calibration rotates the polarization plane in front of a polarizing beam \
             splitter, and no channel of this instrument is `parallel` or `perpendicular`",
        ));
    }
    let seed = opts.seed.unwrap_or(first.config.simulation.seed);
    let opts = simulate::RunOptions {
        seed: Some(if same_noise {
            seed
        } else {
            calibration_seed(seed, rotation_deg)
        }),
        ..opts.clone()
    };
    let mut set = overrides.to_vec();
    set.push(format!("instrument.receiver_rotation_deg={rotation_deg}"));
    simulate_as(config, &set, &opts, threads, format)
}

/// The seed of a calibration run with the receiver rotated by `rotation_deg`, from the
/// run's seed: SplitMix64's finalizer (Steele et al. 2014) of the seed XOR the
/// rotation's f64 bits times the golden-ratio constant, a stream unrelated to the
/// seed's own (and to its channels' `seed ^ k·0x9E37…`) for each rotation. The file
/// stores it as its `simulation.seed`, so the stored config reproduces the file.
pub fn calibration_seed(seed: u64, rotation_deg: f64) -> u64 {
    let mut z = seed ^ rotation_deg.to_bits().wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// [`simulate_as`] without its closing lines: what the run did (the Python module's
/// `simulate`, which raises the warning as a Python warning).
pub fn simulate_quietly(
    config: &Path,
    overrides: &[String],
    opts: &simulate::RunOptions,
    threads: Option<usize>,
    format: OutputFormat,
) -> Result<simulate::RunSummary> {
    let lidar = Lidar::load(config, overrides)?;
    let first = &lidar.first().loaded;
    if format == OutputFormat::Scc && first.config.platform.kind != PlatformKind::Ground {
        return Err(Error::config(
            first.file_label(),
            "platform.kind",
            "is spaceborne: --format scc writes the EARLINET SCC format, which processes \
             ground-based stations only",
        ));
    }
    if format == OutputFormat::Scc && opts.shard.is_some() {
        return Err(Error::Unsupported(
            "--shard writes raw shard files for `lidarsim merge`; --format scc takes a whole run"
                .into(),
        ));
    }
    let mut outputs = outputs_for(lidar.first());
    let out = outputs.add("-o", &opts.output, Stream::Binary)?;
    let pool = match threads {
        Some(0) => return Err(Error::Unsupported("--threads must be at least 1".into())),
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| Error::Unsupported(format!("cannot start {n} threads: {e}")))?,
        ),
        None => None,
    };
    let run = |opts: &simulate::RunOptions, set: Outputs, id| match &pool {
        Some(p) => p.install(|| simulate::run(&lidar, opts, set, id)),
        None => simulate::run(&lidar, opts, set, id),
    };
    let summary = match format {
        OutputFormat::Raw => run(opts, outputs, out)?,
        OutputFormat::Scc => {
            let scratch = ScratchFile::beside(&opts.output, "raw.h5");
            let mut raw_set = outputs_for(lidar.first());
            let raw = raw_set.add("-o", scratch.path(), Stream::Binary)?;
            let raw_opts = simulate::RunOptions {
                output: scratch.path().to_path_buf(),
                ..opts.clone()
            };
            let mut summary = run(&raw_opts, raw_set, raw)?;
            scc::export_scc(
                scratch.path(),
                outputs.temp_path(out)?,
                &scc::SccOptions::default(),
            )?;
            outputs.commit()?;
            summary.output = opts.output.clone();
            summary
        }
    };
    Ok(summary)
}

/// `lidarsim sweep`: the grid of `vary` over the config, the `metrics` of the
/// deterministic model at each point, as CSV (`-` for stdout) and optionally a PNG.
/// With `cancel` (the Python module's Ctrl-C), stops with [`Error::Interrupted`] (no
/// output written) at the next grid point once it is set.
pub fn sweep(
    config: &Path,
    overrides: &[String],
    vary: &[String],
    metrics: &[String],
    csv: &Path,
    png: Option<&Path>,
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<()> {
    use crate::design::sweep::{self, Axis, Metric};
    let never = std::sync::atomic::AtomicBool::new(false);
    let cancel = cancel.unwrap_or(&never);
    if vary.is_empty() || metrics.is_empty() {
        return Err(Error::Unsupported(
            "sweep needs at least one --vary KEY=START..STOP:N and one --metric".into(),
        ));
    }
    let axes = Axis::parse_all(vary)?;
    let parsed = Metric::parse_all(metrics)?;
    let base = Scenario::load(config, overrides)?;
    let mut outputs = outputs_for(&base);
    let csv_id = outputs.add("--csv", csv, Stream::Text)?;
    let png_id = png
        .map(|p| outputs.add("--png", p, Stream::Binary))
        .transpose()?;
    let points = sweep::grid(&axes)?.len();
    // the points run in parallel, each with its own model of the base's size
    let at_once = points.min(rayon::current_num_threads().max(1)) as f64;
    resources::require_memory(
        &format!("sweeping {points} points of {} bins", base.geometry.n_bins),
        at_once * crate::scenario::model_bytes(base.geometry.n_bins as f64, base.path.laid_bytes()),
    )?;
    let bar =
        crate::simulate::progress_bar(std::io::IsTerminal::is_terminal(&std::io::stderr()), points);
    let scenario = |extra: &[String]| {
        let all: Vec<String> = overrides.iter().chain(extra).cloned().collect();
        Scenario::load(config, &all)
    };
    let rows = sweep::run(&axes, &parsed, &scenario, &|| bar.inc(1), cancel)?;
    bar.finish_and_clear();
    outputs.write(csv_id, |w| {
        let header: Vec<&str> = axes
            .iter()
            .map(|a| a.key.as_str())
            .chain(metrics.iter().map(String::as_str))
            .collect();
        writeln!(w, "{}", header.join(","))?;
        for (point, values) in &rows {
            let cells: Vec<String> = point.iter().chain(values).map(|v| format!("{v}")).collect();
            writeln!(w, "{}", cells.join(","))?;
        }
        Ok(())
    })?;
    if let Some(id) = png_id {
        let bytes = crate::figures::sweep_plot::png_bytes(&axes, metrics, &rows)
            .map_err(|r| Error::output(outputs.shown_path(id), r))?;
        outputs.write(id, |w| w.write_all(&bytes))?;
    }
    outputs.commit()?;
    for w in base.loaded.config.plausibility_warnings() {
        crate::tell!("{w}");
    }
    Ok(())
}

/// `lidarsim curtain RAW.h5 --png OUT.png`: one channel's counts per shot against
/// along-track distance (or time) and altitude.
pub fn curtain(raw: &Path, png: &Path, channel: Option<&str>) -> Result<()> {
    let mut outputs = Outputs::new([raw]);
    let id = outputs.add("--png", png, Stream::Binary)?;
    let c = crate::figures::curtain::read(raw, channel)?;
    let bytes = crate::figures::curtain::png_bytes(&c)
        .map_err(|r| Error::output(outputs.shown_path(id), r))?;
    outputs.write(id, |w| w.write_all(&bytes))?;
    outputs.commit()
}

/// `lidarsim export-scc RAW.h5 OUT.nc`: a raw file to the SCC raw NetCDF format.
pub fn export_scc(raw: &Path, out: &Path, opts: &scc::SccOptions) -> Result<()> {
    let mut outputs = Outputs::new([raw]);
    let id = outputs.add("OUT.nc", out, Stream::Binary)?;
    scc::export_scc(raw, outputs.temp_path(id)?, opts)?;
    outputs.commit()?;
    crate::tell!(
        "Wrote {} (SCC raw NetCDF) from {}.",
        out.display(),
        raw.display()
    );
    Ok(())
}

/// `lidarsim export-scc-calibration PLUS45 MINUS45 OUT`: the Δ90 calibration
/// measurement, written whole or not at all.
pub fn export_scc_calibration(
    plus45: &Path,
    minus45: &Path,
    out: &Path,
    opts: &scc::SccCalibrationOptions,
) -> Result<()> {
    let mut outputs = Outputs::new([plus45, minus45]);
    let id = outputs.add("OUT.nc", out, Stream::Binary)?;
    scc::export_scc_calibration(plus45, minus45, outputs.temp_path(id)?, opts)?;
    outputs.commit()?;
    crate::tell!(
        "Wrote {} (SCC calibration measurement, ±45°) from {} and {}.",
        out.display(),
        plus45.display(),
        minus45.display()
    );
    Ok(())
}

/// `lidarsim validate`: the table on stdout, optionally the JSON; `Ok(consistent)`.
pub fn validate(
    config: &Path,
    overrides: &[String],
    opts: &validate::ValidateOptions,
) -> Result<bool> {
    let lidar = Lidar::load(config, overrides)?;
    let mut outputs = outputs_for(lidar.first());
    let json = opts
        .json
        .as_deref()
        .map(|p| outputs.add("--json", p, Stream::Text))
        .transpose()?;
    let report = validate::run(&lidar, opts)?;
    publish_report(outputs, json, opts.json.as_deref(), &report)
}

/// `lidarsim validate --shard K/N --partial PART.json`: shard `shard`'s sufficient
/// statistics, for `validate --combine`.
pub fn validate_partial(
    config: &Path,
    overrides: &[String],
    opts: &validate::ValidateOptions,
    shard: crate::shard::Shard,
    partial: &Path,
) -> Result<()> {
    let lidar = Lidar::load(config, overrides)?;
    let mut outputs = outputs_for(lidar.first());
    let id = outputs.add("--partial", partial, Stream::Text)?;
    let p = validate::partial::partial(&lidar, opts, shard)?;
    outputs.write(id, |w| {
        serde_json::to_writer(&mut *w, &p).map_err(std::io::Error::other)?;
        writeln!(w)
    })?;
    outputs.commit()?;
    crate::tell!(
        "Wrote {}: shard {shard} of the validation, realizations {}–{} of {}; \
         `lidarsim validate --combine` the partials of every shard for the verdict.",
        partial.display(),
        p.first,
        p.end - 1,
        p.realizations
    );
    Ok(())
}

/// `lidarsim validate --combine PART.json ...`: the single run's table and JSON from the
/// partials of its shards; `Ok(consistent)`.
pub fn validate_combine(partials: &[PathBuf], json: Option<&Path>) -> Result<bool> {
    let mut outputs = Outputs::new(partials.iter().map(PathBuf::as_path));
    let json_id = json
        .map(|p| outputs.add("--json", p, Stream::Text))
        .transpose()?;
    let (report, stored_inputs) = validate::partial::combine(partials)?;
    outputs.protect(stored_inputs.iter().map(PathBuf::as_path))?;
    publish_report(outputs, json_id, json, &report)
}

/// `lidarsim validate --file RAW.h5`: the raw file's counts against the expectation and
/// detector law it carries ([`validate::file`]); `Ok(consistent)`.
pub fn validate_file(raw: &Path, json: Option<&Path>) -> Result<bool> {
    let mut outputs = Outputs::new(std::iter::once(raw));
    let json_id = json
        .map(|p| outputs.add("--json", p, Stream::Text))
        .transpose()?;
    let (report, notes) = validate::file::check_file(raw)?;
    publish(outputs, json_id, json, &report, &|w, r| {
        validate::file::write_file_table(w, r, &notes)
    })
}

/// A table writer of a validation report.
type Table<'a> = &'a dyn Fn(&mut dyn Write, &validate::Report) -> std::io::Result<()>;

/// Writes a validation's JSON (output `json` of `outputs`, at `json_path`) and prints
/// its table (on stderr when the JSON holds stdout) and warning; `Ok(consistent)`.
fn publish_report(
    outputs: Outputs,
    json: Option<crate::safe_file::OutputId>,
    json_path: Option<&Path>,
    report: &validate::Report,
) -> Result<bool> {
    publish(outputs, json, json_path, report, &|w, r| {
        validate::write_table(w, r)
    })
}

/// [`publish_report`] with the table `table`.
fn publish(
    mut outputs: Outputs,
    json: Option<crate::safe_file::OutputId>,
    json_path: Option<&Path>,
    report: &validate::Report,
    table: Table,
) -> Result<bool> {
    if let Some(id) = json {
        outputs.write(id, |w| {
            serde_json::to_writer_pretty(&mut *w, report).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
    }
    let table_to_stderr = json_path == Some(Path::new("-"));
    outputs.commit()?;
    if table_to_stderr {
        // the JSON holds standard output; the table for a person goes to stderr
        table(&mut std::io::stderr(), report).map_err(|e| Error::Io {
            path: "<stderr>".into(),
            source: e,
        })?;
    } else {
        to_stdout(|w| table(w, report))?;
    }
    if let Some(w) = &report.warning {
        crate::tell!("{w}");
    }
    Ok(report.consistent)
}

/// `lidarsim merge OUT.h5 SHARD.h5 ...`: the shards of one run into the file of the
/// whole run ([`crate::simulate::merge`]), then one line on stderr.
pub fn merge(out: &Path, shards: &[PathBuf]) -> Result<()> {
    let summary = match crate::shard::kind_of_shards(shards)? {
        crate::shard::ShardKind::Raw => {
            let m = crate::simulate::merge::prepare(out, shards)?;
            let inputs = input_files(m.lidar.first());
            let mut outputs = Outputs::new(shards.iter().chain(&inputs).map(PathBuf::as_path));
            let id = outputs.add("OUT.h5", out, Stream::Binary)?;
            m.write(outputs, id)?
        }
        crate::shard::ShardKind::Product => {
            let m = crate::onboard::merge::prepare(out, shards)?;
            let mut outputs = Outputs::new(shards.iter().map(PathBuf::as_path));
            let id = outputs.add("OUT.h5", out, Stream::Binary)?;
            m.write(outputs, id)?
        }
    };
    crate::tell!("{summary}");
    Ok(())
}

/// `lidarsim onboard --combine PART.json ... [--report PATH]`: the single run's report
/// from the partials of its shards ([`crate::onboard::partial`]), to `report` or stdout.
pub fn onboard_combine(partials: &[PathBuf], report: Option<&Path>) -> Result<()> {
    let mut outputs = Outputs::new(partials.iter().map(PathBuf::as_path));
    let id = outputs.add("--report", report.unwrap_or(Path::new("-")), Stream::Text)?;
    let (native, sums, word_bits) = crate::onboard::partial::combine(partials)?;
    let stored_inputs = native.files_read();
    outputs.protect(stored_inputs.iter().map(PathBuf::as_path))?;
    let input = native.report_input(&sums, word_bits);
    outputs.write(id, |w| crate::onboard::report::write_report(w, &input))?;
    outputs.commit()
}

/// `lidarsim histogram PHOTONS.h5 -o OUT.h5 --bin-width M --shots N`: the profiles of a
/// photon file's events ([`crate::photons::histogram`]).
pub fn histogram(
    photons: &Path,
    output: &Path,
    bin_width_m: Option<f64>,
    shots: Option<u64>,
) -> Result<()> {
    let mut outputs = Outputs::new([photons]);
    let out = outputs.add("-o", output, Stream::Binary)?;
    let h = crate::photons::histogram::histogram(photons, bin_width_m, shots)?;
    crate::photons::histogram::write_histogram(&h, outputs.temp_path(out)?, output)?;
    outputs.commit()?;
    crate::tell!(
        "Wrote {}: {} profiles × {} channels × {} bins of {} m, {} counts in all.",
        output.display(),
        h.profiles,
        h.channels.len(),
        h.bins,
        h.bin_range_m,
        h.counts.iter().sum::<u64>()
    );
    Ok(())
}
