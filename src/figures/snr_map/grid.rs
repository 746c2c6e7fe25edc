//! The S/N map sorted by altitude, on log10(TC), with its mapping to the figure's pixels.

use super::super::plot::isolines::isolines;
use super::super::plot::ticks;
use super::layout::{PLOT_B, PLOT_L, PLOT_R, PLOT_T};
use super::map::{SNR_COLOUR_CAP, SNR_COLOUR_MAX, SNR_COLOUR_MIN, SnrMap, check};

/// The map sorted by ascending altitude, with x = log10(TC), and its mapping to
/// the figure's pixels.
pub(super) struct Grid {
    /// log10(TC), strictly increasing.
    pub(super) x: Vec<f64>,
    /// Altitude (km), strictly increasing.
    pub(super) y: Vec<f64>,
    /// log10(S/N) floored at the colour-scale minimum, `field[iy][ix]`: the field
    /// that is both coloured and contoured, so colours and contour lines agree.
    pub(super) field: Vec<Vec<f64>>,
    /// First and last TC (s).
    pub(super) tc: (f64, f64),
    /// Upper end of the colour scale.
    pub(super) vmax: f64,
    /// Smallest and largest S/N in the map.
    pub(super) min: f64,
    pub(super) max: f64,
}

impl Grid {
    pub(super) fn new(map: &SnrMap) -> std::result::Result<Self, String> {
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
    pub(super) fn contours(&self, level: f64) -> Vec<Vec<(f64, f64)>> {
        isolines(&self.x, &self.y, &self.field, level.log10())
    }

    /// Pixel column of log10(TC) = `lx`.
    pub(super) fn px(&self, lx: f64) -> f64 {
        let (a, b) = ends(&self.x);
        PLOT_L as f64 + (lx - a) / (b - a) * (PLOT_R - PLOT_L) as f64
    }

    /// Pixel row of altitude `z` (km).
    pub(super) fn py(&self, z: f64) -> f64 {
        let (a, b) = ends(&self.y);
        PLOT_B as f64 - (z - a) / (b - a) * (PLOT_B - PLOT_T) as f64
    }

    /// Where log10(S/N) = `lv` falls on the colour scale, 0 (bottom) to 1 (top).
    pub(super) fn scale(&self, lv: f64) -> f64 {
        let (a, b) = (SNR_COLOUR_MIN.log10(), self.vmax.log10());
        (lv - a) / (b - a)
    }

    /// Pixel row of S/N `v` on the colour bar.
    pub(super) fn bar_y(&self, v: f64) -> f64 {
        PLOT_B as f64 - self.scale(v.log10()) * (PLOT_B - PLOT_T) as f64
    }

    /// Labelled TC ticks (s): powers of ten (1-2-5 under two decades).
    pub(super) fn tc_ticks(&self) -> Vec<f64> {
        ticks::log(self.tc.0, self.tc.1, 10)
    }

    /// Labelled altitude ticks (km): a 1-2-5 step, about 7 intervals.
    pub(super) fn z_ticks(&self) -> Vec<f64> {
        let (a, b) = ends(&self.y);
        ticks::linear(a, b, 7.0)
    }
}

/// First and last element.
pub(super) fn ends(v: &[f64]) -> (f64, f64) {
    (v[0], v[v.len() - 1])
}
