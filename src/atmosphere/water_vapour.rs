//! Water vapour: a mixing-ratio profile, what an H₂O Raman channel sees (model.md §8
//! "Raman channels"; docs/model.md §4h).
//!
//! **Profile.** `[atmosphere.water_vapour]` gives rows of altitude (km above sea level,
//! strictly increasing) and the mass mixing ratio of water vapour to dry air `w`
//! (g kg⁻¹), as a radiosonde reports it. Between rows `w` is linear in altitude; below
//! the first row it is the first row's value, above the last row 0 (dry: give rows up to
//! the tropopause and beyond). A changing scene's segment may give its own profile.
//!
//! **Number density.** The molecules of water vapour per molecule of the (dry) air the
//! molecular model counts: `N_H2O/N = w·M_d/M_w`, with `M_d` = 28.9644 g mol⁻¹ (U.S.
//! Standard Atmosphere 1976, `us76::M0`) and `M_w` = 18.01528 g mol⁻¹. So the ratio of
//! an H₂O to an N₂ Raman return is `w` times a constant, the relation water-vapour Raman
//! lidars are calibrated with (Whiteman et al. 1992, Appl. Opt. 31, 3068).
//!
//! **Neglected.** Water vapour adds molecules to the dry air the molecular model counts:
//! its own Rayleigh extinction (a water molecule scatters ≈ 0.75 of an air molecule's)
//! and the dry air it displaces change the molecular extinction by < 0.5 % at 10 g kg⁻¹
//! and are not modelled; nor is absorption by water vapour (none at the Raman lines of
//! 355 and 532 nm lasers).
//!
//! Cost: one binary search in the rows per point of an H₂O channel's model and per bin
//! of the truth's `water_vapour_mixing_ratio`; nothing for a scene without a profile.

use crate::config::{Checker, ScenarioConfig, WaterVapourConfig};
use crate::error::Result;

/// Molar mass of water, g mol⁻¹.
pub const WATER_MOLAR_MASS_G_PER_MOL: f64 = 18.015_28;

/// Most rows a profile may have.
pub const MAX_ROWS: usize = 100_000;

/// Largest mixing ratio accepted, g kg⁻¹: saturation over water at 40 °C and 1000 hPa
/// is ≈ 49 g kg⁻¹.
pub const MAX_MIXING_RATIO_G_PER_KG: f64 = 60.0;

/// Checks `[atmosphere.water_vapour]` and every segment's: at least two rows, as many
/// altitudes as mixing ratios, altitudes finite in [−1, 100] km and strictly
/// increasing, mixing ratios finite in [0, 60] g kg⁻¹.
pub fn validate(config: &ScenarioConfig, c: &Checker) -> Result<()> {
    for (prefix, w) in profiles(config) {
        check(w, &prefix, c)?;
    }
    Ok(())
}

/// Every water-vapour profile of a config with its table's key: `[atmosphere.water_vapour]`
/// and each segment's.
pub fn profiles(config: &ScenarioConfig) -> impl Iterator<Item = (String, &WaterVapourConfig)> {
    let base = config
        .atmosphere
        .water_vapour
        .iter()
        .map(|w| ("atmosphere.water_vapour".to_string(), w));
    let segments = config.scene.iter().flat_map(|s| s.segments.iter());
    let own = segments.enumerate().filter_map(|(i, seg)| {
        let w = seg.water_vapour.as_ref()?;
        Some((format!("scene.segments[{i}].water_vapour"), w))
    });
    base.chain(own)
}

/// Whether model fields give every profile its water vapour (their molecules come from
/// the fields: each profile's specific humidity, docs/model.md §4k).
pub fn from_fields(config: &ScenarioConfig) -> bool {
    config
        .scene
        .as_ref()
        .and_then(|s| s.model_fields.as_ref())
        .is_some_and(|m| m.molecules == crate::config::FieldsMolecules::Fields)
}

