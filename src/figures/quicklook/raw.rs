//! The quicklook of a raw (or merged) file: its profiles in blocks.

use std::path::Path;

use hdf5::Dataset;
use ndarray::{Axis, Ix1, Ix3, s};

use super::axis::{XAxis, latitude_marks, x_axis};
use super::figure::{
    BLOCK_PROFILES, Background, COLUMNS, Calibration, Mask, Quicklook, ROWS, View, add_profile,
};
use super::grid::Grid;
use super::title::{Source, attr_text, span_edges, title_line};
use crate::error::describe_hdf5_error;
use crate::error::{Error, Result};
use crate::figures::plot::panel::{edges, widen};
use crate::output::raw_file::per_profile::PerProfileReader;
use crate::output::raw_file::read::{check, energy_factors, read_text};
use crate::output::scc::signal_free;

/// The file's variables the quicklook reads, opened.
pub(super) struct Vars<'a> {
    pub path: &'a Path,
    pub f: &'a hdf5::Group,
}

impl Vars<'_> {
    pub fn fail(&self, why: String) -> Error {
        Error::output(self.path, why)
    }

    pub fn ds(&self, name: &str) -> Result<Dataset> {
        self.f
            .dataset(name)
            .map_err(|_| self.fail(format!("has no `{name}`")))
    }

    pub fn unreadable(&self, name: &str, e: hdf5::Error) -> Error {
        self.fail(format!(
            "cannot read `{name}`: {}",
            describe_hdf5_error(&e.to_string())
        ))
    }

    pub fn f64s(&self, name: &str) -> Result<Vec<f64>> {
        self.ds(name)?
            .read_raw::<f64>()
            .map_err(|e| self.unreadable(name, e))
    }

    /// Where profiles `a..b` lie along x: the values of `kind`'s variable, or their
    /// indices.
    pub fn x_of(&self, kind: XAxis, a: usize, b: usize) -> Result<Vec<f64>> {
        match kind.variable() {
            Some(name) => self.f64_range(name, a, b),
            None => Ok((a..b).map(|p| p as f64).collect()),
        }
    }

    /// Values `a..b` of a 1-D variable.
    pub fn f64_range(&self, name: &str, a: usize, b: usize) -> Result<Vec<f64>> {
        Ok(self
            .ds(name)?
            .read_slice::<f64, _, Ix1>(s![a..b])
            .map_err(|e| self.unreadable(name, e))?
            .to_vec())
    }
}

/// A channel's calibration from the file.
pub(super) fn calibration(v: &Vars, c: usize) -> Result<Calibration> {
    let at = |name: &str| -> Result<f64> { Ok(v.f64s(name)?.get(c).copied().unwrap_or(f64::NAN)) };
    let analog = read_text(v.path, v.f, "acquisition_mode")
        .map(|m| m.get(c).is_some_and(|m| m == "analog"))
        .unwrap_or(false);
    Ok(Calibration {
        lidar_constant: at("lidar_constant")?,
        codes_per_photoelectron: if analog {
            at("analog_counts_per_photoelectron")?
        } else {
            1.0
        },
        offset_codes: if analog {
            at("analog_offset")? / at("adc_volts_per_count")?
        } else {
            0.0
        },
    })
}

/// The ∥/⊥ partner of channel `c` at its wavelength: `(parallel, perpendicular)`.
pub(super) fn pair(
    names: &[String],
    polarization: &[String],
    wavelength: &[f64],
    c: usize,
) -> Option<(usize, usize)> {
    let find = |pol: &str| {
        (0..names.len()).find(|&k| {
            polarization.get(k).is_some_and(|p| p == pol) && wavelength.get(k) == wavelength.get(c)
        })
    };
    match polarization.get(c).map(String::as_str) {
        Some("parallel") | Some("perpendicular") | Some("total") => {
            Some((find("parallel")?, find("perpendicular")?))
        }
        _ => None,
    }
}

/// The channel's index: `channel` by name, or the first.
pub(super) fn channel_index(v: &Vars, names: &[String], channel: Option<&str>) -> Result<usize> {
    match channel {
        None => Ok(0),
        Some(name) => names.iter().position(|n| n == name).ok_or_else(|| {
            v.fail(format!(
                "has no channel `{name}` (channels: {})",
                names.join(", ")
            ))
        }),
    }
}

