//! False-colour S/N map PNG, after Figs. 2–3 of Fochesatto et al. (2004):
//! log10(S/N) in false colour (viridis) against accumulation time TC (log
//! horizontal axis) and altitude (vertical axis), with labelled contours at
//! S/N = 1, 3 and 10 and a labelled colour bar.
//!
//! Text is drawn with DejaVu Sans embedded in the binary (`assets/fonts/`,
//! licence beside it) through plotters' `ab_glyph` feature, so no system font
//! or fontconfig is needed. The PNG is encoded in memory with the `png` crate
//! and written through [`super::safe_file`] (complete or not at all).

use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, FontTransform, register_font};

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

/// Font family name under which the embedded font is registered with plotters.
pub(crate) const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/assets/fonts/DejaVuSans.ttf"
));

/// Renders `map` as a `WIDTH`×`HEIGHT` PNG, encoded in memory.
///
/// Invalid input (empty grid, fewer than 2 altitudes or times, ragged rows, NaN,
/// infinite or negative S/N, non-increasing or non-positive TC, duplicate
/// altitudes) is an error message; the caller writes the bytes through
/// [`super::safe_file`].
pub fn png_bytes(map: &SnrMap) -> std::result::Result<Vec<u8>, String> {
    let grid = Grid::new(map)?;
    ensure_font()?;
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    render(&grid, map, &mut rgb).map_err(|e| format!("drawing failed: {e}"))?;
    encode_png(&rgb, WIDTH, HEIGHT).map_err(|e| format!("PNG encoding failed: {e}"))
}

pub(crate) fn ensure_font() -> std::result::Result<(), String> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok());
    if ok {
        Ok(())
    } else {
        Err("embedded font DejaVuSans.ttf could not be parsed".into())
    }
}

pub(crate) fn encode_png(
    rgb: &[u8],
    w: u32,
    h: u32,
) -> std::result::Result<Vec<u8>, png::EncodingError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header()?;
        writer.write_image_data(rgb)?;
        writer.finish()?;
    }
    Ok(out)
}

// ---------------------------------------------------------------------------
// Validated grid
// ---------------------------------------------------------------------------

/// The map sorted by ascending altitude, with x = log10(TC).
struct Grid {
    /// log10(TC), strictly increasing.
    x: Vec<f64>,
    /// Altitude (km), strictly increasing.
    y: Vec<f64>,
    /// S/N, `snr[iy][ix]`.
    snr: Vec<Vec<f64>>,
    /// Upper end of the colour scale.
    vmax: f64,
    /// Largest S/N in the map.
    max: f64,
}

impl Grid {
    fn new(map: &SnrMap) -> std::result::Result<Self, String> {
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
            for (j, &v) in row.iter().enumerate() {
                if !v.is_finite() || v < 0.0 {
                    return Err(format!("snr[{i}][{j}] = {v}: S/N must be finite and >= 0"));
                }
            }
        }
        for (i, &z) in map.altitude_km.iter().enumerate() {
            if !z.is_finite() {
                return Err(format!("altitude_km[{i}] = {z} is not finite"));
            }
        }
        let mut prev = 0.0;
        for (j, &t) in map.accumulation_time_s.iter().enumerate() {
            if !t.is_finite() || t <= 0.0 {
                return Err(format!(
                    "accumulation_time_s[{j}] = {t}: must be finite and > 0"
                ));
            }
            if j > 0 && t <= prev {
                return Err(format!(
                    "accumulation_time_s must be strictly increasing (index {j})"
                ));
            }
            prev = t;
        }
        let mut order: Vec<usize> = (0..n_alt).collect();
        order.sort_by(|&a, &b| map.altitude_km[a].total_cmp(&map.altitude_km[b]));
        let y: Vec<f64> = order.iter().map(|&i| map.altitude_km[i]).collect();
        if let Some(w) = y.windows(2).find(|w| w[0] == w[1]) {
            return Err(format!("altitude {} km appears more than once", w[0]));
        }
        let x: Vec<f64> = map.accumulation_time_s.iter().map(|t| t.log10()).collect();
        if x.windows(2).any(|w| w[0] >= w[1]) {
            return Err("accumulation times too close to tell apart on a log axis".into());
        }
        let snr: Vec<Vec<f64>> = order.iter().map(|&i| map.snr[i].clone()).collect();
        let max = snr.iter().flatten().fold(0.0f64, |m, &v| m.max(v));
        let vmax = if max > SNR_COLOUR_MAX {
            10f64.powf(max.log10().ceil()).min(SNR_COLOUR_CAP)
        } else {
            SNR_COLOUR_MAX
        };
        Ok(Grid {
            x,
            y,
            snr,
            vmax,
            max,
        })
    }

    /// log10(S/N) floored at the colour-scale minimum: the field that is both
    /// coloured and contoured, so colours and contour lines agree.
    fn log_field(&self) -> Vec<Vec<f64>> {
        self.snr
            .iter()
            .map(|row| row.iter().map(|&v| v.max(SNR_COLOUR_MIN).log10()).collect())
            .collect()
    }
}

