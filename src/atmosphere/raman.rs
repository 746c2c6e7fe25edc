//! Vibrational Raman backscatter by N₂ and H₂O (model.md §8 "Raman channels";
//! docs/model.md §4h): the line a Raman channel detects and the molecule's differential
//! backscatter cross-section, from which `β_R(z) = N_X(z) · dσ_R/dΩ(π)`. N₂ below; H₂O
//! at [`h2o_backscatter_cross_section_m2_sr`] (Eq. R2), its number density from
//! `super::water_vapour`.
//!
//! **Line.** A laser line λ₀ is shifted by the molecule's vibrational wavenumber Δν̃:
//! `1/λ_R = 1/λ₀ − Δν̃` (Stokes side). N₂: Δν̃ = 2330.7 cm⁻¹ (Wandinger 2005, in Weitkamp
//! (ed.), *Lidar*, Springer, p. 251), so 354.7 → 386.67 nm, 532.1 → 607.43 nm and
//! 1064.2 → 1415.2 nm. Wavelengths are taken as given (air), as the ACTRIS ARC does.
//!
//! **Cross-section.** Placzek's polarizability theory for the fundamental (v = 0 → 1) band
//! of a diatomic molecule, summed over the whole band (the pure vibrational Q line and
//! its O, Q, S rotational-vibrational wings), in backscatter (She 2001, Appl. Opt. 40,
//! 4875; Adam 2009, J. Atmos. Oceanic Technol. 26, 1021, Eq. A3 for the population):
//!
//! ```text
//! dσ_R/dΩ(π) = (π²/ε₀²) · λ_R⁻⁴ · b² · P₀(T) · (a′² + 7/45 · γ′²)          (R1)
//! b² = h / (8π² c Δν̃),   P₀(T) = 1 − exp(−h c Δν̃ / (k T))
//! ```
//!
//! with the isotropic and anisotropic polarizability derivatives a′ and γ′ of N₂ at
//! 355 nm (a′² = 2.62e-14, γ′² = 4.23e-14 cm⁴ g⁻¹ in Gaussian units times (4πε₀)²;
//! Wandinger 2005, p. 245) carried to other wavelengths by the dispersion of Oddershede
//! & Svendsen (1982, Chem. Phys. 64, 359), interpolated linearly between their
//! wavelengths (200–2000 nm). This is the ACTRIS ARC's model (arc-actris 1.1.0,
//! `vibrational_raman_N2`, cross_section('full')), which evaluates each line at its own
//! wavelength: (R1) at the Q line's wavelength is 0.04 % (355 nm), 0.06 % (532 nm) and
//! 0.12 % (1064 nm) above ARC's sum (tests/reference_physics.rs checks ARC's figures).
//! The whole band is 2.745e-34 m² sr⁻¹ at 354.7 nm, 4.03e-35 at 532.1 nm: the
//! λ_R⁻⁴ law alone would make 532 nm 12 % too strong against 355 nm (the derivatives'
//! dispersion). Against the classic measurement, Inaba & Kobayasi (1972, Opto-
//! electronics 4, 101): 3.5e-30 cm² sr⁻¹ ± 10 % at 337.1 nm; (R1) gives 3.62e-30.
//!
//! Cost: a few table look-ups per channel, once per run (the cross-section does not
//! depend on altitude but for P₀(T), which differs from 1 by < 1e-4 below 400 K).

use crate::constants::{
    BOLTZMANN_J_PER_K, PLANCK_J_S, SPEED_OF_LIGHT_M_PER_S, VACUUM_PERMITTIVITY_F_PER_M,
};

/// Vibrational wavenumber of N₂ (the Q branch of the fundamental), m⁻¹: 2330.7 cm⁻¹
/// (Wandinger 2005, p. 251).
pub const N2_SHIFT_PER_M: f64 = 233_070.0;

/// Vibrational wavenumber of H₂O (the ν₁ Q branch), m⁻¹: 3652 cm⁻¹ (Wandinger 2005,
/// p. 251): 354.7 → 407.5 nm, 532.1 → 660.4 nm.
pub const H2O_SHIFT_PER_M: f64 = 365_200.0;

/// The whole H₂O stretching band's differential backscatter cross-section excited at
/// 354.7 nm, m² sr⁻¹: Avila, Fernández, Tejeda & Montero (2004, J. Mol. Spectrosc. 228,
/// 38), Table 4 (819 lines of the ν₁ and ν₃ bands and 2ν₂), their Eq. 15
/// `σ_line = ν̃_s⁴·exp(−E/kT)/Z(T)·Φ`, summed over the ν₁ and ν₃ lines and both of the
/// table's polarization components (parallel and perpendicular), at 288.15 K.
pub const H2O_BAND_CROSS_SECTION_355_M2_SR: f64 = 9.087e-34;

