//! The quicklook of an onboard product: every region group stitched on one grid at
//! its own resolution (its bins over the rows they cover, its profiles over the
//! columns), the background from the product's expected background and dark counts.
//! Every region is checked first as `merge` checks it ([`crate::onboard::merge::check_region`]).

use std::path::Path;

use hdf5::Dataset;
use ndarray::{Axis, Ix1, Ix2, Ix3, s};

use super::axis::{XAxis, x_axis};
use super::figure::{
    BLOCK_PROFILES, Background, COLUMNS, Calibration, Mask, Quicklook, ROWS, View, add_profile,
};
use super::grid::Grid;
use super::raw::{
    Vars, day_night, extend_spans, file_name, pair, start_unix_s, track_latitude_marks,
};
use super::title::{Source, span_edges, title_line};
use crate::error::Result;
use crate::figures::plot::panel::{edges, widen};

/// One region group as the quicklook reads it.
struct Region {
    group: hdf5::Group,
    channels: Vec<String>,
    n_profiles: usize,
    /// Bin edges, km.
    z_edges: Vec<f64>,
    /// First and last profile coordinate (m or s).
    x_ends: (f64, f64),
    /// Native bins per region bin.
    merged: f64,
}

/// The product's region groups (`region_0`, …), checked enough to draw.
fn regions(path: &Path, f: &hdf5::File, xname: &str) -> Result<Vec<Region>> {
    let fail = |why: String| crate::error::Error::output(path, why);
    let mut names: Vec<String> = f
        .member_names()
        .map_err(|_| fail("cannot list the product's groups".into()))?
        .into_iter()
        .filter(|n| n.starts_with("region_"))
        .collect();
    names.sort_by_key(|n| n[7..].parse::<usize>().unwrap_or(usize::MAX));
    let mut out = Vec::new();
    for name in names {
        let group = f
            .group(&name)
            .map_err(|_| fail(format!("`{name}` is not a group")))?;
        // the check `merge` applies to every region of every shard: nothing it refuses
        // is drawn
        crate::onboard::merge::check_region(&group, path)?;
        let v = Vars { path, f: &group };
        let prefix = format!("{name}/");
        let (channels, _) =
            crate::output::raw_file::integrity::channel_labels(path, &group, &prefix)?;
        let altitude_km: Vec<f64> = v.f64s("altitude")?.iter().map(|z| z / 1e3).collect();
        let n_profiles = v.ds("n_shots")?.shape().first().copied().unwrap_or(0);
        if n_profiles == 0 || altitude_km.is_empty() || altitude_km.iter().any(|z| !z.is_finite()) {
            continue;
        }
        let x0 = v.f64_range(xname, 0, 1)?[0];
        let x1 = v.f64_range(xname, n_profiles - 1, n_profiles)?[0];
        let merged = group
            .attr("native_bins_merged")
            .ok()
            .and_then(|a| a.read_scalar::<u32>().ok())
            .unwrap_or(1) as f64;
        out.push(Region {
            z_edges: edges(&altitude_km),
            group,
            channels,
            n_profiles,
            x_ends: (x0, x1),
            merged,
        });
    }
    if out.is_empty() {
        return Err(fail(
            "an onboard product with no region group holding profiles".into(),
        ));
    }
    Ok(out)
}