// ---------------------------------------------------------------------------
// Marching squares
// ---------------------------------------------------------------------------

/// A grid edge: `(iy, ix, vertical)`; horizontal edges join (iy, ix)–(iy, ix+1),
/// vertical ones (iy, ix)–(iy+1, ix).
type EdgeKey = (usize, usize, bool);

/// Contour lines of `f` at `level` by marching squares.
///
/// `f[iy][ix]` is sampled at `(x[ix], y[iy])` with `x` and `y` strictly increasing.
/// Points on grid edges are found by linear interpolation; corners with
/// `f >= level` count as inside. Saddle cells are resolved with the cell-centre
/// mean. Segments are chained into polylines (a closed loop repeats its first
/// point at the end). Returns no lines if the shapes do not match.
pub fn marching_squares(x: &[f64], y: &[f64], f: &[Vec<f64>], level: f64) -> Vec<Vec<(f64, f64)>> {
    let (nx, ny) = (x.len(), y.len());
    if nx < 2 || ny < 2 || f.len() != ny || f.iter().any(|r| r.len() != nx) || !level.is_finite() {
        return Vec::new();
    }
    let inside = |iy: usize, ix: usize| f[iy][ix] >= level;
    let mut segments: Vec<(EdgeKey, EdgeKey)> = Vec::new();
    for iy in 0..ny - 1 {
        for ix in 0..nx - 1 {
            let (a, b) = (inside(iy, ix), inside(iy, ix + 1));
            let (c, d) = (inside(iy + 1, ix + 1), inside(iy + 1, ix));
            let bottom = (iy, ix, false);
            let right = (iy, ix + 1, true);
            let top = (iy + 1, ix, false);
            let left = (iy, ix, true);
            let mut crossed = Vec::with_capacity(4);
            if a != b {
                crossed.push(bottom);
            }
            if b != c {
                crossed.push(right);
            }
            if c != d {
                crossed.push(top);
            }
            if d != a {
                crossed.push(left);
            }
            match crossed.len() {
                2 => segments.push((crossed[0], crossed[1])),
                4 => {
                    let centre =
                        (f[iy][ix] + f[iy][ix + 1] + f[iy + 1][ix + 1] + f[iy + 1][ix]) / 4.0;
                    if a != (centre >= level) {
                        // Corners a and c are cut off; b and d connect through the centre.
                        segments.push((left, bottom));
                        segments.push((right, top));
                    } else {
                        segments.push((bottom, right));
                        segments.push((top, left));
                    }
                }
                _ => {}
            }
        }
    }
    let point = |(iy, ix, vertical): EdgeKey| -> (f64, f64) {
        let (iy2, ix2) = if vertical { (iy + 1, ix) } else { (iy, ix + 1) };
        let (v0, v1) = (f[iy][ix], f[iy2][ix2]);
        let t = if v1 != v0 {
            ((level - v0) / (v1 - v0)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        (x[ix] + t * (x[ix2] - x[ix]), y[iy] + t * (y[iy2] - y[iy]))
    };
    chain(&segments)
        .into_iter()
        .map(|line| line.into_iter().map(point).collect())
        .collect()
}

/// Joins segments sharing an edge into polylines of edge keys.
fn chain(segments: &[(EdgeKey, EdgeKey)]) -> Vec<Vec<EdgeKey>> {
    use std::collections::HashMap;
    let mut at: HashMap<EdgeKey, Vec<usize>> = HashMap::new();
    for (s, &(p, q)) in segments.iter().enumerate() {
        at.entry(p).or_default().push(s);
        at.entry(q).or_default().push(s);
    }
    let mut used = vec![false; segments.len()];
    let mut lines = Vec::new();
    // Open chains start at an edge used once (a grid boundary); then closed loops.
    let mut starts: Vec<(usize, EdgeKey)> = Vec::new();
    for (s, &(p, q)) in segments.iter().enumerate() {
        if at[&p].len() == 1 {
            starts.push((s, p));
        }
        if at[&q].len() == 1 {
            starts.push((s, q));
        }
    }
    starts.extend(segments.iter().enumerate().map(|(s, &(p, _))| (s, p)));
    for (first, from) in starts {
        if used[first] {
            continue;
        }
        let mut line = vec![from];
        let (mut seg, mut cur) = (first, from);
        loop {
            used[seg] = true;
            let (p, q) = segments[seg];
            let next = if p == cur { q } else { p };
            line.push(next);
            cur = next;
            match at[&cur].iter().find(|&&s| !used[s]) {
                Some(&s) => seg = s,
                None => break,
            }
        }
        lines.push(line);
    }
    lines
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

/// 17 samples of matplotlib's viridis.
const VIRIDIS: [(u8, u8, u8); 17] = [
    (68, 1, 84),
    (72, 24, 106),
    (71, 45, 123),
    (66, 64, 134),
    (59, 82, 139),
    (51, 99, 141),
    (44, 114, 142),
    (38, 130, 142),
    (33, 145, 140),
    (31, 160, 136),
    (40, 174, 128),
    (63, 188, 115),
    (94, 201, 98),
    (132, 212, 75),
    (173, 220, 48),
    (216, 226, 25),
    (253, 231, 37),
];

fn viridis(t: f64) -> RGBColor {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (VIRIDIS.len() - 1) as f64;
    let i = (s.floor() as usize).min(VIRIDIS.len() - 2);
    let w = s - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: u8, q: u8| (p as f64 + w * (q as f64 - p as f64)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// How one contour level is drawn.
struct LevelStyle {
    level: f64,
    colour: RGBColor,
    halo: RGBColor,
    dashed: bool,
}

fn level_styles() -> [LevelStyle; 3] {
    [
        LevelStyle {
            level: CONTOUR_LEVELS[0],
            colour: WHITE,
            halo: BLACK,
            dashed: true,
        },
        LevelStyle {
            level: CONTOUR_LEVELS[1],
            colour: WHITE,
            halo: BLACK,
            dashed: false,
        },
        LevelStyle {
            level: CONTOUR_LEVELS[2],
            colour: BLACK,
            halo: WHITE,
            dashed: false,
        },
    ]
}

fn fmt_snr(v: f64) -> String {
    if v < 1.0 {
        format!("{v}")
    } else if v < 1e5 {
        format!("{v:.0}")
    } else {
        format!("1e{}", v.log10().round())
    }
}

fn fmt_tc(v: f64) -> String {
    if v >= 1.0 {
        format!("{v:.0}")
    } else {
        format!("{}", (v * 1e6).round() / 1e6)
    }
}

/// The 1-2-2.5-5 × 10^k step giving the number of intervals over `span` nearest `target`.
fn nice_step(span: f64, target: f64) -> f64 {
    let mag = 10f64.powf((span / target).log10().floor());
    [0.5, 1.0, 2.0, 2.5, 5.0, 10.0, 20.0]
        .map(|m| m * mag)
        .into_iter()
        .min_by(|a, b| ((span / a - target).abs()).total_cmp(&(span / b - target).abs()))
        .unwrap_or(mag)
}

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;
type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;
type AreaResult = std::result::Result<
    (),
    DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>,
>;

fn font(size: f64) -> TextStyle<'static> {
    TextStyle::from((FONT, size).into_font()).color(&BLACK)
}

/// Draws unrotated text anchored at `(x, y)`. plotters' `ab_glyph` renderer puts
/// glyphs lower than its layout box says; shift so that `VPos::Center` centres
/// the capitals on `y` and `VPos::Top` puts their tops at about `y`.
fn label(
    root: &Area,
    text: &str,
    (x, y): (i32, i32),
    style: &TextStyle<'_>,
    h: HPos,
    v: VPos,
) -> AreaResult {
    let size = style.font.get_size();
    let dy = match v {
        VPos::Center => (0.22 * size).round() as i32,
        VPos::Top => (0.13 * size).round() as i32,
        VPos::Bottom => 0,
    };
    root.draw(&Text::new(
        text.to_string(),
        (x, y + dy),
        style.pos(Pos::new(h, v)),
    ))
}

fn render(grid: &Grid, map: &SnrMap, rgb: &mut [u8]) -> DrawResult {
    let root = BitMapBackend::with_buffer(rgb, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    let (lx0, lx1) = (grid.x[0], grid.x[grid.x.len() - 1]);
    let (z0, z1) = (grid.y[0], grid.y[grid.y.len() - 1]);
    let (lv0, lv1) = (SNR_COLOUR_MIN.log10(), grid.vmax.log10());
    let (pw, ph) = ((PLOT_R - PLOT_L) as f64, (PLOT_B - PLOT_T) as f64);
    let px = |lx: f64| PLOT_L as f64 + (lx - lx0) / (lx1 - lx0) * pw;
    let py = |z: f64| PLOT_B as f64 - (z - z0) / (z1 - z0) * ph;
    let field = grid.log_field();

    // --- Title and subtitle (shrunk to fit the width).
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
        label(
            &root,
            text,
            (WIDTH as i32 / 2, y),
            &font(s).color(&colour),
            HPos::Center,
            VPos::Top,
        )?;
    }

    // --- False colour: bilinear in (log TC, altitude) on the field that is contoured.
    let cols: Vec<(usize, f64)> = (PLOT_L..PLOT_R)
        .map(|p| {
            locate(
                &grid.x,
                lx0 + (p as f64 + 0.5 - PLOT_L as f64) / pw * (lx1 - lx0),
            )
        })
        .collect();
    for p in PLOT_T..PLOT_B {
        let (iy, wy) = locate(
            &grid.y,
            z1 - (p as f64 + 0.5 - PLOT_T as f64) / ph * (z1 - z0),
        );
        let (lo, hi) = (&field[iy], &field[iy + 1]);
        for (k, &(ix, wx)) in cols.iter().enumerate() {
            let a = (1.0 - wx) * lo[ix] + wx * lo[ix + 1];
            let b = (1.0 - wx) * hi[ix] + wx * hi[ix + 1];
            let v = (1.0 - wy) * a + wy * b;
            root.draw_pixel((PLOT_L + k as i32, p), &viridis((v - lv0) / (lv1 - lv0)))?;
        }
    }

    // --- Grid lines at the labelled ticks.
    let mut x_major: Vec<f64> = ((lx0 - 1e-9).ceil() as i32..=(lx1 + 1e-9).floor() as i32)
        .map(f64::from)
        .collect();
    if x_major.len() < 2 {
        // Less than a decade shown: label 2× and 5× too.
        x_major = (lx0.floor() as i32..=lx1.ceil() as i32)
            .flat_map(|d| [1.0, 2.0, 5.0].map(|m| (m * 10f64.powi(d)).log10()))
            .filter(|&l| l >= lx0 - 1e-9 && l <= lx1 + 1e-9)
            .collect();
    }
    let z_step = nice_step(z1 - z0, 7.0);
    let z_ticks: Vec<f64> = ((z0 / z_step - 1e-9).ceil() as i64
        ..=(z1 / z_step + 1e-9).floor() as i64)
        .map(|k| k as f64 * z_step)
        .collect();
    // Decimals that show every tick exactly (2.5 × 10^k needs one more).
    let z_decimals = (0..=12)
        .find(|&d| {
            let scaled = z_step * 10f64.powi(d);
            (scaled - scaled.round()).abs() < 1e-6 * scaled.max(1.0)
        })
        .unwrap_or(3) as usize;
    let grid_style = ShapeStyle::from(&WHITE.mix(0.35)).stroke_width(1);
    for &l in &x_major {
        let x = px(l).round() as i32;
        root.draw(&PathElement::new(
            vec![(x, PLOT_T), (x, PLOT_B)],
            grid_style,
        ))?;
    }
    for &z in &z_ticks {
        let y = py(z).round() as i32;
        root.draw(&PathElement::new(
            vec![(PLOT_L, y), (PLOT_R, y)],
            grid_style,
        ))?;
    }

    // --- Contours, then their labels (kept off the other levels' lines).
    let styles = level_styles();
    let contours: Vec<Vec<Vec<(f64, f64)>>> = styles
        .iter()
        .map(|st| {
            marching_squares(&grid.x, &grid.y, &field, st.level.log10())
                .iter()
                .map(|l| l.iter().map(|&(lx, z)| (px(lx), py(z))).collect())
                .collect()
        })
        .collect();
    for (st, lines) in styles.iter().zip(&contours) {
        for line in lines {
            draw_polyline(&root, line, st)?;
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
        place_labels(&root, &contours[k], st, &others, &mut taken)?;
    }

    // --- Frame, ticks, tick labels, axis labels.
    root.draw(&Rectangle::new(
        [(PLOT_L, PLOT_T), (PLOT_R, PLOT_B)],
        ShapeStyle::from(&BLACK).stroke_width(1),
    ))?;
    let tick_font = font(15.0);
    for d in (lx0.floor() as i32)..=(lx1.ceil() as i32) {
        for m in 1..10 {
            let l = (m as f64 * 10f64.powi(d)).log10();
            if l >= lx0 - 1e-9 && l <= lx1 + 1e-9 {
                let x = px(l).round() as i32;
                let len = if m == 1 { 7 } else { 4 };
                root.draw(&PathElement::new(
                    vec![(x, PLOT_B), (x, PLOT_B + len)],
                    BLACK,
                ))?;
            }
        }
    }
    for &l in &x_major {
        let x = px(l).round() as i32;
        root.draw(&PathElement::new(vec![(x, PLOT_B), (x, PLOT_B + 7)], BLACK))?;
        label(
            &root,
            &fmt_tc(10f64.powf(l)),
            (x, PLOT_B + 11),
            &tick_font,
            HPos::Center,
            VPos::Top,
        )?;
    }
    let axis_font = font(17.0);
    let x_title = "accumulation time TC (s)";
    label(
        &root,
        x_title,
        ((PLOT_L + PLOT_R) / 2, PLOT_B + 36),
        &axis_font,
        HPos::Center,
        VPos::Top,
    )?;
    for &z in &z_ticks {
        let y = py(z).round() as i32;
        root.draw(&PathElement::new(vec![(PLOT_L - 7, y), (PLOT_L, y)], BLACK))?;
        let text = format!("{z:.*}", z_decimals);
        label(
            &root,
            &text,
            (PLOT_L - 11, y),
            &tick_font,
            HPos::Right,
            VPos::Center,
        )?;
    }
    root.draw(&Text::new(
        "altitude (km)",
        (26, (PLOT_T + PLOT_B) / 2),
        axis_font
            .transform(FontTransform::Rotate270)
            .pos(Pos::new(HPos::Center, VPos::Center)),
    ))?;

    // --- Colour bar, with the contour levels marked in their line styles.
    let cy = |lv: f64| PLOT_B as f64 - (lv - lv0) / (lv1 - lv0) * ph;
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
    let mut cticks = vec![SNR_COLOUR_MIN, 1.0, 3.0, 10.0];
    let mut v = 100.0;
    while v <= grid.vmax * 1.0001 {
        cticks.push(v);
        v *= 10.0;
    }
    for &v in &cticks {
        let y = cy(v.log10()).round() as i32;
        root.draw(&PathElement::new(vec![(CBAR_R, y), (CBAR_R + 5, y)], BLACK))?;
        let text = if v == SNR_COLOUR_MIN {
            format!("≤{}", fmt_snr(v))
        } else if (v - grid.vmax).abs() < 1e-9 * v && grid.max > grid.vmax {
            format!("≥{}", fmt_snr(v))
        } else {
            fmt_snr(v)
        };
        label(
            &root,
            &text,
            (CBAR_R + 9, y),
            &tick_font,
            HPos::Left,
            VPos::Center,
        )?;
    }
    for st in &styles {
        let y = cy(st.level.log10());
        draw_polyline(
            &root,
            &[(CBAR_L as f64 + 1.0, y), (CBAR_R as f64 - 1.0, y)],
            st,
        )?;
    }
    root.draw(&Text::new(
        "signal-to-noise ratio S/N",
        (WIDTH as i32 - 30, (PLOT_T + PLOT_B) / 2),
        axis_font
            .transform(FontTransform::Rotate90)
            .pos(Pos::new(HPos::Center, VPos::Center)),
    ))?;

    // --- Legend of the contour styles, under the x-axis title.
    let legend_y = PLOT_B + 82;
    let legend_font = font(15.0);
    let items: Vec<String> = styles
        .iter()
        .zip(&contours)
        .map(|(st, lines)| {
            let note = if !lines.is_empty() {
                ""
            } else if grid
                .snr
                .iter()
                .flatten()
                .all(|&v| v.max(SNR_COLOUR_MIN) >= st.level)
            {
                " (exceeded everywhere)"
            } else {
                " (not reached)"
            };
            format!("S/N = {}{note}", fmt_snr(st.level))
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
    let swatch = viridis(0.4);
    for ((st, text), w) in styles.iter().zip(&items).zip(&widths) {
        root.draw(&Rectangle::new(
            [(x, legend_y - 9), (x + sample, legend_y + 9)],
            swatch.filled(),
        ))?;
        let (a, b) = ((x + 4) as f64, (x + sample - 4) as f64);
        draw_polyline(&root, &[(a, legend_y as f64), (b, legend_y as f64)], st)?;
        label(
            &root,
            text,
            (x + sample + 8, legend_y),
            &legend_font,
            HPos::Left,
            VPos::Center,
        )?;
        x += sample + 8 + w + gap;
    }
    root.present()?;
    Ok(())
}

/// Index `i` with `v[i] <= t <= v[i+1]` (clamped) and the weight of `v[i+1]`.
fn locate(v: &[f64], t: f64) -> (usize, f64) {
    let i = v.partition_point(|&a| a <= t).clamp(1, v.len() - 1) - 1;
    let w = ((t - v[i]) / (v[i + 1] - v[i])).clamp(0.0, 1.0);
    (i, w)
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
fn draw_polyline(root: &Area, line: &[(f64, f64)], st: &LevelStyle) -> AreaResult {
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
    for p in &pieces {
        root.draw(&PathElement::new(
            to_i(p),
            ShapeStyle::from(&st.halo.mix(0.55)).stroke_width(4),
        ))?;
    }
    for p in &pieces {
        root.draw(&PathElement::new(
            to_i(p),
            ShapeStyle::from(&st.colour).stroke_width(2),
        ))?;
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
) -> AreaResult {
    let text = format!("S/N = {}", fmt_snr(st.level));
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

    // --- marching squares -------------------------------------------------

    #[test]
    fn marching_squares_linear_field_is_exact() {
        let x = [0.0, 0.3, 0.7, 1.2, 2.0];
        let y = [0.0, 0.5, 1.5, 2.0, 3.0];
        let f: Vec<Vec<f64>> = y
            .iter()
            .map(|&yy| x.iter().map(|&xx| xx + 2.0 * yy).collect())
            .collect();
        let lines = marching_squares(&x, &y, &f, 2.5);
        assert_eq!(lines.len(), 1, "one straight contour expected");
        assert!(lines[0].len() >= 3);
        for &(px, py) in &lines[0] {
            assert!(
                (px + 2.0 * py - 2.5).abs() < 1e-12,
                "({px}, {py}) not on x + 2y = 2.5"
            );
        }
        // An open line ends on the grid boundary.
        for &(px, py) in [lines[0][0], lines[0][lines[0].len() - 1]].iter() {
            assert!(px == 0.0 || px == 2.0 || py == 0.0 || py == 3.0);
        }
    }

    #[test]
    fn marching_squares_circle_is_one_closed_loop() {
        let g: Vec<f64> = (0..=40).map(|i| -2.0 + 0.1 * i as f64).collect();
        let f: Vec<Vec<f64>> = g
            .iter()
            .map(|&y| g.iter().map(|&x| x * x + y * y).collect())
            .collect();
        let lines = marching_squares(&g, &g, &f, 1.0);
        assert_eq!(lines.len(), 1);
        let l = &lines[0];
        assert!(l.len() > 40);
        assert_eq!(l[0], l[l.len() - 1], "loop must close");
        for &(x, y) in l {
            assert!(
                ((x * x + y * y).sqrt() - 1.0).abs() < 0.01,
                "({x}, {y}) off the unit circle"
            );
        }
    }

    #[test]
    fn marching_squares_saddle_uses_centre_value() {
        let (x, y) = ([0.0, 1.0], [0.0, 1.0]);
        let f = vec![vec![1.0, 0.0], vec![0.0, 1.0]];
        let sorted = |mut l: Vec<(f64, f64)>| {
            l.sort_by(|a, b| a.partial_cmp(b).unwrap());
            l
        };
        // Centre 0.5 >= 0.5: the high corners connect, the low corners are cut off.
        let lines = marching_squares(&x, &y, &f, 0.5);
        assert_eq!(lines.len(), 2);
        let got: Vec<_> = lines.into_iter().map(sorted).collect();
        assert!(got.contains(&vec![(0.5, 0.0), (1.0, 0.5)]), "{got:?}");
        assert!(got.contains(&vec![(0.0, 0.5), (0.5, 1.0)]), "{got:?}");
        // Centre 0.5 < 0.6: the high corners are cut off.
        let lines = marching_squares(&x, &y, &f, 0.6);
        assert_eq!(lines.len(), 2);
        let got: Vec<_> = lines.into_iter().map(sorted).collect();
        let near = |l: &Vec<(f64, f64)>, want: [(f64, f64); 2]| {
            l.iter()
                .zip(want)
                .all(|(a, b)| (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12)
        };
        assert!(
            got.iter().any(|l| near(l, [(0.0, 0.4), (0.4, 0.0)])),
            "{got:?}"
        );
        assert!(
            got.iter().any(|l| near(l, [(0.6, 1.0), (1.0, 0.6)])),
            "{got:?}"
        );
    }

    #[test]
    fn marching_squares_without_crossing_or_with_bad_shapes_is_empty() {
        let (x, y) = ([0.0, 1.0, 2.0], [0.0, 1.0]);
        let f = vec![vec![1.0, 2.0, 3.0], vec![4.0, 5.0, 6.0]];
        assert!(marching_squares(&x, &y, &f, 10.0).is_empty());
        assert!(marching_squares(&x, &y, &f, 0.5).is_empty());
        assert!(marching_squares(&x, &y, &f, f64::NAN).is_empty());
        assert!(marching_squares(&x[..1], &y, &f, 2.5).is_empty());
        assert!(marching_squares(&x, &y, &f[..1], 2.5).is_empty());
        assert!(marching_squares(&x, &y, &[vec![1.0, 2.0], vec![4.0, 5.0]], 2.5).is_empty());
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
        let field = grid.log_field();
        for level in CONTOUR_LEVELS {
            let lines = marching_squares(&grid.x, &grid.y, &field, level.log10());
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
    fn altitude_ticks_are_round() {
        assert_eq!(nice_step(30.0, 7.0), 5.0);
        assert_eq!(nice_step(39.9, 7.0), 5.0);
        assert_eq!(nice_step(6.0, 7.0), 1.0);
        assert_eq!(nice_step(0.9, 7.0), 0.1);
        assert_eq!(nice_step(600.0, 7.0), 100.0);
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