/// The laser line of [`H2O_BAND_CROSS_SECTION_355_M2_SR`], nm.
pub const H2O_REFERENCE_LASER_NM: f64 = 354.7;

/// Volume (number) fraction of N₂ in dry air (U.S. Standard Atmosphere 1976, Table 3).
pub const N2_FRACTION_OF_AIR: f64 = 0.780_84;

/// Oddershede & Svendsen (1982): wavelengths (nm) of their dynamic polarizability
/// derivatives of N₂, with a′ and γ′ in atomic units (as tabulated in ARC).
const DISPERSION_NM: [f64; 9] = [
    200.0, 351.1, 363.8, 435.8, 457.9, 488.0, 514.5, 632.8, 2000.0,
];
const ALPHA_PRIME_AU: [f64; 9] = [6.64, 5.23, 5.19, 5.05, 5.02, 4.98, 4.95, 4.88, 4.73];
const GAMMA_PRIME_AU: [f64; 9] = [8.66, 6.78, 6.74, 6.54, 6.50, 6.45, 6.42, 6.16, 6.12];

/// a′² and γ′² of N₂ at 355 nm, cm⁴ g⁻¹ (Gaussian units; Wandinger 2005, p. 245).
const ALPHA_PRIME_SQ_355_CGS: f64 = 2.62e-14;
const GAMMA_PRIME_SQ_355_CGS: f64 = 4.23e-14;

/// The Stokes line of a laser line `laser_nm` shifted by `shift_per_m`, nm.
pub fn shifted_wavelength_nm(laser_nm: f64, shift_per_m: f64) -> f64 {
    1.0 / (1.0 / laser_nm - shift_per_m * 1e-9)
}

/// Linear interpolation in the dispersion table, clamped to its ends.
fn dispersion(values: &[f64; 9], wavelength_nm: f64) -> f64 {
    let x = wavelength_nm.clamp(DISPERSION_NM[0], DISPERSION_NM[8]);
    let i = DISPERSION_NM.partition_point(|&w| w <= x).clamp(1, 8);
    let (x0, x1) = (DISPERSION_NM[i - 1], DISPERSION_NM[i]);
    values[i - 1] + (values[i] - values[i - 1]) * (x - x0) / (x1 - x0)
}

/// A polarizability derivative squared at `laser_nm` in SI units (the Gaussian value
/// times (4πε₀)²): the 355 nm value scaled by the squared dispersion ratio.
fn derivative_sq_si(sq_355_cgs: f64, table: &[f64; 9], laser_nm: f64) -> f64 {
    let ratio = dispersion(table, laser_nm) / dispersion(table, 355.0);
    let four_pi_eps0 = 4.0 * std::f64::consts::PI * VACUUM_PERMITTIVITY_F_PER_M;
    sq_355_cgs * four_pi_eps0 * four_pi_eps0 * ratio * ratio
}

/// Fraction of N₂ molecules in the vibrational ground state at `temperature_k`
/// (harmonic oscillator; Adam 2009, Eq. A3).
pub fn n2_ground_state_fraction(temperature_k: f64) -> f64 {
    let x =
        PLANCK_J_S * SPEED_OF_LIGHT_M_PER_S * N2_SHIFT_PER_M / (BOLTZMANN_J_PER_K * temperature_k);
    -(-x).exp_m1()
}

/// Differential backscatter cross-section of the whole N₂ vibrational Raman band
/// excited at `laser_nm` by molecules at `temperature_k`, m² sr⁻¹ (Eq. R1).
pub fn n2_backscatter_cross_section_m2_sr(laser_nm: f64, temperature_k: f64) -> f64 {
    use std::f64::consts::PI;
    let line_m = shifted_wavelength_nm(laser_nm, N2_SHIFT_PER_M) * 1e-9;
    let b_sq = PLANCK_J_S / (8.0 * PI * PI * SPEED_OF_LIGHT_M_PER_S * N2_SHIFT_PER_M);
    let a_sq = derivative_sq_si(ALPHA_PRIME_SQ_355_CGS, &ALPHA_PRIME_AU, laser_nm);
    let g_sq = derivative_sq_si(GAMMA_PRIME_SQ_355_CGS, &GAMMA_PRIME_AU, laser_nm);
    let eps0_sq = VACUUM_PERMITTIVITY_F_PER_M * VACUUM_PERMITTIVITY_F_PER_M;
    PI * PI / eps0_sq / line_m.powi(4)
        * b_sq
        * n2_ground_state_fraction(temperature_k)
        * (a_sq + 7.0 / 45.0 * g_sq)
}

