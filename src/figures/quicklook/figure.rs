//! What the quicklook shows: its grid, each channel's calibration, how a profile's
//! counts become attenuated backscatter on the grid, and the time or distance axis.

use crate::figures::plot::panel::{Clock, widen};

use super::grid::Grid;

/// The figure's grid: pixel columns and rows of one panel's field.
pub const COLUMNS: usize = 1150;
/// See [`COLUMNS`].
pub const ROWS: usize = 330;
/// The highest altitude shown, km: above it a lidar sees only the background and the
/// air's faint return (a window that ends lower ends the figure there).
pub const TOP_KM: f64 = 40.0;
/// The altitudes a quicklook shows (`quicklook --altitude-range LO,HI`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct View {
    /// The altitude range drawn, km above sea level, `(low, high)`; `None`: from the
    /// lowest bin after the pre-trigger bins to the window's top or [`TOP_KM`].
    pub altitude_range_km: Option<(f64, f64)>,
}

impl View {
    /// The vertical span of the figure, km, for bins whose edges reach from `lowest_km`
    /// to `highest_km` (the pre-trigger bins left out).
    pub fn z_span_km(&self, lowest_km: f64, highest_km: f64) -> (f64, f64) {
        match self.altitude_range_km {
            Some(range) => range,
            None => widen(lowest_km, highest_km.min(TOP_KM)),
        }
    }
}

/// Profiles read at once.
pub(super) const BLOCK_PROFILES: usize = 256;

/// What the figure shows, on its grid.
#[derive(Debug, Clone)]
pub struct Quicklook {
    /// The file and channel.
    pub title: String,
    /// How the background was taken.
    pub background_note: String,
    /// Label of the horizontal axis, with its unit.
    pub x_label: String,
    /// A time axis with a known start: labelled by the UTC clock.
    pub x_clock: Option<Clock>,
    /// The estimated attenuated backscatter, [`Grid::means`] layout.
    pub signal: Grid,
    /// The channel's name.
    pub channel: String,
    /// The ∥/⊥ pair's calibrated signals, when the file has one.
    pub pair: Option<(Grid, Grid, String)>,
    /// The truth's attenuated backscatter, with `--truth`.
    pub truth: Option<Grid>,
    /// Day (true) and night along x: `(x0, x1, day)`.
    pub day: Vec<(f64, f64, bool)>,
}

/// One channel's calibration: counts per shot to attenuated backscatter.
#[derive(Debug, Clone, Copy)]
pub struct Calibration {
    /// The lidar constant `C`, m² sr (at the channel's nominal pulse energy).
    pub lidar_constant: f64,
    /// Codes per photoelectron of an analog channel, 1 for a photon counter.
    pub codes_per_photoelectron: f64,
    /// The baseline of an analog channel's record in ADC codes per shot,
    /// `analog_offset/adc_volts_per_count`; 0 for a photon counter.
    pub offset_codes: f64,
}

impl Calibration {
    /// The record's mean per shot and native bin where only the sky background and the
    /// dark current reach the detector at `photons` (counts per shot and bin): the
    /// offset plus the codes of those photoelectrons (a constant is its own low-pass).
    pub fn record_of(&self, photons: f64) -> f64 {
        self.offset_codes + self.codes_per_photoelectron * photons
    }
}

/// A profile's background per shot and bin.
pub enum Background<'a> {
    /// The mean of these bins' counts per shot.
    Bins(&'a [usize]),
    /// Known.
    Value(f64),
}

/// Adds one profile of one channel to `grid`: `(N/M − B)/(C·w·E/E₀)` per bin, each bin
/// over its rows (`bin_rows`), the profile over `columns`; `energy_factor` is the
/// profile's `E/E₀` at the channel's laser line ([`crate::output::raw_file::read::energy_factors`]).
#[allow(clippy::too_many_arguments)]
pub fn add_profile(
    grid: &mut Grid,
    columns: &[(usize, f64)],
    bin_rows: &[Vec<(usize, f64)>],
    counts: ndarray::ArrayView1<'_, u64>,
    shots: f64,
    background: &Background,
    range_weight: &[f64],
    cal: &Calibration,
    energy_factor: f64,
) {
    if columns.is_empty() || shots.is_nan() || shots <= 0.0 {
        return;
    }
    let per_shot = 1.0 / shots;
    let b = match background {
        Background::Bins(bins) if !bins.is_empty() => {
            bins.iter().map(|&i| counts[i] as f64).sum::<f64>() * per_shot / bins.len() as f64
        }
        Background::Bins(_) => 0.0,
        Background::Value(v) => *v,
    };
    let energy = if energy_factor > 0.0 {
        energy_factor
    } else {
        1.0
    };
    let scale = 1.0 / (cal.lidar_constant * cal.codes_per_photoelectron * energy);
    if !scale.is_finite() {
        return;
    }
    let values = counts.iter().zip(range_weight).map(|(&n, &w)| {
        if w > 0.0 {
            (n as f64 * per_shot - b) * scale / w
        } else {
            f64::NAN
        }
    });
    grid.add_profile(columns, bin_rows, values);
}

/// The horizontal axis from the file's profile coordinate: its values scaled to the
/// shown unit, the label, and for a time axis whose start is known (`start_unix_s`, the
/// Unix time of `time` 0) the UTC clock that labels it, with the date of `first_s` (the
/// first profile's time) in the label.
pub fn x_axis(
    along_track: bool,
    span: f64,
    start_unix_s: Option<f64>,
    first_s: f64,
) -> (f64, String, Option<Clock>) {
    if along_track {
        return (1e-3, "along-track distance (km)".into(), None);
    }
    if let Some(date) = start_unix_s.and_then(|t0| utc_date(t0 + first_s)) {
        let clock = Clock {
            origin_unix_s: start_unix_s.unwrap_or(0.0),
            seconds_per_unit: 1.0,
        };
        return (1.0, format!("time (UTC, {date})"), Some(clock));
    }
    let (scale, label) = x_scale(span);
    (scale, label, None)
}

/// The UTC date `YYYY-MM-DD` of Unix time `t_s` (None outside years 1970–9999).
fn utc_date(t_s: f64) -> Option<String> {
    if !(0.0..2.5e11).contains(&t_s) {
        return None;
    }
    let t = std::time::UNIX_EPOCH.checked_add(std::time::Duration::from_secs_f64(t_s))?;
    let text = humantime::format_rfc3339_seconds(t).to_string();
    text.get(..10).map(str::to_string)
}

/// The unit of a time axis of `span` seconds without a known start: its scale and label.
fn x_scale(span: f64) -> (f64, String) {
    if span < 600.0 {
        (1.0, "time since start (s)".into())
    } else if span < 6.0 * 3600.0 {
        (1.0 / 60.0, "time since start (min)".into())
    } else {
        (1.0 / 3600.0, "time since start (h)".into())
    }
}
