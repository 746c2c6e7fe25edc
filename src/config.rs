//! Scenario configuration: TOML text with the keys of `docs/config.md`,
//! `--set KEY=VALUE` dotted overrides, typed sections and their own checks.
//!
//! Parsing happens in three steps ([`parse`]): the text is parsed into a TOML table,
//! the overrides are applied to that table, and the table is deserialized into
//! [`ScenarioConfig`] (unknown keys are errors). [`ScenarioConfig::validate`] checks
//! what the config alone can tell (ranges, consistency between sections); a check
//! that needs a module's physics or limits lives in that module, beside them, and the
//! loader (`src/loaded.rs`) hands them in ([`OwnerChecks`]), so that every key is
//! still checked in the same order and a config with several errors is told the same
//! first one. Every error names the file, the dotted key and the reason ([`Checker`]
//! words them alike wherever they are checked).
//!
//! This module sits at the bottom of the import graph: it names the error type and
//! leaf modules only (`tests/import_graph.rs` fails if a circle comes through it).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, compact};
use crate::limits::MAX_PROFILES;

/// A whole scenario: instrument, platform, acquisition, atmosphere, background, simulation.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioConfig {
    /// Short name, used in titles.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The lidar instrument.
    pub instrument: InstrumentConfig,
    /// Where the lidar is and where it points.
    pub platform: PlatformConfig,
    /// Range window and accumulation.
    pub acquisition: AcquisitionConfig,
    /// Molecules, aerosols, layers.
    pub atmosphere: AtmosphereConfig,
    /// Sky background.
    pub background: BackgroundConfig,
    /// The surface below a space-borne lidar; absent = no surface echo.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<SurfaceConfig>,
    /// The scene along the track (space-borne); absent = one column everywhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<SceneConfig>,
    /// A circular orbit for a space-borne platform: geolocation of every profile.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orbit: Option<OrbitConfig>,
    /// Monte Carlo settings.
    #[serde(default)]
    pub simulation: SimulationConfig,
    /// How multiple scattering enters the signal (`src/atmosphere/multiple_scattering.rs`).
    #[serde(default)]
    pub multiple_scattering: MultipleScatteringConfig,
}

/// `[multiple_scattering]`: the model of the multiply scattered return (docs/model.md §4j).
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MultipleScatteringConfig {
    /// Which model; absent = `constant` (each layer's η on its optical depth).
    #[serde(default)]
    pub model: MultipleScatteringModel,
    /// Particles whose forward lobe is wider than this, rad, only attenuate in the
    /// small-angle model; absent = 0.1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wide_angle_cutoff_rad: Option<f64>,
}

/// The models of `multiple_scattering.model`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MultipleScatteringModel {
    /// A constant factor η per layer on its optical depth (Platt); the paper's model.
    #[default]
    Constant,
    /// Quasi-small-angle forward scattering: Hogan's (2008) photon variance–covariance
    /// method, which depends on the field of view, the beam and the particles' size.
    SmallAngle,
    /// The small-angle part plus the wide-angle diffuse part (Hogan & Battaglia 2008).
    SmallAndWideAngle,
}

/// A cloud's thermodynamic phase: sets the defaults of its particles' size and
/// asymmetry factor for the multiple-scattering models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CloudPhase {
    /// Liquid droplets (spherical: no depolarization when singly scattered).
    Water,
    /// Ice crystals.
    Ice,
}

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

/// The wavelengths the model covers, nm: a laser's, and the line a channel detects.
pub const WAVELENGTH_RANGE_NM: (f64, f64) = (200.0, 4000.0);

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

/// How the dead period behaves (the detector's law, `src/detector/dead_time.rs`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DeadTimeModel {
    /// Photons in the dead period are lost and do not extend it (default).
    #[default]
    Nonparalyzable,
    /// Every photon restarts the dead period.
    Paralyzable,
}

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

/// Platform kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PlatformKind {
    /// Looking down from orbit (or aircraft).
    Spaceborne,
    /// Looking up from the ground.
    Ground,
}

/// Platform geometry.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PlatformConfig {
    /// Space-borne or ground-based.
    pub kind: PlatformKind,
    /// Platform altitude above sea level, km (space-borne: orbit; ground: station height).
    #[serde(default)]
    pub altitude_km: f64,
    /// Beam angle from nadir (space-borne) or from zenith (ground), degrees.
    #[serde(default)]
    pub off_nadir_deg: f64,
    /// A spherical Earth (default) or the paper's flat Earth for slanted beams.
    #[serde(default = "yes")]
    pub earth_curvature: bool,
}

/// Range window and accumulation.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AcquisitionConfig {
    /// Accumulation time TC per profile, s.
    pub accumulation_time_s: f64,
    /// Top of the altitude window, km.
    pub top_altitude_km: f64,
    /// Bottom of the altitude window, km.
    pub bottom_altitude_km: f64,
    /// Number of profiles a simulation writes.
    #[serde(default = "one_usize")]
    pub profiles: usize,
    /// Signal-free bins a retrieval uses to estimate the background (model.md §2);
    /// absent = the bins of the window above the top of the atmosphere.
    #[serde(default)]
    pub background_bins: Option<usize>,
    /// Bins a ground recorder records before the pulse leaves (background and dark only),
    /// first in the bin grid, at negative range; 0 = none.
    #[serde(default)]
    pub pretrigger_bins: usize,
    /// UTC time of the first shot, RFC 3339 (`2004-03-21T00:00:00Z`): the origin of the
    /// raw file's CF `time`.
    #[serde(default = "default_start_time")]
    pub start_time: String,
}

/// Atmosphere: molecules, an aerosol profile and any number of layers.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AtmosphereConfig {
    /// Molecular atmosphere.
    pub molecular: MolecularConfig,
    /// Background aerosol profile (paper Eq. 5–6); absent = none.
    #[serde(default)]
    pub aerosol: Option<AerosolConfig>,
    /// Aerosol and cloud layers.
    #[serde(default)]
    pub layers: Vec<LayerConfig>,
    /// Ozone absorption (Huggins and Chappuis bands) in T² from a standard ozone profile
    /// (`src/atmosphere/ozone.rs`); on unless set to false.
    #[serde(default = "yes")]
    pub ozone: bool,
    /// Water vapour (`src/atmosphere/water_vapour.rs`): what an H₂O Raman channel sees;
    /// absent = none (and no H₂O channel).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub water_vapour: Option<WaterVapourConfig>,
}

/// A water-vapour mixing-ratio profile (`[atmosphere.water_vapour]`): rows of altitude
/// and mass mixing ratio to dry air, checked by `src/atmosphere/water_vapour.rs`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WaterVapourConfig {
    /// Altitudes above sea level, km, strictly increasing.
    pub altitude_km: Vec<f64>,
    /// Mass mixing ratio of water vapour to dry air at those altitudes, g kg⁻¹.
    pub mixing_ratio_g_per_kg: Vec<f64>,
}

