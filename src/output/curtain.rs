//! The curtain plot (`lidarsim curtain RAW.h5 --png OUT.png`): one channel's counts per
//! shot against along-track distance (or time) and altitude, on a logarithmic colour
//! scale (`colorous` viridis), as a PNG through `plotters`.
//!
//! The plot area is filled pixel by pixel: each pixel shows the profile and bin nearest
//! its centre, so a run of any length draws in time proportional to the image, not to the
//! file.

use std::path::Path;

use ndarray::{Ix2, s};
use plotters::prelude::*;

use super::raw_file;
use super::safe_file::describe_hdf5_error;
use super::snr_map::{FONT, encode_png, ensure_font};
use crate::error::{Error, Result};
use crate::resources::try_vec;

/// Image width and height, pixels.
const WIDTH: u32 = 1200;
const HEIGHT: u32 = 600;
/// Decades of the colour scale below the brightest pixel.
const DECADES: f64 = 6.0;

/// One channel of a raw file, as the plot needs it.
pub struct Curtain {
    /// Counts per shot, (profile, bin) row-major.
    pub counts_per_shot: Vec<f64>,
    /// Bins per profile.
    pub n_bins: usize,
    /// Horizontal coordinate of each profile (km along track, or s).
    pub x: Vec<f64>,
    /// Its label.
    pub x_label: String,
    /// Bin-centre altitude, km.
    pub altitude_km: Vec<f64>,
    /// Title.
    pub title: String,
}

/// Reads channel `channel` (default the first) of the raw file `path`, checked as every
/// reader of raw files checks it ([`raw_file::read::check`]: the dimensions agree, the
/// coordinates are finite, every profile has shots) and refused, naming the file, where
/// its counts would not fit in memory.
pub fn read(path: &Path, channel: Option<&str>) -> Result<Curtain> {
    let fail = |why: String| Error::output(path, why);
    crate::input_file::check("RAW.h5", path)?;
    let f =
        hdf5::File::open(path).map_err(|_| fail("not a lidarsim raw file (not HDF5)".into()))?;
    let header = raw_file::read::check(path, &f)?;
    let names = &header.channels;
    let c = match channel {
        None => 0,
        Some(name) => names.iter().position(|n| n == name).ok_or_else(|| {
            fail(format!(
                "has no channel `{name}` (channels: {})",
                names.join(", ")
            ))
        })?,
    };
    let (profiles, n_bins) = (header.n_profiles, header.n_bins);
    // the channel's counts as read (u64) and per shot (f64), the coordinates
    let values = profiles as f64 * n_bins as f64;
    header.require_memory(
        path,
        "the curtain",
        16.0 * values + 16.0 * (profiles + n_bins) as f64,
    )?;
    let unreadable = |name: &str, e: hdf5::Error| {
        fail(format!(
            "cannot read `{name}`: {}",
            describe_hdf5_error(&e.to_string())
        ))
    };
    let get = |name: &str| {
        f.dataset(name)
            .map_err(|_| fail(format!("has no `{name}`")))
    };
    let read_f64 = |name: &str| -> Result<Vec<f64>> {
        get(name)?
            .read_raw::<f64>()
            .map_err(|e| unreadable(name, e))
    };
    let shots: Vec<u64> = get("n_shots")?
        .read_raw::<u64>()
        .map_err(|e| unreadable("n_shots", e))?;
    let counts = get("counts")?
        .read_slice::<u64, _, Ix2>(s![.., c, ..])
        .map_err(|e| unreadable("counts", e))?;
    let mut counts_per_shot = try_vec("the curtain", profiles * n_bins, 0.0)?;
    for (p, row) in counts.outer_iter().enumerate() {
        let per_shot = 1.0 / shots[p] as f64;
        for (out, &x) in counts_per_shot[p * n_bins..][..n_bins].iter_mut().zip(row) {
            *out = x as f64 * per_shot;
        }
    }
    drop(counts);
    let x_name = if header.along_track {
        "along_track_distance"
    } else {
        "time"
    };
    let (x, x_label) = if header.along_track {
        (
            read_f64("along_track_distance")?
                .iter()
                .map(|m| m / 1e3)
                .collect(),
            "along-track distance (km)".into(),
        )
    } else {
        (read_f64("time")?, "time (s)".into())
    };
    let altitude_km: Vec<f64> = read_f64("altitude")?.iter().map(|z| z / 1e3).collect();
    // an axis whose span overflows f64 has no ticks: plotters would search forever
    for (name, v) in [(x_name, &x), ("altitude", &altitude_km)] {
        let (lo, hi) = bounds(v);
        if !(hi - lo).is_finite() {
            return Err(fail(format!(
                "`{name}` spans {} to {}: wider than a plot axis can hold",
                crate::error::compact(lo),
                crate::error::compact(hi)
            )));
        }
    }
    Ok(Curtain {
        counts_per_shot,
        n_bins,
        x,
        x_label,
        altitude_km,
        title: format!("{}: counts per shot, channel {}", path.display(), names[c]),
    })
}

