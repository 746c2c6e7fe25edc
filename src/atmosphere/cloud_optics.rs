//! Cloud optics from a model's water contents (docs/model.md §4k): extinction from the
//! mass mixing ratio and the effective radius in geometric optics, and the lidar ratio,
//! depolarization and effective radius of each phase.
//!
//! **Extinction.** For particles much larger than the wavelength the extinction
//! efficiency is Q = 2 (the extinction paradox), so a population of effective radius
//! r_e = ⟨r³⟩/⟨r²⟩ and water content W = ρ_air·q has
//! `α = (3/4)·Q·W/(ρ_p·r_e) = (3/4)·Q·ρ_air·q/(ρ_p·r_e)` — the formula of ALCF
//! (Kuma et al. 2021) and COSP for liquid, with ρ_p = ρ_w = 1000 kg m⁻³. Ice uses the
//! same geometric-optics form with ρ_p = ρ_i = 917 kg m⁻³ (solid ice) and, where the
//! model gives no radius, the temperature law of Ou & Liou (1995) below. Q = 2 does
//! not depend on the wavelength, so neither does the extinction.
//!
//! **Air density** `ρ_air = p/(R_d·T_v)` with the virtual temperature
//! `T_v = T·(1 + 0.6078·q)` (R_d/R_v = 0.622) and R_d = 287.0597 J kg⁻¹ K⁻¹ (the IFS
//! value, ECMWF IFS documentation Part IV).

use crate::config::CloudPhase;

/// Density of liquid water, kg m⁻³.
pub const WATER_DENSITY_KG_M3: f64 = 1000.0;
/// Density of solid ice, kg m⁻³.
pub const ICE_DENSITY_KG_M3: f64 = 917.0;
/// Gas constant of dry air, J kg⁻¹ K⁻¹ (IFS).
pub const DRY_AIR_GAS_CONSTANT: f64 = 287.0597;
/// `R_v/R_d − 1`: the virtual-temperature factor of specific humidity.
pub const VIRTUAL_FACTOR: f64 = 1.0 / 0.622 - 1.0;

/// Lidar ratio of liquid water cloud, sr: 18.8 sr (O'Connor, Illingworth & Gaussiat
/// 2004, J. Atmos. Oceanic Technol. 21, 777–786), nearly independent of droplet size and
/// wavelength for droplets much larger than the wavelength; used at every wavelength.
pub const WATER_LIDAR_RATIO_SR: f64 = 18.8;
/// Depolarization of singly scattered light by droplets: 0 (spheres; multiple
/// scattering adds its own, §4j).
pub const WATER_DEPOLARIZATION: f64 = 0.0;
/// Lidar ratio of ice cloud, sr: 29 sr, the mean of Chen, Chiang & Nee (2002, Appl.
/// Opt. 41, 6470–6476) for cirrus at 532 nm (29 ± 12 sr); used at every wavelength.
pub const ICE_LIDAR_RATIO_SR: f64 = 29.0;
/// Linear depolarization ratio of ice cloud: 0.4, within the 0.3–0.5 of ice crystals
/// reported by Sassen (1991, Bull. Amer. Meteor. Soc. 72, 1848–1866).
pub const ICE_DEPOLARIZATION: f64 = 0.4;

/// Air density, kg m⁻³, at pressure `p_pa`, temperature `t_k` and specific humidity `q`.
pub fn air_density(p_pa: f64, t_k: f64, q: f64) -> f64 {
    p_pa / (DRY_AIR_GAS_CONSTANT * t_k * (1.0 + VIRTUAL_FACTOR * q))
}

/// Extinction, m⁻¹, of particles of `phase` at mass mixing ratio `q_cloud` (kg kg⁻¹)
/// in air of density `rho_air` (kg m⁻³), effective radius `r_e_um` (µm), extinction
/// efficiency `efficiency`: `(3/4)·Q·ρ_air·q/(ρ_p·r_e)`.
pub fn extinction_per_m(
    phase: CloudPhase,
    q_cloud: f64,
    rho_air: f64,
    r_e_um: f64,
    efficiency: f64,
) -> f64 {
    let rho_p = match phase {
        CloudPhase::Water => WATER_DENSITY_KG_M3,
        CloudPhase::Ice => ICE_DENSITY_KG_M3,
    };
    0.75 * efficiency * rho_air * q_cloud / (rho_p * r_e_um * 1e-6)
}

/// Effective radius of ice crystals at temperature `t_k`, µm: half the effective size
/// `D_e = 326.3 + 12.42·T + 0.197·T² + 0.0012·T³` (µm, T in °C) of Ou & Liou (1995,
/// Atmos. Res. 35, 127–138), with T held within the law's −60…−20 °C (15.6 µm at
/// −60 °C and colder, 73.6 µm at −20 °C and warmer).
pub fn ice_effective_radius_um(t_k: f64) -> f64 {
    let t = (t_k - 273.15).clamp(-60.0, -20.0);
    0.5 * (326.3 + 12.42 * t + 0.197 * t * t + 0.0012 * t * t * t)
}

/// Lidar ratio (sr) and depolarization of `phase`.
pub fn phase_optics(phase: CloudPhase) -> (f64, f64) {
    match phase {
        CloudPhase::Water => (WATER_LIDAR_RATIO_SR, WATER_DEPOLARIZATION),
        CloudPhase::Ice => (ICE_LIDAR_RATIO_SR, ICE_DEPOLARIZATION),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ice_radius_follows_ou_and_liou() {
        // D_e at −40 °C by hand: 326.3 − 496.8 + 315.2 − 76.8 = 67.9 µm
        assert!((ice_effective_radius_um(233.15) - 33.95).abs() < 1e-9);
        assert!((ice_effective_radius_um(150.0) - 15.55).abs() < 1e-9);
        assert!((ice_effective_radius_um(273.0) - 73.55).abs() < 1e-9);
    }

    #[test]
    fn a_gram_per_cubic_metre_of_10_um_droplets() {
        // W = 1 g m⁻³, r_e = 10 µm: α = 1.5·1e-3/(1000·1e-5) = 0.15 m⁻¹
        let a = extinction_per_m(CloudPhase::Water, 1e-3, 1.0, 10.0, 2.0);
        assert!((a - 0.15).abs() < 1e-15);
    }
}