/// Molecular atmosphere options.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MolecularConfig {
    /// `"us76"`, `"none"` or `{ file = "profile.txt" }`.
    pub model: MolecularModel,
    /// Bucholtz depolarization ρn override; absent = Bucholtz's value at the wavelength.
    #[serde(default)]
    pub depolarization: Option<f64>,
    /// Vertical resolution of the piecewise-constant representation, m (at most a
    /// quarter of a bin's altitude extent is used).
    #[serde(default = "default_grid_m")]
    pub grid_m: f64,
    /// Which part of the molecular line the receiver's filter passes.
    #[serde(default)]
    pub line: MolecularLine,
}

/// The part of the molecular return a filter passes (docs/model.md §4a).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MolecularLine {
    /// From the filter width: Cabannes below 0.4 nm, the whole line above (default).
    #[default]
    Auto,
    /// The Cabannes line alone (narrow filters, e.g. a 37 pm etalon).
    Cabannes,
    /// The whole Rayleigh line, Cabannes and rotational Raman wings (wide filters).
    Rayleigh,
}

/// Source of the molecular number density.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum MolecularModel {
    /// `"us76"` or `"none"`.
    Named(String),
    /// A tabulated profile file (see `docs/model.md`), relative to the config file.
    File {
        /// Path of the profile file.
        file: PathBuf,
    },
}

/// Where the aerosol's near-surface extinction comes from (paper Table 1 has both).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ExtinctionSource {
    /// Eq. 5 from `visibility_km`.
    Visibility,
    /// `surface_extinction_per_km` as given.
    SurfaceExtinction,
}

/// The background aerosol's stratosphere (docs/model.md §4 "Background aerosol").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StratosphericAerosol {
    /// Elterman's (1968) shape throughout, scaled with the surface extinction (the
    /// paper's model; a volcanically loaded 1960s stratosphere).
    #[default]
    Elterman1968,
    /// A present-day background stratospheric aerosol of its own extinction above the
    /// troposphere (`aerosol_profile::background_stratosphere_per_m`).
    Background,
}

/// Background aerosol: Eq. 5 surface extinction with the Eq. 6 vertical shape.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AerosolConfig {
    /// Horizontal visibility V, km.
    pub visibility_km: f64,
    /// Aerosol lidar ratio (extinction-to-backscatter), sr = 1/(B/E).
    pub lidar_ratio_sr: f64,
    /// Near-surface extinction at `reference_wavelength_nm`, km⁻¹ (paper Table 1).
    #[serde(default)]
    pub surface_extinction_per_km: Option<f64>,
    /// Which of the two sets α_aer(0); default: the extinction when given, else the visibility.
    #[serde(default)]
    pub extinction_from: Option<ExtinctionSource>,
    /// Wavelength at which `surface_extinction_per_km` is given, nm.
    #[serde(default = "default_reference_wavelength_nm")]
    pub reference_wavelength_nm: f64,
    /// Ångström exponent to scale `surface_extinction_per_km` to the laser
    /// wavelength; absent = the Kruse exponent of the visibility (Eq. 5).
    #[serde(default)]
    pub angstrom_exponent: Option<f64>,
    /// Linear depolarization ratio δ of the aerosol backscatter.
    #[serde(default)]
    pub depolarization: f64,
    /// Effective radius of the aerosol particles, µm (the multiple-scattering models);
    /// absent = 0.5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub effective_radius_um: Option<f64>,
    /// The stratosphere's aerosol: Elterman's shape (default) or a present-day
    /// background.
    #[serde(default)]
    pub stratosphere: StratosphericAerosol,
}

/// Layer species.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LayerKind {
    /// A cloud layer (goes into β_cld).
    Cloud,
    /// An aerosol layer (goes into β_aer).
    Aerosol,
}

/// A homogeneous layer between two altitudes, values at the laser wavelength.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LayerConfig {
    /// Cloud or aerosol.
    pub kind: LayerKind,
    /// Layer base, km.
    pub base_km: f64,
    /// Layer top, km.
    pub top_km: f64,
    /// Extinction coefficient, km⁻¹.
    pub extinction_per_km: f64,
    /// Lidar ratio, sr = 1/(B/E).
    pub lidar_ratio_sr: f64,
    /// Linear depolarization ratio δ.
    #[serde(default)]
    pub depolarization: f64,
    /// Multiple-scattering factor η_ms multiplying the layer's optical depth (1 = single
    /// scattering): the `constant` model's; the other models compute the multiply
    /// scattered return instead.
    #[serde(default = "one")]
    pub multiple_scattering: f64,
    /// A cloud's phase (water or ice); absent = water below a depolarization of 0.1,
    /// ice from 0.1 (`src/atmosphere/multiple_scattering.rs`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phase: Option<CloudPhase>,
    /// Effective radius of the layer's particles, µm: sets the width of their forward
    /// diffraction lobe; absent = the kind's and phase's default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub effective_radius_um: Option<f64>,
    /// Asymmetry factor g of the particles' phase function (wide-angle scattering);
    /// absent = 0.85 for droplets, 0.75 for ice, 0.7 for aerosol.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub asymmetry_factor: Option<f64>,
    /// Fraction of the track the layer covers (broken cloud, docs/model.md §4f); absent = 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cloud_fraction: Option<f64>,
    /// Mean length of the layer's cells along the track, km (with `cloud_fraction`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell_length_km: Option<f64>,
    /// Ångström exponent å: at wavelength λ the extinction is `α·(λ_ref/λ)^å`; absent =
    /// 0 for a cloud, required for an aerosol layer seen at another wavelength.
    #[serde(default)]
    pub angstrom_exponent: Option<f64>,
    /// Wavelength λ_ref at which `extinction_per_km` and `lidar_ratio_sr` are given, nm;
    /// absent = `instrument.wavelength_nm`.
    #[serde(default)]
    pub reference_wavelength_nm: Option<f64>,
    /// Lidar ratios at other wavelengths, sr, keyed by the wavelength in nm
    /// (`{ 1064 = 30.0 }`); a wavelength not listed uses `lidar_ratio_sr`.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub lidar_ratio_sr_by_wavelength: std::collections::BTreeMap<String, f64>,
}

impl LayerConfig {
    /// The layer's extinction (km⁻¹) and lidar ratio (sr) at `wavelength_nm`, where
    /// `instrument_nm` is the wavelength its values are given at unless it says otherwise.
    pub fn at_wavelength(&self, wavelength_nm: f64, instrument_nm: f64) -> (f64, f64) {
        let reference = self.reference_wavelength_nm.unwrap_or(instrument_nm);
        let exponent = self.angstrom_exponent.unwrap_or(0.0);
        let extinction = self.extinction_per_km * (reference / wavelength_nm).powf(exponent);
        let lidar_ratio = self
            .lidar_ratio_sr_by_wavelength
            .iter()
            .find(|(k, _)| {
                k.parse::<f64>()
                    .is_ok_and(|w| (w - wavelength_nm).abs() < 0.5)
            })
            .map_or(self.lidar_ratio_sr, |(_, v)| *v);
        (extinction, lidar_ratio)
    }
}

