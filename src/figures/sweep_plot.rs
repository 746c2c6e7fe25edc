//! The `sweep` figure: one panel per metric in one PNG (stacked; in two or three columns
//! from four metrics on), the image sized to the number of panels.
//!
//! * Two varied keys: each metric a field over the grid ([`ImagePanel`]), the first key
//!   across, the second up; a colour bar with the metric's name and unit, logarithmic
//!   when the metric spans more than two decades; grey where there is no value; the
//!   S/N = 1, 3 and 10 isolines, each labelled and drawn in its own style, on `snr_at`
//!   metrics.
//! * One varied key: each metric a line against the key, on a log axis when its values
//!   are positive and span more than a decade (altitudes always linear).
//!
//! Axes read as people read them (`plot::describe`: "pulse energy (mJ)", values scaled
//! to the shown unit), with nice ticks; an axis is logarithmic when its values are
//! positive and log-spaced (`--vary KEY=A..B:log:N`) or span more than two decades.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::plot::colour::ColourScale;
use super::plot::isolines::IsolineStyle;
use super::plot::panel::{self, ImagePanel, Isoline};
use super::plot::text::{FONT, encode_png, ensure_font};
use super::plot::{DrawResult, Label, describe, ticks};
use crate::design::sweep::Axis as SweepAxis;

/// Width of one panel, pixels.
const PANEL_WIDTH: u32 = 1000;
/// Height of one heatmap panel (two varied keys), pixels.
const MAP_HEIGHT: u32 = 620;
/// Height of one line panel (one varied key), pixels.
const LINE_HEIGHT: u32 = 460;
/// Blank strip right of each panel, pixels.
const PANEL_GAP: u32 = 28;
/// Most metrics one figure draws (the CSV holds any number).
const MAX_PANELS: usize = 24;
/// Decades a log colour scale shows at most, below the largest value.
const MAX_DECADES: f64 = 12.0;

/// The S/N isolines of an `snr_at` heatmap: level, line colour, halo colour, width.
const SNR_ISOLINES: [(f64, RGBColor, RGBColor, u32); 3] = [
    (1.0, RGBColor(255, 120, 60), BLACK, 2),
    (3.0, WHITE, BLACK, 2),
    (10.0, BLACK, WHITE, 3),
];

/// The PNG of a sweep over `axes` (one or two varied keys): one panel per metric of
/// `names`; `rows` holds each grid point (the last axis fastest) with every metric's
/// value, in the order of `names`.
pub fn png_bytes(
    axes: &[SweepAxis],
    names: &[String],
    rows: &[(Vec<f64>, Vec<f64>)],
) -> std::result::Result<Vec<u8>, String> {
    ensure_font()?;
    let n = names.len();
    if n == 0 {
        return Err("a figure needs at least one --metric".into());
    }
    if n > MAX_PANELS {
        return Err(format!(
            "a figure holds at most {MAX_PANELS} metrics, not {n} (the CSV has all)"
        ));
    }
    let points: usize = axes.iter().map(|a| a.values.len()).product();
    if rows.len() != points || rows.iter().any(|r| r.1.len() < n) {
        return Err(format!(
            "the sweep has {} rows for {points} grid points of {n} metrics",
            rows.len()
        ));
    }
    let panel_height = match axes.len() {
        1 => LINE_HEIGHT,
        2 => MAP_HEIGHT,
        k => {
            return Err(format!(
                "a figure needs one or two varied keys, not {k} (the CSV has all)"
            ));
        }
    };
    let (grid_rows, cols) = layout(n);
    let (w, h) = (PANEL_WIDTH * cols as u32, panel_height * grid_rows as u32);
    let mut rgb = vec![0u8; (w as usize) * (h as usize) * 3];
    let shown: Vec<Shown> = axes.iter().map(Shown::of).collect();
    draw(&mut rgb, (w, h), (grid_rows, cols), &shown, names, rows)
        .map_err(|e| format!("drawing failed: {e}"))?;
    encode_png(&rgb, w, h).map_err(|e| format!("PNG encoding failed: {e}"))
}

/// Rows and columns of panels for `n` metrics: one column up to three, two up to
/// eight, then three.
fn layout(n: usize) -> (usize, usize) {
    let cols = match n {
        0..=3 => 1,
        4..=8 => 2,
        _ => 3,
    };
    (n.div_ceil(cols), cols)
}

fn draw(
    rgb: &mut [u8],
    size: (u32, u32),
    grid: (usize, usize),
    shown: &[Shown],
    names: &[String],
    rows: &[(Vec<f64>, Vec<f64>)],
) -> DrawResult {
    let root = BitMapBackend::with_buffer(rgb, size).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly(grid);
    for (m, (name, area)) in names.iter().zip(&areas).enumerate() {
        let values: Vec<f64> = rows.iter().map(|r| r.1[m]).collect();
        // a gap on the right: a colour bar's label apart from the image's edge and from
        // the next column's axis label
        let area = area.margin(0, 0, 0, PANEL_GAP);
        let area = &area;
        if let [x, y] = shown {
            heatmap(area, x, y, name, &values)?;
        } else {
            line(area, &shown[0], name, &values)?;
        }
    }
    root.present()?;
    Ok(())
}

