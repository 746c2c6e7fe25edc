//! Isolines of a gridded field through the `contour` crate (marching squares, linear
//! interpolation along the cells' edges), returned in the grid's own coordinates, and
//! drawn with a halo and a label that tells each level apart.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::text::{FONT, font};

/// The isolines of `f` at `level`: `f[iy][ix]` sampled at `(x[ix], y[iy])` (each axis
/// monotonic, any spacing), as polylines in those coordinates. The lines stop at the
/// grid's edge (the `contour` crate closes rings around it; those pieces are dropped).
pub fn isolines(x: &[f64], y: &[f64], f: &[Vec<f64>], level: f64) -> Vec<Vec<(f64, f64)>> {
    let (nx, ny) = (x.len(), y.len());
    if nx < 2 || ny < 2 || f.len() != ny || f.iter().any(|r| r.len() != nx) {
        return vec![];
    }
    let values: Vec<f64> = f
        .iter()
        .flat_map(|r| {
            r.iter()
                .map(|&v| if v.is_nan() { f64::NEG_INFINITY } else { v })
        })
        .collect();
    let Ok(lines) = contour::ContourBuilder::new(nx, ny, true).lines(&values, &[level]) else {
        return vec![];
    };
    // the crate puts sample (i, j) at (i + 0.5, j + 0.5)
    let at = |v: &[f64], c: f64| {
        let t = (c - 0.5).clamp(0.0, (v.len() - 1) as f64);
        let i = (t.floor() as usize).min(v.len() - 2);
        v[i] + (t - i as f64) * (v[i + 1] - v[i])
    };
    let inside = |c: f64, n: usize| c > 0.5 + 1e-9 && c < n as f64 - 0.5 - 1e-9;
    let mut out = Vec::new();
    for line in &lines {
        for ring in &line.geometry().0 {
            let mut piece: Vec<(f64, f64)> = Vec::new();
            for p in &ring.0 {
                if inside(p.x, nx) && inside(p.y, ny) || on_edge_crossing(p.x, p.y, nx, ny) {
                    piece.push((at(x, p.x), at(y, p.y)));
                } else if !piece.is_empty() {
                    if piece.len() > 1 {
                        out.push(std::mem::take(&mut piece));
                    }
                    piece.clear();
                }
            }
            if piece.len() > 1 {
                out.push(piece);
            }
        }
    }
    out
}

/// A point on the grid's outer edge where a line crosses it (not a corner of the
/// closing ring): kept so that lines reach the edge.
fn on_edge_crossing(cx: f64, cy: f64, nx: usize, ny: usize) -> bool {
    let on = |c: f64, n: usize| (c - 0.5).abs() < 1e-9 || (c - (n as f64 - 0.5)).abs() < 1e-9;
    let strict = |c: f64, n: usize| c > 0.5 + 1e-9 && c < n as f64 - 0.5 - 1e-9;
    (on(cx, nx) && strict(cy, ny)) || (on(cy, ny) && strict(cx, nx))
}

/// How an isoline is drawn.
#[derive(Debug, Clone, Copy)]
pub struct IsolineStyle {
    /// Line colour.
    pub colour: RGBColor,
    /// Halo colour (behind the line, for contrast on any colour map).
    pub halo: RGBColor,
    /// Line width, pixels.
    pub width: u32,
}

/// Draws `lines` (already in pixel coordinates of `area`) with their halo, and writes
/// `text` once on the longest, on a white patch at its middle point.
pub fn draw_labelled<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    lines: &[Vec<(i32, i32)>],
    style: &IsolineStyle,
    text: &str,
) -> super::result::DrawResult
where
    DB::ErrorType: 'static,
{
    for l in lines {
        area.draw(&PathElement::new(
            l.clone(),
            style.halo.stroke_width(style.width + 2),
        ))?;
        area.draw(&PathElement::new(
            l.clone(),
            style.colour.stroke_width(style.width),
        ))?;
    }
    if let Some(longest) = lines.iter().max_by_key(|l| l.len()) {
        let (x, y) = longest[longest.len() / 2];
        let f = font(13.0);
        let (w, h) = area.estimate_text_size(text, &f)?;
        let (w, h) = (w as i32 + 6, h as i32 + 4);
        area.draw(&Rectangle::new(
            [(x - w / 2, y - h / 2), (x + w / 2, y + h / 2)],
            WHITE.mix(0.85).filled(),
        ))?;
        super::text::label(
            area,
            text,
            (x, y),
            &(FONT, 13).into_font().color(&BLACK),
            plotters::style::text_anchor::HPos::Center,
            plotters::style::text_anchor::VPos::Center,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear field's isoline is exact: f = x + 0·y, level 2.25 at x = 2.25.
    #[test]
    fn linear_field_isoline_is_exact() {
        let x: Vec<f64> = (0..6).map(|i| i as f64).collect();
        let y: Vec<f64> = (0..4).map(|j| 10.0 * j as f64).collect();
        let f: Vec<Vec<f64>> = y.iter().map(|_| x.clone()).collect();
        let lines = isolines(&x, &y, &f, 2.25);
        assert_eq!(lines.len(), 1, "{lines:?}");
        for &(px, py) in &lines[0] {
            assert!((px - 2.25).abs() < 1e-9, "{px}");
            assert!((0.0..=30.0).contains(&py));
        }
        // it spans the grid from edge to edge
        let ys: Vec<f64> = lines[0].iter().map(|p| p.1).collect();
        assert!(
            ys.iter().any(|&v| v < 1e-9) && ys.iter().any(|&v| v > 30.0 - 1e-9),
            "{ys:?}"
        );
    }

    /// A circle: one closed loop of radius √level around the centre, on an uneven grid.
    #[test]
    fn circle_is_one_closed_loop() {
        let x: Vec<f64> = (0..41).map(|i| -2.0 + 0.1 * i as f64).collect();
        let y: Vec<f64> = (0..31).map(|j| -1.5 + 0.1 * j as f64).collect();
        let f: Vec<Vec<f64>> = y
            .iter()
            .map(|&b| x.iter().map(|&a| a * a + b * b).collect())
            .collect();
        let lines = isolines(&x, &y, &f, 1.0);
        assert_eq!(lines.len(), 1);
        let l = &lines[0];
        assert_eq!(l.first(), l.last());
        for &(a, b) in l {
            assert!(((a * a + b * b).sqrt() - 1.0).abs() < 0.01);
        }
    }

    #[test]
    fn bad_shapes_give_nothing() {
        assert!(isolines(&[0.0], &[0.0, 1.0], &[vec![0.0], vec![1.0]], 0.5).is_empty());
        assert!(isolines(&[0.0, 1.0], &[0.0, 1.0], &[vec![0.0, 1.0]], 0.5).is_empty());
    }
}
