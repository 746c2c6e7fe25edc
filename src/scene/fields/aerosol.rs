//! The aerosol of a model-field column from its CAMS species (docs/model.md §4l): each
//! level's species through ECMWF's optics table ([`AerosolOpticsTable`]) at the laser
//! wavelength, and, for a Raman channel, at its detected line too, the species'
//! depolarization from the defaults or the config's overrides, and the share of each
//! species the truth reports (`alpha_aer_<species>`, docs/file-format.md).

use crate::atmosphere::aerosol_optics_table::AerosolOpticsTable;
use crate::atmosphere::aerosol_species::{
    CAMS_SPECIES, particle_depolarization_or, relative_humidity_over_water,
};
use crate::atmosphere::cloud_optics::air_density;
use crate::config::{AerosolDepolarization, LayerConfig, LayerKind, SpeciesExtinction};
use crate::error::{Error, Result};

use super::column::FieldColumn;

/// What turns a column's species into aerosol layers: the table, the wavelengths and
/// the depolarization overrides.
#[derive(Debug, Clone)]
pub struct FieldAerosol {
    /// ECMWF's aerosol optics table.
    pub table: AerosolOpticsTable,
    /// The laser wavelength, m (a wavelength of the table's `wavelength_mono`).
    pub wavelength_m: f64,
    /// A Raman channel's detected line, m: its layers carry the extinction there as an
    /// Ångström exponent (within the table's wavelengths, [`AerosolOpticsTable::mass_extinction_at`]).
    pub line_m: Option<f64>,
    /// `scene.model_fields.aerosol_depolarization`.
    pub depolarization: AerosolDepolarization,
}

impl FieldAerosol {
    /// The table at `path`, checked to hold the laser wavelength `wavelength_m` and to
    /// reach the line `line_m`.
    pub fn read(
        path: &std::path::Path,
        wavelength_m: f64,
        line_m: Option<f64>,
        depolarization: AerosolDepolarization,
    ) -> Result<Self> {
        let table = AerosolOpticsTable::read(path)?;
        table.wavelength_index(wavelength_m)?;
        if let Some(l) = line_m {
            table.bracket(l)?;
        }
        Ok(FieldAerosol {
            table,
            wavelength_m,
            line_m,
            depolarization,
        })
    }

    /// The aerosol layers of column `c`: at each level with aerosol, `ρ_air = p/(R_d·T_v)`,
    /// the RH over water from q, T, p, and per species `α_s = ρ_air·mmr_s·k_ext,s(RH, λ)`,
    /// `β_s = α_s/S_s` from the table; the level's layer has `α = Σα_s`, lidar ratio
    /// `α/Σβ_s` and the depolarization of the mixture,
    /// `δ = Σβ_s·δ_s/(1 + δ_s) / Σβ_s/(1 + δ_s)` (the ratio of the species' summed
    /// perpendicular to summed parallel backscatter, so that the layer's `β⊥` is the
    /// species' sum exactly). With a Raman line `λ_R`, the layer's Ångström exponent
    /// `å = ln(α/α_R)/ln(λ_R/λ)` (`α_R = Σ ρ_air·mmr_s·k_ext,s(RH, λ_R)`) makes its
    /// extinction at `λ_R` equal α_R; each species carries its own likewise (the truth's).
    pub fn layers(&self, c: &FieldColumn) -> Result<Vec<LayerConfig>> {
        let mut out = Vec::new();
        for (k, l) in c.levels.iter().enumerate() {
            if l.aerosol_mmr.iter().all(|x| *x <= 0.0) {
                continue;
            }
            let rho = air_density(l.p_pa, l.t_k, l.q);
            let rh = relative_humidity_over_water(l.q, l.t_k, l.p_pa);
            let (mut alpha, mut alpha_line, mut parallel, mut perpendicular) = (0.0, 0.0, 0.0, 0.0);
            let mut species = Vec::new();
            for (i, (s, mmr)) in CAMS_SPECIES.iter().zip(l.aerosol_mmr).enumerate() {
                if mmr <= 0.0 {
                    continue;
                }
                let (k_ext, lidar_ratio) = self.table.optics(s, rh, self.wavelength_m)?;
                let delta = particle_depolarization_or(s, self.wavelength_m, &self.depolarization)
                    .ok_or_else(|| {
                        Error::Unsupported(format!(
                            "{}: no default depolarization at {} nm (only 355, 532, 1064 nm): \
                             give scene.model_fields.aerosol_depolarization",
                            s.short_name,
                            self.wavelength_m * 1e9
                        ))
                    })?;
                let a = rho * mmr * k_ext;
                let beta = a / lidar_ratio;
                alpha += a;
                parallel += beta / (1.0 + delta);
                perpendicular += beta * delta / (1.0 + delta);
                let a_line = match self.line_m {
                    Some(line) => rho * mmr * self.table.mass_extinction_at(s, rh, line)?,
                    None => a,
                };
                if (a > 0.0) != (a_line > 0.0) {
                    return Err(Error::Unsupported(format!(
                        "{}: {}'s mass extinction is 0 at one of {} nm and the Raman line {} nm \
                         but not the other: no Ångström law joins them",
                        self.table.path.display(),
                        s.short_name,
                        self.wavelength_m * 1e9,
                        self.line_m.unwrap_or(self.wavelength_m) * 1e9
                    )));
                }
                alpha_line += a_line;
                species.push(SpeciesExtinction {
                    species: i,
                    extinction_per_km: a * 1e3,
                    angstrom_exponent: self.exponent(a, a_line),
                });
            }
            if alpha <= 0.0 || parallel <= 0.0 {
                continue;
            }
            out.push(LayerConfig {
                kind: LayerKind::Aerosol,
                base_km: c.interfaces_m[k] / 1e3,
                top_km: c.interfaces_m[k + 1] / 1e3,
                extinction_per_km: alpha * 1e3,
                lidar_ratio_sr: alpha / (parallel + perpendicular),
                depolarization: perpendicular / parallel,
                multiple_scattering: 1.0,
                phase: None,
                effective_radius_um: None,
                asymmetry_factor: None,
                angstrom_exponent: Some(self.exponent(alpha, alpha_line)),
                reference_wavelength_nm: Some(self.wavelength_m * 1e9),
                lidar_ratio_sr_by_wavelength: Default::default(),
                cloud_fraction: None,
                cell_length_km: None,
                species: Some(species.into()),
            });
        }
        Ok(out)
    }

    /// The Ångström exponent taking extinction `alpha` at the laser wavelength to
    /// `alpha_line` at the Raman line: `ln(α/α_R)/ln(λ_R/λ)`; 0 without a line or
    /// without extinction at it.
    fn exponent(&self, alpha: f64, alpha_line: f64) -> f64 {
        match self.line_m {
            Some(line) if alpha > 0.0 && alpha_line > 0.0 => {
                (alpha / alpha_line).ln() / (line / self.wavelength_m).ln()
            }
            _ => 0.0,
        }
    }
}