/// The bins of channel `c` that hold no signal: the pre-trigger bins, else those whose
/// expected signal (in the first and the last profile) is below 1 % of their expected
/// background and dark.
fn background_bins(
    v: &Vars,
    t: &PerProfileReader,
    c: usize,
    n_profiles: usize,
    n_bins: usize,
) -> Result<Vec<usize>> {
    let n = pretrigger_bins(v.f);
    if n > 0 {
        return Ok((0..n.min(n_bins)).collect());
    }
    let last = n_profiles.saturating_sub(1);
    let row = |name: &str, p: usize| -> Result<Vec<f64>> {
        let r = t.rows(name, p..p + 1)?;
        Ok(r[c * n_bins..(c + 1) * n_bins].to_vec())
    };
    let (s0, s1) = (row("expected_signal", 0)?, row("expected_signal", last)?);
    let noise: Vec<f64> = row("expected_background", 0)?
        .iter()
        .zip(row("expected_dark", 0)?)
        .map(|(b, d)| b + d)
        .collect();
    Ok((0..n_bins.min(noise.len()).min(s0.len()).min(s1.len()))
        .filter(|&i| signal_free(s0[i].max(s1[i]), noise[i]))
        .collect())
}

/// The root attribute `pretrigger_bins`: bins recorded before the pulse leaves (0 when
/// absent or not a count).
fn pretrigger_bins(f: &hdf5::Group) -> usize {
    f.attr("pretrigger_bins")
        .and_then(|a| a.read_scalar::<i64>())
        .map_or(0, |n| n.max(0) as usize)
}

/// The origin of `time` (Unix seconds): the root attribute `start_time`, else the
/// `units` of `time` ("seconds since …").
pub(super) fn start_unix_s(root: &hdf5::Group, time: Option<&Dataset>) -> Option<f64> {
    let text = |a: hdf5::Attribute| attr_text(&a);
    let start = root.attr("start_time").ok().and_then(text).or_else(|| {
        time.and_then(|t| t.attr("units").ok())
            .and_then(text)
            .and_then(|u| u.strip_prefix("seconds since ").map(str::to_string))
    })?;
    let t = humantime::parse_rfc3339(start.trim()).ok()?;
    Some(t.duration_since(std::time::UNIX_EPOCH).ok()?.as_secs_f64())
}

/// The latitude ticks of a group's track (`along_track_distance` × `x_scale` against
/// its `latitude` and `longitude`), about six.
pub(super) fn track_latitude_marks(v: &Vars, x_scale: f64) -> Result<Vec<(f64, String)>> {
    let x: Vec<f64> = v
        .f64s("along_track_distance")?
        .iter()
        .map(|x| x * x_scale)
        .collect();
    Ok(latitude_marks(
        &x,
        &v.f64s("latitude")?,
        &v.f64s("longitude")?,
        6.0,
    ))
}

/// Appends `more` spans to `day`, joining the first to the last when they agree.
pub(super) fn extend_spans(day: &mut Vec<(f64, f64, bool)>, more: Vec<(f64, f64, bool)>) {
    for s in more {
        match day.last_mut() {
            Some((_, x1, d)) if *d == s.2 => *x1 = s.1,
            _ => day.push(s),
        }
    }
}

/// Day and night spans along the profiles' x, from the sun's zenith angle at each
/// profile's time (after `t0`, Unix seconds) and place.
pub(super) fn day_night(
    t0: f64,
    x: &[f64],
    time: &[f64],
    lat: &[f64],
    lon: &[f64],
) -> Vec<(f64, f64, bool)> {
    let mut spans: Vec<(f64, f64, bool)> = Vec::new();
    let e = edges(x);
    for k in 0..x.len().min(time.len()).min(lat.len()).min(lon.len()) {
        let day = crate::scene::sun::solar_zenith_deg(t0 + time[k], lat[k], lon[k]) < 90.0;
        match spans.last_mut() {
            Some(last) if last.2 == day => last.1 = e[k + 1],
            _ => spans.push((e[k], e[k + 1], day)),
        }
    }
    spans
}