/// A circular orbit (`src/scene/orbit.rs`, which checks it) at `platform.altitude_km`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OrbitConfig {
    /// Inclination, degrees (above 90: retrograde, e.g. 98.2 sun-synchronous).
    pub inclination_deg: f64,
    /// Latitude of the first shot, degrees north.
    #[serde(default)]
    pub start_latitude_deg: f64,
    /// Longitude of the first shot, degrees east.
    #[serde(default)]
    pub start_longitude_deg: f64,
    /// Moving north at the first shot (else south).
    #[serde(default = "yes")]
    pub ascending: bool,
}

/// The scene along the track (`src/scene/`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneConfig {
    /// Stretches of the track, in order from the first shot; the last continues to the
    /// end of the run.
    #[serde(default)]
    pub segments: Vec<SegmentConfig>,
    /// A tabulated curtain (along-track × altitude aerosol and cloud, `src/scene/curtain.rs`),
    /// relative to the config file; instead of `segments`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curtain: Option<PathBuf>,
}

/// One stretch of the track with its own layers, aerosol and surface.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentConfig {
    /// Length along the track, km.
    pub length_km: f64,
    /// The layers of this stretch (replacing `[[atmosphere.layers]]`); absent = those.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layers: Option<Vec<LayerConfig>>,
    /// The background aerosol of this stretch (replacing `[atmosphere.aerosol]`), or
    /// `"none"`; absent = that of `[atmosphere]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aerosol: Option<SegmentAerosol>,
    /// The surface of this stretch (replacing `[surface]`); absent = that one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<SurfaceConfig>,
    /// The water vapour of this stretch (replacing `[atmosphere.water_vapour]`); absent
    /// = that one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub water_vapour: Option<WaterVapourConfig>,
}

/// A segment's aerosol: `"none"` or a whole `[atmosphere.aerosol]` table.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum SegmentAerosol {
    /// `"none"`: no background aerosol in this stretch.
    Named(String),
    /// This stretch's aerosol.
    Given(AerosolConfig),
}

/// A Lambertian surface (docs/model.md §4e, `src/surface.rs`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceConfig {
    /// What the surface is (sets the default albedo).
    #[serde(default)]
    pub kind: SurfaceKind,
    /// Lambertian reflectance ρ at the laser wavelength; absent = the kind's.
    #[serde(default)]
    pub albedo: Option<f64>,
    /// Altitude of the surface above sea level, km.
    #[serde(default)]
    pub altitude_km: f64,
}

/// Surface presets.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceKind {
    /// Open ocean.
    Ocean,
    /// Vegetated land (default).
    #[default]
    Land,
    /// Fresh snow.
    Snow,
}

/// Which efficiencies the detected sky background carries (model.md §1).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BackgroundEfficiency {
    /// ε_bkg = TR·Qλ: the background crosses the same receiver as the signal (default).
    #[default]
    Receiver,
    /// ε_bkg = 1: the paper's literal Eq. 3.
    Paper,
}

/// Sky background.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BackgroundConfig {
    /// `"fixed"` (the paper's: `radiance`) or `"solar"` (sunlight from the scene).
    #[serde(default)]
    pub model: BackgroundModel,
    /// Spectral radiance Lλ, photons m⁻² s⁻¹ sr⁻¹ nm⁻¹ (paper: 1.1e10 night, 1.1e15
    /// day); required by the fixed model; with the solar model a floor added to the
    /// reflected sunlight (night sky, moonlight).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radiance: Option<f64>,
    /// Efficiencies applied to the background.
    #[serde(default)]
    pub efficiency: BackgroundEfficiency,
    /// Solar model: a stated two-way transmission of the sunlight (sun → scene →
    /// instrument), whatever the angle; absent = the slant path through the modelled
    /// atmosphere and its path radiance (`SunlightPath` in `src/scene/sun.rs`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transmission: Option<f64>,
    /// Solar model: albedo of an optically thick cloud top (column optical depth ≥ 1); absent = 0.7.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cloud_albedo: Option<f64>,
    /// Solar model: a fixed solar zenith angle, degrees (instead of the sun's position
    /// along the orbit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solar_zenith_deg: Option<f64>,
    /// Solar model: whether the air's once-scattered sunlight (path radiance) is added
    /// to the reflected sunlight (`src/scene/sky.rs`); absent = true.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path_radiance: Option<bool>,
}

/// Where the sky background comes from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BackgroundModel {
    /// A fixed radiance (`background.radiance`), the paper's way.
    #[default]
    Fixed,
    /// Sunlight reflected by the surface or a cloud top below a space-borne lidar, from
    /// the solar zenith angle at each profile's time and place (docs/model.md §4f).
    Solar,
}

/// Monte Carlo method (docs/config.md `--method`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// `aggregate` whenever the scene allows it, else `shot`.
    #[default]
    Auto,
    /// Every shot drawn.
    Shot,
    /// One exact Poisson(M·λ) draw per bin per profile.
    Aggregate,
}

/// Monte Carlo settings.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationConfig {
    /// Random seed: a whole number, or one above 2^63 − 1 (beyond a TOML integer) as a
    /// string of its digits ([`seed_value`]).
    #[serde(default, deserialize_with = "seed_of")]
    pub seed: u64,
    /// Sampling method.
    #[serde(default)]
    pub method: Method,
    /// Store signal, background and dark counts separately as well.
    #[serde(default)]
    pub components: bool,
    /// With `method = "auto"`: the largest Kolmogorov–Smirnov distance per bin to the
    /// exact law that a faster approximate method may have (see `docs/simulation.md`).
    #[serde(default)]
    pub tolerance: Option<f64>,
}

/// The TOML value of `simulation.seed`: an integer, or the string of its digits above
/// 2^63 − 1, which a TOML integer cannot hold (every seed `--seed` takes, 0 to 2^64 − 1,
/// can so be written into a config).
pub fn seed_value(seed: u64) -> toml::Value {
    match i64::try_from(seed) {
        Ok(n) => toml::Value::Integer(n),
        Err(_) => toml::Value::String(seed.to_string()),
    }
}

