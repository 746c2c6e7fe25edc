//! The curtain plot (`lidarsim curtain RAW.h5 --png OUT.png`): one channel's counts per
//! shot against along-track distance (or time) and altitude, on a logarithmic colour
//! scale (`colorous` viridis), as a PNG through `plotters`.
//!
//! The plot area is filled pixel by pixel: each pixel shows the profile and bin nearest
//! its centre, so a run of any length draws in time proportional to the image, not to the
//! file.

use std::path::Path;

use plotters::prelude::*;

use super::snr_map::{FONT, encode_png, ensure_font};
use crate::error::{Error, Result};

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

/// Reads channel `channel` (default the first) of the raw file `path`.
pub fn read(path: &Path, channel: Option<&str>) -> Result<Curtain> {
    let fail = |why: String| Error::output(path, why);
    crate::input_file::check("RAW.h5", path)?;
    let f =
        hdf5::File::open(path).map_err(|_| fail("not a lidarsim raw file (not HDF5)".into()))?;
    let get = |name: &str| {
        f.dataset(name).map_err(|_| {
            fail(format!(
                "has no `{name}`: not a lidarsim raw file of format 2"
            ))
        })
    };
    let names: Vec<String> = get("channel")?
        .read_raw::<hdf5::types::VarLenUnicode>()
        .map_err(|e| fail(e.to_string()))?
        .iter()
        .map(|s| s.as_str().to_string())
        .collect();
    let c = match channel {
        None => 0,
        Some(name) => names.iter().position(|n| n == name).ok_or_else(|| {
            fail(format!(
                "has no channel `{name}` (channels: {})",
                names.join(", ")
            ))
        })?,
    };
    let counts = get("counts")?;
    let shape = counts.shape();
    let [profiles, _, n_bins] = shape[..] else {
        return Err(fail("`counts` is not (profile, channel, bin)".into()));
    };
    let read_f64 = |name: &str| -> Result<Vec<f64>> {
        get(name)?
            .read_raw::<f64>()
            .map_err(|e| fail(e.to_string()))
    };
    let shots: Vec<f64> = get("n_shots")?
        .read_raw::<u64>()
        .map_err(|e| fail(e.to_string()))?
        .iter()
        .map(|&n| n as f64)
        .collect();
    let all: Vec<u64> = counts.read_raw().map_err(|e| fail(e.to_string()))?;
    let mut counts_per_shot = Vec::with_capacity(profiles * n_bins);
    for p in 0..profiles {
        let row = &all[(p * names.len() + c) * n_bins..][..n_bins];
        counts_per_shot.extend(row.iter().map(|&x| x as f64 / shots[p].max(1.0)));
    }
    let (x, x_label) = match read_f64("along_track_distance") {
        Ok(d) => (
            d.iter().map(|m| m / 1e3).collect(),
            "along-track distance (km)".into(),
        ),
        Err(_) => (read_f64("time")?, "time (s)".into()),
    };
    Ok(Curtain {
        counts_per_shot,
        n_bins,
        x,
        x_label,
        altitude_km: read_f64("altitude")?.iter().map(|z| z / 1e3).collect(),
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

/// `(min, max)` of `v`, widened when they coincide.
fn bounds(v: &[f64]) -> (f64, f64) {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi > lo {
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
