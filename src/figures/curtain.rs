//! The curtain plot (`lidarsim curtain RAW.h5 --png OUT.png`): one channel's counts per
//! shot against along-track distance (or time) and altitude, on a logarithmic colour
//! scale (viridis) with its colour bar, as a PNG through `plot::ImagePanel`.
//!
//! The panel is filled pixel by pixel from at most one cell per pixel: each shows the
//! profile and bin nearest its centre, so a run of any length draws in time proportional
//! to the image, not to the file.

use std::path::Path;

use ndarray::{Ix2, s};
use plotters::prelude::*;

use super::plot::panel::{Axis, ImagePanel, edges};
use super::plot::text::{encode_png, ensure_font};
use super::plot::{ColourScale, DrawResult};
use crate::error::describe_hdf5_error;
use crate::error::{Error, Result};
use crate::output::raw_file;
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

/// The PNG of a curtain: the counts per shot against the profiles' coordinate and
/// altitude, with a colour bar of counts per shot ([`ImagePanel`], log scale).
pub fn png_bytes(c: &Curtain) -> std::result::Result<Vec<u8>, String> {
    ensure_font()?;
    let panel = panel(c);
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    draw(&panel, &mut rgb).map_err(|e| format!("drawing failed: {e}"))?;
    encode_png(&rgb, WIDTH, HEIGHT).map_err(|e| format!("PNG encoding failed: {e}"))
}

