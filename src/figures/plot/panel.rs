//! An image panel: a field on a grid of cells drawn pixel by pixel against two axes
//! (linear or logarithmic, nice ticks, labels with units), with its colour bar, a
//! title, and optional labelled isolines. Every false-colour figure is one or more of
//! these.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::colour::{ColourScale, draw_colour_bar};
use super::isolines::{IsolineStyle, draw_labelled, isolines};
use super::text::FONT;
use super::ticks;

/// Width of a panel's colour bar with its ticks and label, pixels.
pub const BAR_WIDTH: u32 = 120;
/// About how many intervals a panel's x and y ticks divide the axes into.
const X_TICKS: usize = 10;
/// See [`X_TICKS`].
const Y_TICKS: usize = 8;

/// One axis of a panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Label with its unit.
    pub label: String,
    /// The axis' ends (`lo` at the left or bottom).
    pub lo: f64,
    /// See `lo`.
    pub hi: f64,
    /// Logarithmic (both ends > 0).
    pub log: bool,
    /// A time axis labelled by the UTC clock (`HH:MM`) rather than by its numbers.
    pub clock: Option<Clock>,
    /// Ticks given with their labels, `(value, text)`, rather than nice numbers (a
    /// track's latitude and longitude).
    pub marks: Option<Vec<(f64, String)>>,
}

/// What makes a linear axis of times a clock: value `v` is the UTC time
/// `origin_unix_s + v·seconds_per_unit` (Unix seconds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clock {
    /// Unix time of the axis' value 0, s.
    pub origin_unix_s: f64,
    /// Seconds per unit of the axis' values (1 for s, 60 for min).
    pub seconds_per_unit: f64,
}

impl Clock {
    fn unix_s(&self, v: f64) -> f64 {
        self.origin_unix_s + v * self.seconds_per_unit
    }
}

impl Axis {
    /// A linear axis.
    pub fn linear(label: impl Into<String>, lo: f64, hi: f64) -> Self {
        let (lo, hi) = widen(lo, hi);
        Axis {
            label: label.into(),
            lo,
            hi,
            log: false,
            clock: None,
            marks: None,
        }
    }

    /// A linear axis whose ticks are `marks`, `(value, text)`, those inside it.
    pub fn marked(label: impl Into<String>, lo: f64, hi: f64, marks: Vec<(f64, String)>) -> Self {
        let mut a = Axis::linear(label, lo, hi);
        let (lo, hi) = (a.lo, a.hi);
        a.marks = Some(
            marks
                .into_iter()
                .filter(|(v, _)| (lo..=hi).contains(v))
                .collect(),
        );
        a
    }

    /// A linear axis of times labelled by the UTC clock (`clock`), `lo` and `hi` in its
    /// values.
    pub fn clock(label: impl Into<String>, lo: f64, hi: f64, clock: Clock) -> Self {
        let mut a = Axis::linear(label, lo, hi);
        a.clock = (clock.origin_unix_s.is_finite()
            && clock.seconds_per_unit.is_finite()
            && clock.seconds_per_unit > 0.0)
            .then_some(clock);
        a
    }

    /// A logarithmic axis (falls back to linear unless `0 < lo < hi`).
    pub fn log(label: impl Into<String>, lo: f64, hi: f64) -> Self {
        let mut a = Axis::linear(label, lo, hi);
        a.log = a.lo > 0.0 && a.hi > a.lo;
        a
    }

    /// The axis' coordinate of `v` (log10 on a log axis).
    pub fn coord(&self, v: f64) -> f64 {
        if self.log { v.log10() } else { v }
    }

    /// The inverse of [`Axis::coord`].
    pub fn value(&self, c: f64) -> f64 {
        if self.log { 10f64.powf(c) } else { c }
    }

    /// The tick label of coordinate `c`: the clock time, or the number.
    fn tick_label(&self, c: f64) -> String {
        if let Some(marks) = &self.marks {
            return marks
                .iter()
                .min_by(|a, b| (a.0 - c).abs().total_cmp(&(b.0 - c).abs()))
                .map(|m| m.1.clone())
                .unwrap_or_default();
        }
        match self.clock {
            Some(k) => ticks::clock_label(k.unix_s(c), self.clock_ticks(X_TICKS).1),
            None => ticks::format(self.value(c)),
        }
    }

    /// A clock axis' ticks (in its values) about `n` apart, and their step in seconds.
    fn clock_ticks(&self, n: usize) -> (Vec<f64>, f64) {
        let Some(k) = self.clock else {
            return (vec![], 1.0);
        };
        let (t, step) = ticks::clock(k.unix_s(self.lo), k.unix_s(self.hi), n as f64 / 2.0);
        let v = t
            .into_iter()
            .map(|t| (t - k.origin_unix_s) / k.seconds_per_unit);
        (v.collect(), step)
    }

