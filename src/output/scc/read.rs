//! Reading what the SCC export needs from a lidarsim raw file (format version 2,
//! `docs/file-format.md`). Every failure is an [`Error::Output`] naming the raw file.

use std::path::Path;

use hdf5::types::VarLenUnicode;

use crate::error::describe_hdf5_error;
use crate::error::{Error, Result};
use crate::output::raw_file::{self, BIN_DIM, CHANNEL_DIM, PROFILE_DIM};

/// The parts of a raw file the SCC export uses, as read (no SCC meaning yet).
#[derive(Debug, Clone)]
pub struct RawRun {
    /// Channel names (`channel` coordinate), e.g. `532_parallel`.
    pub channels: Vec<String>,
    /// Profiles (length of `profile`).
    pub n_profiles: usize,
    /// Bins per profile (length of `bin`).
    pub n_bins: usize,
    /// `counts(profile, channel, bin)`, row-major.
    pub counts: Vec<u64>,
    /// `time(profile)`: profile centre, s since the origin in [`RawRun::time_units`].
    pub time_s: Vec<f64>,
    /// `units` of `time`, e.g. `seconds since 2000-01-01 00:00:00`.
    pub time_units: String,
    /// `n_shots(profile)`.
    pub n_shots: Vec<u64>,
    /// `range(bin)`: bin-centre range, m.
    pub range_m: Vec<f64>,
    /// `expected_signal(channel, bin)`, counts per shot; in a changing scene (where the
    /// file's `expected_signal` is (profile, channel, bin)) the largest over profiles.
    pub expected_signal: Vec<f64>,
    /// `expected_background + expected_dark` (channel, bin), counts per shot; in a
    /// changing scene the smallest background over profiles.
    pub expected_noise: Vec<f64>,
    /// `expected_induced` (channel, bin), the signal-induced counts per shot (0 where
    /// the file has none); in a changing scene the largest over profiles.
    pub expected_induced: Vec<f64>,
    /// `expected_afterpulse` (channel, bin), the afterpulses per shot of the recorded
    /// counts (0 where the file has none); in a changing scene the largest over profiles.
    pub expected_afterpulse: Vec<f64>,
    /// Root attribute `pretrigger_bins` (bins recorded before the pulse leaves, at the
    /// start of each profile; a format-3 feature), 0 when the file has none.
    pub pretrigger_bins: usize,
    /// Root attribute `wavelength_nm`.
    pub wavelength_nm: f64,
    /// Root attribute `rep_rate_hz`.
    pub rep_rate_hz: f64,
    /// Root attribute `bin_width_s`.
    pub bin_width_s: f64,
    /// Root attribute `accumulation_time_s`.
    pub accumulation_time_s: f64,
    /// Root attribute `config`, parsed.
    pub config: toml::Table,
}

