//! Nice ticks: 1-2-5 steps on linear axes, powers of ten on logarithmic ones, and
//! numbers written as a person writes them (`250`, `0.05`, `1e-7`), never `2.500e2`.

use std::ops::Range;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;

/// A plotters axis range whose ticks are given (ours, not plotters' own choice).
#[derive(Clone)]
pub struct TickedRange {
    inner: RangedCoordf64,
    ticks: Vec<f64>,
}

impl TickedRange {
    /// The range `lo..hi` with tick marks at `ticks` (both in the axis' coordinate).
    pub fn new(lo: f64, hi: f64, ticks: Vec<f64>) -> Self {
        TickedRange {
            inner: (lo..hi).into(),
            ticks,
        }
    }
}

impl Ranged for TickedRange {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        // every k-th tick when there are more than plotters asks for
        let k = self
            .ticks
            .len()
            .div_ceil(hint.max_num_points().max(1))
            .max(1);
        self.ticks.iter().copied().step_by(k).collect()
    }

    fn range(&self) -> Range<f64> {
        self.inner.range()
    }
}

/// The 1-2-5 × 10^k step giving the number of intervals over `span` nearest `target`.
pub fn nice_step(span: f64, target: f64) -> f64 {
    if !(span > 0.0 && span.is_finite() && target > 0.0) {
        return 1.0;
    }
    let mag = 10f64.powf((span / target).log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .map(|m| m * mag)
        .into_iter()
        .min_by(|a, b| ((span / a - target).abs()).total_cmp(&(span / b - target).abs()))
        .unwrap_or(mag)
}

/// Ticks on a linear axis from `lo` to `hi`: the multiples of a 1-2-5 step inside it,
/// about `target` intervals.
pub fn linear(lo: f64, hi: f64, target: f64) -> Vec<f64> {
    let (lo, hi) = (lo.min(hi), lo.max(hi));
    let step = nice_step(hi - lo, target);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    if last < first || last - first > 1000 {
        return vec![];
    }
    (first..=last)
        .map(|k| {
            // rounded to the step's last digit: 0.6, not 0.6000000000000001
            let scale = 10f64.powi((-step.log10().floor()) as i32 + 1);
            let v = (k as f64 * step * scale).round() / scale;
            if v.abs() < step * 1e-9 { 0.0 } else { v }
        })
        .collect()
}

/// Ticks on a logarithmic axis from `lo` to `hi` (> 0): every power of ten inside it
/// (every second, third… when there are more than `max_labels`), with 2 and 5 times
/// them when it spans less than two decades.
pub fn log(lo: f64, hi: f64, max_labels: usize) -> Vec<f64> {
    let (lo, hi) = (lo.min(hi), lo.max(hi));
    if !(lo > 0.0 && hi.is_finite()) {
        return vec![];
    }
    let (d0, d1) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
    let decades = (hi / lo).log10();
    let mut out = Vec::new();
    if decades < 2.0 {
        for d in (d0 - 1)..=(d1 + 1) {
            for m in [1.0, 2.0, 5.0] {
                let v = m * 10f64.powi(d);
                if v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9) {
                    out.push(v);
                }
            }
        }
    } else {
        let every = (((d1 - d0 + 1) as usize).div_ceil(max_labels.max(1))).max(1) as i32;
        out = (d0..=d1)
            .filter(|d| d.rem_euclid(every) == 0)
            .map(|d| 10f64.powi(d))
            .collect();
    }
    out
}

/// Steps of a clock axis, s: seconds, minutes and hours a person counts in.
const CLOCK_STEPS_S: [f64; 17] = [
    1.0, 2.0, 5.0, 10.0, 15.0, 30.0, 60.0, 120.0, 300.0, 600.0, 900.0, 1800.0, 3600.0, 7200.0,
    10800.0, 21600.0, 43200.0,
];