/// Reads `simulation.seed` as [`seed_value`] writes it.
fn seed_of<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<u64, D::Error> {
    struct Seed;
    impl serde::de::Visitor<'_> for Seed {
        type Value = u64;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a whole number from 0 to 18446744073709551615")
        }
        fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<u64, E> {
            Ok(v)
        }
        fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<u64, E> {
            u64::try_from(v).map_err(|_| E::invalid_value(serde::de::Unexpected::Signed(v), &self))
        }
        fn visit_str<E: serde::de::Error>(self, v: &str) -> std::result::Result<u64, E> {
            v.trim()
                .parse()
                .map_err(|_| E::invalid_value(serde::de::Unexpected::Str(v), &self))
        }
    }
    d.deserialize_any(Seed)
}

fn yes() -> bool {
    true
}
fn one() -> f64 {
    1.0
}
fn one_usize() -> usize {
    1
}
fn default_bin_width_s() -> f64 {
    2e-6
}
fn default_start_time() -> String {
    DEFAULT_START_TIME.to_string()
}
/// Default `acquisition.start_time`.
pub const DEFAULT_START_TIME: &str = "2000-01-01T00:00:00Z";
fn default_grid_m() -> f64 {
    10.0
}
fn default_reference_wavelength_nm() -> f64 {
    532.0
}

/// Pulse energy above which a config is warned of a unit slip, J
/// ([`ScenarioConfig::plausibility_warnings`]).
pub const PLAUSIBLE_PULSE_ENERGY_J: f64 = 10.0;

/// How much longer than the distance to the ground a window may be before a config is
/// warned of a unit slip, km ([`ScenarioConfig::plausibility_warnings`]).
pub const PLAUSIBLE_WINDOW_BEYOND_GROUND_KM: f64 = 100.0;

/// The unambiguous range of a pulsed lidar, `c/(2 fL)`, m: a return from farther
/// arrives after the next pulse has left.
pub fn unambiguous_range_m(rep_rate_hz: f64) -> f64 {
    crate::constants::SPEED_OF_LIGHT_M_PER_S / (2.0 * rep_rate_hz)
}

/// A config parsed from TOML text, overrides applied: the typed sections, not yet
/// validated.
#[derive(Debug, Clone)]
pub struct Parsed {
    /// The typed sections.
    pub config: ScenarioConfig,
    /// The TOML table after overrides (the receiver expands its channels from it).
    pub table: toml::Table,
    /// The resolved TOML after overrides (stored in output files).
    pub resolved_toml: String,
}

/// Parses `text`, applies `overrides` (`KEY=VALUE`, dotted keys) and deserializes; `path`
/// names the source in errors, and an error in a key that an override set names the
/// override. Validation is the loader's (`src/loaded.rs`): [`ScenarioConfig::validate`]
/// and the checks of the modules that own a section.
pub fn parse(text: &str, path: &Path, overrides: &[String]) -> Result<Parsed> {
    let file = path.display().to_string();
    let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
        let at = e
            .span()
            .map(|s| line_column(text, s.start))
            .unwrap_or_default();
        Error::config(
            &file,
            "",
            format!("{at}malformed TOML: {}", one_line(e.message())),
        )
    })?;
    for item in overrides {
        apply_override(&mut table, item)
            .map_err(|reason| Error::config(format!("--set {item}"), key_of(item), reason))?;
    }
    let resolved_toml = toml::to_string(&table).unwrap_or_default();
    let de = toml::Value::Table(table.clone());
    let config = deserialize(de, &file).map_err(|e| attribute_to_override(e, overrides))?;
    Ok(Parsed {
        config,
        table,
        resolved_toml,
    })
}

/// `"line 10, column 17: "` for a byte offset into `text`.
fn line_column(text: &str, offset: usize) -> String {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    format!("line {line}, column {column}: ")
}

/// A message on one line.
fn one_line(msg: &str) -> String {
    msg.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A deserialization message in the user's words: no Rust type names.
pub fn plain_serde_message(key: &str, msg: &str) -> String {
    let msg = one_line(msg);
    if key.ends_with("molecular.model") {
        return "expected \"us76\", \"none\" or { file = \"profile.txt\" }".into();
    }
    if let Some(rest) = msg.strip_prefix("invalid type: ") {
        let (got, want) = rest
            .split_once(", expected ")
            .unwrap_or((rest, "another type"));
        if want == "string only" || got == "unit variant" {
            // toml's enums: a number or a table where one of the key's names belongs
            return "expected a string, one of the names this key takes (docs/config.md)".into();
        }
        let want = match want {
            w if w.starts_with("struct ") || w.starts_with("a map") => "a table".to_string(),
            "f64" | "f32" => "a number".to_string(),
            "usize" | "u64" | "u32" => "a whole number".to_string(),
            "a boolean" | "bool" => "true or false".to_string(),
            w if w.starts_with("a sequence") => "an array".to_string(),
            w => w.to_string(),
        };
        return format!("expected {want}, got {}", got.replace('`', "'"));
    }
    if let Some(rest) = msg.strip_prefix("invalid value: ") {
        let (got, want) = rest
            .split_once(", expected ")
            .unwrap_or((rest, "another value"));
        let want = match want {
            "usize" | "u64" | "u32" => "a whole number >= 0",
            w => w,
        };
        return format!("expected {want}, got {}", got.replace('`', "'"));
    }
    if let Some(rest) = msg.strip_prefix("unknown field ") {
        return format!("unknown key {}", rest.replace('`', "'"));
    }
    if let Some(rest) = msg.strip_prefix("missing field ") {
        return format!("missing key {}", rest.replace('`', "'"));
    }
    if msg.contains("untagged enum") || msg.contains("internally tagged") {
        return "does not have one of the forms this key takes (see docs/config.md)".into();
    }
    msg.replace('`', "'")
}

/// An error in a key that a `--set` override set (the key or a table above it) names
/// that override rather than the file.
pub fn attribute_to_override(e: Error, overrides: &[String]) -> Error {
    let Error::Config { file, key, reason } = e else {
        return e;
    };
    // "atmosphere.layers[0].top_km" -> "atmosphere.layers.0.top_km"
    let dotted = key.replace('[', ".").replace(']', "");
    let hit = overrides.iter().rev().find(|item| {
        let k = key_of(item);
        !k.is_empty() && (dotted == k || dotted.starts_with(&format!("{k}.")))
    });
    match hit {
        Some(item) => Error::config(format!("--set {item}"), key, reason),
        None => Error::Config { file, key, reason },
    }
}

fn key_of(item: &str) -> String {
    item.split_once('=')
        .map(|(k, _)| k.trim())
        .unwrap_or(item)
        .to_string()
}

/// Applies one `KEY=VALUE` override to `table`. The value is read as a TOML value
/// (number, boolean, string in quotes, inline table, array); anything that is not
/// valid TOML is taken as a bare string, so `--set platform.kind=ground` works.
/// Array elements are addressed by index: `atmosphere.layers.0.top_km=12`.
pub fn apply_override(table: &mut toml::Table, item: &str) -> std::result::Result<(), String> {
    let (key, raw) = item
        .split_once('=')
        .ok_or_else(|| format!("--set expects KEY=VALUE, got `{item}`"))?;
    let key = key.trim();
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(format!("--set has an empty key part in `{item}`"));
    }
    let parts: Vec<&str> = key.split('.').collect();
    let mut root = toml::Value::Table(std::mem::take(table));
    let result = set_path(&mut root, &parts, parse_value(raw.trim()));
    if let toml::Value::Table(t) = root {
        *table = t;
    }
    result
}

