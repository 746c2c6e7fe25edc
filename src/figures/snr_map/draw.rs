//! The S/N map's layout: titles, the false-colour field, grid lines, axes, colour bar,
//! legend.

use plotters::prelude::*;
use plotters::style::FontTransform;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::super::plot::colour::viridis;
use super::super::plot::text::{font, label};
use super::super::plot::{DrawResult, ticks};
use super::contours::{Bbox, densify, draw_polyline, place_labels};
use super::grid::{Grid, ends};
use super::layout::{
    Area, CBAR_L, CBAR_R, LevelStyle, PLOT_B, PLOT_L, PLOT_R, PLOT_T, level_styles,
};
use super::map::{HEIGHT, SNR_COLOUR_MIN, SnrMap, WIDTH};

pub(super) fn render(grid: &Grid, map: &SnrMap, rgb: &mut [u8]) -> DrawResult {
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
pub(super) fn draw_titles(root: &Area, map: &SnrMap) -> DrawResult {
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
pub(super) fn draw_field(root: &Area, g: &Grid) -> DrawResult {
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
pub(super) fn locate(v: &[f64], t: f64) -> (usize, f64) {
    let i = v.partition_point(|&a| a <= t).clamp(1, v.len() - 1) - 1;
    let w = ((t - v[i]) / (v[i + 1] - v[i])).clamp(0.0, 1.0);
    (i, w)
}

/// Faint grid lines at the labelled ticks.
pub(super) fn draw_grid_lines(root: &Area, g: &Grid) -> DrawResult {
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
pub(super) fn draw_contours(
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
pub(super) fn draw_tc_axis(root: &Area, g: &Grid) -> DrawResult {
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
pub(super) fn draw_z_axis(root: &Area, g: &Grid) -> DrawResult {
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
pub(super) fn line(root: &Area, a: (i32, i32), b: (i32, i32)) -> DrawResult {
    root.draw(&PathElement::new(vec![a, b], BLACK))?;
    Ok(())
}

/// An axis title turned on its side, centred on `at`.
pub(super) fn upright(root: &Area, text: &str, at: (i32, i32), turn: FontTransform) -> DrawResult {
    let style = font(17.0)
        .transform(turn)
        .pos(Pos::new(HPos::Center, VPos::Center));
    root.draw(&Text::new(text, at, style))?;
    Ok(())
}

/// The colour bar's marks: the floor (≤), the contour levels, the decades up to the
/// top (≥ when the data go past it), with their labels.
pub(super) fn bar_marks(g: &Grid) -> Vec<(f64, String)> {
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
pub(super) fn draw_colour_bar(root: &Area, g: &Grid, styles: &[LevelStyle]) -> DrawResult {
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
pub(super) fn draw_legend(
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