/// Reads `path`, refusing a file that is not a lidarsim raw file of format version 2 as
/// every reader of raw files checks it ([`raw_file::read::check`]), or whose sizes would
/// not fit in memory.
pub fn read_raw(path: &Path) -> Result<RawRun> {
    crate::input_file::check("RAW.h5", path)?;
    let f = hdf5::File::open(path).map_err(|_| {
        bad(
            path,
            "not a lidarsim raw file (not an HDF5 / netCDF-4 file)",
        )
    })?;
    let header = raw_file::read::check(path, &f)?;
    let (n_profiles, n_channels, n_bins) =
        (header.n_profiles, header.channels.len(), header.n_bins);
    // the counts (u64) and the (channel, bin) variables read, with the coordinates
    let values = n_profiles as f64 * n_channels as f64 * n_bins as f64;
    header.require_memory(
        path,
        "the SCC export",
        8.0 * values + 32.0 * (n_channels * n_bins) as f64 + 24.0 * (n_profiles + n_bins) as f64,
    )?;
    let time_ds = dataset(path, &f, "time")?;
    // the expectations of every profile, whatever their form in the file
    let truth = raw_file::per_profile::PerProfileReader::new(path, &f, &header)?;
    let every = |name: &str| -> Result<Vec<f64>> {
        match truth.is_fixed(name) {
            true => truth.rows(name, 0..1),
            false => truth.rows(name, 0..n_profiles),
        }
    };
    let run = RawRun {
        channels: header.channels.clone(),
        n_profiles,
        n_bins,
        counts: read_values::<u64>(path, &f, "counts")?,
        time_s: read_values::<f64>(path, &f, "time")?,
        time_units: str_attr(path, &time_ds, "time", "units")?,
        n_shots: read_values::<u64>(path, &f, "n_shots")?,
        range_m: read_values::<f64>(path, &f, "range")?,
        expected_signal: over_profiles(
            path,
            "expected_signal",
            every("expected_signal")?,
            (n_profiles, n_channels * n_bins),
            f64::max,
        )?,
        expected_noise: sum(
            &over_profiles(
                path,
                "expected_background",
                every("expected_background")?,
                (n_profiles, n_channels * n_bins),
                f64::min,
            )?,
            &read_values::<f64>(path, &f, "expected_dark")?,
        ),
        expected_induced: optional_largest(
            path,
            &f,
            "expected_induced",
            n_profiles,
            n_channels * n_bins,
        )?,
        expected_afterpulse: optional_largest(
            path,
            &f,
            "expected_afterpulse",
            n_profiles,
            n_channels * n_bins,
        )?,
        pretrigger_bins: pretrigger_bins(path, &f, n_bins)?,
        wavelength_nm: f64_attr(path, &f, "wavelength_nm")?,
        rep_rate_hz: f64_attr(path, &f, "rep_rate_hz")?,
        bin_width_s: f64_attr(path, &f, "bin_width_s")?,
        accumulation_time_s: f64_attr(path, &f, "accumulation_time_s")?,
        config: read_config(path, &f)?,
    };
    check_shapes(path, &run, n_channels)?;
    Ok(run)
}

/// A failure reading variable `name` of the raw file, in one line.
fn unreadable(path: &Path, name: &str, e: hdf5::Error) -> Error {
    bad(
        path,
        &format!(
            "cannot read `{name}`: {}",
            describe_hdf5_error(&e.to_string())
        ),
    )
}

/// An [`Error::Output`] about the raw file.
pub(super) fn bad(path: &Path, reason: &str) -> Error {
    Error::output(path, reason)
}

fn dataset(path: &Path, f: &hdf5::File, name: &str) -> Result<hdf5::Dataset> {
    f.dataset(name)
        .map_err(|_| bad(path, &format!("missing variable `{name}`")))
}

/// A dataset's values, a one-line error naming it if they cannot be read as `T`.
fn read_values<T: hdf5::H5Type>(path: &Path, f: &hdf5::File, name: &str) -> Result<Vec<T>> {
    dataset(path, f, name)?
        .read_raw::<T>()
        .map_err(|e| unreadable(path, name, e))
}

fn f64_attr(path: &Path, f: &hdf5::File, name: &str) -> Result<f64> {
    let a = f
        .attr(name)
        .map_err(|_| bad(path, &format!("missing root attribute `{name}`")))?;
    let x: f64 = a
        .read_scalar()
        .map_err(|_| bad(path, &format!("root attribute `{name}` is not a number")))?;
    if !x.is_finite() || x <= 0.0 {
        return Err(bad(
            path,
            &format!("root attribute `{name}` is {x}, not a positive number"),
        ));
    }
    Ok(x)
}

fn str_attr(path: &Path, loc: &hdf5::Location, owner: &str, name: &str) -> Result<String> {
    let a = loc
        .attr(name)
        .map_err(|_| bad(path, &format!("`{owner}` has no attribute `{name}`")))?;
    let v: VarLenUnicode = a.read_scalar().map_err(|_| {
        bad(
            path,
            &format!("`{owner}` attribute `{name}` is not a string"),
        )
    })?;
    Ok(v.as_str().to_string())
}

fn read_config(path: &Path, f: &hdf5::File) -> Result<toml::Table> {
    let text = str_attr(path, f, "the root group", "config")?;
    text.parse::<toml::Table>().map_err(|e| {
        let first = e.to_string();
        let first = first.lines().next().unwrap_or("").to_string();
        bad(
            path,
            &format!("root attribute `config` is not TOML: {first}"),
        )
    })
}