fn set_path(
    node: &mut toml::Value,
    parts: &[&str],
    value: toml::Value,
) -> std::result::Result<(), String> {
    let mut node = node;
    for (i, part) in parts.iter().enumerate() {
        let last = i + 1 == parts.len();
        let here = parts[..i].join(".");
        node = match node {
            toml::Value::Table(t) => {
                if last {
                    t.insert((*part).to_string(), value);
                    return Ok(());
                }
                t.entry((*part).to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            toml::Value::Array(a) => {
                let idx: usize = part
                    .parse()
                    .map_err(|_| format!("`{here}` is an array: address its elements by index"))?;
                let len = a.len();
                let slot = a.get_mut(idx).ok_or_else(|| {
                    format!("index {idx} is out of range (`{here}` has {len} elements)")
                })?;
                if last {
                    *slot = value;
                    return Ok(());
                }
                slot
            }
            _ => return Err(format!("`{here}` is a value, not a table")),
        };
    }
    Err("empty key".into())
}

fn parse_value(raw: &str) -> toml::Value {
    let doc = format!("v = {raw}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or_else(|| toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.trim_matches('"').to_string()),
    }
}

/// Deserializes a whole config table; errors name `file` and the dotted key.
pub fn deserialize(table: toml::Value, file: &str) -> Result<ScenarioConfig> {
    serde_path_to_error::deserialize(table).map_err(|e| {
        let key = e.path().to_string();
        let key = if key == "." { String::new() } else { key };
        let reason = plain_serde_message(&key, e.inner().message());
        Error::config(file, key, reason)
    })
}

/// Collects the checks of one file; the first failure becomes the error. Every module
/// that checks a section of the config words its errors through it, so that a range
/// reads the same whoever checks it.
#[derive(Debug, Clone, Copy)]
pub struct Checker<'a> {
    /// The file (or `--set` override) errors name.
    pub file: &'a str,
}

impl Checker<'_> {
    /// The error for `key`, naming the file.
    pub fn fail(&self, key: &str, reason: impl Into<String>) -> Error {
        Error::config(self.file, key, reason)
    }

    /// `value` must be finite and within `[lo, hi]` (bounds inclusive).
    pub fn range(&self, key: &str, value: f64, lo: f64, hi: f64) -> Result<()> {
        if !value.is_finite() {
            return Err(self.fail(key, format!("must be a finite number, got {value}")));
        }
        if value < lo || value > hi {
            return Err(self.fail(
                key,
                format!(
                    "must be within [{}, {}], got {}",
                    compact(lo),
                    compact(hi),
                    compact(value)
                ),
            ));
        }
        Ok(())
    }

    /// `value` must be finite and strictly positive, at most `hi`.
    pub fn positive(&self, key: &str, value: f64, hi: f64) -> Result<()> {
        self.range(key, value, 0.0, hi)?;
        if value == 0.0 {
            return Err(self.fail(key, "must be greater than 0"));
        }
        Ok(())
    }

    /// A fraction in (0, 1].
    pub fn efficiency(&self, key: &str, value: f64) -> Result<()> {
        self.positive(key, value, 1.0)
    }
}

/// A check of the keys whose limits another module's physics sets.
pub type OwnerCheck = fn(&ScenarioConfig, &Checker) -> Result<()>;

/// The checks the modules that own a section's limits make, handed to
/// [`ScenarioConfig::validate`] by the loader: the config names none of those modules,
/// and runs each check where its keys always were checked.
#[derive(Debug, Clone, Copy)]
pub struct OwnerChecks {
    /// `instrument.pulse_energy_jitter` (the laser's law).
    pub laser: OwnerCheck,
    /// `[instrument.detector]` (the detector).
    pub detector: OwnerCheck,
    /// `atmosphere.ozone` (the ozone cross-section table).
    pub ozone: OwnerCheck,
    /// `[atmosphere.water_vapour]` and the segments' (the mixing-ratio profile).
    pub water_vapour: OwnerCheck,
    /// `[orbit]` (an orbit that exists).
    pub orbit: OwnerCheck,
    /// `[simulation]` (the sampler's tolerance).
    pub simulation: OwnerCheck,
    /// `[multiple_scattering]` and the particles' sizes (the multiple-scattering model).
    pub multiple_scattering: OwnerCheck,
}

impl ScenarioConfig {
    /// Every file the config names, with its key, as written (relative to the config
    /// file): the molecular profile file and the scene's curtain. A key that names a
    /// file belongs here, so that the file is an input no output may replace
    /// (`LoadedConfig::files_read`); its reader opens it through `src/input_file.rs`.
    pub fn named_files(&self) -> Vec<(&'static str, &Path)> {
        let mut files = Vec::new();
        if let MolecularModel::File { file } = &self.atmosphere.molecular.model {
            files.push(("atmosphere.molecular.model.file", file.as_path()));
        }
        if let Some(curtain) = self.scene.as_ref().and_then(|s| s.curtain.as_ref()) {
            files.push(("scene.curtain", curtain.as_path()));
        }
        files
    }

    /// A layer's values at other wavelengths: Ångström exponent, reference wavelength and
    /// lidar ratios per wavelength; an aerosol layer seen at another wavelength than its
    /// values' needs its exponent.
    fn validate_layer_spectrum(&self, c: &Checker, n: usize, l: &LayerConfig) -> Result<()> {
        let key = |k: &str| format!("atmosphere.layers[{n}].{k}");
        if let Some(x) = l.angstrom_exponent {
            c.range(&key("angstrom_exponent"), x, -1.0, 4.0)?;
        }
        let wl = self.instrument.wavelength_nm;
        let reference = l.reference_wavelength_nm.unwrap_or(wl);
        c.range(&key("reference_wavelength_nm"), reference, 200.0, 4000.0)?;
        for (w, ratio) in &l.lidar_ratio_sr_by_wavelength {
            let k = key(&format!("lidar_ratio_sr_by_wavelength.{w}"));
            match w.parse::<f64>() {
                Ok(w) if (200.0..=4000.0).contains(&w) => c.range(&k, *ratio, 1.0, 1e4)?,
                _ => return Err(c.fail(&k, "the key must be a wavelength in nm from 200 to 4000")),
            }
        }
        if l.kind == LayerKind::Aerosol
            && l.angstrom_exponent.is_none()
            && (reference - wl).abs() > 1e-9
        {
            return Err(c.fail(
                &key("angstrom_exponent"),
                format!(
                    "the layer's values are at {reference} nm and a channel sees it at {wl} nm: \
                     give the layer's Ångström exponent (about 1–1.5 for fine aerosol, 0 for dust)"
                ),
            ));
        }
        Ok(())
    }

