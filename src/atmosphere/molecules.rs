//! The molecules of the atmosphere (model.md §4): where their number density comes from
//! (none, US76, a profile file), their scattering at the laser line and their state.

use super::profile_file::MolecularProfile;
use super::us76;
use crate::constants::BOLTZMANN_J_PER_K;

/// Where the molecular number density comes from.
#[derive(Debug, Clone)]
pub enum MolecularSource {
    /// No molecules.
    None,
    /// U.S. Standard Atmosphere 1976 (embedded, up to 86 km).
    Us76,
    /// A tabulated profile read from a file.
    Profile(MolecularProfile),
}

/// Molecular scattering: Bucholtz (1995) cross-section and lidar ratio at the laser wavelength.
#[derive(Debug, Clone)]
pub struct Molecules {
    /// Number density source.
    pub source: MolecularSource,
    /// Rayleigh cross-section per molecule σ(λ), m².
    pub cross_section_m2: f64,
    /// Molecular lidar ratio of the part of the line the filter passes, sr:
    /// `S_mol = (8π/3)(1+2γ)/(1+γ)` for the whole line, divided by the share the filter
    /// passes (the Cabannes fraction for the Cabannes line; docs/model.md §4a).
    pub lidar_ratio_sr: f64,
    /// Linear depolarization ratio of that part's backscatter: `γ = ρn/(2−ρn)` for the
    /// whole line, `3ε/(180+4ε)` for the Cabannes line, between them for the Cabannes
    /// line with some rotational Raman lines (`rotational_raman::seen_line`).
    pub depolarization: f64,
    /// Which part of the elastic molecular line the channel's filter passes.
    pub part: LinePart,
    /// For a profile file that ends below the US76 top (86 km): the factor by which US76
    /// continues it above its top row, `N_file(top)/N_US76(top)`, so that the density is
    /// continuous there.
    pub us76_above_scale: Option<f64>,
}

impl Molecules {
    /// Number density at altitude `z_m`, m⁻³.
    pub fn number_density_m3(&self, z_m: f64) -> f64 {
        match &self.source {
            MolecularSource::None => 0.0,
            MolecularSource::Us76 => us76::number_density_m3(z_m),
            MolecularSource::Profile(p) => match self.us76_above_scale {
                Some(scale) if z_m > p.top_altitude_m() => scale * us76::number_density_m3(z_m),
                _ => p.number_density_m3(z_m),
            },
        }
    }

    /// A note for the run summary when a profile file is continued with US76 above its
    /// top.
    pub fn continuation_note(&self) -> Option<String> {
        let (MolecularSource::Profile(p), Some(scale)) = (&self.source, self.us76_above_scale)
        else {
            return None;
        };
        Some(format!(
            "lidarsim: note: the molecular profile ends at {:.1} km; above it the US Standard \
             Atmosphere 1976 continues it (to 86 km), scaled by {scale:.4} to match at the junction",
            p.top_altitude_m() / 1e3
        ))
    }

    /// Altitude above which there are no molecules, m.
    pub fn top_m(&self) -> f64 {
        match &self.source {
            MolecularSource::None => f64::NEG_INFINITY,
            MolecularSource::Us76 => us76::TOP_ALTITUDE_M,
            MolecularSource::Profile(p) => match self.us76_above_scale {
                Some(_) => us76::TOP_ALTITUDE_M,
                None => p.top_altitude_m(),
            },
        }
    }

    /// The molecular state at altitude `z_m`: US76's pressure and temperature, a
    /// profile file's (interpolated log-linearly in p, `T = p/(k_B·N)`), or scaled US76
    /// above a profile's top (p scaled as N is, US76's T).
    pub fn state_at(&self, z_m: f64) -> MolecularState {
        let n = self.number_density_m3(z_m);
        // US76 has a state up to its top (where its N > 0), none above
        let us76 = |z: f64, scale: f64| match us76::state(z.max(us76::BOTTOM_ALTITUDE_M)) {
            Some(s) => (scale * s.pressure_pa, s.temperature_k),
            None => (f64::NAN, f64::NAN),
        };
        let (pressure_pa, temperature_k) = match &self.source {
            MolecularSource::None => (f64::NAN, f64::NAN),
            MolecularSource::Us76 => us76(z_m, 1.0),
            MolecularSource::Profile(p) => match self.us76_above_scale {
                Some(scale) if z_m > p.top_altitude_m() => us76(z_m, scale),
                _ => match p.pressure_pa(z_m) {
                    Some(pa) if n > 0.0 => (pa, pa / (BOLTZMANN_J_PER_K * n)),
                    _ => (f64::NAN, f64::NAN),
                },
            },
        };
        MolecularState {
            pressure_pa,
            temperature_k,
            number_density_m3: n,
            water_vapour_mixing_ratio: f64::NAN,
        }
    }

    /// `α_mol = N·σ`, m⁻¹.
    pub fn extinction_per_m(&self, z_m: f64) -> f64 {
        self.number_density_m3(z_m) * self.cross_section_m2
    }
}

/// The part of the elastic molecular line a channel's filter passes (docs/model.md §4a).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinePart {
    /// The Cabannes line alone.
    Cabannes,
    /// The Cabannes line and some of the rotational Raman lines.
    CabannesAndSomeRotationalRaman,
    /// The whole Rayleigh line, rotational Raman wings included.
    Whole,
}

impl LinePart {
    /// The name the raw file gives it (`beta_mol`'s `line`, `molecular_line`).
    pub fn name(self) -> &'static str {
        match self {
            LinePart::Cabannes => "cabannes",
            LinePart::CabannesAndSomeRotationalRaman => "cabannes+partial_rr",
            LinePart::Whole => "whole",
        }
    }
}

/// The molecular state at one altitude (model.md §8): what the number density comes
/// from. Pressure and temperature are NaN where the source does not give them (a profile
/// file of number densities, no molecules, above the US76 top); the raw file marks them
/// missing there (`_FillValue`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MolecularState {
    /// Pressure, Pa.
    pub pressure_pa: f64,
    /// Temperature, K.
    pub temperature_k: f64,
    /// Number density, m⁻³: the one the model uses, `p/(k_B·T)` where p and T are known.
    pub number_density_m3: f64,
    /// Mass mixing ratio of water vapour to dry air, kg kg⁻¹ (NaN where the scene has no
    /// water-vapour profile; `Atmosphere::state_at` fills it).
    pub water_vapour_mixing_ratio: f64,
}
