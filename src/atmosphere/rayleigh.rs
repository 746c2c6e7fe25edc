//! Molecular (Rayleigh) optics of dry air after Bucholtz (1995),
//! "Rayleigh-scattering calculations for the terrestrial atmosphere",
//! Appl. Opt. 34(15), 2765–2773, doi:10.1364/AO.34.002765.
//!
//! * Cross-section per molecule: Bucholtz's four-parameter fit (his Eq. 8 and
//!   Table 3), `σ(λ) = A·λ^−(B + C·λ + D/λ)` cm², λ in µm, one coefficient set for
//!   0.2–0.5 µm and one for λ > 0.5 µm (docs/model.md §4; the same coefficients
//!   are used, e.g., in ECMWF's ecCKD, github.com/ecmwf-ifs/ecckd,
//!   src/ecckd/rayleigh_scattering.h). The fit reproduces his full expression
//!   (Eq. 2 with the Peck & Reeder refractive index, the King factor of the
//!   table below and N_s = 2.54743e19 cm⁻³) to better than 0.1 % at 355, 532
//!   and 1064 nm (see the tests).
//! * Depolarization factor ρn: Bucholtz's Table 1 (0.200–1.000 µm), linearly
//!   interpolated, held constant outside the table (0.02730 from 0.8 µm up, so
//!   1064 nm gets 0.02730). Values as transcribed in public code:
//!   github.com/twright1521/OceanColorPolarizationModel_V1,
//!   getAtmosphericDepolarizationFactor.m ("Table of values from Bucholtz
//!   (1995)"); a second, independent public copy (a Python `rayleigh.py` lidar
//!   module whose repository the code index did not name) has the same 36
//!   values and documents 355 nm 0.03010, 532 nm 0.02842, 1064 nm 0.02730.
//! * Molecular lidar ratio: the whole Rayleigh line (Cabannes + rotational Raman),
//!   from Bucholtz's phase function with depolarization (his Eqs. 12–13, after
//!   Chandrasekhar) `P(θ) = 3/(4(1+2γ))·[(1+3γ) + (1−γ)cos²θ]`, so
//!   `P(π) = 3(1+γ)/(2(1+2γ))` and `S = 4π/P(π) = (8π/3)(1+2γ)/(1+γ)`,
//!   `γ = ρn/(2−ρn)`: 8.50 sr at 532 nm. This is what a lidar with a filter wide
//!   enough to pass the rotational Raman lines measures; the Cabannes line alone
//!   (filters narrower than [`CABANNES_FILTER_MAX_NM`]) carries [`cabannes_fraction`]
//!   (0.975) of the backscatter, so 8.71 sr, with [`cabannes_depolarization`] (0.0037):
//!   `docs/model.md` §4a.

/// Bucholtz (1995) Table 1: wavelength (µm) and depolarization factor ρn (in %).
const DEPOLARIZATION_TABLE: [(f64, f64); 36] = [
    (0.200, 4.545),
    (0.205, 4.384),
    (0.210, 4.221),
    (0.215, 4.113),
    (0.220, 4.004),
    (0.225, 3.895),
    (0.230, 3.785),
    (0.240, 3.675),
    (0.250, 3.565),
    (0.260, 3.455),
    (0.270, 3.400),
    (0.280, 3.289),
    (0.290, 3.233),
    (0.300, 3.178),
    (0.310, 3.178),
    (0.320, 3.122),
    (0.330, 3.066),
    (0.340, 3.066),
    (0.350, 3.010),
    (0.360, 3.010),
    (0.370, 3.010),
    (0.380, 2.955),
    (0.390, 2.955),
    (0.400, 2.955),
    (0.450, 2.899),
    (0.500, 2.842),
    (0.550, 2.842),
    (0.600, 2.786),
    (0.650, 2.786),
    (0.700, 2.786),
    (0.750, 2.786),
    (0.800, 2.730),
    (0.850, 2.730),
    (0.900, 2.730),
    (0.950, 2.730),
    (1.000, 2.730),
];

/// Rayleigh scattering cross-section per air molecule, m², at `wavelength_nm`
/// (Bucholtz 1995 fit; intended for 200 nm – 4 µm, the range of his tables).
pub fn cross_section_m2(wavelength_nm: f64) -> f64 {
    let l = wavelength_nm * 1e-3; // µm
    let (a, b, c, d) = if l <= 0.5 {
        (3.01577e-28, 3.55212, 1.35579, 0.11563)
    } else {
        (4.01061e-28, 3.99668, 1.10298e-3, 2.71393e-2)
    };
    let sigma_cm2 = a * l.powf(-(b + c * l + d / l));
    sigma_cm2 * 1e-4
}