/// The PNG of a curtain.
pub fn png_bytes(c: &Curtain) -> std::result::Result<Vec<u8>, String> {
    ensure_font()?;
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    draw(c, &mut rgb).map_err(|e| format!("drawing failed: {e}"))?;
    encode_png(&rgb, WIDTH, HEIGHT).map_err(|e| format!("PNG encoding failed: {e}"))
}

fn draw(c: &Curtain, rgb: &mut [u8]) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(rgb, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    let (x0, x1) = bounds(&c.x);
    let (z0, z1) = bounds(&c.altitude_km);
    let mut chart = ChartBuilder::on(&root)
        .caption(&c.title, (FONT, 16))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(x0..x1, z0..z1)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(c.x_label.as_str())
        .y_desc("altitude (km)")
        .label_style((FONT, 13))
        .draw()?;
    let peak = c.counts_per_shot.iter().fold(0.0f64, |m, &v| m.max(v));
    let top = peak.max(1e-300).log10();
    let area = chart.plotting_area();
    let (px, py) = area.get_pixel_range();
    let (w, h) = (px.end - px.start, py.end - py.start);
    // the data point at the centre of each pixel column and row, and its nearest profile and bin
    let xs: Vec<f64> = (0..w)
        .map(|i| x0 + (x1 - x0) * (f64::from(i) + 0.5) / f64::from(w))
        .collect();
    let zs: Vec<f64> = (0..h)
        .map(|j| z1 - (z1 - z0) * (f64::from(j) + 0.5) / f64::from(h))
        .collect();
    let profiles: Vec<usize> = xs.iter().map(|&x| nearest(&c.x, x)).collect();
    let bins: Vec<usize> = zs.iter().map(|&z| nearest(&c.altitude_km, z)).collect();
    for (x, &p) in xs.iter().zip(&profiles) {
        for (z, &b) in zs.iter().zip(&bins) {
            let v = c.counts_per_shot[p * c.n_bins + b];
            let t = if v > 0.0 {
                ((v.log10() - top) / DECADES + 1.0).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let col = colorous::VIRIDIS.eval_continuous(t);
            area.draw_pixel((*x, *z), &RGBColor(col.r, col.g, col.b))?;
        }
    }
    root.present()?;
    Ok(())
}

/// `(min, max)` of the finite values of `v`, widened when they coincide; `(0, 1)` when
/// there are none. Never infinite: an infinite axis range makes the axis' tick search
/// run forever (the hang of issue 18, with `inf` in `time`).
fn bounds(v: &[f64]) -> (f64, f64) {
    let finite = v.iter().copied().filter(|x| x.is_finite());
    let lo = finite.clone().fold(f64::INFINITY, f64::min);
    let hi = finite.fold(f64::NEG_INFINITY, f64::max);
    if !(lo.is_finite() && hi.is_finite()) {
        (0.0, 1.0)
    } else if hi - lo > 0.0 && (hi - lo).is_finite() {
        (lo, hi)
    } else {
        (lo - 0.5, hi + 0.5)
    }
}

/// Index of the element of `v` nearest `x` (v monotonic, either way).
fn nearest(v: &[f64], x: f64) -> usize {
    (0..v.len())
        .min_by(|&a, &b| (v[a] - x).abs().total_cmp(&(v[b] - x).abs()))
        .unwrap_or(0)
}
