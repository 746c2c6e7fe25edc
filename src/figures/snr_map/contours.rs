//! The S/N = 1, 3, 10 contour lines: densified, dashed, drawn on a halo, labelled.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

use super::super::plot::text::{font, label};
use super::super::plot::{DrawResult, ticks};
use super::layout::{Area, LevelStyle, PLOT_B, PLOT_L, PLOT_R, PLOT_T};

pub(super) fn seg_len(a: (f64, f64), b: (f64, f64)) -> f64 {
    ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt()
}

/// The polyline's points with extra ones so that none are more than `step` apart.
pub(super) fn densify(line: &[(f64, f64)], step: f64) -> Vec<(f64, f64)> {
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
pub(super) fn draw_polyline(root: &Area, line: &[(f64, f64)], st: &LevelStyle) -> DrawResult {
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
pub(super) fn dash(line: &[(f64, f64)], on: f64, off: f64) -> Vec<Vec<(f64, f64)>> {
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
pub(super) type Bbox = (i32, i32, i32, i32);

/// Puts "S/N = L" boxes on the level's longest lines (at most 2 labels), near
/// each line's middle, inside the frame, clear of other labels and of the
/// other levels' lines (`others`, densified pixel points).
pub(super) fn place_labels(
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