/// Reads the quicklook of an onboard product.
pub(super) fn read(
    path: &Path,
    f: &hdf5::File,
    channel: Option<&str>,
    truth: bool,
    view: View,
) -> Result<Quicklook> {
    let fail = |why: String| crate::error::Error::output(path, why);
    let first = f
        .member_names()
        .ok()
        .and_then(|n| n.into_iter().find(|n| n.starts_with("region_")))
        .and_then(|n| f.group(&n).ok())
        .ok_or_else(|| fail("an onboard product with no region group".into()))?;
    let along_track = first.dataset("along_track_distance").is_ok();
    let kind = view.x_axis.resolve(along_track);
    if let Some(why) = kind.refusal(along_track, true) {
        return Err(fail(why));
    }
    let xname = kind.variable().unwrap_or("time");
    let regions = regions(path, f, xname)?;
    let all: Vec<&String> = regions.iter().flat_map(|r| &r.channels).collect();
    let name = match channel {
        Some(c) => all
            .iter()
            .find(|n| n.as_str() == c)
            .map(|n| n.to_string())
            .ok_or_else(|| fail(format!("has no channel `{c}`")))?,
        None => regions[0]
            .channels
            .first()
            .cloned()
            .ok_or_else(|| fail("a region without channels".into()))?,
    };
    let span = regions
        .iter()
        .map(|r| (r.x_ends.1 - r.x_ends.0).abs())
        .fold(0.0, f64::max);
    let t0 = start_unix_s(f, first.dataset("time").ok().as_ref());
    let x_first = regions
        .iter()
        .map(|r| r.x_ends.0.min(r.x_ends.1))
        .fold(f64::INFINITY, f64::min);
    let (x_scale, x_label, x_clock) = x_axis(kind, span, t0, x_first);
    let title = product_title(path, f, &regions[0].group, t0, along_track)?;
    let x_marks = match kind {
        // the first region's track places the ticks
        XAxis::Latitude => Some(track_latitude_marks(
            &Vars {
                path,
                f: &regions[0].group,
            },
            x_scale,
        )?),
        _ => None,
    };
    let (mut xlo, mut xhi, mut zlo, mut zhi) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for r in &regions {
        let dx = spacing(r);
        xlo = xlo.min(r.x_ends.0.min(r.x_ends.1) - 0.5 * dx.abs());
        xhi = xhi.max(r.x_ends.0.max(r.x_ends.1) + 0.5 * dx.abs());
        for &z in &r.z_edges {
            zlo = zlo.min(z);
            zhi = zhi.max(z);
        }
    }
    let empty = Grid::new(
        COLUMNS,
        ROWS,
        widen(xlo * x_scale, xhi * x_scale),
        view.z_span_km(zlo, zhi),
    );
    let mut signal = empty.clone();
    let (mut par, mut perp) = (empty.clone(), empty.clone());
    let mut has_pair = false;
    let mut truth_grid = truth.then(|| empty.clone());
    let mut mask = view.mask_snr.map(|x| (x, empty.clone()));
    let mut day = Vec::new();
    for r in &regions {
        let v = Vars { path, f: &r.group };
        // a product's groups name their channels only: `<wavelength>_<polarization>`
        // (the default names, docs/config.md) tell the pair
        let polarization: Vec<String> = r
            .channels
            .iter()
            .map(|n| n.rsplit('_').next().unwrap_or("").to_string())
            .collect();
        let wavelength: Vec<f64> = r
            .channels
            .iter()
            .map(|n| {
                n.split('_')
                    .next()
                    .and_then(|w| w.parse().ok())
                    .unwrap_or(f64::NAN)
            })
            .collect();
        let c = r.channels.iter().position(|n| *n == name);
        let p = c
            .and_then(|c| pair(&r.channels, &polarization, &wavelength, c))
            .or_else(|| {
                // a region without the channel may still hold a pair of the same wavelength
                let k = r.channels.iter().position(|n| n.ends_with("parallel"))?;
                pair(&r.channels, &polarization, &wavelength, k)
            });
        let bin_rows: Vec<Vec<(usize, f64)>> = r
            .z_edges
            .windows(2)
            .map(|w| empty.rows_of(w[0], w[1]))
            .collect();
        let range_weight = v.f64s("range_weight")?;
        let nominal = v.f64s("nominal_pulse_energy")?;
        let dx = spacing(r);
        let mut jobs: Vec<(usize, &mut Grid)> = Vec::new();
        if let Some(c) = c {
            jobs.push((c, &mut signal));
        }
        if let Some((a, b)) = p {
            has_pair = true;
            jobs.push((a, &mut par));
            jobs.push((b, &mut perp));
        }
        let cals: Vec<Calibration> = jobs
            .iter()
            .map(|(k, _)| product_calibration(&v, *k))
            .collect::<Result<_>>()?;
        let counts = v.ds("counts")?;
        let atb = match (truth, c) {
            (true, Some(_)) => Some(v.ds("attenuated_backscatter")?),
            _ => None,
        };
        for p0 in (0..r.n_profiles).step_by(BLOCK_PROFILES) {
            let p1 = (p0 + BLOCK_PROFILES).min(r.n_profiles);
            let x = v.f64_range(xname, p0, p1)?;
            let shots: Vec<u64> = v
                .ds("n_shots")?
                .read_slice::<u64, _, Ix1>(s![p0..p1])
                .map_err(|e| v.unreadable("n_shots", e))?
                .to_vec();
            let energy = energy_factors(&v, p0, p1, &nominal)?;
            let columns: Vec<Vec<(usize, f64)>> = x
                .iter()
                .map(|&x| empty.columns((x - 0.5 * dx) * x_scale, (x + 0.5 * dx) * x_scale))
                .collect();
            for (j, ((k, grid), cal)) in jobs.iter_mut().zip(&cals).enumerate() {
                let bkg = noise_block(&v, *k, p0, p1)?;
                let block = counts
                    .read_slice::<u64, _, Ix3>(s![p0..p1, *k..*k + 1, ..])
                    .map_err(|e| v.unreadable("counts", e))?;
                let block = block.index_axis(Axis(1), 0);
                for (i, row) in block.outer_iter().enumerate() {
                    let m = match (&mut mask, j, c) {
                        (Some((threshold, grid)), 0, Some(_)) => Some(Mask {
                            threshold: *threshold,
                            grid,
                            offset: cal.offset_codes * r.merged,
                        }),
                        _ => None,
                    };
                    add_profile(
                        m,
                        grid,
                        &columns[i],
                        &bin_rows,
                        row,
                        shots[i] as f64,
                        &Background::Value(cal.record_of(bkg[i]) * r.merged),
                        &range_weight,
                        cal,
                        energy.get(i * nominal.len() + *k).copied().unwrap_or(1.0),
                    );
                }
            }
            if let (Some(t), Some(d), Some(c)) = (truth_grid.as_mut(), atb.as_ref(), c) {
                add_column_truth(&v, t, d, c, p0, p1, &columns, &bin_rows)?;
            }
            // day and night from the first region's profiles
            if let (Some(t0), true, Ok(time), Ok(lat), Ok(lon)) = (
                t0,
                std::ptr::eq(r, &regions[0]),
                v.f64_range("time", p0, p1),
                v.f64_range("latitude", p0, p1),
                v.f64_range("longitude", p0, p1),
            ) {
                let scaled: Vec<f64> = x.iter().map(|x| x * x_scale).collect();
                extend_spans(&mut day, day_night(t0, &scaled, &time, &lat, &lon));
            }
        }
    }
    Ok(Quicklook {
        title,
        file: file_name(path),
        background_note: format!(
            "{} regions; background: the product's expected background and dark counts",
            regions.len()
        ),
        x_label,
        x_clock,
        x_marks,
        signal,
        channel: name,
        pair: has_pair.then(|| (par, perp, "perpendicular / parallel".to_string())),
        truth: truth_grid,
        day,
        mask,
    })
}