    /// The plotters range in the axis' coordinate, with nice ticks as key points.
    fn range(&self, n: usize) -> ticks::TickedRange {
        let t = if let Some(marks) = &self.marks {
            marks.iter().map(|m| m.0).collect()
        } else if self.clock.is_some() {
            self.clock_ticks(n).0
        } else if self.log {
            ticks::log(self.lo, self.hi, n)
        } else {
            ticks::linear(self.lo, self.hi, n as f64)
        };
        let pts: Vec<f64> = t.into_iter().map(|v| self.coord(v)).collect();
        ticks::TickedRange::new(self.coord(self.lo), self.coord(self.hi), pts)
    }
}

/// `(lo, hi)` finite and apart; `(0, 1)` when neither is finite. Never an infinite range
/// (an infinite axis makes plotters' tick search run forever: issue 18).
pub fn widen(lo: f64, hi: f64) -> (f64, f64) {
    match (lo.is_finite(), hi.is_finite()) {
        (true, true) if hi > lo => (lo, hi),
        (true, true) if lo > hi => (hi, lo),
        (true, true) => (lo - 0.5, hi + 0.5),
        (true, false) => (lo - 0.5, lo + 0.5),
        (false, true) => (hi - 0.5, hi + 0.5),
        _ => (0.0, 1.0),
    }
}

/// Cell edges from cell centres (monotonic): midpoints, the ends extended by half a cell.
pub fn edges(centres: &[f64]) -> Vec<f64> {
    match centres.len() {
        0 => vec![],
        1 => vec![centres[0] - 0.5, centres[0] + 0.5],
        n => {
            let mut e = Vec::with_capacity(n + 1);
            e.push(centres[0] - 0.5 * (centres[1] - centres[0]));
            e.extend(centres.windows(2).map(|w| 0.5 * (w[0] + w[1])));
            e.push(centres[n - 1] + 0.5 * (centres[n - 1] - centres[n - 2]));
            e
        }
    }
}

/// An isoline to draw on a panel: its level, label and style.
#[derive(Debug, Clone)]
pub struct Isoline {
    /// Field value of the line.
    pub level: f64,
    /// Text written on it.
    pub text: String,
    /// How it is drawn.
    pub style: IsolineStyle,
}

/// A field on a grid of cells, ready to draw.
#[derive(Debug, Clone)]
pub struct ImagePanel {
    /// Title over the panel.
    pub title: String,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// Cell edges along x (`nx + 1`, monotonic, in values, not coordinates).
    pub x_edges: Vec<f64>,
    /// Cell edges along y (`ny + 1`).
    pub y_edges: Vec<f64>,
    /// `values[iy * nx + ix]`; NaN for no value (grey).
    pub values: Vec<f64>,
    /// Colour scale.
    pub scale: ColourScale,
    /// Colour bar label, with the unit.
    pub bar_label: String,
    /// Isolines, drawn over the field.
    pub isolines: Vec<Isoline>,
}

impl ImagePanel {
    fn nx(&self) -> usize {
        self.x_edges.len().saturating_sub(1)
    }

    fn ny(&self) -> usize {
        self.y_edges.len().saturating_sub(1)
    }

    /// Draws the panel into `area`: the field on the left, its colour bar on the right.
    pub fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> super::result::DrawResult
    where
        DB::ErrorType: 'static,
    {
        self.draw_with_marks(area, &[])
    }