    /// The surface: an albedo in [0, 1], within the window's reach, space-borne only.
    fn validate_surface(&self, c: &Checker, s: &SurfaceConfig) -> Result<()> {
        if self.platform.kind == PlatformKind::Ground {
            return Err(c.fail(
                "surface",
                "a ground-based lidar looks up and sees no surface; remove [surface]",
            ));
        }
        if let Some(a) = s.albedo {
            c.range("surface.albedo", a, 0.0, 1.0)?;
        }
        c.range("surface.altitude_km", s.altitude_km, -0.5, 9.0)?;
        Ok(())
    }

    /// A broken layer: a fraction in (0, 1] with a cell length, on a moving platform.
    fn validate_broken(&self, c: &Checker, prefix: &str, l: &LayerConfig) -> Result<()> {
        match (l.cloud_fraction, l.cell_length_km) {
            (None, None) => Ok(()),
            (Some(_), None) | (None, Some(_)) => Err(c.fail(
                &format!("{prefix}cloud_fraction"),
                "a broken layer needs both cloud_fraction and cell_length_km",
            )),
            (Some(f), Some(len)) => {
                c.positive(&format!("{prefix}cloud_fraction"), f, 1.0)?;
                c.positive(&format!("{prefix}cell_length_km"), len, 1e5)?;
                if self.platform.kind == PlatformKind::Ground {
                    return Err(c.fail(
                        &format!("{prefix}cloud_fraction"),
                        "broken cloud moves past a space-borne lidar; a ground lidar stays put",
                    ));
                }
                Ok(())
            }
        }
    }

    /// The scene's segments: positive lengths; their layers, aerosol and surface as the
    /// `[atmosphere]` and `[surface]` ones.
    fn validate_scene(&self, c: &Checker, scene: &SceneConfig) -> Result<()> {
        if self.platform.kind == PlatformKind::Ground && !scene.segments.is_empty() {
            return Err(c.fail(
                "scene.segments",
                "a scene along the track needs a space-borne platform",
            ));
        }
        if scene.curtain.is_some() && !scene.segments.is_empty() {
            return Err(c.fail(
                "scene.curtain",
                "gives the scene along the track: use it or scene.segments, not both",
            ));
        }
        if scene.curtain.is_some() && self.platform.kind == PlatformKind::Ground {
            return Err(c.fail("scene.curtain", "a curtain needs a space-borne platform"));
        }
        if scene.segments.len() > 10_000 {
            return Err(c.fail("scene.segments", "at most 10,000 segments"));
        }
        for (i, seg) in scene.segments.iter().enumerate() {
            let key = |k: &str| format!("scene.segments[{i}].{k}");
            c.positive(&key("length_km"), seg.length_km, 1e6)?;
            for (n, l) in seg.layers.iter().flatten().enumerate() {
                let k = key(&format!("layers[{n}]."));
                if l.top_km <= l.base_km {
                    return Err(c.fail(&format!("{k}top_km"), "must be above base_km"));
                }
                c.range(
                    &format!("{k}extinction_per_km"),
                    l.extinction_per_km,
                    0.0,
                    1e4,
                )?;
                c.range(&format!("{k}lidar_ratio_sr"), l.lidar_ratio_sr, 1.0, 1e4)?;
                c.range(&format!("{k}depolarization"), l.depolarization, 0.0, 1.0)?;
                self.validate_broken(c, &k, l)?;
            }
            if seg
                .layers
                .iter()
                .flatten()
                .filter(|l| l.cloud_fraction.is_some())
                .count()
                > 3
            {
                return Err(c.fail(&key("layers"), "at most 3 broken layers per segment"));
            }
            if let Some(SegmentAerosol::Named(name)) = &seg.aerosol
                && name != "none"
            {
                return Err(c.fail(&key("aerosol"), "must be \"none\" or an aerosol table"));
            }
            if let Some(surface) = &seg.surface {
                self.validate_surface(c, surface)?;
            }
        }
        Ok(())
    }

    /// The background: a radiance for the fixed model; the solar model's sun and scene.
    fn validate_background(&self, c: &Checker) -> Result<()> {
        let b = &self.background;
        match b.model {
            BackgroundModel::Fixed => match b.radiance {
                Some(r) => c.range("background.radiance", r, 0.0, 1e25),
                None => Err(c.fail(
                    "background.radiance",
                    "is required (photons m-2 s-1 sr-1 nm-1; the paper: 1.1e10 night, 1.1e15 day), \
                     or set background.model = \"solar\"",
                )),
            },
            BackgroundModel::Solar => {
                if let Some(r) = b.radiance {
                    c.range("background.radiance", r, 0.0, 1e25)?;
                }
                if self.platform.kind == PlatformKind::Ground {
                    return Err(c.fail(
                        "background.model",
                        "\"solar\" is sunlight reflected below a space-borne lidar; a ground lidar \
                         takes a fixed sky radiance",
                    ));
                }
                if self.orbit.is_none() && b.solar_zenith_deg.is_none() {
                    return Err(c.fail(
                        "background.model",
                        "\"solar\" needs the sun's angle: give [orbit] (and acquisition.start_time) \
                         or background.solar_zenith_deg",
                    ));
                }
                if let Some(t) = b.transmission {
                    c.range("background.transmission", t, 0.0, 1.0)?;
                }
                if let Some(a) = b.cloud_albedo {
                    c.range("background.cloud_albedo", a, 0.0, 1.0)?;
                }
                if let Some(z) = b.solar_zenith_deg {
                    c.range("background.solar_zenith_deg", z, 0.0, 180.0)?;
                }
                Ok(())
            }
        }
    }

    /// Checks every field: finite, in range, consistent. A check that needs a module's
    /// physics or limits is that module's, one of `owners` (the loader's,
    /// `src/loaded.rs`), run in its place among the others. `file` names the source in
    /// errors.
    pub fn validate(&self, file: &str, owners: &OwnerChecks) -> Result<()> {
        let c = Checker { file };
        self.validate_instrument(&c, owners)?;
        self.validate_geometry(&c)?;
        self.validate_atmosphere(&c, owners)?;
        self.validate_background(&c)?;
        if let Some(surface) = &self.surface {
            self.validate_surface(&c, surface)?;
        }
        if let Some(scene) = &self.scene {
            self.validate_scene(&c, scene)?;
        }
        if let Some(o) = &self.orbit {
            if self.platform.kind == PlatformKind::Ground {
                return Err(c.fail("orbit", "an orbit needs a space-borne platform"));
            }
            c.range(
                "orbit.start_longitude_deg",
                o.start_longitude_deg,
                -360.0,
                360.0,
            )?;
            (owners.orbit)(self, &c)?;
        }
        if self
            .atmosphere
            .layers
            .iter()
            .filter(|l| l.cloud_fraction.is_some())
            .count()
            > 3
        {
            return Err(c.fail("atmosphere.layers", "at most 3 broken layers"));
        }
        (owners.multiple_scattering)(self, &c)?;
        (owners.simulation)(self, &c)
    }