/// A (channel, bin) variable that is (profile, channel, bin) in a changing scene, folded
/// over profiles with `fold` (`f64::max` for the signal, `f64::min` for the background);
/// a (channel, bin) variable as it is. Another length is left for `check_shapes`.
fn over_profiles(
    path: &Path,
    name: &str,
    values: Vec<f64>,
    (n_profiles, per_profile): (usize, usize),
    fold: fn(f64, f64) -> f64,
) -> Result<Vec<f64>> {
    if values.iter().any(|x| !x.is_finite()) {
        return Err(bad(
            path,
            &format!("`{name}` holds a value that is not finite"),
        ));
    }
    if n_profiles < 2 || per_profile == 0 || values.len() != n_profiles * per_profile {
        return Ok(values);
    }
    let mut out = values[..per_profile].to_vec();
    for row in values.chunks_exact(per_profile).skip(1) {
        for (o, &x) in out.iter_mut().zip(row) {
            *o = fold(*o, x);
        }
    }
    Ok(out)
}

/// A detector's (channel, bin) variable the file writes only when some channel has it
/// (`expected_induced`, `expected_afterpulse`): its largest value over profiles, zeros
/// when absent.
fn optional_largest(
    path: &Path,
    f: &hdf5::File,
    name: &str,
    n_profiles: usize,
    per_profile: usize,
) -> Result<Vec<f64>> {
    if f.dataset(name).is_err() {
        return Ok(vec![0.0; per_profile]);
    }
    let values = read_values::<f64>(path, f, name)?;
    over_profiles(path, name, values, (n_profiles, per_profile), f64::max)
}

/// Root attribute `pretrigger_bins` (format 3: bins recorded before the pulse, at the
/// start of each profile), 0 when absent; refused unless a whole number below the bins.
fn pretrigger_bins(path: &Path, f: &hdf5::File, n_bins: usize) -> Result<usize> {
    let Ok(a) = f.attr("pretrigger_bins") else {
        return Ok(0);
    };
    let n: i64 = a
        .read_scalar()
        .map_err(|_| bad(path, "root attribute `pretrigger_bins` is not an integer"))?;
    match usize::try_from(n) {
        Ok(n) if n < n_bins => Ok(n),
        _ => Err(bad(
            path,
            &format!(
                "root attribute `pretrigger_bins` is {n}, not 0 to {}",
                n_bins.saturating_sub(1)
            ),
        )),
    }
}

fn sum(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + y).collect()
}

/// Every variable the export uses must agree with `counts(profile, channel, bin)`.
fn check_shapes(path: &Path, r: &RawRun, n_channels: usize) -> Result<()> {
    let per_channel_bin = n_channels * r.n_bins;
    let checks = [
        ("channel", r.channels.len(), n_channels, CHANNEL_DIM),
        ("time", r.time_s.len(), r.n_profiles, PROFILE_DIM),
        ("n_shots", r.n_shots.len(), r.n_profiles, PROFILE_DIM),
        ("range", r.range_m.len(), r.n_bins, BIN_DIM),
        (
            "expected_signal",
            r.expected_signal.len(),
            per_channel_bin,
            "channel × bin",
        ),
        (
            "expected_background/dark",
            r.expected_noise.len(),
            per_channel_bin,
            "channel × bin",
        ),
        (
            "expected_induced",
            r.expected_induced.len(),
            per_channel_bin,
            "channel × bin",
        ),
        (
            "expected_afterpulse",
            r.expected_afterpulse.len(),
            per_channel_bin,
            "channel × bin",
        ),
    ];
    for (name, got, want, dims) in checks {
        if got != want {
            return Err(bad(
                path,
                &format!("`{name}` has {got} values, `counts` implies {want} ({dims})"),
            ));
        }
    }
    if r.n_profiles == 0 || r.n_bins == 0 || n_channels == 0 {
        return Err(bad(path, "`counts` is empty"));
    }
    Ok(())
}