fn draw(panel: &ImagePanel, rgb: &mut [u8]) -> DrawResult {
    let root = BitMapBackend::with_buffer(rgb, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    panel.draw(&root)?;
    root.present()?;
    Ok(())
}

/// The curtain as an image panel. Its cells are the profiles and bins themselves when
/// there are no more of them than pixels (edges halfway between neighbours), else one
/// cell per pixel or so showing the profile (bin) nearest its centre: the panel holds
/// at most [`WIDTH`] × [`HEIGHT`] cells however long the run. Zero counts are drawn in
/// the scale's darkest colour (a log scale has no zero).
fn panel(c: &Curtain) -> ImagePanel {
    let scale = colour_scale(&c.counts_per_shot);
    let (profiles, x_edges) = cells(&c.x, WIDTH as usize);
    let (bins, z_edges) = cells(&c.altitude_km, HEIGHT as usize);
    let values: Vec<f64> = bins
        .iter()
        .flat_map(|&b| profiles.iter().map(move |&p| (p, b)))
        .map(|(p, b)| {
            let v = if b < c.n_bins {
                c.counts_per_shot.get(p * c.n_bins + b).copied()
            } else {
                None
            };
            match v.unwrap_or(f64::NAN) {
                0.0 => scale.lo,
                v => v,
            }
        })
        .collect();
    let ends = |e: &[f64]| match e {
        [] => (0.0, 1.0),
        [first, .., last] => (first.min(*last), first.max(*last)),
        [only] => (*only - 0.5, *only + 0.5),
    };
    let (x0, x1) = ends(&x_edges);
    let (z0, z1) = ends(&z_edges);
    ImagePanel {
        title: c.title.clone(),
        x: Axis::linear(c.x_label.clone(), x0, x1),
        y: Axis::linear("altitude (km)", z0, z1),
        x_edges,
        y_edges: z_edges,
        values,
        scale,
        bar_label: "counts per shot (zero: darkest)".into(),
        isolines: vec![],
    }
}

/// The log colour scale of counts per shot: up to the brightest value, down to a decade
/// below the faintest non-zero one (where zero is drawn, so that one count stands out
/// from none) but at most [`DECADES`] below the brightest.
fn colour_scale(v: &[f64]) -> ColourScale {
    let finite = v.iter().copied().filter(|x| x.is_finite());
    let peak = finite.clone().fold(f64::NEG_INFINITY, f64::max);
    let faintest = finite.filter(|&x| x > 0.0).fold(f64::INFINITY, f64::min);
    if peak > 0.0 && faintest.is_finite() {
        let lo = (faintest / 10.0).max(peak * 10f64.powf(-DECADES));
        ColourScale {
            lo,
            hi: peak,
            log: true,
        }
    } else {
        ColourScale::over(v.iter().copied(), true, DECADES)
    }
}

/// The cells of a coordinate `v` drawn on about `n` pixels: the indices of `v` each
/// cell shows and the cells' edges (one more). All of `v`, edges halfway between
/// neighbours, when it is finite, strictly monotonic and no longer than `n`; else `n`
/// equal cells over its range, each showing the element nearest its centre (neighbours
/// showing the same element merged).
fn cells(v: &[f64], n: usize) -> (Vec<usize>, Vec<f64>) {
    if v.is_empty() || n == 0 {
        return (vec![], vec![]);
    }
    let finite = v.iter().all(|x| x.is_finite());
    let ascending = v.windows(2).all(|w| w[1] > w[0]);
    let descending = v.windows(2).all(|w| w[1] < w[0]);
    let sorted = finite && (ascending || descending);
    if sorted && v.len() <= n {
        return ((0..v.len()).collect(), edges(v));
    }
    let (lo, hi) = bounds(v);
    let at = |k: usize| lo + (hi - lo) * k as f64 / n as f64;
    let mut shown: Vec<usize> = Vec::with_capacity(n);
    let mut e = vec![at(0)];
    for k in 0..n {
        let i = nearest(v, lo + (hi - lo) * (k as f64 + 0.5) / n as f64, sorted);
        if shown.last() == Some(&i) {
            if let Some(last) = e.last_mut() {
                *last = at(k + 1);
            }
        } else {
            shown.push(i);
            e.push(at(k + 1));
        }
    }
    (shown, e)
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

/// Index of the element of `v` nearest `x`: by bisection when `v` is `sorted`
/// (strictly monotonic, either way), else by looking at every element.
fn nearest(v: &[f64], x: f64, sorted: bool) -> usize {
    let distance = |i: usize| (v[i] - x).abs();
    if sorted && !v.is_empty() {
        let ascending = v[v.len() - 1] >= v[0];
        let p = v.partition_point(|&a| if ascending { a < x } else { a > x });
        let (a, b) = (p.saturating_sub(1), p.min(v.len() - 1));
        return if distance(b) < distance(a) { b } else { a };
    }
    (0..v.len())
        .min_by(|&a, &b| distance(a).total_cmp(&distance(b)))
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_by_bisection_agrees_with_the_scan() {
        let up: Vec<f64> = (0..50).map(|i| (i as f64).powf(1.3)).collect();
        let down: Vec<f64> = up.iter().rev().copied().collect();
        for k in 0..400 {
            let x = -5.0 + 0.4 * k as f64;
            for v in [&up, &down] {
                let (a, b) = (nearest(v, x, true), nearest(v, x, false));
                assert!((v[a] - x).abs() == (v[b] - x).abs(), "{x}: {a} {b}");
            }
        }
    }

    #[test]
    fn cells_are_the_elements_or_one_per_pixel() {
        let (i, e) = cells(&[10.0, 8.0, 6.0], 100);
        assert_eq!((i, e), (vec![0, 1, 2], vec![11.0, 9.0, 7.0, 5.0]));
        let long: Vec<f64> = (0..10_000).map(f64::from).collect();
        let (i, e) = cells(&long, 100);
        assert_eq!((i.len(), e.len()), (100, 101));
        assert!(i.windows(2).all(|w| w[1] > w[0]));
        // not monotonic (a NaN): equal cells, each the nearest finite element
        let (i, e) = cells(&[0.0, f64::NAN, 2.0], 4);
        assert_eq!(i, vec![0, 2]);
        assert_eq!(e, vec![0.0, 1.0, 2.0]);
    }
}
