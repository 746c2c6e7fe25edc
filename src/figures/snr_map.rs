//! False-colour S/N map PNG, after Figs. 2–3 of Fochesatto et al. (2004):
//! log10(S/N) in false colour (viridis) against accumulation time TC (log
//! horizontal axis) and altitude (vertical axis), with labelled contours at
//! S/N = 1, 3 and 10 and a labelled colour bar.
//!
//! The shared pieces (embedded font and text, PNG encoding, ticks, viridis,
//! isolines) come from [`super::plot`]; this file holds the figure's layout. The
//! PNG is encoded in memory and written by the caller through
//! [`crate::safe_file`] (complete or not at all).

use plotters::prelude::*;
use plotters::style::FontTransform;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::plot::colour::viridis;
use super::plot::isolines::isolines;
use super::plot::text::{font, label};
use super::plot::{DrawResult, ticks};

use super::plot::text::{encode_png, ensure_font};

/// S/N against altitude and accumulation time, ready to be drawn.
#[derive(Debug, Clone)]
pub struct SnrMap {
    /// Bin-centre altitudes (km), any order, distinct and finite.
    pub altitude_km: Vec<f64>,
    /// Accumulation times TC (s), strictly increasing and > 0 (log-spaced, e.g. 1..1000 s).
    pub accumulation_time_s: Vec<f64>,
    /// `snr[i_alt][j_tc]`, finite and >= 0 (0 where there is no signal).
    pub snr: Vec<Vec<f64>>,
    /// Figure title, e.g. "Scenario 1 — cirrus 10–12 km + polluted aerosol".
    pub title: String,
    /// Instrument summary, e.g. "E0 = 1 J, fL = 10 Hz, A = 0.1 m², 532 nm, night".
    pub subtitle: String,
}

/// Width of the written PNG in pixels.
pub const WIDTH: u32 = 1000;
/// Height of the written PNG in pixels.
pub const HEIGHT: u32 = 700;
/// S/N levels drawn as labelled contours.
pub const CONTOUR_LEVELS: [f64; 3] = [1.0, 3.0, 10.0];
/// Lower end of the colour scale: smaller S/N (including 0) get the bottom colour.
pub const SNR_COLOUR_MIN: f64 = 0.1;
/// Default upper end of the colour scale; raised to the next decade when the data go higher.
pub const SNR_COLOUR_MAX: f64 = 1000.0;
/// The colour scale never extends past this.
const SNR_COLOUR_CAP: f64 = 1e6;

/// Renders `map` as a `WIDTH`×`HEIGHT` PNG, encoded in memory.
///
/// Invalid input (empty grid, fewer than 2 altitudes or times, ragged rows, NaN,
/// infinite or negative S/N, non-increasing or non-positive TC, duplicate
/// altitudes) is an error message; the caller writes the bytes through
/// [`crate::safe_file`].
pub fn png_bytes(map: &SnrMap) -> std::result::Result<Vec<u8>, String> {
    let grid = Grid::new(map)?;
    ensure_font()?;
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    render(&grid, map, &mut rgb).map_err(|e| format!("drawing failed: {e}"))?;
    encode_png(&rgb, WIDTH, HEIGHT).map_err(|e| format!("PNG encoding failed: {e}"))
}

// ---------------------------------------------------------------------------
// Validated grid
// ---------------------------------------------------------------------------

/// Why `map` cannot be drawn, if it cannot (shapes, finite values, increasing TC).
fn check(map: &SnrMap) -> std::result::Result<(), String> {
    let (n_alt, n_tc) = (map.altitude_km.len(), map.accumulation_time_s.len());
    if n_alt < 2 || n_tc < 2 {
        return Err(format!(
            "S/N map needs at least 2 altitudes and 2 accumulation times, got {n_alt} × {n_tc}"
        ));
    }
    if map.snr.len() != n_alt {
        return Err(format!(
            "snr has {} rows but there are {n_alt} altitudes",
            map.snr.len()
        ));
    }
    for (i, row) in map.snr.iter().enumerate() {
        if row.len() != n_tc {
            return Err(format!(
                "snr[{i}] has {} values but there are {n_tc} accumulation times",
                row.len()
            ));
        }
        if let Some((j, v)) = row
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(format!("snr[{i}][{j}] = {v}: S/N must be finite and >= 0"));
        }
    }
    if let Some((i, z)) = map
        .altitude_km
        .iter()
        .enumerate()
        .find(|(_, z)| !z.is_finite())
    {
        return Err(format!("altitude_km[{i}] = {z} is not finite"));
    }
    for (j, &t) in map.accumulation_time_s.iter().enumerate() {
        if !t.is_finite() || t <= 0.0 {
            return Err(format!(
                "accumulation_time_s[{j}] = {t}: must be finite and > 0"
            ));
        }
        if j > 0 && t <= map.accumulation_time_s[j - 1] {
            return Err(format!(
                "accumulation_time_s must be strictly increasing (index {j})"
            ));
        }
    }
    Ok(())
}