/// Differential backscatter cross-section of the H₂O stretching band excited at
/// `laser_nm`, m² sr⁻¹ (Eq. R2): Avila et al.'s band at 354.7 nm carried by the fourth
/// power of the Raman line's wavenumber, as their Eq. 15 carries each line:
///
/// ```text
/// dσ_H2O/dΩ(π; λ₀) = σ_A · (ν̃_R(λ₀)/ν̃_R(354.7 nm))⁴,   ν̃_R = 1/λ₀ − 3652 cm⁻¹       (R2)
/// ```
///
/// Against the band summed line by line at each laser line: 0.08 % above at 337.1 nm,
/// 0.4 % above at 532.1 nm (1.312e-34 m² sr⁻¹). The band's temperature dependence
/// (−0.1 % from 250 to 300 K) is neglected. It is 3.31 times the N₂ band (R1) at 354.7
/// nm, 3.26 times at 532.1 nm; 77.4 % of it lies in the ν₁ Q branch (3600–3670 cm⁻¹,
/// both polarization components: 7.032e-34 of 9.084e-34 in Avila et al.'s lines at
/// 354.7 nm; docs/model.md §4h), which a narrow filter passes alone
/// (`band_transmission`).
pub fn h2o_backscatter_cross_section_m2_sr(laser_nm: f64) -> f64 {
    let line_wavenumber = |nm: f64| 1.0 / shifted_wavelength_nm(nm, H2O_SHIFT_PER_M);
    H2O_BAND_CROSS_SECTION_355_M2_SR
        * (line_wavenumber(laser_nm) / line_wavenumber(H2O_REFERENCE_LASER_NM)).powi(4)
}

#[cfg(test)]
mod tests {
    //! Internal properties; the comparison with ARC and with Inaba & Kobayasi is in
    //! tests/reference_physics.rs.
    use super::*;

    #[test]
    fn dispersion_reproduces_the_table_and_interpolates_between() {
        for (k, &w) in DISPERSION_NM.iter().enumerate() {
            assert_eq!(dispersion(&ALPHA_PRIME_AU, w), ALPHA_PRIME_AU[k]);
        }
        // halfway between 435.8 and 457.9 nm
        let mid = dispersion(&GAMMA_PRIME_AU, (435.8 + 457.9) / 2.0);
        assert!((mid - 6.52).abs() < 1e-12, "{mid}");
        // clamped beyond the table
        assert_eq!(dispersion(&ALPHA_PRIME_AU, 100.0), 6.64);
        assert_eq!(dispersion(&ALPHA_PRIME_AU, 5000.0), 4.73);
    }

    #[test]
    fn shift_moves_to_the_red_and_back() {
        let line = shifted_wavelength_nm(532.1, N2_SHIFT_PER_M);
        assert!(line > 532.1);
        assert!((shifted_wavelength_nm(line, -N2_SHIFT_PER_M) - 532.1).abs() < 1e-9);
    }

    /// Eq. R2 against Avila et al.'s (2004) band summed line by line (their Table 4 and
    /// Eq. 15, ν₁ + ν₃, both polarizations, 288.15 K) at the other laser lines:
    /// 1.148e-33 m² sr⁻¹ at 337.1 nm and 1.312e-34 at 532.1 nm. A 1 % error in the
    /// anchor or the λ⁻⁴ law's exponent off by 0.1 fails.
    #[test]
    fn the_water_band_follows_the_line_sums_at_other_laser_lines() {
        for (laser_nm, sum, tol) in [(337.1, 1.148e-33, 2e-3), (532.1, 1.312e-34, 5e-3)] {
            let got = h2o_backscatter_cross_section_m2_sr(laser_nm);
            assert!(
                (got / sum - 1.0).abs() < tol,
                "{laser_nm} nm: {got:e} vs {sum:e}"
            );
        }
        assert_eq!(h2o_backscatter_cross_section_m2_sr(354.7), 9.087e-34);
    }

    #[test]
    fn ground_state_fraction_is_nearly_one_at_air_temperatures() {
        let p = n2_ground_state_fraction(288.15);
        // exp(−11.65) ≈ 8.8e-6
        assert!((1.0 - p - 8.8e-6).abs() < 0.2e-6, "{p}");
        assert!(n2_ground_state_fraction(1000.0) < p);
    }
}