    /// Warnings for values that are legal but almost surely a unit slip, one line each
    /// (`lidarsim: warning: KEY ...`), in a fixed order: [`Self::pulse_energy_warning`],
    /// [`Self::window_length_warning`], [`Self::pulses_in_window_warning`]. The run goes
    /// on; a command prints them once, after it succeeds.
    pub fn plausibility_warnings(&self) -> Vec<String> {
        [
            self.pulse_energy_warning(),
            self.window_length_warning(),
            self.pulses_in_window_warning(),
        ]
        .into_iter()
        .flatten()
        .map(|w| format!("lidarsim: warning: {w}"))
        .collect()
    }

    /// A pulse energy above [`PLAUSIBLE_PULSE_ENERGY_J`]: no lidar laser in service
    /// gives more than about 1 J per pulse, so 110 (mJ) written for 0.110 (J) is likely.
    fn pulse_energy_warning(&self) -> Option<String> {
        let e = self.instrument.pulse_energy_j;
        (e > PLAUSIBLE_PULSE_ENERGY_J).then(|| {
            format!(
                "instrument.pulse_energy_j = {} J is above {} J, more than any lidar laser \
                 gives per pulse (a value in mJ written as J?); the run goes on",
                compact(e),
                compact(PLAUSIBLE_PULSE_ENERGY_J)
            )
        })
    }

    /// A window (along the beam, `(top − bottom)/cos θ`) longer than the distance from
    /// the lidar to the ground along the beam (`|h|/cos θ`) plus
    /// [`PLAUSIBLE_WINDOW_BEYOND_GROUND_KM`]: beyond the atmosphere's top (~100 km) there
    /// is nothing to see, so metres written as km (`top_altitude_km = 15000`) is likely.
    fn window_length_warning(&self) -> Option<String> {
        let a = &self.acquisition;
        let cos = self.platform.off_nadir_deg.to_radians().cos();
        let window_km = (a.top_altitude_km - a.bottom_altitude_km) / cos;
        let ground_km = self.platform.altitude_km.abs() / cos;
        (window_km > ground_km + PLAUSIBLE_WINDOW_BEYOND_GROUND_KM).then(|| {
            format!(
                "acquisition.top_altitude_km = {} and acquisition.bottom_altitude_km = {} make a \
                 window of {} km along the beam, longer than the {} km to the ground plus {} km \
                 (a value in m written as km?); the run goes on",
                compact(a.top_altitude_km),
                compact(a.bottom_altitude_km),
                format_args!("{window_km:.1}"),
                format_args!("{ground_km:.1}"),
                compact(PLAUSIBLE_WINDOW_BEYOND_GROUND_KM)
            )
        })
    }

    /// A ground lidar whose window reaches beyond the unambiguous range `c/(2 fL)`: the
    /// return from the window's far end arrives after the next pulse has left, so more
    /// than one pulse is in the window at once (second-trip echoes the model does not
    /// draw). A space-borne lidar has pulses in flight by design (the `pulses_in_flight`
    /// sweep metric) and its window is far from the platform, so it is not warned.
    fn pulses_in_window_warning(&self) -> Option<String> {
        if self.platform.kind != PlatformKind::Ground {
            return None;
        }
        let fl = self.instrument.rep_rate_hz;
        let cos = self.platform.off_nadir_deg.to_radians().cos();
        let far_m = (self.acquisition.top_altitude_km - self.platform.altitude_km) * 1e3 / cos;
        let unambiguous_m = unambiguous_range_m(fl);
        (far_m > unambiguous_m).then(|| {
            format!(
                "instrument.rep_rate_hz = {} Hz: the window's far end ({} km along the beam) is \
                 beyond c/(2 fL) = {} km, so more than one pulse is in the window at once \
                 (a rate in Hz written for kHz, or a window in m written as km?); the run goes on",
                compact(fl),
                format_args!("{:.1}", far_m / 1e3),
                format_args!("{:.1}", unambiguous_m / 1e3)
            )
        })
    }

    fn validate_instrument(&self, c: &Checker, owners: &OwnerChecks) -> Result<()> {
        let i = &self.instrument;
        let (shortest, longest) = WAVELENGTH_RANGE_NM;
        c.range(
            "instrument.wavelength_nm",
            i.wavelength_nm,
            shortest,
            longest,
        )?;
        c.positive("instrument.pulse_energy_j", i.pulse_energy_j, 1e3)?;
        (owners.laser)(self, c)?;
        c.positive("instrument.rep_rate_hz", i.rep_rate_hz, 1e7)?;
        c.positive("instrument.telescope_area_m2", i.telescope_area_m2, 1e3)?;
        c.efficiency("instrument.optical_efficiency", i.optical_efficiency)?;
        c.efficiency("instrument.receiver_efficiency", i.receiver_efficiency)?;
        c.efficiency("instrument.filter_transmission", i.filter_transmission)?;
        c.efficiency("instrument.quantum_efficiency", i.quantum_efficiency)?;
        c.positive("instrument.fov_rad", i.fov_rad, 0.1)?;
        c.positive("instrument.filter_width_nm", i.filter_width_nm, 100.0)?;
        c.range(
            "instrument.dark_count_rate_hz",
            i.dark_count_rate_hz,
            0.0,
            1e9,
        )?;
        c.range("instrument.bin_width_s", i.bin_width_s, 1e-10, 1e-3)?;
        c.range("instrument.crosstalk", i.crosstalk, 0.0, 0.5)?;
        c.range("instrument.diattenuation", i.diattenuation, -0.99, 0.99)?;
        c.range(
            "instrument.receiver_rotation_deg",
            i.receiver_rotation_deg,
            -90.0,
            90.0,
        )?;
        if i.crosstalk > 0.0 && i.channel == Channel::Total {
            return Err(c.fail(
                "instrument.crosstalk",
                "applies to a parallel or perpendicular channel; a total channel sees both",
            ));
        }
        match i.energy_drift {
            None => {}
            Some(EnergyDriftConfig::Linear { per_hour }) => {
                c.range("instrument.energy_drift.per_hour", per_hour, -0.5, 0.5)?;
            }
            Some(EnergyDriftConfig::Periodic {
                amplitude,
                period_s,
                phase_deg,
            }) => {
                c.range("instrument.energy_drift.amplitude", amplitude, 0.0, 0.5)?;
                c.positive("instrument.energy_drift.period_s", period_s, 1e9)?;
                c.range(
                    "instrument.energy_drift.phase_deg",
                    phase_deg,
                    -360.0,
                    360.0,
                )?;
            }
        }
        (owners.detector)(self, c)?;
        match &i.overlap {
            None | Some(OverlapConfig::None) => {}
            Some(OverlapConfig::FullRange { full_overlap_m }) => {
                c.positive("instrument.overlap.full_overlap_m", *full_overlap_m, 1e6)?;
            }
            Some(OverlapConfig::Geometric {
                beam_radius_m,
                beam_divergence_rad,
                axis_offset_m,
            }) => {
                c.positive("instrument.overlap.beam_radius_m", *beam_radius_m, 10.0)?;
                c.range(
                    "instrument.overlap.beam_divergence_rad",
                    *beam_divergence_rad,
                    0.0,
                    0.1,
                )?;
                c.range(
                    "instrument.overlap.axis_offset_m",
                    *axis_offset_m,
                    0.0,
                    100.0,
                )?;
            }
        }
        Ok(())
    }