/// Reads the quicklook of a raw file.
pub(super) fn read(
    path: &Path,
    f: &hdf5::File,
    channel: Option<&str>,
    truth: bool,
    view: View,
) -> Result<Quicklook> {
    let header = check(path, f)?;
    let v = Vars { path, f };
    let per_profile = PerProfileReader::new(path, f, &header)?;
    let names = header.channels.clone();
    let c = channel_index(&v, &names, channel)?;
    let (n_profiles, n_bins) = (header.n_profiles, header.n_bins);
    header.require_memory(
        path,
        "the quicklook",
        8.0 * (4 * COLUMNS * ROWS) as f64 * 2.0 + 8.0 * 4.0 * (BLOCK_PROFILES * n_bins) as f64,
    )?;
    let polarization = read_text(path, f, "polarization").unwrap_or_default();
    let wavelength = v.f64s("wavelength").unwrap_or_default();
    let pair = pair(&names, &polarization, &wavelength, c);

    // the axes: profiles along x, bins along z
    let kind = view.x_axis.resolve(header.along_track);
    if let Some(why) = kind.refusal(header.along_track, false) {
        return Err(v.fail(why));
    }
    let (x_first, x_last) = (
        v.x_of(kind, 0, 1)?[0],
        v.x_of(kind, n_profiles - 1, n_profiles)?[0],
    );
    let t0 = start_unix_s(f, f.dataset("time").ok().as_ref());
    let (x_scale, x_label, x_clock) = x_axis(kind, (x_last - x_first).abs(), t0, x_first);
    let title = raw_title(&v, t0, n_profiles, header.along_track)?;
    let x_marks = match kind {
        XAxis::Latitude => Some(track_latitude_marks(&v, x_scale)?),
        _ => None,
    };
    let dx = if n_profiles > 1 {
        (x_last - x_first) / (n_profiles - 1) as f64
    } else {
        1.0
    };
    let altitude_km: Vec<f64> = v.f64s("altitude")?.iter().map(|z| z / 1e3).collect();
    let z_edges = edges(&altitude_km);
    // the pre-trigger bins (before the pulse leaves) are left out of the figure
    let first_bin = pretrigger_bins(f).min(n_bins);
    let drawn = &z_edges[first_bin.min(z_edges.len())..];
    let zspan = view.z_span_km(
        drawn.iter().copied().fold(f64::INFINITY, f64::min),
        drawn.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let xspan = widen(
        (x_first - 0.5 * dx).min(x_last + 0.5 * dx) * x_scale,
        (x_first - 0.5 * dx).max(x_last + 0.5 * dx) * x_scale,
    );
    let empty = Grid::new(COLUMNS, ROWS, xspan, zspan);
    let bin_rows: Vec<Vec<(usize, f64)>> = z_edges
        .windows(2)
        .enumerate()
        .map(|(i, w)| {
            if i < first_bin {
                Vec::new()
            } else {
                empty.rows_of(w[0], w[1])
            }
        })
        .collect();
    let range_weight = v.f64s("range_weight")?;

    let channels: Vec<usize> = match pair {
        Some((a, b)) => vec![c, a, b],
        None => vec![c],
    };
    let cals: Vec<Calibration> = channels
        .iter()
        .map(|&k| calibration(&v, k))
        .collect::<Result<_>>()?;
    let bkg: Vec<Vec<usize>> = channels
        .iter()
        .map(|&k| background_bins(&v, &per_profile, k, n_profiles, n_bins))
        .collect::<Result<_>>()?;
    let mut grids = vec![empty.clone(); channels.len()];
    let mut mask = view.mask_snr.map(|x| (x, empty.clone()));
    let mut truth_grid = truth.then(|| empty.clone());
    let atb = truth.then_some(&per_profile);
    let counts = v.ds("counts")?;
    let nominal = v.f64s("nominal_pulse_energy")?;
    let geolocated = f.dataset("latitude").is_ok() && f.dataset("longitude").is_ok();
    let mut day = Vec::new();
    for p0 in (0..n_profiles).step_by(BLOCK_PROFILES) {
        let p1 = (p0 + BLOCK_PROFILES).min(n_profiles);
        let x: Vec<f64> = v.x_of(kind, p0, p1)?;
        let shots: Vec<u64> = counts_shots(&v, p0, p1)?;
        let energy = energy_factors(path, f, &header, p0..p1, &nominal)?;
        let columns: Vec<Vec<(usize, f64)>> = x
            .iter()
            .map(|&x| empty.columns((x - 0.5 * dx) * x_scale, (x + 0.5 * dx) * x_scale))
            .collect();
        for (j, (g, (&k, (cal, bins)))) in grids
            .iter_mut()
            .zip(channels.iter().zip(cals.iter().zip(&bkg)))
            .enumerate()
        {
            let block = counts
                .read_slice::<u64, _, Ix3>(s![p0..p1, k..k + 1, ..])
                .map_err(|e| v.unreadable("counts", e))?;
            // (a selection that keeps the channel axis reads 6 times faster in HDF5)
            let block = block.index_axis(Axis(1), 0);
            for (i, row) in block.outer_iter().enumerate() {
                let m = match (&mut mask, j) {
                    (Some((threshold, grid)), 0) => Some(Mask {
                        threshold: *threshold,
                        grid,
                        offset: cal.offset_codes,
                    }),
                    _ => None,
                };
                add_profile(
                    m,
                    g,
                    &columns[i],
                    &bin_rows,
                    row,
                    shots[i] as f64,
                    &Background::Bins(bins),
                    &range_weight,
                    cal,
                    energy.get(i * names.len() + k).copied().unwrap_or(1.0),
                );
            }
        }
        if let (Some(t), Some(d)) = (truth_grid.as_mut(), atb.as_ref()) {
            add_truth(t, d, c, n_bins, p0, p1, &columns, &bin_rows)?;
        }
        if let (true, Some(t0)) = (geolocated, t0) {
            let scaled: Vec<f64> = x.iter().map(|x| x * x_scale).collect();
            let (time, lat, lon) = (
                v.f64_range("time", p0, p1)?,
                v.f64_range("latitude", p0, p1)?,
                v.f64_range("longitude", p0, p1)?,
            );
            extend_spans(&mut day, day_night(t0, &scaled, &time, &lat, &lon));
        }
    }
    let background_note = if bkg[0].is_empty() {
        "no signal-free bin: background not subtracted".to_string()
    } else {
        format!("background from {} signal-free bins", bkg[0].len())
    };
    let mut grids = grids.into_iter();
    let signal = grids.next().expect("one channel");
    let pair = match (pair, grids.next(), grids.next()) {
        (Some(_), Some(a), Some(b)) => Some((
            a,
            b,
            format!("{} / {}", names[channels[2]], names[channels[1]]),
        )),
        _ => None,
    };
    Ok(Quicklook {
        title,
        file: file_name(path),
        background_note,
        x_label,
        x_clock,
        x_marks,
        signal,
        channel: names[c].clone(),
        pair,
        truth: truth_grid,
        day,
        mask,
    })
}

/// The file's name, as the figure shows it.
pub(super) fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The title of a raw file's figure: its instrument, the UTC times of its first and last
/// profile, its station or its track.
fn raw_title(v: &Vars, t0: Option<f64>, n: usize, orbit: bool) -> Result<String> {
    let (first, last) = (
        v.f64_range("time", 0, 1)?[0],
        v.f64_range("time", n - 1, n)?[0],
    );
    let point = |p: usize| -> Result<(f64, f64)> {
        Ok((
            v.f64_range("latitude", p, p + 1)?[0],
            v.f64_range("longitude", p, p + 1)?[0],
        ))
    };
    let track = if orbit {
        Some((point(0)?, point(n - 1)?))
    } else {
        None
    };
    Ok(title_line(
        &Source::of(v.f),
        t0.map(|t| span_edges(t + first, t + last, n)),
        track,
    ))
}

/// `n_shots` of profiles `p0..p1`.
fn counts_shots(v: &Vars, p0: usize, p1: usize) -> Result<Vec<u64>> {
    Ok(v.ds("n_shots")?
        .read_slice::<u64, _, Ix1>(s![p0..p1])
        .map_err(|e| v.unreadable("n_shots", e))?
        .to_vec())
}

/// Adds the truth's attenuated backscatter of profiles `p0..p1` (whatever its form in
/// the file: [`PerProfileReader`]).
#[allow(clippy::too_many_arguments)]
fn add_truth(
    grid: &mut Grid,
    t: &PerProfileReader,
    c: usize,
    n_bins: usize,
    p0: usize,
    p1: usize,
    columns: &[Vec<(usize, f64)>],
    bin_rows: &[Vec<(usize, f64)>],
) -> Result<()> {
    let rows = t.rows("attenuated_backscatter", p0..p1)?;
    let per = rows.len() / (p1 - p0).max(1);
    for (row, cols) in rows.chunks(per.max(1)).zip(columns) {
        let r = &row[c * n_bins..(c + 1) * n_bins];
        grid.add_profile(cols, bin_rows, r.iter().copied());
    }
    Ok(())
}