/// The map sorted by ascending altitude, with x = log10(TC), and its mapping to
/// the figure's pixels.
struct Grid {
    /// log10(TC), strictly increasing.
    x: Vec<f64>,
    /// Altitude (km), strictly increasing.
    y: Vec<f64>,
    /// log10(S/N) floored at the colour-scale minimum, `field[iy][ix]`: the field
    /// that is both coloured and contoured, so colours and contour lines agree.
    field: Vec<Vec<f64>>,
    /// First and last TC (s).
    tc: (f64, f64),
    /// Upper end of the colour scale.
    vmax: f64,
    /// Smallest and largest S/N in the map.
    min: f64,
    max: f64,
}

impl Grid {
    fn new(map: &SnrMap) -> std::result::Result<Self, String> {
        check(map)?;
        let mut order: Vec<usize> = (0..map.altitude_km.len()).collect();
        order.sort_by(|&a, &b| map.altitude_km[a].total_cmp(&map.altitude_km[b]));
        let y: Vec<f64> = order.iter().map(|&i| map.altitude_km[i]).collect();
        if let Some(w) = y.windows(2).find(|w| w[0] == w[1]) {
            return Err(format!("altitude {} km appears more than once", w[0]));
        }
        let x: Vec<f64> = map.accumulation_time_s.iter().map(|t| t.log10()).collect();
        if x.windows(2).any(|w| w[0] >= w[1]) {
            return Err("accumulation times too close to tell apart on a log axis".into());
        }
        let field = order
            .iter()
            .map(|&i| {
                map.snr[i]
                    .iter()
                    .map(|&v| v.max(SNR_COLOUR_MIN).log10())
                    .collect()
            })
            .collect();
        let all = || map.snr.iter().flatten().copied();
        let (min, max) = (
            all().fold(f64::INFINITY, f64::min),
            all().fold(0.0, f64::max),
        );
        let vmax = if max > SNR_COLOUR_MAX {
            10f64.powf(max.log10().ceil()).min(SNR_COLOUR_CAP)
        } else {
            SNR_COLOUR_MAX
        };
        let tc = &map.accumulation_time_s;
        Ok(Grid {
            x,
            y,
            field,
            tc: (tc[0], tc[tc.len() - 1]),
            vmax,
            min,
            max,
        })
    }

    /// The contour lines at S/N = `level`, in (log10 TC, altitude km).
    fn contours(&self, level: f64) -> Vec<Vec<(f64, f64)>> {
        isolines(&self.x, &self.y, &self.field, level.log10())
    }

    /// Pixel column of log10(TC) = `lx`.
    fn px(&self, lx: f64) -> f64 {
        let (a, b) = ends(&self.x);
        PLOT_L as f64 + (lx - a) / (b - a) * (PLOT_R - PLOT_L) as f64
    }

    /// Pixel row of altitude `z` (km).
    fn py(&self, z: f64) -> f64 {
        let (a, b) = ends(&self.y);
        PLOT_B as f64 - (z - a) / (b - a) * (PLOT_B - PLOT_T) as f64
    }

    /// Where log10(S/N) = `lv` falls on the colour scale, 0 (bottom) to 1 (top).
    fn scale(&self, lv: f64) -> f64 {
        let (a, b) = (SNR_COLOUR_MIN.log10(), self.vmax.log10());
        (lv - a) / (b - a)
    }

    /// Pixel row of S/N `v` on the colour bar.
    fn bar_y(&self, v: f64) -> f64 {
        PLOT_B as f64 - self.scale(v.log10()) * (PLOT_B - PLOT_T) as f64
    }

    /// Labelled TC ticks (s): powers of ten (1-2-5 under two decades).
    fn tc_ticks(&self) -> Vec<f64> {
        ticks::log(self.tc.0, self.tc.1, 10)
    }

    /// Labelled altitude ticks (km): a 1-2-5 step, about 7 intervals.
    fn z_ticks(&self) -> Vec<f64> {
        let (a, b) = ends(&self.y);
        ticks::linear(a, b, 7.0)
    }
}

/// First and last element.
fn ends(v: &[f64]) -> (f64, f64) {
    (v[0], v[v.len() - 1])
}

// ---------------------------------------------------------------------------
// Drawing
// ---------------------------------------------------------------------------