    fn validate_geometry(&self, c: &Checker) -> Result<()> {
        let p = &self.platform;
        let a = &self.acquisition;
        c.range("platform.off_nadir_deg", p.off_nadir_deg, 0.0, 85.0)?;
        c.range(
            "acquisition.accumulation_time_s",
            a.accumulation_time_s,
            0.0,
            1e7,
        )?;
        let shots = a.accumulation_time_s * self.instrument.rep_rate_hz;
        if shots.round() < 1.0 {
            return Err(c.fail(
                "acquisition.accumulation_time_s",
                format!("accumulates {shots} shots at instrument.rep_rate_hz; a profile needs at least one"),
            ));
        }
        c.range("acquisition.top_altitude_km", a.top_altitude_km, -10.0, 1e5)?;
        c.range(
            "acquisition.bottom_altitude_km",
            a.bottom_altitude_km,
            -10.0,
            1e5,
        )?;
        if a.bottom_altitude_km >= a.top_altitude_km {
            return Err(c.fail(
                "acquisition.bottom_altitude_km",
                format!(
                    "must be below acquisition.top_altitude_km ({} km)",
                    a.top_altitude_km
                ),
            ));
        }
        if a.profiles == 0 || a.profiles as u64 > MAX_PROFILES {
            return Err(c.fail(
                "acquisition.profiles",
                format!("must be from 1 to {}", compact(MAX_PROFILES as f64)),
            ));
        }
        if let Err(e) = humantime::parse_rfc3339(&a.start_time) {
            return Err(c.fail(
                "acquisition.start_time",
                format!(
                    "must be a UTC time like \"2004-03-21T00:00:00Z\" (RFC 3339), got {:?}: {e}",
                    a.start_time
                ),
            ));
        }
        match p.kind {
            PlatformKind::Spaceborne => {
                c.positive("platform.altitude_km", p.altitude_km, 1e5)?;
                if a.top_altitude_km >= p.altitude_km {
                    return Err(c.fail(
                        "acquisition.top_altitude_km",
                        format!(
                            "the window must lie below the platform ({} km)",
                            p.altitude_km
                        ),
                    ));
                }
            }
            PlatformKind::Ground => {
                c.range("platform.altitude_km", p.altitude_km, -0.5, 9.0)?;
                if a.bottom_altitude_km < p.altitude_km {
                    return Err(c.fail(
                        "acquisition.bottom_altitude_km",
                        format!(
                            "a ground lidar sees nothing below its station ({} km)",
                            p.altitude_km
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    fn validate_atmosphere(&self, c: &Checker, owners: &OwnerChecks) -> Result<()> {
        let m = &self.atmosphere.molecular;
        if let MolecularModel::Named(name) = &m.model
            && name != "us76"
            && name != "none"
        {
            return Err(c.fail(
                "atmosphere.molecular.model",
                format!(
                    "unknown model `{name}`: expected \"us76\", \"none\" or {{ file = \"...\" }}"
                ),
            ));
        }
        if let Some(rho) = m.depolarization {
            c.range("atmosphere.molecular.depolarization", rho, 0.0, 0.2)?;
        }
        c.range("atmosphere.molecular.grid_m", m.grid_m, 0.1, 1000.0)?;
        (owners.ozone)(self, c)?;
        (owners.water_vapour)(self, c)?;
        if let Some(a) = &self.atmosphere.aerosol {
            c.positive("atmosphere.aerosol.visibility_km", a.visibility_km, 1e4)?;
            c.range(
                "atmosphere.aerosol.lidar_ratio_sr",
                a.lidar_ratio_sr,
                1.0,
                1e4,
            )?;
            if let Some(e) = a.surface_extinction_per_km {
                c.range("atmosphere.aerosol.surface_extinction_per_km", e, 0.0, 1e3)?;
            }
            if a.extinction_from == Some(ExtinctionSource::SurfaceExtinction)
                && a.surface_extinction_per_km.is_none()
            {
                return Err(c.fail(
                    "atmosphere.aerosol.extinction_from",
                    "is \"surface_extinction\" but atmosphere.aerosol.surface_extinction_per_km is not set",
                ));
            }
            c.range(
                "atmosphere.aerosol.reference_wavelength_nm",
                a.reference_wavelength_nm,
                200.0,
                4000.0,
            )?;
            if let Some(x) = a.angstrom_exponent {
                c.range("atmosphere.aerosol.angstrom_exponent", x, -1.0, 4.0)?;
            }
            c.range(
                "atmosphere.aerosol.depolarization",
                a.depolarization,
                0.0,
                1.0,
            )?;
        }
        for (n, l) in self.atmosphere.layers.iter().enumerate() {
            let key = |k: &str| format!("atmosphere.layers[{n}].{k}");
            c.range(&key("base_km"), l.base_km, -1.0, 100.0)?;
            c.range(&key("top_km"), l.top_km, -1.0, 100.0)?;
            if l.top_km <= l.base_km {
                return Err(c.fail(
                    &key("top_km"),
                    format!("must be above base_km ({} km)", l.base_km),
                ));
            }
            c.range(&key("extinction_per_km"), l.extinction_per_km, 0.0, 1e4)?;
            c.range(&key("lidar_ratio_sr"), l.lidar_ratio_sr, 1.0, 1e4)?;
            c.range(&key("depolarization"), l.depolarization, 0.0, 1.0)?;
            c.efficiency(&key("multiple_scattering"), l.multiple_scattering)?;
            self.validate_layer_spectrum(c, n, l)?;
            self.validate_broken(c, &key(""), l)?;
        }
        Ok(())
    }
}
