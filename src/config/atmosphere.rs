//! `[atmosphere]`: the molecular atmosphere, the background aerosol, the layers, ozone
//! and water vapour.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::defaults::{one, yes};

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
    /// The Cabannes line and the rotational Raman lines of N₂ and O₂ that fall inside the
    /// top-hat `instrument.filter_width_nm` centred on the laser line
    /// (`atmosphere::rotational_raman`).
    Filter,
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
    /// A profile given in the config (a model column's, a sonde's), as a profile file's
    /// `altitude_km pressure_hpa temperature_k` rows.
    Table {
        /// Altitudes above sea level, km, strictly increasing.
        altitude_km: Vec<f64>,
        /// Pressures, hPa, > 0.
        pressure_hpa: Vec<f64>,
        /// Temperatures, K, > 0.
        temperature_k: Vec<f64>,
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
    /// The CAMS species that make a model-field aerosol layer, for the truth
    /// (`src/scene/fields/aerosol.rs`); not a config key (None in a config's layers).
    #[serde(skip)]
    pub species: Option<std::sync::Arc<[SpeciesExtinction]>>,
}

/// One species' part of a layer's extinction (a model-field aerosol layer's
/// [`LayerConfig::species`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeciesExtinction {
    /// The species, 0-based in CAMS's order (`aermr01` at 0).
    pub species: usize,
    /// Its extinction at the layer's `reference_wavelength_nm`, km⁻¹.
    pub extinction_per_km: f64,
    /// Its Ångström exponent: at λ its extinction is `extinction_per_km·(λ_ref/λ)^å`.
    pub angstrom_exponent: f64,
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

    /// Its species' extinctions at `wavelength_nm`, km⁻¹ (`(species, α_s)`; none but in
    /// a model-field aerosol layer), each by its own Ångström exponent as
    /// [`Self::at_wavelength`] scales the layer's.
    pub fn species_at_wavelength(
        &self,
        wavelength_nm: f64,
        instrument_nm: f64,
    ) -> Vec<(usize, f64)> {
        let reference = self.reference_wavelength_nm.unwrap_or(instrument_nm);
        self.species
            .iter()
            .flat_map(|s| s.iter())
            .map(|s| {
                let scale = (reference / wavelength_nm).powf(s.angstrom_exponent);
                (s.species, s.extinction_per_km * scale)
            })
            .collect()
    }
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

fn default_grid_m() -> f64 {
    10.0
}

fn default_reference_wavelength_nm() -> f64 {
    532.0
}