// Layout (pixels).
const PLOT_L: i32 = 92;
const PLOT_R: i32 = 812;
const PLOT_T: i32 = 84;
const PLOT_B: i32 = 592;
const CBAR_L: i32 = 846;
const CBAR_R: i32 = 870;

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// How one contour level is drawn.
struct LevelStyle {
    level: f64,
    colour: RGBColor,
    halo: RGBColor,
    dashed: bool,
}

/// S/N = 1 dashed white, 3 white, 10 black, each on a contrasting halo.
fn level_styles() -> [LevelStyle; 3] {
    let style = |k: usize, colour, halo, dashed| LevelStyle {
        level: CONTOUR_LEVELS[k],
        colour,
        halo,
        dashed,
    };
    [
        style(0, WHITE, BLACK, true),
        style(1, WHITE, BLACK, false),
        style(2, BLACK, WHITE, false),
    ]
}

fn render(grid: &Grid, map: &SnrMap, rgb: &mut [u8]) -> DrawResult {
    let root = BitMapBackend::with_buffer(rgb, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    draw_titles(&root, map)?;
    draw_field(&root, grid)?;
    draw_grid_lines(&root, grid)?;
    let styles = level_styles();
    let contours: Vec<Vec<Vec<(f64, f64)>>> = styles
        .iter()
        .map(|st| {
            grid.contours(st.level)
                .iter()
                .map(|l| l.iter().map(|&(lx, z)| (grid.px(lx), grid.py(z))).collect())
                .collect()
        })
        .collect();
    draw_contours(&root, &styles, &contours)?;
    draw_tc_axis(&root, grid)?;
    draw_z_axis(&root, grid)?;
    draw_colour_bar(&root, grid, &styles)?;
    draw_legend(&root, grid, &styles, &contours)?;
    root.present()?;
    Ok(())
}

/// Title and subtitle, centred, each shrunk to fit the width.
fn draw_titles(root: &Area, map: &SnrMap) -> DrawResult {
    for (text, size, y, colour) in [
        (map.title.as_str(), 24.0, 12, BLACK),
        (map.subtitle.as_str(), 16.0, 47, RGBColor(70, 70, 70)),
    ] {
        if text.trim().is_empty() {
            continue;
        }
        let mut s = size;
        while s > 9.0 && root.estimate_text_size(text, &font(s))?.0 as i32 > WIDTH as i32 - 30 {
            s -= 1.0;
        }
        let style = font(s).color(&colour);
        label(
            root,
            text,
            (WIDTH as i32 / 2, y),
            &style,
            HPos::Center,
            VPos::Top,
        )?;
    }
    Ok(())
}

/// The false colour: bilinear in (log TC, altitude) on the field that is contoured.
fn draw_field(root: &Area, g: &Grid) -> DrawResult {
    let (lx0, lx1) = ends(&g.x);
    let (z0, z1) = ends(&g.y);
    let (pw, ph) = ((PLOT_R - PLOT_L) as f64, (PLOT_B - PLOT_T) as f64);
    let cols: Vec<(usize, f64)> = (PLOT_L..PLOT_R)
        .map(|p| locate(&g.x, lx0 + ((p - PLOT_L) as f64 + 0.5) / pw * (lx1 - lx0)))
        .collect();
    for p in PLOT_T..PLOT_B {
        let (iy, wy) = locate(&g.y, z1 - ((p - PLOT_T) as f64 + 0.5) / ph * (z1 - z0));
        let (lo, hi) = (&g.field[iy], &g.field[iy + 1]);
        for (k, &(ix, wx)) in cols.iter().enumerate() {
            let a = (1.0 - wx) * lo[ix] + wx * lo[ix + 1];
            let b = (1.0 - wx) * hi[ix] + wx * hi[ix + 1];
            let v = (1.0 - wy) * a + wy * b;
            root.draw_pixel((PLOT_L + k as i32, p), &viridis(g.scale(v)))?;
        }
    }
    Ok(())
}

/// Index `i` with `v[i] <= t <= v[i+1]` (clamped) and the weight of `v[i+1]`.
fn locate(v: &[f64], t: f64) -> (usize, f64) {
    let i = v.partition_point(|&a| a <= t).clamp(1, v.len() - 1) - 1;
    let w = ((t - v[i]) / (v[i + 1] - v[i])).clamp(0.0, 1.0);
    (i, w)
}

/// Faint grid lines at the labelled ticks.
fn draw_grid_lines(root: &Area, g: &Grid) -> DrawResult {
    let style = ShapeStyle::from(&WHITE.mix(0.35)).stroke_width(1);
    for t in g.tc_ticks() {
        let x = g.px(t.log10()).round() as i32;
        root.draw(&PathElement::new(vec![(x, PLOT_T), (x, PLOT_B)], style))?;
    }
    for z in g.z_ticks() {
        let y = g.py(z).round() as i32;
        root.draw(&PathElement::new(vec![(PLOT_L, y), (PLOT_R, y)], style))?;
    }
    Ok(())
}

/// The contour lines (pixels), then their labels, kept off the other levels' lines.
fn draw_contours(
    root: &Area,
    styles: &[LevelStyle],
    contours: &[Vec<Vec<(f64, f64)>>],
) -> DrawResult {
    for (st, lines) in styles.iter().zip(contours) {
        for line in lines {
            draw_polyline(root, line, st)?;
        }
    }
    let mut taken: Vec<Bbox> = Vec::new();
    for (k, st) in styles.iter().enumerate() {
        let others: Vec<(f64, f64)> = contours
            .iter()
            .enumerate()
            .filter(|&(m, _)| m != k)
            .flat_map(|(_, lines)| lines.iter().flat_map(|l| densify(l, 2.0)))
            .collect();
        place_labels(root, &contours[k], st, &others, &mut taken)?;
    }
    Ok(())
}

/// The frame, and the TC axis: ticks at 1..9 × 10^k (longer at powers of ten and at
/// the labels), tick labels and title.
fn draw_tc_axis(root: &Area, g: &Grid) -> DrawResult {
    root.draw(&Rectangle::new(
        [(PLOT_L, PLOT_T), (PLOT_R, PLOT_B)],
        ShapeStyle::from(&BLACK).stroke_width(1),
    ))?;
    let (lx0, lx1) = ends(&g.x);
    for d in (lx0.floor() as i32)..=(lx1.ceil() as i32) {
        for m in 1..10 {
            let l = (m as f64 * 10f64.powi(d)).log10();
            if l >= lx0 - 1e-9 && l <= lx1 + 1e-9 {
                let (x, len) = (g.px(l).round() as i32, if m == 1 { 7 } else { 4 });
                line(root, (x, PLOT_B), (x, PLOT_B + len))?;
            }
        }
    }
    let tick_font = font(15.0);
    for t in g.tc_ticks() {
        let x = g.px(t.log10()).round() as i32;
        line(root, (x, PLOT_B), (x, PLOT_B + 7))?;
        let (text, at) = (ticks::format(t), (x, PLOT_B + 11));
        label(root, &text, at, &tick_font, HPos::Center, VPos::Top)?;
    }
    let (title, at) = (
        "accumulation time TC (s)",
        ((PLOT_L + PLOT_R) / 2, PLOT_B + 36),
    );
    label(root, title, at, &font(17.0), HPos::Center, VPos::Top)?;
    Ok(())
}

/// The altitude axis: ticks, tick labels and title.
fn draw_z_axis(root: &Area, g: &Grid) -> DrawResult {
    let tick_font = font(15.0);
    for z in g.z_ticks() {
        let y = g.py(z).round() as i32;
        line(root, (PLOT_L - 7, y), (PLOT_L, y))?;
        let (text, at) = (ticks::format(z), (PLOT_L - 11, y));
        label(root, &text, at, &tick_font, HPos::Right, VPos::Center)?;
    }
    let at = (26, (PLOT_T + PLOT_B) / 2);
    upright(root, "altitude (km)", at, FontTransform::Rotate270)
}

/// A thin black line from `a` to `b`.
fn line(root: &Area, a: (i32, i32), b: (i32, i32)) -> DrawResult {
    root.draw(&PathElement::new(vec![a, b], BLACK))?;
    Ok(())
}

/// An axis title turned on its side, centred on `at`.
fn upright(root: &Area, text: &str, at: (i32, i32), turn: FontTransform) -> DrawResult {
    let style = font(17.0)
        .transform(turn)
        .pos(Pos::new(HPos::Center, VPos::Center));
    root.draw(&Text::new(text, at, style))?;
    Ok(())
}

/// The colour bar's marks: the floor (≤), the contour levels, the decades up to the
/// top (≥ when the data go past it), with their labels.
fn bar_marks(g: &Grid) -> Vec<(f64, String)> {
    let mut marks = vec![SNR_COLOUR_MIN, 1.0, 3.0, 10.0];
    let mut v = 100.0;
    while v <= g.vmax * 1.0001 {
        marks.push(v);
        v *= 10.0;
    }
    marks
        .into_iter()
        .map(|v| {
            let bound = if v == SNR_COLOUR_MIN {
                "≤"
            } else if (v - g.vmax).abs() < 1e-9 * v && g.max > g.vmax {
                "≥"
            } else {
                ""
            };
            (v, format!("{bound}{}", ticks::format(v)))
        })
        .collect()
}

/// The colour bar with its marks and title, the contour levels drawn on it in their
/// line styles.
fn draw_colour_bar(root: &Area, g: &Grid, styles: &[LevelStyle]) -> DrawResult {
    let ph = (PLOT_B - PLOT_T) as f64;
    for p in PLOT_T..PLOT_B {
        let t = (PLOT_B as f64 - (p as f64 + 0.5)) / ph;
        root.draw(&PathElement::new(
            vec![(CBAR_L, p), (CBAR_R - 1, p)],
            viridis(t),
        ))?;
    }
    root.draw(&Rectangle::new(
        [(CBAR_L, PLOT_T), (CBAR_R, PLOT_B)],
        ShapeStyle::from(&BLACK).stroke_width(1),
    ))?;
    let tick_font = font(15.0);
    for (v, text) in bar_marks(g) {
        let y = g.bar_y(v).round() as i32;
        line(root, (CBAR_R, y), (CBAR_R + 5, y))?;
        label(
            root,
            &text,
            (CBAR_R + 9, y),
            &tick_font,
            HPos::Left,
            VPos::Center,
        )?;
    }
    for st in styles {
        let y = g.bar_y(st.level);
        let (a, b) = ((CBAR_L + 1) as f64, (CBAR_R - 1) as f64);
        draw_polyline(root, &[(a, y), (b, y)], st)?;
    }
    let at = (WIDTH as i32 - 30, (PLOT_T + PLOT_B) / 2);
    upright(
        root,
        "signal-to-noise ratio S/N",
        at,
        FontTransform::Rotate90,
    )
}

/// The legend of the contour styles, under the x-axis title, noting levels that
/// are not drawn (not reached, or exceeded everywhere).
fn draw_legend(
    root: &Area,
    g: &Grid,
    styles: &[LevelStyle],
    contours: &[Vec<Vec<(f64, f64)>>],
) -> DrawResult {
    let (legend_y, legend_font) = (PLOT_B + 82, font(15.0));
    let items: Vec<String> = styles
        .iter()
        .zip(contours)
        .map(|(st, lines)| {
            let note = if !lines.is_empty() {
                ""
            } else if g.min.max(SNR_COLOUR_MIN) >= st.level {
                " (exceeded everywhere)"
            } else {
                " (not reached)"
            };
            format!("S/N = {}{note}", ticks::format(st.level))
        })
        .collect();
    let mut widths = Vec::with_capacity(items.len());
    for t in &items {
        widths.push(root.estimate_text_size(t, &legend_font)?.0 as i32);
    }
    let (sample, gap) = (36, 30);
    let total: i32 =
        widths.iter().map(|w| sample + 8 + w).sum::<i32>() + gap * (items.len() as i32 - 1);
    let mut x = (PLOT_L + PLOT_R) / 2 - total / 2;
    for ((st, text), w) in styles.iter().zip(&items).zip(&widths) {
        root.draw(&Rectangle::new(
            [(x, legend_y - 9), (x + sample, legend_y + 9)],
            viridis(0.4).filled(),
        ))?;
        let (a, b) = ((x + 4) as f64, (x + sample - 4) as f64);
        draw_polyline(root, &[(a, legend_y as f64), (b, legend_y as f64)], st)?;
        let at = (x + sample + 8, legend_y);
        label(root, text, at, &legend_font, HPos::Left, VPos::Center)?;
        x += sample + 8 + w + gap;
    }
    Ok(())
}

fn seg_len(a: (f64, f64), b: (f64, f64)) -> f64 {
    ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt()
}

/// The polyline's points with extra ones so that none are more than `step` apart.
fn densify(line: &[(f64, f64)], step: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = line.first().copied().into_iter().collect();
    for w in line.windows(2) {
        let n = (seg_len(w[0], w[1]) / step).ceil().clamp(1.0, 10_000.0) as usize;
        out.extend((1..=n).map(|k| {
            let t = k as f64 / n as f64;
            (
                w[0].0 + t * (w[1].0 - w[0].0),
                w[0].1 + t * (w[1].1 - w[0].1),
            )
        }));
    }
    out
}

/// Draws a polyline (pixel coordinates) over a contrasting halo, dashed if the style says so.
fn draw_polyline(root: &Area, line: &[(f64, f64)], st: &LevelStyle) -> DrawResult {
    let pieces = if st.dashed {
        dash(line, 9.0, 6.0)
    } else {
        vec![line.to_vec()]
    };
    let to_i = |p: &Vec<(f64, f64)>| {
        p.iter()
            .map(|&(x, y)| (x.round() as i32, y.round() as i32))
            .collect::<Vec<_>>()
    };
    for (colour, width) in [(st.halo.mix(0.55), 4), (st.colour.to_rgba(), 2)] {
        for p in &pieces {
            let style = ShapeStyle::from(&colour).stroke_width(width);
            root.draw(&PathElement::new(to_i(p), style))?;
        }
    }
    Ok(())
}
/// Splits a polyline into dashes of length `on` separated by gaps `off` (pixels).
fn dash(line: &[(f64, f64)], on: f64, off: f64) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut cur: Vec<(f64, f64)> = line.first().copied().into_iter().collect();
    let (mut drawing, mut left) = (true, on);
    for w in line.windows(2) {
        let (mut a, b) = (w[0], w[1]);
        let mut len = seg_len(a, b);
        while len > left {
            let t = left / len;
            let m = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            if drawing {
                cur.push(m);
                out.push(std::mem::take(&mut cur));
            } else {
                cur = vec![m];
            }
            drawing = !drawing;
            len -= left;
            left = if drawing { on } else { off };
            a = m;
        }
        left -= len;
        if drawing {
            cur.push(b);
        }
    }
    if drawing && cur.len() > 1 {
        out.push(cur);
    }
    out
}

