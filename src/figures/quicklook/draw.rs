//! The quicklook figure: the signal panel, the truth beside it on the same scale, the
//! volume depolarization, each an [`ImagePanel`] of the shared plotting module.

use plotters::prelude::*;

use super::figure::Quicklook;
use super::grid::Grid;
use crate::figures::plot::colour::ColourScale;
use crate::figures::plot::panel::{Axis, ImagePanel};
use crate::figures::plot::text::{encode_png, ensure_font, font, label};
use plotters::style::text_anchor::{HPos, VPos};

/// Figure width, pixels.
const WIDTH: u32 = 1400;
/// Height of one panel, pixels.
pub const PANEL_HEIGHT: u32 = 430;
/// Height of the figure's title (two lines), pixels.
pub const TITLE_HEIGHT: u32 = 52;
/// Decades of the signal's colour scale below its top.
const DECADES: f64 = 3.5;
/// The signal's colour scale tops at [`HEADROOM`] times this quantile of the cells (the
/// bulk of the clear air's return near the ground), or at the brightest cells if they
/// are less: clouds take the upper colours, a surface echo brighter than them
/// saturates rather than darken the rest.
const BULK_QUANTILE: f64 = 0.99;
/// See [`BULK_QUANTILE`].
const HEADROOM: f64 = 30.0;
/// The volume depolarization's colour scale.
const DEPOLARIZATION: (f64, f64) = (0.0, 0.5);

/// The `q`-quantile of the finite positive values.
fn quantile(v: &[f64], q: f64) -> Option<f64> {
    let mut p: Vec<f64> = v
        .iter()
        .copied()
        .filter(|x| x.is_finite() && *x > 0.0)
        .collect();
    if p.is_empty() {
        return None;
    }
    let k = ((p.len() - 1) as f64 * q).round() as usize;
    let (_, x, _) = p.select_nth_unstable_by(k, f64::total_cmp);
    Some(*x)
}

/// A panel of grid `g`'s `values`.
fn panel(
    q: &Quicklook,
    g: &Grid,
    title: String,
    values: Vec<f64>,
    scale: ColourScale,
    bar: &str,
) -> ImagePanel {
    let step = |(lo, hi): (f64, f64), n: usize| -> Vec<f64> {
        (0..=n)
            .map(|k| lo + (hi - lo) * k as f64 / n as f64)
            .collect()
    };
    let mut y_edges = step(g.z, g.rows);
    y_edges.reverse(); // row 0 is the top
    ImagePanel {
        title,
        x: match (&q.x_marks, q.x_clock) {
            (Some(m), _) => Axis::marked(q.x_label.clone(), g.x.0, g.x.1, m.clone()),
            (None, Some(clock)) => Axis::clock(q.x_label.clone(), g.x.0, g.x.1, clock),
            (None, None) => Axis::linear(q.x_label.clone(), g.x.0, g.x.1),
        },
        y: Axis::linear("altitude (km)", g.z.0, g.z.1),
        x_edges: step(g.x, g.cols),
        y_edges,
        values,
        scale,
        bar_label: bar.into(),
        isolines: vec![],
    }
}