/// Checks one profile, `prefix` naming its table in errors.
fn check(w: &WaterVapourConfig, prefix: &str, c: &Checker) -> Result<()> {
    let key = |k: &str| format!("{prefix}.{k}");
    let (z, r) = (&w.altitude_km, &w.mixing_ratio_g_per_kg);
    if z.len() < 2 || z.len() > MAX_ROWS {
        return Err(c.fail(
            &key("altitude_km"),
            format!("needs 2 to {MAX_ROWS} rows, has {}", z.len()),
        ));
    }
    if r.len() != z.len() {
        return Err(c.fail(
            &key("mixing_ratio_g_per_kg"),
            format!(
                "has {} values for {} altitudes: give one per altitude",
                r.len(),
                z.len()
            ),
        ));
    }
    for (k, &zk) in z.iter().enumerate() {
        let at = format!("{}[{k}]", key("altitude_km"));
        c.range(&at, zk, -1.0, 100.0)?;
        if k > 0 && zk <= z[k - 1] {
            return Err(c.fail(
                &at,
                format!("must be above the row before ({} km)", z[k - 1]),
            ));
        }
    }
    for (k, &v) in r.iter().enumerate() {
        c.range(
            &format!("{}[{k}]", key("mixing_ratio_g_per_kg")),
            v,
            0.0,
            MAX_MIXING_RATIO_G_PER_KG,
        )?;
    }
    Ok(())
}

/// A checked water-vapour profile.
#[derive(Debug, Clone, PartialEq)]
pub struct WaterVapour {
    /// Altitudes, m, strictly increasing.
    altitude_m: Vec<f64>,
    /// Mass mixing ratios to dry air, kg kg⁻¹.
    mixing_ratio: Vec<f64>,
}

impl WaterVapour {
    /// The profile of a validated `[atmosphere.water_vapour]` table.
    pub fn from_config(w: &WaterVapourConfig) -> Self {
        WaterVapour {
            altitude_m: w.altitude_km.iter().map(|z| z * 1e3).collect(),
            mixing_ratio: w.mixing_ratio_g_per_kg.iter().map(|r| r * 1e-3).collect(),
        }
    }

    /// Mass mixing ratio of water vapour to dry air at `z_m`, kg kg⁻¹: linear between
    /// rows, the first row's value below it, 0 above the last row.
    pub fn mixing_ratio_kg_per_kg(&self, z_m: f64) -> f64 {
        let (z, w) = (&self.altitude_m, &self.mixing_ratio);
        let i = z.partition_point(|&a| a <= z_m);
        if i == 0 {
            return w[0];
        }
        if i == z.len() {
            return if z_m == z[i - 1] { w[i - 1] } else { 0.0 };
        }
        let f = (z_m - z[i - 1]) / (z[i] - z[i - 1]);
        w[i - 1] + f * (w[i] - w[i - 1])
    }

    /// Water molecules per molecule of dry air at `z_m`: `w·M_d/M_w`.
    pub fn molecules_per_air_molecule(&self, z_m: f64) -> f64 {
        self.mixing_ratio_kg_per_kg(z_m) * crate::atmosphere::us76::M0 / WATER_MOLAR_MASS_G_PER_MOL
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn profile() -> WaterVapour {
        WaterVapour::from_config(&WaterVapourConfig {
            altitude_km: vec![0.0, 2.0, 10.0],
            mixing_ratio_g_per_kg: vec![8.0, 4.0, 0.0],
        })
    }

    #[test]
    fn mixing_ratio_is_linear_between_rows_held_below_and_dry_above() {
        let p = profile();
        assert_eq!(p.mixing_ratio_kg_per_kg(-500.0), 8e-3);
        assert_eq!(p.mixing_ratio_kg_per_kg(0.0), 8e-3);
        assert!((p.mixing_ratio_kg_per_kg(1000.0) - 6e-3).abs() < 1e-15);
        assert!((p.mixing_ratio_kg_per_kg(6000.0) - 2e-3).abs() < 1e-15);
        assert_eq!(p.mixing_ratio_kg_per_kg(10_000.0), 0.0);
        assert_eq!(p.mixing_ratio_kg_per_kg(10_001.0), 0.0);
    }

    #[test]
    fn number_ratio_is_the_mass_ratio_times_the_molar_mass_ratio() {
        // 8 g/kg: 0.008 × 28.9644 / 18.01528 = 0.0128622
        let x = profile().molecules_per_air_molecule(0.0);
        assert!((x - 0.012_862_2).abs() < 1e-7, "{x}");
    }
}