/// The title of a product's figure: the native run's instrument, the UTC times of the
/// first region's first and last profile, its station or its track.
fn product_title(
    path: &Path,
    root: &hdf5::File,
    g: &hdf5::Group,
    t0: Option<f64>,
    orbit: bool,
) -> Result<String> {
    let v = Vars { path, f: g };
    let time = v.f64s("time")?;
    let (first, last) = (
        time.first().copied().unwrap_or(0.0),
        time.last().copied().unwrap_or(0.0),
    );
    let track = if orbit {
        let (lat, lon) = (v.f64s("latitude")?, v.f64s("longitude")?);
        lat.first()
            .zip(lon.first())
            .zip(lat.last().zip(lon.last()))
            .map(|((a, b), (c, d))| ((*a, *b), (*c, *d)))
    } else {
        None
    };
    Ok(title_line(
        &Source::of(root),
        t0.map(|t| span_edges(t + first, t + last, time.len())),
        track,
    ))
}

/// Channel `c`'s calibration in a product's region: its lidar constant and how its counts
/// record photoelectrons (`counts_per_photoelectron`, `counts_offset`: the analog chain's
/// codes and baseline, 1 and 0 for a photon counter).
fn product_calibration(v: &Vars, c: usize) -> Result<Calibration> {
    let at = |name: &str| -> Result<f64> { Ok(v.f64s(name)?.get(c).copied().unwrap_or(f64::NAN)) };
    Ok(Calibration {
        lidar_constant: at("lidar_constant")?,
        codes_per_photoelectron: at("counts_per_photoelectron")?,
        offset_codes: at("counts_offset")?,
    })
}

