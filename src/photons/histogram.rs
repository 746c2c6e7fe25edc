//! `lidarsim histogram`: the profiles of a photon file's events at any range resolution
//! and shot accumulation, with their truth (the counts of each origin).
//!
//! At the run's own bin width and shots per profile the counts are the raw file's, bit
//! for bit. A bin width that is a whole multiple of the run's sums its bins (exact); any
//! other places each event by its range. A profile is `shots` consecutive shots (the last
//! one may have fewer: `n_shots`), its time the centre of its shots, its position the
//! footprint of its centre shot.

use std::path::Path;

use hdf5::{Dataset, File};

use super::model::ORIGINS;
use super::writer::FLUSH_EVENTS;
use crate::hdf5_ds::{attach_scales, set_scale, write_num_attr, write_str_attr};

/// The variable of the channels' names, as in the raw file.
const CHANNEL_NAME: &str = "channel_name";
use crate::error::{Error, Result};

/// The profiles made of a photon file's events.
#[derive(Debug, Clone)]
pub struct Histogram {
    /// Counts, (profile, channel, bin).
    pub counts: Vec<u64>,
    /// Counts of each origin of [`ORIGINS`], each (profile, channel, bin).
    pub by_origin: Vec<Vec<u64>>,
    /// Profiles.
    pub profiles: usize,
    /// Channel names.
    pub channels: Vec<String>,
    /// Bins.
    pub bins: usize,
    /// Bin-centre range, m.
    pub range_m: Vec<f64>,
    /// Bin width, m.
    pub bin_range_m: f64,
    /// Shots of each profile.
    pub n_shots: Vec<u64>,
    /// Profile time since the run's start (centre of its shots), s.
    pub time_s: Vec<f64>,
    /// CF units of `time_s`: `seconds since <acquisition.start_time>`.
    pub time_units: String,
    /// Latitude and longitude of each profile's centre shot (NaN without an orbit).
    pub latitude: Vec<f64>,
    /// See `latitude`.
    pub longitude: Vec<f64>,
}

/// An error of input file `path`.
fn input_err(path: &Path, reason: impl std::fmt::Display) -> Error {
    Error::Unsupported(format!("{}: {reason}", path.display()))
}

fn bad(path: &Path, what: impl std::fmt::Display) -> Error {
    input_err(path, format!("not a lidarsim photon file: {what}"))
}

fn attr<T: hdf5::H5Type>(f: &File, path: &Path, name: &str) -> Result<T> {
    f.attr(name)
        .and_then(|a| a.read_scalar::<T>())
        .map_err(|_| {
            bad(
                path,
                format!("attribute `{name}` missing or of the wrong type"),
            )
        })
}

fn dataset(f: &File, path: &Path, name: &str) -> Result<Dataset> {
    f.dataset(name)
        .map_err(|_| bad(path, format!("dataset `{name}` missing")))
}

fn read_1d<T: hdf5::H5Type + Copy>(
    ds: &Dataset,
    path: &Path,
    a: usize,
    b: usize,
) -> Result<Vec<T>> {
    ds.read_slice_1d::<T, _>(a..b)
        .map(|v| v.iter().copied().collect())
        .map_err(|e| input_err(path, format!("cannot read `{}`: {e}", ds.name())))
}