/// A varied key as shown: its label, its values in the shown unit, its spacing.
struct Shown {
    label: Label,
    values: Vec<f64>,
    log: bool,
}

impl Shown {
    fn of(a: &SweepAxis) -> Shown {
        let label = describe(&a.key);
        let values: Vec<f64> = a.values.iter().map(|v| tidy(v * label.scale)).collect();
        let log = log_spaced(&values);
        Shown { label, values, log }
    }

    /// The panel axis from the first value to the last (one value: its cell), and the
    /// cells' edges (geometric midpoints on a log axis).
    fn axis(&self) -> (panel::Axis, Vec<f64>) {
        let v = &self.values;
        let edges = if self.log {
            let logs: Vec<f64> = v.iter().map(|x| x.log10()).collect();
            panel::edges(&logs)
                .into_iter()
                .map(|e| 10f64.powf(e))
                .collect()
        } else {
            panel::edges(v)
        };
        let (lo, hi) = if v.len() > 1 {
            (v[0], v[v.len() - 1])
        } else {
            (edges[0], edges[edges.len() - 1])
        };
        let text = self.label.text();
        let axis = if self.log {
            panel::Axis::log(text, lo.min(hi), lo.max(hi))
        } else {
            panel::Axis::linear(text, lo.min(hi), lo.max(hi))
        };
        (axis, edges)
    }
}

/// `v` to 12 significant digits: a log sweep's 1e-4 J is 0.1 mJ, not 0.10000000000000009
/// (whose decade would round up, losing the axis' first tick).
fn tidy(v: f64) -> f64 {
    if v.is_finite() && v != 0.0 {
        format!("{v:.11e}").parse().unwrap_or(v)
    } else {
        v
    }
}

/// Whether values are all positive and either span more than two decades or are
/// log-spaced (three or more, a constant ratio other than 1).
fn log_spaced(v: &[f64]) -> bool {
    if v.is_empty() || !v.iter().all(|&x| x > 0.0 && x.is_finite()) {
        return false;
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi / lo > 100.0 {
        return true;
    }
    if v.len() < 3 {
        return false;
    }
    let r = v[1] / v[0];
    (r - 1.0).abs() > 1e-6 && v.windows(2).all(|w| (w[1] / w[0] / r - 1.0).abs() < 1e-6)
}

/// Whether the finite values (those drawn) are all positive and span more than
/// `ratio` (max/min).
fn spans(v: &[f64], ratio: f64) -> bool {
    let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    lo > 0.0 && hi.is_finite() && hi / lo > ratio
}

/// The label of a metric: `plot::describe`, with the sweep's own metrics it lacks.
fn metric_label(name: &str) -> Label {
    match name {
        "mean_laser_power_w" => Label {
            name: "mean laser power".into(),
            unit: "W",
            scale: 1.0,
        },
        _ => describe(name),
    }
}

/// What a point without a value means for metric `name`.
fn missing_meaning(name: &str) -> String {
    match name.split_once(':') {
        Some(("max_altitude", x)) => {
            format!("S/N < {} at every altitude", x.trim_start_matches("snr="))
        }
        Some(("time_to_snr", _)) => "no signal".into(),
        _ => "no value".into(),
    }
}

/// Metric `name` over two varied keys (`values` in the grid's order, the last key
/// fastest) as a field with its colour bar.
fn heatmap<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    x: &Shown,
    y: &Shown,
    name: &str,
    values: &[f64],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let label = metric_label(name);
    let (nx, ny) = (x.values.len(), y.values.len());
    let field: Vec<f64> = (0..ny)
        .flat_map(|iy| (0..nx).map(move |ix| ix * ny + iy))
        .map(|k| values[k] * label.scale)
        .map(|v| if v.is_finite() { v } else { f64::NAN })
        .collect();
    let scale = ColourScale::over(field.iter().copied(), false, MAX_DECADES);
    let missing = field
        .iter()
        .filter(|&&v| scale.fraction(v).is_none())
        .count();
    let (x_axis, x_edges) = x.axis();
    let (y_axis, y_edges) = y.axis();
    let mut title = format!(
        "{} against {} and {}",
        label.name, x.label.name, y.label.name
    );
    if missing > 0 {
        title += &format!(" (grey: {})", missing_meaning(name));
    }
    let isolines = if name.starts_with("snr_at:") {
        SNR_ISOLINES
            .iter()
            .map(|&(level, colour, halo, width)| Isoline {
                level,
                text: format!("S/N = {}", ticks::format(level)),
                style: IsolineStyle {
                    colour,
                    halo,
                    width,
                },
            })
            .collect()
    } else {
        vec![]
    };
    ImagePanel {
        title,
        x: x_axis,
        y: y_axis,
        x_edges,
        y_edges,
        values: field,
        scale,
        bar_label: label.text(),
        isolines,
    }
    .draw(area)
}