/// The figure's panels of one channel, top to bottom: its signal, its truth with
/// `--truth`, and with `with_pair` the volume depolarization of its ∥/⊥ pair.
pub fn panels(q: &Quicklook, with_pair: bool) -> Vec<ImagePanel> {
    let signal = q.signal.means();
    let truth = q.truth.as_ref().map(Grid::means);
    let bulk = quantile(&signal, BULK_QUANTILE)
        .into_iter()
        .chain(truth.as_ref().and_then(|t| quantile(t, BULK_QUANTILE)))
        .fold(f64::NAN, f64::max);
    let top = quantile(&signal, 0.9999).unwrap_or(f64::INFINITY);
    let hi = (bulk * HEADROOM).min(top.max(bulk));
    let hi = if hi.is_finite() { hi } else { 1.0 };
    let scale = ColourScale {
        lo: hi * 10f64.powf(-DECADES),
        hi,
        log: true,
    };
    let floored = |v: Vec<f64>| -> Vec<f64> {
        // noise below the floor (or below zero after the background) is the floor's
        v.into_iter()
            .map(|x| if x.is_nan() { x } else { x.max(scale.lo) })
            .collect()
    };
    let bar = "attenuated backscatter (m⁻¹ sr⁻¹)";
    let mut shown = floored(signal);
    let mut masked = String::new();
    // grey where more than half the cell's bins have an S/N below X
    let below: Option<Vec<bool>> = q
        .mask
        .as_ref()
        .map(|(_, m)| m.means().iter().map(|&s| s > 0.5).collect());
    let grey = |v: &mut [f64]| {
        for (v, &b) in v.iter_mut().zip(below.iter().flatten()) {
            if b {
                *v = f64::NAN;
            }
        }
    };
    if let Some((x, _)) = &q.mask {
        grey(&mut shown);
        masked = format!(
            "; grey: S/N < {} (from the counts)",
            crate::error::compact(*x)
        );
    }
    let mut out = vec![panel(
        q,
        &q.signal,
        format!(
            "{}: background-subtracted, range-corrected signal over the lidar constant{masked}",
            q.channel
        ),
        shown,
        scale,
        bar,
    )];
    if let Some(t) = truth {
        out.push(panel(
            q,
            &q.signal,
            format!("{}: truth (attenuated_backscatter)", q.channel),
            floored(t),
            scale,
            bar,
        ));
    }
    if let (true, Some((par, perp, name))) = (with_pair, &q.pair) {
        let (a, b) = (par.means(), perp.means());
        let mut delta: Vec<f64> = a
            .iter()
            .zip(&b)
            .map(|(&p, &s)| if p > scale.lo { s / p } else { f64::NAN })
            .collect();
        grey(&mut delta);
        let depol = ColourScale {
            lo: DEPOLARIZATION.0,
            hi: DEPOLARIZATION.1,
            log: false,
        };
        out.push(panel(
            q,
            par,
            format!("volume depolarization ratio ({name}){masked}"),
            delta,
            depol,
            "volume depolarization ratio",
        ));
    }
    out
}

/// The PNG of the quicklook of one or more channels of a file (`qs`, one per channel,
/// read with the same view): a title of two lines, then each channel's panels, stacked
/// on the same x axis; the volume depolarization only when one channel is drawn.
pub fn png_bytes(qs: &[Quicklook]) -> std::result::Result<Vec<u8>, String> {
    ensure_font()?;
    let Some(q) = qs.first() else {
        return Err("no channel to draw".into());
    };
    let panels: Vec<ImagePanel> = qs.iter().flat_map(|c| panels(c, qs.len() == 1)).collect();
    let height = TITLE_HEIGHT + PANEL_HEIGHT * panels.len() as u32;
    let mut rgb = vec![255u8; (WIDTH * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (title, rest) = root.split_vertically(TITLE_HEIGHT);
        let day_note = if q.day.is_empty() {
            ""
        } else {
            "; band along the top: day (yellow), night (navy)"
        };
        let mid = (WIDTH / 2) as i32;
        label(
            &title,
            &q.title,
            (mid, 16),
            &font(18.0),
            HPos::Center,
            VPos::Center,
        )
        .map_err(|e| e.to_string())?;
        label(
            &title,
            &format!("{} — {}{day_note}", q.file, q.background_note),
            (mid, 39),
            &font(13.0),
            HPos::Center,
            VPos::Center,
        )
        .map_err(|e| e.to_string())?;
        let marks: Vec<(f64, f64, RGBColor)> = q
            .day
            .iter()
            .map(|&(a, b, day)| {
                (
                    a,
                    b,
                    if day {
                        RGBColor(250, 200, 30)
                    } else {
                        RGBColor(20, 30, 90)
                    },
                )
            })
            .collect();
        for (k, (p, area)) in panels
            .iter()
            .zip(rest.split_evenly((panels.len(), 1)))
            .enumerate()
        {
            let m = if k == 0 { marks.as_slice() } else { &[] };
            p.draw_with_marks(&area, m)
                .map_err(|e| format!("drawing failed: {e}"))?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    encode_png(&rgb, WIDTH, height).map_err(|e| format!("PNG encoding failed: {e}"))
}