/// Pixel box (x0, y0, x1, y1).
type Bbox = (i32, i32, i32, i32);

/// Puts "S/N = L" boxes on the level's longest lines (at most 2 labels), near
/// each line's middle, inside the frame, clear of other labels and of the
/// other levels' lines (`others`, densified pixel points).
fn place_labels(
    root: &Area,
    lines: &[Vec<(f64, f64)>],
    st: &LevelStyle,
    others: &[(f64, f64)],
    taken: &mut Vec<Bbox>,
) -> DrawResult {
    let text = format!("S/N = {}", ticks::format(st.level));
    let style = font(15.0);
    let (tw, th) = root.estimate_text_size(&text, &style)?;
    let (hw, hh) = (tw as i32 / 2 + 5, th as i32 / 2 + 4);
    let mut order: Vec<(f64, &Vec<(f64, f64)>)> = lines
        .iter()
        .map(|l| (l.windows(2).map(|w| seg_len(w[0], w[1])).sum(), l))
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut placed = 0;
    for (len, line) in order {
        if placed >= 2 || len < 80.0 {
            break;
        }
        let pts = densify(line, 3.0);
        let mid = pts.len() / 2;
        let mut cands: Vec<usize> = (0..pts.len()).collect();
        cands.sort_by_key(|&i| i.abs_diff(mid));
        for i in cands {
            let (x, y) = (pts[i].0.round() as i32, pts[i].1.round() as i32);
            let b = (x - hw, y - hh, x + hw, y + hh);
            let inside =
                b.0 > PLOT_L + 4 && b.2 < PLOT_R - 4 && b.1 > PLOT_T + 4 && b.3 < PLOT_B - 4;
            let apart = |t: &Bbox| b.2 + 8 < t.0 || t.2 + 8 < b.0 || b.3 + 6 < t.1 || t.3 + 6 < b.1;
            let clear = |&(ox, oy): &(f64, f64)| {
                ox < (b.0 - 3) as f64
                    || ox > (b.2 + 3) as f64
                    || oy < (b.1 - 3) as f64
                    || oy > (b.3 + 3) as f64
            };
            if inside && taken.iter().all(apart) && others.iter().all(clear) {
                root.draw(&Rectangle::new(
                    [(b.0, b.1), (b.2, b.3)],
                    WHITE.mix(0.9).filled(),
                ))?;
                root.draw(&Rectangle::new(
                    [(b.0, b.1), (b.2, b.3)],
                    ShapeStyle::from(&BLACK).stroke_width(1),
                ))?;
                label(root, &text, (x, y), &style, HPos::Center, VPos::Center)?;
                taken.push(b);
                placed += 1;
                break;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::{Path, PathBuf};

    /// A fresh scratch directory for one test.
    fn scratch_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("lidarsim_snr_map_{}_{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn log_times(n: usize) -> Vec<f64> {
        (0..n)
            .map(|j| 10f64.powf(3.0 * j as f64 / (n - 1) as f64))
            .collect()
    }

    /// snr = s1(z)·sqrt(TC): s1 falls from 30 at 0 km to 0.01 at 30 km, ×10 in a
    /// cloud at 10–12 km and 0 in its shadow at 8.5–10 km; 300 m bins.
    fn synthetic_map() -> SnrMap {
        let altitude_km: Vec<f64> = (0..=100).map(|i| i as f64 * 0.3).collect();
        let accumulation_time_s = log_times(80);
        let s1 = |z: f64| {
            let clear = 30.0 * (-z / 3.747).exp();
            if (10.0..=12.0).contains(&z) {
                10.0 * clear
            } else if (8.5..10.0).contains(&z) {
                0.0
            } else {
                clear
            }
        };
        let snr = altitude_km
            .iter()
            .map(|&z| {
                accumulation_time_s
                    .iter()
                    .map(|&t| s1(z) * t.sqrt())
                    .collect()
            })
            .collect();
        SnrMap {
            altitude_km,
            accumulation_time_s,
            snr,
            title: "Scenario 1 — cirrus 10–12 km + polluted aerosol".into(),
            subtitle: "E0 = 1 J, fL = 10 Hz, A = 0.1 m², 532 nm, night".into(),
        }
    }

    fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
        let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        let mut reader = png::Decoder::new(file).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    }

    /// Renders `map` and writes it to `path` (the command goes through safe_file).
    fn write_png(path: &Path, map: &SnrMap) -> std::result::Result<(), String> {
        std::fs::write(path, png_bytes(map)?).map_err(|e| e.to_string())
    }

    #[test]
    fn snr_contours_follow_the_analytic_curve() {
        // snr = 30·exp(-z/5)·sqrt(TC) is linear in (log10 TC, z) after log10, so the
        // contour is exact: S/N = L at z = 5·ln(30·sqrt(TC)/L). Altitudes descending.
        let altitude_km: Vec<f64> = (0..=100).rev().map(|i| i as f64 * 0.3).collect();
        let accumulation_time_s = log_times(61);
        let snr = altitude_km
            .iter()
            .map(|&z| {
                accumulation_time_s
                    .iter()
                    .map(|&t| 30.0 * (-z / 5.0f64).exp() * t.sqrt())
                    .collect()
            })
            .collect();
        let map = SnrMap {
            altitude_km,
            accumulation_time_s,
            snr,
            title: String::new(),
            subtitle: String::new(),
        };
        let grid = Grid::new(&map).unwrap();
        assert!(grid.y.windows(2).all(|w| w[0] < w[1]));
        for level in CONTOUR_LEVELS {
            // the lines the figure draws (before they are mapped to pixels)
            let lines = grid.contours(level);
            assert_eq!(lines.len(), 1, "level {level}");
            for &(lx, z) in &lines[0] {
                let want = 5.0 * (30.0 * 10f64.powf(lx).sqrt() / level).ln();
                assert!(
                    (z - want).abs() < 1e-9,
                    "S/N {level} at TC {}: z {z} vs {want}",
                    10f64.powf(lx)
                );
            }
            // Runs from TC = 1 s to the right edge (1000 s) or, for S/N = 1, out of the top (30 km).
            let (a, b) = (lines[0][0], lines[0][lines[0].len() - 1]);
            let (start, end) = if a.0 < b.0 { (a, b) } else { (b, a) };
            assert!(start.0.abs() < 1e-12, "level {level} starts at {start:?}");
            assert!(
                (end.0 - 3.0).abs() < 1e-12 || (end.1 - 30.0).abs() < 1e-12,
                "level {level} ends at {end:?}"
            );
        }
    }

    #[test]
    fn axis_ticks_are_round() {
        // plot's 1-2-5 steps (this file's own had 2.5 too; none of these spans used it)
        use crate::figures::plot::ticks::nice_step;
        assert_eq!(nice_step(30.0, 7.0), 5.0);
        assert_eq!(nice_step(39.9, 7.0), 5.0);
        assert_eq!(nice_step(6.0, 7.0), 1.0);
        assert_eq!(nice_step(0.9, 7.0), 0.1);
        assert_eq!(nice_step(600.0, 7.0), 100.0);
        // the ticks the figure labels
        let grid = Grid::new(&synthetic_map()).unwrap();
        let z: Vec<f64> = (0..=6).map(|k| 5.0 * k as f64).collect();
        assert_eq!(grid.z_ticks(), z);
        assert_eq!(grid.tc_ticks(), vec![1.0, 10.0, 100.0, 1000.0]);
    }

    #[test]
    fn dashes_alternate_with_gaps() {
        let dashes = dash(&[(0.0, 0.0), (50.0, 0.0), (50.0, 50.0)], 9.0, 6.0);
        // 100 px with period 15: 6 full dashes and a 10 px remainder (9 on, 1 off) -> 7.
        assert_eq!(dashes.len(), 7);
        let len: f64 = dashes
            .iter()
            .map(|d| d.windows(2).map(|w| seg_len(w[0], w[1])).sum::<f64>())
            .sum();
        assert!((len - 63.0).abs() < 1e-9, "{len}");
    }

    // --- PNG ----------------------------------------------------------------

    #[test]
    fn writes_a_decodable_png_of_the_right_size_with_text_and_colour() {
        let dir = scratch_dir("png");
        let path = dir.join("snr.png");
        write_png(&path, &synthetic_map()).unwrap();
        let (w, h, rgb) = decode(&path);
        assert_eq!((w, h), (WIDTH, HEIGHT));
        let at = |x: u32, y: u32| {
            let i = ((y * w + x) * 3) as usize;
            (rgb[i], rgb[i + 1], rgb[i + 2])
        };
        // The title was rendered: dark pixels in its band, above the plot.
        let dark = (0..PLOT_T as u32 - 40)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let (r, g, b) = at(x, y);
                r < 100 && g < 100 && b < 100
            })
            .count();
        assert!(dark > 300, "title band has only {dark} dark pixels");
        // Near the ground at TC = 1000 s S/N ≈ 950: bright yellow-green.
        let (r, g, b) = at(PLOT_R as u32 - 3, PLOT_B as u32 - 3);
        assert!(g > 200 && b < 100 && r > 150, "({r}, {g}, {b})");
        // In the cloud shadow S/N = 0: the bottom colour of the scale.
        let y_shadow = PLOT_B as f64 - 9.25 / 30.0 * (PLOT_B - PLOT_T) as f64;
        assert_eq!(
            at(((PLOT_L + PLOT_R) / 2) as u32 + 17, y_shadow as u32),
            (68, 1, 84)
        );
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn odd_but_valid_maps_are_drawn() {
        let dir = scratch_dir("odd");
        let base = || SnrMap {
            altitude_km: vec![5.0, 1.0],
            accumulation_time_s: vec![1.0, 1000.0],
            snr: vec![vec![0.0, 0.0], vec![0.0, 0.0]],
            title: String::new(),
            subtitle: String::new(),
        };
        let mut cases = vec![("all_zero", base())];
        let mut m = base();
        m.snr = vec![vec![1e12, 1e12], vec![1e12, 1e12]];
        m.title = "x".repeat(400);
        cases.push(("huge_snr_long_title", m));
        let mut m = base();
        m.accumulation_time_s = vec![2.0, 5.0];
        m.snr = vec![vec![0.5, 2.0], vec![5.0, 20.0]];
        cases.push(("under_a_decade", m));
        let mut m = base();
        m.altitude_km = vec![-0.5, 1e-3];
        m.accumulation_time_s = vec![1e-3, 1e-2];
        m.snr = vec![vec![3.0, 3.0], vec![3.0, 3.0]];
        cases.push(("flat_at_a_level", m));
        for (name, map) in cases {
            let path = dir.join(format!("{name}.png"));
            write_png(&path, &map).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(decode(&path).0, WIDTH, "{name}");
        }
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn bad_inputs_are_errors_and_write_nothing() {
        let dir = scratch_dir("bad");
        let path = dir.join("bad.png");
        let good = synthetic_map();
        let mut cases: Vec<(&str, SnrMap, &str)> = Vec::new();
        let empty = SnrMap {
            altitude_km: vec![],
            accumulation_time_s: vec![],
            snr: vec![],
            title: String::new(),
            subtitle: String::new(),
        };
        cases.push(("empty", empty, "at least 2"));
        let mut m = good.clone();
        m.altitude_km.truncate(1);
        m.snr.truncate(1);
        cases.push(("one altitude", m, "at least 2"));
        let mut m = good.clone();
        m.accumulation_time_s.truncate(1);
        m.snr.iter_mut().for_each(|r| r.truncate(1));
        cases.push(("one time", m, "at least 2"));
        for (what, v) in [
            ("NaN", f64::NAN),
            ("inf", f64::INFINITY),
            ("negative", -1.0),
        ] {
            let mut m = good.clone();
            m.snr[7][3] = v;
            cases.push((what, m, "snr[7][3]"));
        }
        let mut m = good.clone();
        m.snr[4].pop();
        cases.push(("ragged", m, "snr[4]"));
        let mut m = good.clone();
        m.snr.pop();
        cases.push(("rows", m, "rows"));
        let mut m = good.clone();
        m.accumulation_time_s.swap(3, 4);
        cases.push(("not increasing", m, "strictly increasing"));
        let mut m = good.clone();
        m.accumulation_time_s[0] = 0.0;
        cases.push(("zero time", m, "accumulation_time_s[0]"));
        let mut m = good.clone();
        m.altitude_km[5] = m.altitude_km[6];
        cases.push(("duplicate altitude", m, "more than once"));
        let mut m = good.clone();
        m.altitude_km[2] = f64::NAN;
        cases.push(("NaN altitude", m, "altitude_km[2]"));
        for (what, map, needle) in cases {
            let reason = write_png(&path, &map).expect_err(what);
            assert!(
                reason.contains(needle),
                "{what}: {reason:?} lacks {needle:?}"
            );
            assert!(!path.exists(), "{what}: a file was written");
        }
        std::fs::remove_dir_all(dir).unwrap();
    }
}
