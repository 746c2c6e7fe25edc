//! `[instrument.detector]`: photon counting, analog recording or both, the dead time,
//! signal-induced noise and afterpulsing.

use serde::{Deserialize, Serialize};

/// The detector (docs/model.md §4b): a photon counter with dead time, an analog
/// recorder (photomultiplier gain, electronics, ADC), or both at once.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DetectorConfig {
    /// What the channel records: photon counts, ADC codes, or both from the same photons.
    #[serde(default)]
    pub mode: DetectionMode,
    /// Dead time τ of the photon counter, s (0 = none).
    #[serde(default)]
    pub dead_time_s: f64,
    /// `"nonparalyzable"` or `"paralyzable"`.
    #[serde(default)]
    pub dead_time_model: DeadTimeModel,
    /// Detector pixels sharing the channel's photons evenly, each with its own dead time
    /// (ICESat-2's 16 per strong beam); absent = 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pixels: Option<u32>,
    /// Mean gain G of the photomultiplier, electrons per photoelectron (analog).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain: Option<f64>,
    /// Excess noise factor F = 1 + Var(g)/G² of the gain (analog).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub excess_noise_factor: Option<f64>,
    /// Load (transimpedance) resistance the anode current flows through, Ω (analog).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_resistance_ohm: Option<f64>,
    /// −3 dB bandwidth of the electronics' first-order low-pass, Hz; 0 = no smearing (analog).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bandwidth_hz: Option<f64>,
    /// Rms Gaussian electronic noise of one sample (one bin, one shot), V (analog).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub electronic_noise_v: Option<f64>,
    /// Baseline offset added before the ADC, V (analog).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset_v: Option<f64>,
    /// ADC resolution, bits (analog).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adc_bits: Option<u32>,
    /// ADC input range (full scale), V (analog).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adc_range_v: Option<f64>,
    /// Signal-induced noise of the photomultiplier; absent = none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signal_induced_noise: Option<SignalInducedNoiseConfig>,
    /// Afterpulsing of the photon counter; absent = none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub afterpulsing: Option<AfterpulsingConfig>,
}

/// Afterpulsing of a photon counter (`src/detector/afterpulse.rs`, docs/model.md §4b):
/// a probability per recorded count and a delay law, a sum of exponentials.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AfterpulsingConfig {
    /// Probability p of an afterpulse per recorded count.
    pub probability: f64,
    /// Mean delays τ_i of the exponential components, s.
    pub time_constants_s: Vec<f64>,
    /// Relative weights a_i of the components (normalized); absent = equal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weights: Option<Vec<f64>>,
}

impl AfterpulsingConfig {
    /// The components' weights as given, or equal ones.
    pub fn weights(&self) -> Vec<f64> {
        self.weights
            .clone()
            .unwrap_or_else(|| vec![1.0; self.time_constants_s.len()])
    }
}

/// Signal-induced noise: spurious counts after a strong return, decaying with the delay
/// (`src/detector/induced.rs`, docs/model.md §4b).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
pub enum SignalInducedNoiseConfig {
    /// Rate ∝ `e^{−t/τ}`.
    Exponential {
        /// Expected induced counts per signal photoelectron (all delays).
        fraction: f64,
        /// Decay time τ, s.
        time_constant_s: f64,
    },
    /// Rate ∝ `(1 + t/τ)^{−p}`.
    PowerLaw {
        /// Expected induced counts per signal photoelectron (all delays).
        fraction: f64,
        /// Time scale τ, s.
        time_constant_s: f64,
        /// Exponent p > 1.
        exponent: f64,
    },
}

/// What a channel's detector records (docs/model.md §4b).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DetectionMode {
    /// Photon counts, through the dead time (default).
    #[default]
    PhotonCounting,
    /// The photomultiplier's anode signal through the electronics and an ADC: ADC codes.
    Analog,
    /// Both at once from the same photons (a transient recorder): the channel becomes two
    /// file channels, `<name>_an` and `<name>_pc`.
    Both,
}

impl DetectionMode {
    /// The name in files and configs.
    pub fn name(self) -> &'static str {
        match self {
            DetectionMode::PhotonCounting => "photon_counting",
            DetectionMode::Analog => "analog",
            DetectionMode::Both => "both",
        }
    }
}

/// How the dead period behaves (the detector's law, `src/detector/dead_time/`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DeadTimeModel {
    /// Photons in the dead period are lost and do not extend it (default).
    #[default]
    Nonparalyzable,
    /// Every photon restarts the dead period.
    Paralyzable,
}