/// Depolarization factor ρn of air at `wavelength_nm` (Bucholtz 1995 Table 1,
/// linear interpolation; clamped to the end values outside 200–1000 nm).
pub fn depolarization_rho_n(wavelength_nm: f64) -> f64 {
    let l = wavelength_nm * 1e-3;
    let t = &DEPOLARIZATION_TABLE;
    let percent = if l <= t[0].0 {
        t[0].1
    } else if l >= t[t.len() - 1].0 {
        t[t.len() - 1].1
    } else {
        let i = t.partition_point(|&(w, _)| w <= l) - 1;
        let (w0, r0) = t[i];
        let (w1, r1) = t[i + 1];
        r0 + (l - w0) / (w1 - w0) * (r1 - r0)
    };
    percent * 1e-2
}

/// γ = ρn/(2 − ρn) (Bucholtz Eq. 13); also the linear depolarization ratio of
/// the molecular backscatter (whole Rayleigh line).
pub fn gamma(rho_n: f64) -> f64 {
    rho_n / (2.0 - rho_n)
}

/// Molecular extinction-to-backscatter ratio, sr:
/// `S_mol = (8π/3)·(1 + 2γ)/(1 + γ)`, γ = [`gamma`]`(rho_n)`.
pub fn lidar_ratio_sr(rho_n: f64) -> f64 {
    let g = gamma(rho_n);
    8.0 * std::f64::consts::PI / 3.0 * (1.0 + 2.0 * g) / (1.0 + g)
}

/// Anisotropy ε = (Δα/ᾱ)² of the air molecule's polarizability from the depolarization
/// factor: `ρn = 6ε/(45 + 7ε)` ⇒ `ε = 45ρn/(6 − 7ρn)` (She 2001, Appl. Opt. 40, 4875).
pub fn anisotropy(rho_n: f64) -> f64 {
    45.0 * rho_n / (6.0 - 7.0 * rho_n)
}

/// Linear depolarization ratio of the backscattered Cabannes line (the central line
/// without the rotational Raman wings): `δ_C = 3ε/(180 + 4ε)`, 0.0036 at 532 nm against
/// `3ε/(45 + 4ε)` = [`gamma`] = 0.0144 for the whole line (She 2001; Behrendt & Nakamura
/// 2002, Opt. Express 10, 805).
pub fn cabannes_depolarization(rho_n: f64) -> f64 {
    let e = anisotropy(rho_n);
    3.0 * e / (180.0 + 4.0 * e)
}

/// The Cabannes line's share of the whole line's backscatter: the isotropic part and a
/// quarter of the anisotropic part, `(45 + 7ε/4)/(45 + 7ε)`: 0.975 at 532 nm.
pub fn cabannes_fraction(rho_n: f64) -> f64 {
    let e = anisotropy(rho_n);
    (45.0 + 1.75 * e) / (45.0 + 7.0 * e)
}

/// Widest filter (full width, nm) that `line = "auto"` takes for the Cabannes line alone.
/// The nearest rotational Raman lines of N2 and O2 lie 0.338 and 0.407 nm from a 532 nm
/// line (`rotational_raman`), so a filter narrower than 0.4 nm keeps them out (as does
/// one up to 0.676 nm: `line = "filter"` places the lines; docs/model.md §4a).
pub const CABANNES_FILTER_MAX_NM: f64 = 0.4;