/// The profiles of `path`'s events at bin width `bin_width_m` (default: the run's) and
/// `shots` shots per profile (default: the run's).
pub fn histogram(path: &Path, bin_width_m: Option<f64>, shots: Option<u64>) -> Result<Histogram> {
    let f = File::open(path).map_err(|e| {
        bad(
            path,
            format!(
                "cannot open it as HDF5 ({})",
                crate::error::describe_hdf5_error(&e.to_string())
            ),
        )
    })?;
    let run_shots: u64 = attr(&f, path, "shots_per_profile")?;
    let run_profiles: u64 = attr(&f, path, "profiles")?;
    let rep: f64 = attr(&f, path, "rep_rate_hz")?;
    let dr: f64 = attr(&f, path, "bin_range_m")?;
    let names: hdf5::types::VarLenUnicode = attr(&f, path, "channels")?;
    let channels: Vec<String> = names.as_str().split(',').map(str::to_string).collect();
    let starts: Vec<f64> = dataset(&f, path, "bins/range_start")?
        .read_raw()
        .map_err(|e| input_err(path, format!("cannot read `bins/range_start`: {e}")))?;
    let n_run_bins = starts.len();
    let r0 = starts.first().copied().unwrap_or(0.0);
    let width = bin_width_m.unwrap_or(dr);
    if !(width.is_finite() && width > 0.0) {
        return Err(Error::Unsupported(format!(
            "--bin-width must be a positive number of metres, got {width}"
        )));
    }
    let shots = shots.unwrap_or(run_shots);
    if shots == 0 {
        return Err(Error::Unsupported("--shots must be at least 1".into()));
    }
    let k = width / dr;
    let whole = (k - k.round()).abs() < 1e-9 * k && k.round() >= 1.0;
    let bins = if whole {
        n_run_bins.div_ceil(k.round() as usize)
    } else {
        ((n_run_bins as f64 * dr / width).ceil() as usize).max(1)
    };
    let total_shots = run_shots * run_profiles;
    let profiles = total_shots.div_ceil(shots) as usize;
    let nc = channels.len();
    let size = profiles
        .checked_mul(nc * bins)
        .filter(|&n| n <= (1usize << 40))
        .ok_or_else(|| Error::Unsupported("the histogram's size overflows".into()))?;
    crate::resources::require_memory(
        "the histogram",
        size as f64 * 8.0 * (1.0 + ORIGINS.len() as f64),
    )?;
    let mut counts = vec![0u64; size];
    let mut by_origin = vec![vec![0u64; size]; ORIGINS.len()];
    let pulse = dataset(&f, path, "heights/ph_id_pulse")?;
    let channel = dataset(&f, path, "heights/ph_id_channel")?;
    let bin = dataset(&f, path, "heights/ph_id_bin")?;
    let range = dataset(&f, path, "heights/range")?;
    let origin = dataset(&f, path, "heights/truth_origin")?;
    let n = pulse.size();
    for a in (0..n).step_by(FLUSH_EVENTS) {
        let b = (a + FLUSH_EVENTS).min(n);
        let p: Vec<u64> = read_1d(&pulse, path, a, b)?;
        let c: Vec<u16> = read_1d(&channel, path, a, b)?;
        let o: Vec<u8> = read_1d(&origin, path, a, b)?;
        let new_bin: Vec<usize> = if whole {
            let kk = k.round() as usize;
            read_1d::<u32>(&bin, path, a, b)?
                .into_iter()
                .map(|x| x as usize / kk)
                .collect()
        } else {
            read_1d::<f64>(&range, path, a, b)?
                .into_iter()
                .map(|r| (((r - r0) / width).floor().max(0.0) as usize).min(bins - 1))
                .collect()
        };
        for i in 0..p.len() {
            let prof = (p[i] / shots) as usize;
            let ch = c[i] as usize;
            if prof >= profiles || ch >= nc || new_bin[i] >= bins {
                return Err(bad(path, format!("event {} lies outside the run", a + i)));
            }
            let at = (prof * nc + ch) * bins + new_bin[i];
            counts[at] += 1;
            if let Some(j) = ORIGINS.iter().position(|(x, _)| *x as u8 == o[i]) {
                by_origin[j][at] += 1;
            }
        }
    }
    let n_shots: Vec<u64> = (0..profiles as u64)
        .map(|p| shots.min(total_shots - p * shots))
        .collect();
    let time_s = (0..profiles)
        .map(|p| (p as f64 * shots as f64 + 0.5 * n_shots[p] as f64) / rep)
        .collect();
    let time_units = dataset(&f, path, "pulse/delta_time")?
        .attr("units")
        .and_then(|a| a.read_scalar::<hdf5::types::VarLenUnicode>())
        .map_err(|_| bad(path, "`pulse/delta_time` has no `units`"))?
        .to_string();
    let lat_ds = dataset(&f, path, "pulse/latitude")?;
    let lon_ds = dataset(&f, path, "pulse/longitude")?;
    let (mut latitude, mut longitude) = (Vec::new(), Vec::new());
    for p in 0..profiles as u64 {
        let s = (p * shots + n_shots[p as usize] / 2).min(total_shots - 1) as usize;
        latitude.push(read_1d::<f64>(&lat_ds, path, s, s + 1)?[0]);
        longitude.push(read_1d::<f64>(&lon_ds, path, s, s + 1)?[0]);
    }
    let range_m = (0..bins).map(|j| r0 + (j as f64 + 0.5) * width).collect();
    Ok(Histogram {
        counts,
        by_origin,
        profiles,
        channels,
        bins,
        range_m,
        bin_range_m: width,
        n_shots,
        time_s,
        time_units,
        latitude,
        longitude,
    })
}

