//! Colour scales: values to viridis (`colorous`), linear or logarithmic, and the colour
//! bar that shows one with its ticks and unit.

use plotters::prelude::*;

use super::text::FONT;
use super::ticks;

/// Colour of a missing value (NaN, or ≤ 0 on a log scale).
pub const MISSING: RGBColor = RGBColor(200, 200, 200);

/// Maps values from `lo` to `hi` (clamped beyond) on to viridis, dark to yellow.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColourScale {
    /// Value of the darkest colour.
    pub lo: f64,
    /// Value of the brightest colour.
    pub hi: f64,
    /// Logarithmic (both ends > 0).
    pub log: bool,
}

impl ColourScale {
    /// A scale over the finite values of `v`: logarithmic when they are all positive
    /// and span more than two decades (or `force_log`), its lower end then at most
    /// `max_decades` below the top.
    pub fn over(v: impl Iterator<Item = f64> + Clone, force_log: bool, max_decades: f64) -> Self {
        let finite = v.filter(|x| x.is_finite());
        let positive = finite.clone().filter(|&x| x > 0.0);
        let lo = finite.clone().fold(f64::INFINITY, f64::min);
        let hi = finite.clone().fold(f64::NEG_INFINITY, f64::max);
        let lo_pos = positive.clone().fold(f64::INFINITY, f64::min);
        if !(hi.is_finite() && lo.is_finite()) {
            return ColourScale {
                lo: 0.0,
                hi: 1.0,
                log: false,
            };
        }
        let spans = lo > 0.0 && hi / lo > 100.0;
        if (force_log || spans) && hi > 0.0 && lo_pos.is_finite() {
            let lo = lo_pos.max(hi * 10f64.powf(-max_decades));
            let (lo, hi) = if hi > lo {
                (lo, hi)
            } else {
                (hi / 10.0, hi * 10.0)
            };
            return ColourScale { lo, hi, log: true };
        }
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo - 0.5, hi + 0.5)
        };
        ColourScale { lo, hi, log: false }
    }

    /// Where `v` falls, 0 at `lo` to 1 at `hi` (clamped); `None` for a missing value.
    pub fn fraction(&self, v: f64) -> Option<f64> {
        let t = if self.log {
            if v.is_nan() || v <= 0.0 {
                return None;
            }
            (v / self.lo).log10() / (self.hi / self.lo).log10()
        } else {
            (v - self.lo) / (self.hi - self.lo)
        };
        t.is_finite().then(|| t.clamp(0.0, 1.0)).or(if v.is_nan() {
            None
        } else {
            Some(if t > 0.0 { 1.0 } else { 0.0 })
        })
    }

    /// The colour of `v`.
    pub fn colour(&self, v: f64) -> RGBColor {
        self.fraction(v).map_or(MISSING, viridis)
    }

    /// The scale's coordinate of `v` on its bar (log10 on a log scale).
    fn coord(&self, v: f64) -> f64 {
        if self.log { v.log10() } else { v }
    }

    /// The ticks of the scale (at most `n` labels on a log scale).
    pub fn ticks(&self, n: usize) -> Vec<f64> {
        if self.log {
            ticks::log(self.lo, self.hi, n)
        } else {
            ticks::linear(self.lo, self.hi, n as f64)
        }
    }

    /// The bar's axis in the scale's coordinate with its ticks as key points.
    pub fn axis(&self, n: usize) -> ticks::TickedRange {
        let pts: Vec<f64> = self.ticks(n).into_iter().map(|v| self.coord(v)).collect();
        ticks::TickedRange::new(self.coord(self.lo), self.coord(self.hi), pts)
    }
}

/// viridis at `t` ∈ [0, 1].
pub fn viridis(t: f64) -> RGBColor {
    let c = colorous::VIRIDIS.eval_continuous(if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    });
    RGBColor(c.r, c.g, c.b)
}

/// Draws the colour bar of `scale` filling `area` (a narrow upright strip), labelled
/// `label` (with its unit) along its side and with the scale's ticks.
pub fn draw_colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    scale: &ColourScale,
    label: &str,
) -> super::result::DrawResult
where
    DB::ErrorType: 'static,
{
    let log = scale.log;
    let (w, _) = area.dim_in_pixel();
    let mut chart = ChartBuilder::on(area)
        .margin_right(2)
        .y_label_area_size(0)
        .right_y_label_area_size(w.saturating_sub(24).max(40))
        .build_cartesian_2d(0.0..1.0, scale.axis(8))?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(label)
        .y_label_formatter(&|v: &f64| ticks::format(if log { 10f64.powf(*v) } else { *v }))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .draw()?;
    let (c0, c1) = (scale.coord(scale.lo), scale.coord(scale.hi));
    let n = 200;
    chart.draw_series((0..n).map(|k| {
        let a = c0 + (c1 - c0) * k as f64 / n as f64;
        let b = c0 + (c1 - c0) * (k + 1) as f64 / n as f64;
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            viridis((k as f64 + 0.5) / n as f64).filled(),
        )
    }))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_scale_when_values_span_decades() {
        let s = ColourScale::over([1e-3, 1.0, 10.0].into_iter(), false, 6.0);
        assert!(s.log && s.lo == 1e-3 && s.hi == 10.0);
        assert_eq!(s.fraction(1e-3), Some(0.0));
        assert!((s.fraction(0.1).unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(s.fraction(0.0), None);
        assert_eq!(s.fraction(f64::NAN), None);
        let lin = ColourScale::over([1.0, 2.0, 3.0].into_iter(), false, 6.0);
        assert!(!lin.log && lin.fraction(2.0) == Some(0.5));
        // the log scale's floor: at most `max_decades` below the top
        let deep = ColourScale::over([1e-20, 1.0].into_iter(), true, 6.0);
        assert_eq!(deep.lo, 1e-6);
    }

    #[test]
    fn viridis_runs_dark_to_yellow() {
        let (a, b) = (viridis(0.0), viridis(1.0));
        assert!(a.0 < 100 && a.2 > 60 && b.0 > 230 && b.1 > 200 && b.2 < 60);
    }
}
