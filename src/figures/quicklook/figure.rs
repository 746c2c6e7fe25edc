//! What the quicklook shows: its grid, each channel's calibration, how a profile's
//! counts become attenuated backscatter on the grid, and the time or distance axis.

use crate::figures::plot::panel::{Clock, widen};

use super::axis::XAxis;
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
    /// What the x axis shows (`--x-axis`).
    pub x_axis: XAxis,
    /// Cells whose bins mostly have an S/N below this are grey (`--mask-snr X`).
    pub mask_snr: Option<f64>,
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
    /// The title's line: instrument, date and times, place ([`super::title::title_line`]).
    pub title: String,
    /// The file's name.
    pub file: String,
    /// How the background was taken.
    pub background_note: String,
    /// Label of the horizontal axis, with its unit.
    pub x_label: String,
    /// A time axis with a known start: labelled by the UTC clock.
    pub x_clock: Option<Clock>,
    /// A latitude axis' ticks: `(x, label)`, x in the grid's unit.
    pub x_marks: Option<Vec<(f64, String)>>,
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
    /// With `--mask-snr X`: X, and per cell the share (by weight) of the signal's bins
    /// whose S/N ([`snr`]) is below X.
    pub mask: Option<(f64, Grid)>,
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

/// The S/N mask of one channel's profiles: the threshold, the grid of shares below it,
/// and the record's baseline per shot and bin (an analog channel's offset in codes
/// times the native bins merged; 0 for a photon counter).
pub struct Mask<'a> {
    /// `--mask-snr X`.
    pub threshold: f64,
    /// Where the shares go.
    pub grid: &'a mut Grid,
    /// The baseline per shot and bin, in the record's units.
    pub offset: f64,
}

/// The S/N of a bin estimated from its counts alone: `n` recorded over `shots` shots,
/// `b` the background per shot (from the profile's signal-free bins, as the signal),
/// `offset` the record's baseline per shot and `g` its codes per photoelectron (1 and 0
/// for a photon counter): the signal `S = (n − M·b)/g` photoelectrons over the Poisson
/// noise of all the photoelectrons recorded, `√((n − M·offset)/g)` (at least one).
pub fn snr(n: f64, shots: f64, b: f64, offset: f64, g: f64) -> f64 {
    let signal = (n - shots * b) / g;
    let total = ((n - shots * offset) / g).max(1.0);
    signal / total.sqrt()
}

/// Adds one profile of one channel to `grid`: `(N/M − B)/(C·w·E/E₀)` per bin, each bin
/// over its rows (`bin_rows`), the profile over `columns`; `energy_factor` is the
/// profile's `E/E₀` at the channel's laser line ([`crate::output::raw_file::read::energy_factors`]).
/// With `mask`, each bin's 1 (S/N below the threshold) or 0 goes to the mask's grid.
#[allow(clippy::too_many_arguments)]
pub fn add_profile(
    mask: Option<Mask>,
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
    if let Some(m) = mask {
        let g = cal.codes_per_photoelectron;
        let below = counts.iter().zip(range_weight).map(|(&n, &w)| {
            if w > 0.0 {
                let s = snr(n as f64, shots, b, m.offset, g);
                if s < m.threshold { 1.0 } else { 0.0 }
            } else {
                f64::NAN
            }
        });
        m.grid.add_profile(columns, bin_rows, below);
    }
}