    /// [`ImagePanel::draw`], with `marks` — spans `(x0, x1, colour)` along x, in values —
    /// drawn as a band along the top of the field (day and night along a track).
    pub fn draw_with_marks<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        marks: &[(f64, f64, RGBColor)],
    ) -> super::result::DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (w, _) = area.dim_in_pixel();
        let (main, bar) = area.split_horizontally(w.saturating_sub(BAR_WIDTH));
        let (x, y) = (&self.x, &self.y);
        let mut chart = ChartBuilder::on(&main)
            .caption(&self.title, (FONT, 17))
            .margin(10)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(x.range(X_TICKS), y.range(Y_TICKS))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(x.label.as_str())
            .y_desc(y.label.as_str())
            .x_label_formatter(&|c: &f64| x.tick_label(*c))
            .y_label_formatter(&|c: &f64| y.tick_label(*c))
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 15))
            .draw()?;
        self.fill(chart.plotting_area())?;
        let plot = chart.plotting_area();
        let (cy0, cy1) = (y.coord(y.lo), y.coord(y.hi));
        let band = (cy1 - cy0) * 0.025;
        for &(x0, x1, colour) in marks {
            plot.draw(&Rectangle::new(
                [(x.coord(x0), cy1 - band), (x.coord(x1), cy1)],
                colour.filled(),
            ))?;
        }
        for iso in &self.isolines {
            let lines = self.isolines_in_pixels(iso.level, plot);
            draw_labelled(&plot.strip_coord_spec(), &lines, &iso.style, &iso.text)?;
        }
        // level with the plotting area: under the caption, over the x labels
        let bar = bar.margin(40, 58, 6, 0);
        draw_colour_bar(&bar, &self.scale, &self.bar_label)?;
        Ok(())
    }

    /// Each pixel of the plotting area shows the cell under its centre.
    fn fill<DB: DrawingBackend>(
        &self,
        plot: &DrawingArea<DB, Cartesian2d<ticks::TickedRange, ticks::TickedRange>>,
    ) -> super::result::DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (px, py) = plot.get_pixel_range();
        let (nx, ny) = (self.nx(), self.ny());
        if nx == 0 || ny == 0 || self.values.len() != nx * ny {
            return Ok(());
        }
        let (x, y) = (&self.x, &self.y);
        let (cx0, cx1) = (x.coord(x.lo), x.coord(x.hi));
        let (cy0, cy1) = (y.coord(y.lo), y.coord(y.hi));
        let (w, h) = ((px.end - px.start) as f64, (py.end - py.start) as f64);
        let cell = |e: &[f64], v: f64| {
            let ascending = e[e.len() - 1] >= e[0];
            let k = if ascending {
                e.partition_point(|&b| b <= v)
            } else {
                e.partition_point(|&b| b >= v)
            };
            (k >= 1 && k < e.len()).then(|| k - 1)
        };
        let columns: Vec<Option<usize>> = (px.start..px.end)
            .map(|p| {
                cell(
                    &self.x_edges,
                    x.value(cx0 + (cx1 - cx0) * ((p - px.start) as f64 + 0.5) / w),
                )
            })
            .collect();
        let backend_area = plot.strip_coord_spec();
        for (row, p) in (py.start..py.end).enumerate() {
            let v = y.value(cy1 - (cy1 - cy0) * (row as f64 + 0.5) / h);
            let Some(iy) = cell(&self.y_edges, v) else {
                continue;
            };
            for (col, ix) in columns.iter().enumerate() {
                if let Some(ix) = ix {
                    let c = self.scale.colour(self.values[iy * nx + ix]);
                    backend_area.draw_pixel((col as i32, p - py.start), &c)?;
                }
            }
        }
        Ok(())
    }

    /// The isolines at `level` through the cell centres, in pixels of `plot`.
    fn isolines_in_pixels<DB: DrawingBackend>(
        &self,
        level: f64,
        plot: &DrawingArea<DB, Cartesian2d<ticks::TickedRange, ticks::TickedRange>>,
    ) -> Vec<Vec<(i32, i32)>> {
        let (nx, ny) = (self.nx(), self.ny());
        if nx < 2 || ny < 2 || self.values.len() != nx * ny {
            return vec![];
        }
        let centres = |e: &[f64], a: &Axis| -> Vec<f64> {
            e.windows(2)
                .map(|w| a.value(0.5 * (a.coord(w[0]) + a.coord(w[1]))))
                .collect()
        };
        let (xc, yc) = (
            centres(&self.x_edges, &self.x),
            centres(&self.y_edges, &self.y),
        );
        let f: Vec<Vec<f64>> = (0..ny)
            .map(|j| self.values[j * nx..(j + 1) * nx].to_vec())
            .collect();
        let (ox, oy) = (
            plot.get_pixel_range().0.start,
            plot.get_pixel_range().1.start,
        );
        isolines(&xc, &yc, &f, level)
            .into_iter()
            .map(|l| {
                l.into_iter()
                    .map(|(a, b)| {
                        let (px, py) = plot.map_coordinate(&(self.x.coord(a), self.y.coord(b)));
                        (px - ox, py - oy)
                    })
                    .collect()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figures::plot::text::{encode_png, ensure_font};

    /// A synthetic S/N-like field (log colour, log x axis, labelled isolines), drawn:
    /// the PNG decodes to the right size and holds many colours.
    pub(crate) fn synthetic_png() -> Vec<u8> {
        ensure_font().unwrap();
        let (w, h) = (900u32, 560u32);
        let xs: Vec<f64> = (0..40).map(|i| 10f64.powf(i as f64 / 13.0)).collect();
        let ys: Vec<f64> = (0..30).map(|j| j as f64 * 0.5).collect();
        let values: Vec<f64> = ys
            .iter()
            .flat_map(|&z| xs.iter().map(move |&t| 30.0 * t.sqrt() * (-z / 5.0).exp()))
            .collect();
        let panel = ImagePanel {
            title: "S/N".into(),
            x: Axis::log("accumulation time (s)", 1.0, 1000.0),
            y: Axis::linear("altitude (km)", -0.25, 14.75),
            x_edges: edges(&xs),
            y_edges: edges(&ys),
            scale: ColourScale::over(values.iter().copied(), true, 4.0),
            values,
            bar_label: "S/N".into(),
            isolines: [(3.0, WHITE, BLACK), (10.0, BLACK, WHITE)]
                .into_iter()
                .map(|(l, c, halo)| Isoline {
                    level: l,
                    text: format!("S/N = {l}"),
                    style: IsolineStyle {
                        colour: c,
                        halo,
                        width: 2,
                    },
                })
                .collect(),
        };
        let mut rgb = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            root.fill(&WHITE).unwrap();
            panel.draw(&root).unwrap();
            root.present().unwrap();
        }
        encode_png(&rgb, w, h).unwrap()
    }

    #[test]
    fn a_panel_draws() {
        let png = synthetic_png();
        if let Ok(dir) = std::env::var("LIDARSIM_PLOT_DIR") {
            std::fs::write(std::path::Path::new(&dir).join("panel.png"), &png).unwrap();
        }
        assert!(png.len() > 10_000);
    }
}
