//! The particles of the atmosphere: the background aerosol profile (paper Eq. 5–6) and
//! the homogeneous aerosol or cloud layers, built from the config at the laser line.

use super::{aerosol_profile, multiple_scattering};
use crate::config::{
    ExtinctionSource, LayerKind, MultipleScatteringModel, ScenarioConfig, StratosphericAerosol,
};

/// The background aerosol of Eq. 5–6: `α_aer(z) = α_aer(0)·Np(z)/Np(0)`.
#[derive(Debug, Clone)]
pub struct BackgroundAerosol {
    /// Near-surface extinction at the laser wavelength, m⁻¹.
    pub surface_extinction_per_m: f64,
    /// Lidar ratio, sr.
    pub lidar_ratio_sr: f64,
    /// Linear depolarization ratio.
    pub depolarization: f64,
    /// Its particles' forward-lobe 1/e half-width Θ, rad (`multiple_scattering`).
    pub forward_lobe_rad: f64,
    /// With a present-day background stratosphere, the laser wavelength, nm (the
    /// stratosphere's extinction is its own, not Elterman's scaled with the surface's).
    pub background_stratosphere_nm: Option<f64>,
}

impl BackgroundAerosol {
    /// Its particles' asymmetry factor (`wide_angle`).
    pub const ASYMMETRY: f64 = multiple_scattering::DEFAULT_AEROSOL_ASYMMETRY;

    /// `α_aer(z)`, m⁻¹ (Eq. 6; with a background stratosphere,
    /// `aerosol_profile::with_background_stratosphere_per_m`).
    pub fn extinction_per_m(&self, z_m: f64) -> f64 {
        match self.background_stratosphere_nm {
            None => self.surface_extinction_per_m * aerosol_profile::relative_concentration(z_m),
            Some(wl) => aerosol_profile::with_background_stratosphere_per_m(
                self.surface_extinction_per_m,
                z_m,
                wl,
            ),
        }
    }
}

/// A homogeneous aerosol or cloud layer.
#[derive(Debug, Clone)]
pub struct Layer {
    /// Cloud or aerosol.
    pub kind: LayerKind,
    /// Base altitude, m.
    pub base_m: f64,
    /// Top altitude, m.
    pub top_m: f64,
    /// Extinction, m⁻¹.
    pub extinction_per_m: f64,
    /// Lidar ratio, sr.
    pub lidar_ratio_sr: f64,
    /// Linear depolarization ratio.
    pub depolarization: f64,
    /// Multiple-scattering factor η_ms on the layer's optical depth (1 but in the
    /// `constant` model).
    pub multiple_scattering: f64,
    /// Its particles' forward-lobe 1/e half-width Θ, rad (`multiple_scattering`).
    pub forward_lobe_rad: f64,
    /// Its particles' asymmetry factor g (`wide_angle`).
    pub asymmetry_factor: f64,
    /// A cloud of liquid droplets (`multiple_scattering::phase`).
    pub water: bool,
    /// A model-field aerosol layer's extinction by CAMS species, m⁻¹ (`(species
    /// 0-based, α_s)`, summing to `extinction_per_m`); empty for any other layer.
    pub species: Vec<(usize, f64)>,
}

impl Layer {
    pub(super) fn contains(&self, z_m: f64) -> bool {
        z_m >= self.base_m && z_m < self.top_m
    }
}

/// The aerosol extinction by CAMS species at `z_m`, m⁻¹, added into `out` (indexed by
/// species, 0-based): the species of the aerosol layers that contain it, as
/// `elastic_optics_at` adds their extinction into `alpha_aer`.
pub fn add_species_extinction(layers: &[Layer], z_m: f64, out: &mut [f64]) {
    for l in layers.iter().filter(|l| l.contains(z_m)) {
        for &(s, a) in &l.species {
            out[s] += a;
        }
    }
}

/// Eq. 5 near-surface extinction at the laser wavelength, from the visibility or from
/// the given surface extinction (scaled by the Ångström exponent), as the config selects.
pub(super) fn background_aerosol(cfg: &ScenarioConfig) -> Option<BackgroundAerosol> {
    let a = cfg.atmosphere.aerosol.as_ref()?;
    let wl = cfg.instrument.wavelength_nm;
    let source = a
        .extinction_from
        .unwrap_or(if a.surface_extinction_per_km.is_some() {
            ExtinctionSource::SurfaceExtinction
        } else {
            ExtinctionSource::Visibility
        });
    let surface_extinction_per_m = match (source, a.surface_extinction_per_km) {
        (ExtinctionSource::SurfaceExtinction, Some(e)) => {
            let q = a
                .angstrom_exponent
                .unwrap_or_else(|| aerosol_profile::kruse_exponent(a.visibility_km));
            e * 1e-3 * (a.reference_wavelength_nm / wl).powf(q)
        }
        _ => aerosol_profile::surface_extinction_per_m(a.visibility_km, wl),
    };
    Some(BackgroundAerosol {
        surface_extinction_per_m,
        lidar_ratio_sr: a.lidar_ratio_sr,
        depolarization: a.depolarization,
        forward_lobe_rad: multiple_scattering::forward_lobe_half_width_rad(
            wl,
            a.effective_radius_um
                .unwrap_or(multiple_scattering::DEFAULT_AEROSOL_RADIUS_UM),
        ),
        background_stratosphere_nm: (a.stratosphere == StratosphericAerosol::Background)
            .then_some(wl),
    })
}

pub(super) fn layers(cfg: &ScenarioConfig) -> Vec<Layer> {
    cfg.atmosphere
        .layers
        .iter()
        .map(|l| {
            let wl = cfg.instrument.wavelength_nm;
            let (extinction_per_km, lidar_ratio_sr) = l.at_wavelength(wl, wl);
            Layer {
                kind: l.kind,
                base_m: l.base_km * 1e3,
                top_m: l.top_km * 1e3,
                extinction_per_m: extinction_per_km * 1e-3,
                lidar_ratio_sr,
                depolarization: l.depolarization,
                // the other models compute the multiply scattered return instead
                multiple_scattering: match cfg.multiple_scattering.model {
                    MultipleScatteringModel::Constant => l.multiple_scattering,
                    _ => 1.0,
                },
                forward_lobe_rad: multiple_scattering::forward_lobe_half_width_rad(
                    wl,
                    multiple_scattering::effective_radius_um(l),
                ),
                asymmetry_factor: multiple_scattering::asymmetry_factor(l),
                water: l.kind == LayerKind::Cloud
                    && multiple_scattering::phase(l) == crate::config::CloudPhase::Water,
                species: l
                    .species_at_wavelength(wl, wl)
                    .into_iter()
                    .map(|(s, a)| (s, a * 1e-3))
                    .collect(),
            }
        })
        .collect()
}