/// Writes `h` to `path` (a temporary name, shown as `shown`) in the raw file's names
/// and conventions (docs/file-format.md): dimension scales `profile`, `channel` (numbers,
/// `channel_name` the names) and `bin`; `counts` (profile, channel, bin) and the truth
/// `<origin>_counts`; `range` (bin), `time`, `n_shots`, `latitude`, `longitude`
/// (profile); CF-1.10 attributes, so that xarray and netCDF readers see named dimensions.
pub fn write_histogram(h: &Histogram, path: &Path, shown: &Path) -> Result<()> {
    let fail = |e: hdf5::Error| Error::output(shown, format!("cannot write: {e}"));
    let f = File::with_options()
        .with_fapl(|fapl| {
            fapl.libver_bounds(
                hdf5::file::LibraryVersion::V18,
                hdf5::file::LibraryVersion::V18,
            )
        })
        .with_fcpl(|fcpl| fcpl.obj_track_times(false))
        .create(path)
        .map_err(fail)?;
    let w = || -> hdf5::Result<()> {
        let text = |ds: &Dataset, pairs: &[(&str, &str)]| -> hdf5::Result<()> {
            pairs.iter().try_for_each(|(k, v)| write_str_attr(ds, k, v))
        };
        let index = |name: &str, n: usize, long_name: &str| -> hdf5::Result<Dataset> {
            let ds = f
                .new_dataset::<i64>()
                .shape(n)
                .obj_track_times(false)
                .create(name)?;
            ds.write(&(0..n as i64).collect::<Vec<_>>())?;
            text(&ds, &[("long_name", long_name), ("units", "1")])?;
            set_scale(&ds, name)?;
            Ok(ds)
        };
        let profile = index("profile", h.profiles, "profile index")?;
        let channel = index("channel", h.channels.len(), "channel number")?;
        let bin = index("bin", h.bins, "range bin index, 0 nearest the instrument")?;
        let names: Vec<hdf5::types::VarLenUnicode> = h
            .channels
            .iter()
            .map(|c| c.parse().unwrap_or_default())
            .collect();
        let name = f
            .new_dataset::<hdf5::types::VarLenUnicode>()
            .shape(names.len())
            .obj_track_times(false)
            .create(CHANNEL_NAME)?;
        name.write(&names)?;
        text(&name, &[("long_name", "channel name")])?;
        attach_scales(&name, &[&channel])?;
        let per_profile = |name: &str, data: &[f64], attrs: &[(&str, &str)]| {
            let ds = f
                .new_dataset::<f64>()
                .shape(data.len())
                .obj_track_times(false)
                .create(name)?;
            ds.write(data)?;
            text(&ds, attrs)?;
            attach_scales(&ds, &[&profile])
        };
        per_profile(
            "time",
            &h.time_s,
            &[
                ("units", h.time_units.as_str()),
                ("standard_name", "time"),
                ("long_name", "profile centre time"),
                ("calendar", "standard"),
                ("axis", "T"),
            ],
        )?;
        for (n, data, units) in [
            ("latitude", &h.latitude, "degrees_north"),
            ("longitude", &h.longitude, "degrees_east"),
        ] {
            let attrs = [
                ("units", units),
                ("standard_name", n),
                ("long_name", "footprint of the profile's centre shot"),
            ];
            per_profile(n, data, &attrs)?;
        }
        let shots = f
            .new_dataset::<u64>()
            .shape(h.n_shots.len())
            .obj_track_times(false)
            .create("n_shots")?;
        shots.write(&h.n_shots)?;
        text(
            &shots,
            &[("units", "1"), ("long_name", "laser shots accumulated")],
        )?;
        attach_scales(&shots, &[&profile])?;
        let range = f
            .new_dataset::<f64>()
            .shape(h.range_m.len())
            .obj_track_times(false)
            .create("range")?;
        range.write(&h.range_m)?;
        let range_attrs = [
            ("units", "m"),
            ("long_name", "bin-centre range from the instrument"),
        ];
        text(&range, &range_attrs)?;
        attach_scales(&range, &[&bin])?;
        let shape = (h.profiles, h.channels.len(), h.bins);
        let chunk = (1, h.channels.len().max(1), h.bins.max(1));
        let counts = |name: &str, data: &[u64], long_name: &str| -> hdf5::Result<()> {
            let ds = f
                .new_dataset::<u64>()
                .shape(shape)
                .chunk(chunk)
                .shuffle()
                .deflate(1)
                .obj_track_times(false)
                .create(name)?;
            let view = ndarray::ArrayView3::from_shape(shape, data)
                .map_err(|e| hdf5::Error::from(e.to_string().as_str()))?;
            ds.write(view)?;
            let attrs = [
                ("units", "count"),
                ("long_name", long_name),
                ("coordinates", "time latitude longitude channel_name range"),
            ];
            text(&ds, &attrs)?;
            attach_scales(&ds, &[&profile, &channel, &bin])
        };
        counts(
            "counts",
            &h.counts,
            "photon counts, the histogram of the events",
        )?;
        for ((_, origin), c) in ORIGINS.iter().zip(&h.by_origin) {
            let long_name = format!("counts of the {origin} events (truth)");
            counts(&format!("{origin}_counts"), c, &long_name)?;
        }
        for (k, v) in [
            ("Conventions", "CF-1.10"),
            ("title", "lidarsim histogram of time-tagged photon events"),
            ("source", "lidarsim histogram"),
            (
                "history",
                "lidarsim histogram: the profiles of a photon file's events",
            ),
        ] {
            write_str_attr(&f, k, v)?;
        }
        write_str_attr(&f, "channels", &h.channels.join(","))?;
        write_num_attr(&f, "bin_range_m", &h.bin_range_m)
    };
    w().map_err(fail)
}
