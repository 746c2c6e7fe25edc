//! The `sweep` figure: the first metric against one varied key (a line) or two (a
//! heatmap, viridis through `colorous`, the colour bar's range in the caption).

use plotters::prelude::*;

use super::snr_map::{FONT, encode_png, ensure_font};
use crate::design::sweep::Axis;

const WIDTH: u32 = 1000;
const HEIGHT: u32 = 650;

/// The PNG of a sweep's first metric (`name`) over `axes` (one or two).
pub fn png_bytes(
    axes: &[Axis],
    name: &str,
    rows: &[(Vec<f64>, Vec<f64>)],
) -> std::result::Result<Vec<u8>, String> {
    ensure_font()?;
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    let drawn = match axes.len() {
        1 => line(&mut rgb, &axes[0], name, rows),
        2 => heatmap(&mut rgb, axes, name, rows),
        n => {
            return Err(format!(
                "a figure needs one or two varied keys, not {n} (the CSV has all)"
            ));
        }
    };
    drawn.map_err(|e| format!("drawing failed: {e}"))?;
    encode_png(&rgb, WIDTH, HEIGHT).map_err(|e| format!("PNG encoding failed: {e}"))
}

fn finite_range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if lo < hi {
        (lo, hi)
    } else if lo.is_finite() {
        (lo - 0.5, lo + 0.5)
    } else {
        (0.0, 1.0)
    }
}

/// Whether values span more than two decades, all positive (drawn on a log axis).
fn wants_log(v: impl Iterator<Item = f64> + Clone) -> bool {
    let (lo, hi) = finite_range(v.clone());
    lo > 0.0 && hi / lo > 100.0 && v.filter(|x| x.is_finite()).all(|x| x > 0.0)
}

fn line(
    rgb: &mut [u8],
    axis: &Axis,
    name: &str,
    rows: &[(Vec<f64>, Vec<f64>)],
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(rgb, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    let log_x = wants_log(axis.values.iter().copied());
    let log_y = wants_log(rows.iter().map(|r| r.1[0]));
    let tx = |v: f64| if log_x { v.log10() } else { v };
    let ty = |v: f64| if log_y { v.log10() } else { v };
    let (x0, x1) = finite_range(axis.values.iter().map(|&v| tx(v)));
    let (y0, y1) = finite_range(rows.iter().map(|r| ty(r.1[0])));
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{name} against {}", axis.key), (FONT, 18))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let label = |log: bool| {
        move |v: &f64| {
            if log {
                format!("{:.2e}", 10f64.powf(*v))
            } else {
                format!("{v:.3}")
            }
        }
    };
    chart
        .configure_mesh()
        .x_desc(if log_x {
            format!("{} (log scale)", axis.key)
        } else {
            axis.key.clone()
        })
        .y_desc(if log_y {
            format!("{name} (log scale)")
        } else {
            name.to_string()
        })
        .x_label_formatter(&label(log_x))
        .y_label_formatter(&label(log_y))
        .label_style((FONT, 13))
        .draw()?;
    let points: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.1[0].is_finite())
        .map(|r| (tx(r.0[0]), ty(r.1[0])))
        .collect();
    chart.draw_series(std::iter::once(PathElement::new(
        points.clone(),
        BLUE.stroke_width(2),
    )))?;
    chart.draw_series(points.into_iter().map(|p| Circle::new(p, 3, BLUE.filled())))?;
    root.present()?;
    Ok(())
}

fn heatmap(
    rgb: &mut [u8],
    axes: &[Axis],
    name: &str,
    rows: &[(Vec<f64>, Vec<f64>)],
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(rgb, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    let (lo, hi) = finite_range(rows.iter().map(|r| r.1[0]));
    let (nx, ny) = (axes[0].values.len(), axes[1].values.len());
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{name} (dark {lo:.3e} to yellow {hi:.3e}; grey: none{})",
                if name.starts_with("snr_at") {
                    "; white: S/N = 1, 3, 10"
                } else {
                    ""
                }
            ),
            (FONT, 18),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..nx as f64, 0.0..ny as f64)?;
    let label = |axis: &Axis, v: f64| {
        let i = (v.floor() as usize).min(axis.values.len() - 1);
        format!("{:.3e}", axis.values[i])
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(axes[0].key.as_str())
        .y_desc(axes[1].key.as_str())
        .x_label_formatter(&|v| label(&axes[0], *v))
        .y_label_formatter(&|v| label(&axes[1], *v))
        .label_style((FONT, 12))
        .draw()?;
    chart.draw_series(rows.iter().enumerate().map(|(k, r)| {
        let (i, j) = ((k / ny) as f64, (k % ny) as f64);
        let v = r.1[0];
        let color = if v.is_finite() {
            let c = colorous::VIRIDIS.eval_continuous(((v - lo) / (hi - lo)).clamp(0.0, 1.0));
            RGBColor(c.r, c.g, c.b)
        } else {
            RGBColor(200, 200, 200)
        };
        Rectangle::new([(i, j), (i + 1.0, j + 1.0)], color.filled())
    }))?;
    if name.starts_with("snr_at") {
        // S/N contours (marching squares, `contour`), in the heatmap's cell coordinates
        let values: Vec<f64> = (0..ny)
            .flat_map(|j| (0..nx).map(move |i| (i, j)))
            .map(|(i, j)| rows[i * ny + j].1[0])
            .map(|v| if v.is_finite() { v } else { 0.0 })
            .collect();
        let lines = contour::ContourBuilder::new(nx, ny, true)
            .lines(&values, &SNR_CONTOURS)
            .map_err(|e| format!("contours: {e}"))?;
        for line in &lines {
            for path in line.geometry().0.iter() {
                // the rings close along the grid's edge: draw only the inner pieces
                let on_edge = |x: f64, y: f64| {
                    x <= 0.51 || y <= 0.51 || x >= nx as f64 - 0.51 || y >= ny as f64 - 0.51
                };
                for w in path.0.windows(2) {
                    let (a, b) = (w[0], w[1]);
                    if on_edge(a.x, a.y) && on_edge(b.x, b.y) {
                        continue;
                    }
                    let segment = vec![(a.x, a.y), (b.x, b.y)];
                    chart.draw_series(std::iter::once(PathElement::new(
                        segment,
                        WHITE.stroke_width(2),
                    )))?;
                }
            }
        }
    }
    root.present()?;
    Ok(())
}

/// The S/N contours drawn on a heatmap of an `snr_at` metric.
const SNR_CONTOURS: [f64; 3] = [1.0, 3.0, 10.0];
