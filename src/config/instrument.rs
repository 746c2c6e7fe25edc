//! `[instrument]`: the laser, the telescope and receiver, the polarization channel, the
//! overlap and the energy drift (the detector is `detector.rs`).

use serde::{Deserialize, Serialize};

use super::defaults::one;
use super::detector::DetectorConfig;

/// Instrument parameters (paper Eq. 2–3 symbols in brackets).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InstrumentConfig {
    /// Laser wavelength λ0, nm.
    pub wavelength_nm: f64,
    /// Pulse energy E0, J.
    pub pulse_energy_j: f64,
    /// Relative rms shot-to-shot pulse-energy jitter (0 = none; at most 0.2).
    #[serde(default)]
    pub pulse_energy_jitter: f64,
    /// Laser pulse duration, full width at half maximum, s: the surface echo's width in
    /// the photon file's event times (`simulate --photons`, docs/photons.md); absent =
    /// a pulse far shorter than a bin (the echo at the surface range).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pulse_fwhm_s: Option<f64>,
    /// Pulse repetition frequency fL, Hz.
    pub rep_rate_hz: f64,
    /// Effective telescope collecting area A, m².
    pub telescope_area_m2: f64,
    /// Overall optical transmission efficiency K (signal path only).
    #[serde(default = "one")]
    pub optical_efficiency: f64,
    /// Receiving optics efficiency TR.
    pub receiver_efficiency: f64,
    /// Spectral filter transmission TF.
    pub filter_transmission: f64,
    /// Detector quantum efficiency Qλ.
    pub quantum_efficiency: f64,
    /// Receiver full field-of-view angle θ, rad.
    pub fov_rad: f64,
    /// The laser beam's divergence as the 1/e **half**-width of its Gaussian angular
    /// profile, rad (Hogan 2008's ρ_t); what the multiple-scattering models need.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beam_divergence_rad: Option<f64>,
    /// Filter width Δλ, nm.
    pub filter_width_nm: f64,
    /// Detector dark-count rate, counts s⁻¹.
    pub dark_count_rate_hz: f64,
    /// Time bin width Δt, s (2 µs = 300 m in the paper).
    #[serde(default = "default_bin_width_s")]
    pub bin_width_s: f64,
    /// Which polarization the receiver channel sees (`polarization` is accepted too).
    #[serde(default, alias = "polarization")]
    pub channel: Channel,
    /// Fraction of the other polarization's light a polarization channel sees (docs/model.md §4c).
    #[serde(default)]
    pub crosstalk: f64,
    /// Diattenuation D of the receiving optics in front of the calibrator: `(1+D)` of the
    /// light polarized parallel to the laser passes, `(1−D)` of the perpendicular
    /// (`src/receiver/polarization.rs`).
    #[serde(default)]
    pub diattenuation: f64,
    /// Rotation of the received light's polarization plane in front of the polarizing
    /// beam splitter, degrees: 0 to measure, ±45 for the Δ90 calibration runs.
    #[serde(default)]
    pub receiver_rotation_deg: f64,
    /// Slow drift of the emitted pulse energy (the energy monitor reports it); absent = none.
    #[serde(default)]
    pub energy_drift: Option<EnergyDriftConfig>,
    /// Receiver channels, `[[instrument.channels]]`: each a table of `name`, `kind`,
    /// `polarization`, `crosstalk` and any instrument key it overrides (expanded into one
    /// config per channel by the receiver, `src/receiver/mod.rs`); empty = one channel.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<toml::Table>,
    /// Overlap function η(r); absent = full overlap everywhere.
    #[serde(default)]
    pub overlap: Option<OverlapConfig>,
    /// The detector; absent = an ideal linear photon counter.
    #[serde(default)]
    pub detector: Option<DetectorConfig>,
}

/// A slow drift of the emitted pulse energy, as a relative factor of time `t` since the
/// first shot (docs/model.md §4d, energy monitor).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(tag = "model", rename_all = "lowercase", deny_unknown_fields)]
pub enum EnergyDriftConfig {
    /// `1 + per_hour·t/3600 s`.
    Linear {
        /// Relative change per hour (e.g. -0.01 = 1 % less energy after an hour).
        per_hour: f64,
    },
    /// `1 + amplitude·sin(2π·t/period_s + phase)`.
    Periodic {
        /// Relative amplitude (at most 0.5).
        amplitude: f64,
        /// Period, s (an orbit: ~5,900 s).
        period_s: f64,
        /// Phase at the first shot, degrees.
        #[serde(default)]
        phase_deg: f64,
    },
}

/// The wavelengths the model covers, nm: a laser's, and the line a channel detects.
pub const WAVELENGTH_RANGE_NM: (f64, f64) = (200.0, 4000.0);

/// Receiver channel with respect to the laser's linear polarization (model.md §4).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Channel {
    /// One channel that sees the total backscatter (default).
    #[default]
    Total,
    /// Co-polarized channel: β/(1+δ).
    Parallel,
    /// Cross-polarized channel: β·δ/(1+δ).
    Perpendicular,
}

impl Channel {
    /// The name of the polarization: `total`, `parallel` or `perpendicular`.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Total => "total",
            Channel::Parallel => "parallel",
            Channel::Perpendicular => "perpendicular",
        }
    }
}

/// Overlap function models.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
pub enum OverlapConfig {
    /// η = 1 everywhere (the same as no `overlap` key).
    None,
    /// η = 0 below `full_overlap_m`, 1 beyond.
    FullRange {
        /// Range where overlap becomes complete, m.
        full_overlap_m: f64,
    },
    /// Geometric overlap of a biaxial lidar: fraction of the laser spot inside the
    /// receiver field of view, two circles in a plane at range r.
    Geometric {
        /// Laser beam radius at the exit, m.
        beam_radius_m: f64,
        /// Laser beam full divergence angle, rad.
        beam_divergence_rad: f64,
        /// Distance between the laser and telescope axes, m (0 = coaxial).
        axis_offset_m: f64,
    },
}

fn default_bin_width_s() -> f64 {
    2e-6
}