/// Ticks on a clock axis from `lo` to `hi` (Unix seconds, UTC): the multiples of the step
/// of [`CLOCK_STEPS_S`] (whole days beyond them) giving the number of intervals nearest
/// `target`, and that step.
pub fn clock(lo: f64, hi: f64, target: f64) -> (Vec<f64>, f64) {
    let (lo, hi) = (lo.min(hi), lo.max(hi));
    if !(lo.is_finite() && hi.is_finite() && hi > lo && target > 0.0) {
        return (vec![], 1.0);
    }
    let span = hi - lo;
    let days = 86400.0 * nice_step(span / 86400.0, target).max(1.0);
    let step = CLOCK_STEPS_S
        .into_iter()
        .chain([days])
        .min_by(|a, b| ((span / a - target).abs()).total_cmp(&(span / b - target).abs()))
        .unwrap_or(days);
    let (first, last) = ((lo / step).ceil(), (hi / step).floor());
    if !(last >= first && last - first <= 1000.0) {
        return (vec![], step);
    }
    (
        (first as i64..=last as i64)
            .map(|k| k as f64 * step)
            .collect(),
        step,
    )
}

/// A UTC time of day as a clock axis writes it: `HH:MM`, or `HH:MM:SS` when the ticks
/// are less than a minute apart (`step_s`).
pub fn clock_label(unix_s: f64, step_s: f64) -> String {
    let t = unix_s.round().rem_euclid(86400.0) as u64;
    let (h, m, s) = (t / 3600, t / 60 % 60, t % 60);
    if step_s < 60.0 {
        format!("{h:02}:{m:02}:{s:02}")
    } else {
        format!("{h:02}:{m:02}")
    }
}

/// A number as a person writes it on an axis: plain decimals from 1e-3 to 1e5 with no
/// trailing zeros (`0.05`, `250`, `1.5`), else a power of ten (`1e-7`, `3e8`).
pub fn format(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let s = format!("{v:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        let e = a.log10().floor() as i32;
        let m = v / 10f64.powi(e);
        let m = (m * 1000.0).round() / 1000.0;
        if (m.abs() - 1.0).abs() < 1e-9 {
            format!("{}1e{e}", if v < 0.0 { "-" } else { "" })
        } else {
            format!("{}e{e}", format(m))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_ticks_are_round_multiples() {
        assert_eq!(linear(0.0, 10.0, 5.0), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!(linear(0.13, 0.96, 4.0), vec![0.2, 0.4, 0.6, 0.8]);
        assert_eq!(linear(-1.0, 1.0, 4.0), vec![-1.0, -0.5, 0.0, 0.5, 1.0]);
        assert!(linear(1.0, 1.0, 5.0).len() <= 1);
    }

    #[test]
    fn log_ticks_are_powers_of_ten() {
        assert_eq!(log(0.5, 2000.0, 10), vec![1.0, 10.0, 100.0, 1000.0]);
        assert_eq!(log(1e-12, 1.0, 4), vec![1e-12, 1e-8, 1e-4, 1.0]);
        assert_eq!(log(1.5, 40.0, 10), vec![2.0, 5.0, 10.0, 20.0]);
        assert!(log(0.0, 1.0, 10).is_empty());
    }

    #[test]
    fn clock_ticks_fall_on_whole_minutes_and_read_as_utc() {
        // 2000-01-01 21:03:20 to 21:08:20 UTC: a tick a minute from 21:04
        let t0 = 946_760_600.0;
        let (t, step) = clock(t0, t0 + 300.0, 5.0);
        assert_eq!(step, 60.0);
        assert_eq!(t.len(), 5);
        assert_eq!(clock_label(t[0], step), "21:04");
        assert_eq!(clock_label(t[4], step), "21:08");
        assert_eq!(clock_label(t0, 30.0), "21:03:20");
        // eight hours: every 2 h
        let (t, step) = clock(0.0, 8.0 * 3600.0, 5.0);
        assert_eq!((step, t.len()), (7200.0, 5));
        assert_eq!(clock_label(t[4], step), "08:00");
        assert!(clock(1.0, f64::INFINITY, 5.0).0.is_empty());
    }

    #[test]
    fn numbers_read_as_written() {
        assert_eq!(format(250.0), "250");
        assert_eq!(format(0.05), "0.05");
        assert_eq!(format(1.5), "1.5");
        assert_eq!(format(1e-7), "1e-7");
        assert_eq!(format(3e8), "3e8");
        assert_eq!(format(2.5e-6), "2.5e-6");
        assert_eq!(format(-0.001), "-0.001");
        assert_eq!(format(0.0), "0");
    }
}