/// The spacing of a region's profiles along x (1 for a single profile).
fn spacing(r: &Region) -> f64 {
    if r.n_profiles > 1 {
        (r.x_ends.1 - r.x_ends.0) / (r.n_profiles - 1) as f64
    } else {
        1.0
    }
}

/// The energy factors `E/E₀` of a region's profiles `p0..p1`, (profile, channel)
/// row-major: `pulse_energy[p, c] / nominal_pulse_energy[c]`; a product of an earlier
/// version kept one energy per profile, at the first channel's nominal energy, whose
/// factor every channel shares (one laser's shots). A nominal energy of 0: factor 1.
fn energy_factors(v: &Vars, p0: usize, p1: usize, nominal: &[f64]) -> Result<Vec<f64>> {
    let d = v.ds("pulse_energy")?;
    let ratio = |e: f64, e0: f64| if e0 > 0.0 { e / e0 } else { 1.0 };
    Ok(match d.ndim() {
        2 => d
            .read_slice::<f64, _, Ix2>(s![p0..p1, ..])
            .map_err(|e| v.unreadable("pulse_energy", e))?
            .outer_iter()
            .flat_map(|row| {
                row.iter()
                    .zip(nominal)
                    .map(|(&e, &e0)| ratio(e, e0))
                    .collect::<Vec<_>>()
            })
            .collect(),
        _ => {
            let e0 = nominal.first().copied().unwrap_or(0.0);
            v.f64_range("pulse_energy", p0, p1)?
                .iter()
                .flat_map(|&e| std::iter::repeat_n(ratio(e, e0), nominal.len()))
                .collect()
        }
    })
}

/// `expected_background + expected_dark` per shot and native bin, profiles `p0..p1`
/// (photoelectrons: an analog channel's record of them is [`Calibration::record_of`]).
fn noise_block(v: &Vars, c: usize, p0: usize, p1: usize) -> Result<Vec<f64>> {
    let read = |name: &str| -> Result<Vec<f64>> {
        Ok(v.ds(name)?
            .read_slice::<f64, _, Ix1>(s![p0..p1, c])
            .map_err(|e| v.unreadable(name, e))?
            .to_vec())
    };
    Ok(read("expected_background")?
        .iter()
        .zip(read("expected_dark")?)
        .map(|(b, d)| b + d)
        .collect())
}

/// Adds the truth of profiles `p0..p1`: each profile's columns' attenuated backscatter
/// weighted by the share of its shots that saw them.
#[allow(clippy::too_many_arguments)]
fn add_column_truth(
    v: &Vars,
    grid: &mut Grid,
    d: &Dataset,
    c: usize,
    p0: usize,
    p1: usize,
    columns: &[Vec<(usize, f64)>],
    bin_rows: &[Vec<(usize, f64)>],
) -> Result<()> {
    let n_columns = d.shape().first().copied().unwrap_or(0);
    let per_column: Vec<Vec<f64>> = (0..n_columns)
        .map(|k| {
            Ok(d.read_slice::<f64, _, Ix1>(s![k, c, ..])
                .map_err(|e| v.unreadable("attenuated_backscatter", e))?
                .to_vec())
        })
        .collect::<Result<_>>()?;
    let col = v
        .ds("profile_column")?
        .read_slice::<i32, _, Ix2>(s![p0..p1, ..])
        .map_err(|e| v.unreadable("profile_column", e))?;
    let w = v
        .ds("profile_column_weight")?
        .read_slice::<f64, _, Ix2>(s![p0..p1, ..])
        .map_err(|e| v.unreadable("profile_column_weight", e))?;
    for (i, cols) in columns.iter().enumerate() {
        for (b, rows) in bin_rows.iter().enumerate() {
            let mut sum = 0.0;
            for (k, &ck) in col.row(i).iter().enumerate() {
                if let Some(truth) = usize::try_from(ck).ok().and_then(|ck| per_column.get(ck)) {
                    sum += w[[i, k]] * truth.get(b).copied().unwrap_or(0.0);
                }
            }
            grid.add_covered(cols, rows, sum);
        }
    }
    Ok(())
}