/// Metric `name` against one varied key, a line through the points (broken where a
/// point has no value).
fn line<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    x: &Shown,
    name: &str,
    values: &[f64],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let label = metric_label(name);
    let ys: Vec<f64> = values.iter().map(|v| v * label.scale).collect();
    // a log axis from a decade on (a power law is a straight line), altitudes excepted
    let log_y = !name.starts_with("max_altitude:") && spans(&ys, 10.0);
    let drawn = |v: f64| v.is_finite() && (!log_y || v > 0.0);
    let x_axis = x.axis().0;
    let (y_lo, y_hi) = {
        let v = ys.iter().copied().filter(|&v| drawn(v));
        let lo = v.clone().fold(f64::INFINITY, f64::min);
        let hi = v.fold(f64::NEG_INFINITY, f64::max);
        panel::widen(lo, hi)
    };
    let y_axis = if log_y {
        panel::Axis::log(label.text(), y_lo, y_hi)
    } else {
        panel::Axis::linear(label.text(), y_lo, y_hi)
    };
    // the y range a little wider than the values, so that no point sits on the frame
    let (c0, c1) = (y_axis.coord(y_axis.lo), y_axis.coord(y_axis.hi));
    let pad = 0.05 * (c1 - c0);
    let (c0, c1) = (c0 - pad, c1 + pad);
    let y_ticks: Vec<f64> = if y_axis.log {
        ticks::log(y_axis.value(c0), y_axis.value(c1), 8)
    } else {
        ticks::linear(c0, c1, 6.0)
    };
    let x_ticks: Vec<f64> = if x_axis.log {
        ticks::log(x_axis.lo, x_axis.hi, 10)
    } else {
        ticks::linear(x_axis.lo, x_axis.hi, 8.0)
    };
    let to_coords = |a: &panel::Axis, t: Vec<f64>| t.into_iter().map(|v| a.coord(v)).collect();
    let x_range = ticks::TickedRange::new(
        x_axis.coord(x_axis.lo),
        x_axis.coord(x_axis.hi),
        to_coords(&x_axis, x_ticks),
    );
    let y_range = ticks::TickedRange::new(c0, c1, to_coords(&y_axis, y_ticks));
    let missing = ys.iter().filter(|&&v| !drawn(v)).count();
    let mut title = format!("{} against {}", label.name, x.label.name);
    if missing > 0 {
        title += &format!(
            " (a gap: {} at {missing} of {} points)",
            missing_meaning(name),
            ys.len()
        );
    }
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, 17))
        .margin(10)
        .margin_right(30)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d(x_range, y_range)?;
    chart
        .configure_mesh()
        .bold_line_style(RGBColor(225, 225, 225))
        .light_line_style(TRANSPARENT)
        .x_desc(x_axis.label.as_str())
        .y_desc(y_axis.label.as_str())
        .x_label_formatter(&|c: &f64| ticks::format(x_axis.value(*c)))
        .y_label_formatter(&|c: &f64| ticks::format(y_axis.value(*c)))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .draw()?;
    // the runs of consecutive points with a value, each one line
    let mut runs: Vec<Vec<(f64, f64)>> = vec![vec![]];
    for (&xv, &yv) in x.values.iter().zip(&ys) {
        if drawn(yv) {
            if let Some(r) = runs.last_mut() {
                r.push((x_axis.coord(xv), y_axis.coord(yv)));
            }
        } else if runs.last().is_some_and(|r| !r.is_empty()) {
            runs.push(vec![]);
        }
    }
    let colour = RGBColor(31, 119, 180);
    for run in &runs {
        chart.draw_series(std::iter::once(PathElement::new(
            run.clone(),
            colour.stroke_width(2),
        )))?;
        chart.draw_series(run.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_spacing_is_recognised() {
        let log: Vec<f64> = (0..5).map(|i| 10f64.powf(-1.0 + 0.25 * i as f64)).collect();
        assert!(log_spaced(&log));
        assert!(!log_spaced(&[10.0, 20.0, 30.0, 40.0]));
        assert!(log_spaced(&[0.1, 100.0]));
        assert!(!log_spaced(&[0.1, 5.0]));
        assert!(!log_spaced(&[-1.0, 1.0, 100.0]));
        assert!(!log_spaced(&[2.0]));
    }

    #[test]
    fn shown_values_are_tidy() {
        assert_eq!(tidy(1.0000000000000009e-4 * 1e3), 0.1);
        assert_eq!(tidy(250.0), 250.0);
        assert_eq!(tidy(0.0), 0.0);
    }

    #[test]
    fn panels_fill_a_grid() {
        assert_eq!(layout(1), (1, 1));
        assert_eq!(layout(3), (3, 1));
        assert_eq!(layout(4), (2, 2));
        assert_eq!(layout(5), (3, 2));
        assert_eq!(layout(9), (3, 3));
    }
}
