//! The checks of `[atmosphere]`: the molecular model, the aerosol, every layer (its values
//! at other wavelengths, broken cloud), with the ozone and water-vapour checks in their places.

use crate::config::atmosphere::{ExtinctionSource, LayerConfig, LayerKind, MolecularModel};
use crate::config::scenario::ScenarioConfig;
use crate::config::scene::PlatformKind;
use crate::error::Result;

use super::{Checker, OwnerChecks};

/// A molecular model's name (`atmosphere.molecular.model` or a segment's `molecular`,
/// `key`); a file is read at build, a table checked by its owner (`owners.molecular`).
pub(super) fn check_molecular_model(model: &MolecularModel, key: &str, c: &Checker) -> Result<()> {
    match model {
        MolecularModel::Named(name) if name != "us76" && name != "none" => Err(c.fail(
            key,
            format!(
                "unknown model `{name}`: expected \"us76\", \"none\", {{ file = \"...\" }} or \
                 {{ altitude_km = [...], pressure_hpa = [...], temperature_k = [...] }}"
            ),
        )),
        _ => Ok(()),
    }
}

impl ScenarioConfig {
    pub(super) fn validate_atmosphere(&self, c: &Checker, owners: &OwnerChecks) -> Result<()> {
        let m = &self.atmosphere.molecular;
        check_molecular_model(&m.model, "atmosphere.molecular.model", c)?;
        if let Some(rho) = m.depolarization {
            c.range("atmosphere.molecular.depolarization", rho, 0.0, 0.2)?;
        }
        c.range("atmosphere.molecular.grid_m", m.grid_m, 0.1, 1000.0)?;
        (owners.ozone)(self, c)?;
        (owners.water_vapour)(self, c)?;
        (owners.molecular)(self, c)?;
        (owners.aerosol_species)(self, c)?;
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

    /// A layer's values at other wavelengths: Ångström exponent, reference wavelength and
    /// lidar ratios per wavelength; an aerosol layer seen at another wavelength than its
    /// values' needs its exponent.
    pub(super) fn validate_layer_spectrum(
        &self,
        c: &Checker,
        n: usize,
        l: &LayerConfig,
    ) -> Result<()> {
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

    /// A broken layer: a fraction in (0, 1] with a cell length, on a moving platform.
    pub(super) fn validate_broken(&self, c: &Checker, prefix: &str, l: &LayerConfig) -> Result<()> {
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
}