/// Molecular extinction coefficient α_mol = N·σ, m⁻¹.
pub fn extinction_per_m(number_density_m3: f64, wavelength_nm: f64) -> f64 {
    number_density_m3 * cross_section_m2(wavelength_nm)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cabannes_line_figures_at_532_nm() {
        // She (2001): δ 0.0036 Cabannes vs 0.0144 whole line; 0.976 of the backscatter
        let rho = depolarization_rho_n(532.0);
        assert!((gamma(rho) - 0.0144).abs() < 2e-4, "{}", gamma(rho));
        assert!((cabannes_depolarization(rho) - 0.0036).abs() < 1e-4);
        assert!((cabannes_fraction(rho) - 0.976).abs() < 2e-3);
        // the Cabannes lidar ratio: 8.71 sr (docs/model.md §4a; She 2001: ≈ 8.7)
        assert!((lidar_ratio_sr(rho) / cabannes_fraction(rho) - 8.70).abs() < 0.02);
    }
    use crate::atmosphere::us76;

    fn rel(a: f64, b: f64) -> f64 {
        (a / b - 1.0).abs()
    }

    /// Bucholtz's full expression (his Eq. 2): σ = 24π³(n²−1)²/(λ⁴N_s²(n²+2)²)·F_k,
    /// F_k = (6+3ρn)/(6−7ρn), n of standard air from Peck & Reeder (1972) (his
    /// Eq. 4, λ > 0.23 µm), N_s = 2.54743e19 cm⁻³. Returns m².
    fn full_formula_m2(wavelength_nm: f64) -> f64 {
        let l_um = wavelength_nm * 1e-3;
        let s2 = 1.0 / (l_um * l_um);
        let n = 1.0 + (5_791_817.0 / (238.0185 - s2) + 167_909.0 / (57.362 - s2)) * 1e-8;
        let rho = depolarization_rho_n(wavelength_nm);
        let king = (6.0 + 3.0 * rho) / (6.0 - 7.0 * rho);
        let l_cm = wavelength_nm * 1e-7;
        let ns = 2.54743e19;
        let pi3 = std::f64::consts::PI.powi(3);
        let x = (n * n - 1.0) / (n * n + 2.0);
        24.0 * pi3 / (l_cm.powi(4) * ns * ns) * x * x * king * 1e-4
    }

    #[test]
    fn cross_section_at_lidar_wavelengths() {
        // Fit vs the full formula: 532 nm fit 5.162e-27 cm², full formula 5.165e-27 cm².
        assert!(rel(cross_section_m2(532.0), 5.162e-31) < 5e-4);
        assert!(rel(full_formula_m2(532.0), 5.165e-31) < 5e-4);
        // 355 nm: 2.754e-30 m² (fit), 2.755e-30 (full formula) — the brief's ≈ 2.76e-30.
        assert!(rel(cross_section_m2(355.0), 2.754e-30) < 5e-4);
        // 1064 nm: 3.125e-32 m² by both the fit and the full formula; NOT 3.17e-32.
        assert!(rel(cross_section_m2(1064.0), 3.125e-32) < 5e-4);
        for wl in [355.0, 532.0, 1064.0] {
            assert!(
                rel(cross_section_m2(wl), full_formula_m2(wl)) < 1e-3,
                "fit vs full at {wl} nm"
            );
        }
    }

    #[test]
    fn fit_tracks_full_formula_over_its_range() {
        // The fit stays within 0.3 % of the full formula over 240–1000 nm.
        let mut wl = 240.0;
        while wl <= 1000.0 {
            assert!(
                rel(cross_section_m2(wl), full_formula_m2(wl)) < 3e-3,
                "at {wl} nm"
            );
            wl += 5.0;
        }
    }

    #[test]
    fn fit_switches_coefficients_continuously_at_500_nm() {
        assert!(rel(cross_section_m2(499.999), cross_section_m2(500.001)) < 2e-3);
    }

    #[test]
    fn depolarization_table_values() {
        assert!((depolarization_rho_n(532.0) - 0.0284).abs() < 1e-4);
        assert!((depolarization_rho_n(532.0) - 0.02842).abs() < 1e-9);
        assert!((depolarization_rho_n(355.0) - 0.03010).abs() < 1e-9);
        assert!((depolarization_rho_n(1064.0) - 0.02730).abs() < 1e-9);
        assert!((depolarization_rho_n(150.0) - 0.04545).abs() < 1e-9);
        // Linear between 0.45 µm (2.899 %) and 0.50 µm (2.842 %).
        assert!((depolarization_rho_n(475.0) - 0.028705).abs() < 1e-9);
    }

    #[test]
    fn king_factor_and_gamma_at_532() {
        let rho = depolarization_rho_n(532.0);
        let king = (6.0 + 3.0 * rho) / (6.0 - 7.0 * rho);
        assert!((king - 1.049).abs() < 5e-4, "{king}");
        assert!((gamma(rho) - 0.014415).abs() < 1e-5);
    }

    #[test]
    fn molecular_lidar_ratio() {
        assert!((lidar_ratio_sr(0.0) - 8.0 * std::f64::consts::PI / 3.0).abs() < 1e-12);
        let s = lidar_ratio_sr(depolarization_rho_n(532.0));
        assert!((s - 8.50).abs() < 0.005, "{s}");
    }

    #[test]
    fn sea_level_coefficients_at_532() {
        let n = us76::number_density_m3(0.0);
        let alpha = extinction_per_m(n, 532.0);
        let beta = alpha / lidar_ratio_sr(depolarization_rho_n(532.0));
        assert!(rel(alpha, 1.31e-5) < 0.01, "{alpha}");
        assert!(rel(beta, 1.55e-6) < 0.01, "{beta}");
    }

    #[test]
    fn column_optical_depth_at_532() {
        // Trapezoid over US76, 0–86 km in 10 m steps.
        let dz = 10.0;
        let steps = (us76::TOP_ALTITUDE_M / dz) as usize;
        let mut tau = 0.0;
        for k in 0..steps {
            let z = k as f64 * dz;
            tau += 0.5
                * dz
                * (extinction_per_m(us76::number_density_m3(z), 532.0)
                    + extinction_per_m(us76::number_density_m3(z + dz), 532.0));
        }
        // docs/model.md §4: 0.111 (US76); within 3 % of 0.11.
        assert!(rel(tau, 0.11) < 0.03, "{tau}");
        assert!(rel(tau, 0.111) < 0.01, "{tau}");
    }
}
