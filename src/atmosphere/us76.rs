//! U.S. Standard Atmosphere 1976 (US76), −5 km to 86 km geometric altitude.
//!
//! Computed from the definition, not looked up: U.S. Standard Atmosphere, 1976,
//! NOAA-S/T 76-1562 / NASA-TM-X-74335 (U.S. Government Printing Office,
//! Washington, D.C., 1976), Part 1, §1.2–1.3:
//!
//! * geopotential altitude `H = r0·Z/(r0 + Z)` (Eq. 18), `r0 = 6 356 766 m`;
//! * seven geopotential layers with base `H_b` and molecular-scale temperature
//!   gradient `L_M,b` (Table 4); `T_M = T_M,b + L_M,b·(H − H_b)` (Eq. 23);
//! * hydrostatic pressure (Eqs. 33a/33b):
//!   `P = P_b·[T_M,b/(T_M,b + L_M,b·(H − H_b))]^(g0'·M0/(R*·L_M,b))` for `L_M,b ≠ 0`,
//!   `P = P_b·exp(−g0'·M0·(H − H_b)/(R*·T_M,b))` for `L_M,b = 0`,
//!   with `P_0 = 101 325 Pa`, `T_M,0 = 288.15 K`, and the layer-base pressures
//!   obtained by chaining the layers upward;
//! * kinetic temperature `T = T_M·(M/M0)`, with the mean-molecular-weight ratio
//!   `M/M0` of Table 8 (1 below 80 km, falling to 0.999579 at 86 km; linear
//!   interpolation between its 0.5 km entries);
//! * number density `N = P/(k_B·T)` with the CODATA k_B of `crate::constants` (the
//!   Standard's Eq. 29, `N_A·P/(R*·T)`, uses its own `N_A/R*`, 2e-5 above `1/k_B`: its
//!   Table I's 2.5470e25 m⁻³ at sea level is 2.5469e25 here). So the raw file's
//!   `number_density`, `pressure` and `temperature` satisfy the ideal-gas law with the
//!   constant a reader has (docs/file-format.md).
//!
//! The defining constants of the Standard (`R* = 8.31432 J mol⁻¹ K⁻¹`,
//! `M0 = 28.9644 kg kmol⁻¹`, `g0' = 9.80665 m² s⁻² m'⁻¹`) are kept here, as part of the
//! model's definition, rather than the CODATA values in `crate::constants`: they
//! reproduce the published pressures and temperatures digit for digit.
//!
//! The layer structure extends the first layer (−6.5 K/km) down to −5 km, as the
//! Standard does. Above 86 km the Standard switches to a different (non-hydrostatic,
//! diffusive) formulation that this module does not implement.

use crate::constants::BOLTZMANN_J_PER_K;

/// Highest geometric altitude of the model, m.
pub const TOP_ALTITUDE_M: f64 = 86_000.0;
/// Lowest geometric altitude of the model, m (the Standard's tables start at −5 km).
pub const BOTTOM_ALTITUDE_M: f64 = -5_000.0;

/// Universal gas constant of the Standard, J kmol⁻¹ K⁻¹.
const R_STAR: f64 = 8.31432e3;
/// Sea-level mean molecular weight of dry air, kg kmol⁻¹ (also the mass of an air
/// molecule in the Doppler width of the Cabannes line, `cabannes_line.rs`).
pub const M0: f64 = 28.9644;
/// Standard gravity g0', m² s⁻² m'⁻¹ (geopotential metre).
const G0: f64 = 9.80665;
/// Effective Earth radius for the geopotential conversion, m.
const R0: f64 = 6_356_766.0;
/// Sea-level pressure, Pa.
const P0: f64 = 101_325.0;
/// Sea-level (molecular-scale) temperature, K.
const T0: f64 = 288.15;
/// g0'·M0/R*, K per geopotential metre.
const GMR: f64 = G0 * M0 / R_STAR;

/// Layer bases, geopotential m (Table 4).
const LAYER_BASE_H: [f64; 7] = [
    0.0, 11_000.0, 20_000.0, 32_000.0, 47_000.0, 51_000.0, 71_000.0,
];
/// Molecular-scale temperature gradients, K per geopotential m (Table 4).
const LAYER_LAPSE: [f64; 7] = [-6.5e-3, 0.0, 1.0e-3, 2.8e-3, 0.0, -2.8e-3, -2.0e-3];

/// M/M0 between 80 and 86 km geometric altitude at 0.5 km steps (Table 8).
const MW_RATIO_START_M: f64 = 80_000.0;
const MW_RATIO_STEP_M: f64 = 500.0;
const MW_RATIO: [f64; 13] = [
    1.000000, 0.999996, 0.999989, 0.999971, 0.999941, 0.999909, 0.999870, 0.999829, 0.999786,
    0.999741, 0.999694, 0.999641, 0.999579,
];

/// Thermodynamic state of the standard atmosphere at one altitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// Pressure, Pa.
    pub pressure_pa: f64,
    /// Kinetic temperature, K.
    pub temperature_k: f64,
    /// Air molecule number density, m⁻³.
    pub number_density_m3: f64,
}

/// Geopotential altitude (geopotential m) of geometric altitude `z_m` (Eq. 18).
pub fn geopotential_altitude_m(z_m: f64) -> f64 {
    R0 * z_m / (R0 + z_m)
}

/// Geometric altitude (m) of geopotential altitude `h_m` (inverse of Eq. 18).
pub fn geometric_altitude_m(h_m: f64) -> f64 {
    R0 * h_m / (R0 - h_m)
}

/// Pressure at the top of layer `i` (= its height `dh` above the base) from its base values.
fn layer_pressure(i: usize, t_base: f64, p_base: f64, dh: f64) -> f64 {
    let lapse = LAYER_LAPSE[i];
    if lapse == 0.0 {
        p_base * (-GMR * dh / t_base).exp()
    } else {
        p_base * (t_base / (t_base + lapse * dh)).powf(GMR / lapse)
    }
}

/// Molecular-scale temperature (K) and pressure (Pa) at geopotential altitude `h_m`.
fn molecular_temperature_and_pressure(h_m: f64) -> (f64, f64) {
    let (mut t_base, mut p_base) = (T0, P0);
    let mut i = 0;
    // Chain the layer bases upward (at most six steps); the first layer also covers H < 0.
    while i + 1 < LAYER_BASE_H.len() && h_m >= LAYER_BASE_H[i + 1] {
        let dh = LAYER_BASE_H[i + 1] - LAYER_BASE_H[i];
        p_base = layer_pressure(i, t_base, p_base, dh);
        t_base += LAYER_LAPSE[i] * dh;
        i += 1;
    }
    let dh = h_m - LAYER_BASE_H[i];
    (
        t_base + LAYER_LAPSE[i] * dh,
        layer_pressure(i, t_base, p_base, dh),
    )
}

/// Mean-molecular-weight ratio M/M0 at geometric altitude `z_m` (Table 8, linear).
fn molecular_weight_ratio(z_m: f64) -> f64 {
    if z_m <= MW_RATIO_START_M {
        return 1.0;
    }
    let x = (z_m - MW_RATIO_START_M) / MW_RATIO_STEP_M;
    let last = MW_RATIO.len() - 1;
    if x >= last as f64 {
        return MW_RATIO[last];
    }
    let k = x.floor() as usize;
    let f = x - k as f64;
    MW_RATIO[k] + f * (MW_RATIO[k + 1] - MW_RATIO[k])
}

/// US76 state at geometric altitude `altitude_m`; `None` outside
/// [`BOTTOM_ALTITUDE_M`, `TOP_ALTITUDE_M`] (or for NaN).
pub fn state(altitude_m: f64) -> Option<State> {
    if !(BOTTOM_ALTITUDE_M..=TOP_ALTITUDE_M).contains(&altitude_m) {
        return None;
    }
    let h = geopotential_altitude_m(altitude_m);
    let (t_molecular, pressure_pa) = molecular_temperature_and_pressure(h);
    let temperature_k = t_molecular * molecular_weight_ratio(altitude_m);
    let number_density_m3 = pressure_pa / (BOLTZMANN_J_PER_K * temperature_k);
    Some(State {
        pressure_pa,
        temperature_k,
        number_density_m3,
    })
}

/// US76 number density (m⁻³) at geometric altitude `altitude_m`: 0 above
/// [`TOP_ALTITUDE_M`], the value at [`BOTTOM_ALTITUDE_M`] below it; NaN for NaN.
pub fn number_density_m3(altitude_m: f64) -> f64 {
    if altitude_m.is_nan() {
        return f64::NAN;
    }
    if altitude_m > TOP_ALTITUDE_M {
        return 0.0;
    }
    let z = altitude_m.max(BOTTOM_ALTITUDE_M);
    state(z).map_or(0.0, |s| s.number_density_m3)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        (a / b - 1.0).abs()
    }

    /// Published US76 values at geometric altitudes (NOAA-S/T 76-1562, Part 4,
    /// Table I, SI units): (Z m, P Pa, T K). Cross-checked, at the 4 digits it
    /// prints, against the public PDAS table (Carmichael, "A Table of the Standard
    /// Atmosphere to 86 km in SI units", github.com/kurtsansom/pdas,
    /// docs/source/atmosTable1SI.rst: 20 km 5.529e3 Pa, 32 km 8.890e2 Pa,
    /// 86 km 186.9 K); 86 km pressure 3.7338e-1 Pa as also transcribed in
    /// several public US76 implementations.
    const TABLE_I: [(f64, f64, f64); 10] = [
        (0.0, 1.01325e5, 288.150),
        (1_000.0, 8.9876e4, 281.651),
        (5_000.0, 5.4048e4, 255.676),
        (11_000.0, 2.2700e4, 216.774),
        (20_000.0, 5.5293e3, 216.650),
        (32_000.0, 8.8906e2, 228.490),
        (47_000.0, 1.1585e2, 269.684),
        (51_000.0, 7.0458e1, 270.650),
        (71_000.0, 4.4796e0, 216.846),
        (86_000.0, 3.7338e-1, 186.870),
    ];

    #[test]
    fn matches_published_table_at_geometric_altitudes() {
        for &(z, p, t) in &TABLE_I {
            let s = state(z).unwrap();
            assert!(
                rel(s.pressure_pa, p) < 1e-4,
                "P at {z}: {} vs {p}",
                s.pressure_pa
            );
            assert!(
                rel(s.temperature_k, t) < 1e-4,
                "T at {z}: {} vs {t}",
                s.temperature_k
            );
            // N in Table I is N_A·P/(R*·T) of the tabulated P and T (N_A = 6.022169e26
            // kmol⁻¹); the module's P/(k_B·T) is 2e-5 below it
            let n = 6.022169e26 * p / (R_STAR * t);
            assert!(
                rel(s.number_density_m3, n) < 2e-4,
                "N at {z}: {} vs {n}",
                s.number_density_m3
            );
        }
    }

    #[test]
    fn published_number_densities() {
        // Table I: 2.5470e25 m⁻³ at sea level, 1.4474e20 m⁻³ at 86 km (≈ 1.4e20).
        assert!(rel(number_density_m3(0.0), 2.5470e25) < 1e-4);
        assert!(rel(number_density_m3(86_000.0), 1.4474e20) < 1e-3);
        // US76 sea level p/kT = 2.5469e25 m⁻³ (CODATA k_B).
        let s = state(0.0).unwrap();
        let n_codata = s.pressure_pa / (BOLTZMANN_J_PER_K * s.temperature_k);
        assert!(rel(n_codata, 2.5469e25) < 1e-4);
    }

    #[test]
    fn layer_bases_match_table_4() {
        // Table 4: base pressures at the geopotential layer bases
        // (11 km' is 11.019 km geometric: 22632 Pa, 216.65 K).
        let bases = [
            (11_000.0, 2.2632e4, 216.65),
            (20_000.0, 5.4749e3, 216.65),
            (32_000.0, 8.6802e2, 228.65),
            (47_000.0, 1.1091e2, 270.65),
            (51_000.0, 6.6939e1, 270.65),
            (71_000.0, 3.9564e0, 214.65),
        ];
        for &(h, p, t) in &bases {
            let s = state(geometric_altitude_m(h)).unwrap();
            assert!(
                rel(s.pressure_pa, p) < 1e-4,
                "P at H={h}: {}",
                s.pressure_pa
            );
            assert!(
                rel(s.temperature_k, t) < 1e-6,
                "T at H={h}: {}",
                s.temperature_k
            );
        }
        // Top: H = 84.852 km' ↔ Z = 86 km, T_M = 186.946 K.
        assert!((geopotential_altitude_m(86_000.0) - 84_852.05).abs() < 0.1);
        let (tm, _) = molecular_temperature_and_pressure(geopotential_altitude_m(86_000.0));
        assert!((tm - 186.946).abs() < 1e-3);
    }

    #[test]
    fn geopotential_conversion_round_trips() {
        for z in [-5_000.0, 0.0, 1234.5, 47_000.0, 86_000.0] {
            assert!((geometric_altitude_m(geopotential_altitude_m(z)) - z).abs() < 1e-6);
        }
    }

    #[test]
    fn continuous_across_layer_boundaries() {
        for &h in &LAYER_BASE_H[1..] {
            let z = geometric_altitude_m(h);
            let below = state(z - 1e-3).unwrap();
            let above = state(z + 1e-3).unwrap();
            assert!(rel(below.pressure_pa, above.pressure_pa) < 1e-6);
            assert!((below.temperature_k - above.temperature_k).abs() < 1e-4);
        }
    }

    #[test]
    fn range_and_clamping() {
        assert!(state(-5_000.0).is_some());
        assert!(state(-5_000.1).is_none());
        assert!(state(86_000.1).is_none());
        assert!(state(f64::NAN).is_none());
        // −5 km: 320.65 K (molecular-scale, −6.5 K/km extended) and P ≈ 1.778e5 Pa.
        let s = state(-5_000.0).unwrap();
        assert!((s.temperature_k - 320.676).abs() < 0.01);
        assert!(rel(s.pressure_pa, 1.7776e5) < 2e-4);
        assert_eq!(number_density_m3(86_000.5), 0.0);
        assert_eq!(number_density_m3(-10_000.0), number_density_m3(-5_000.0));
        assert!(number_density_m3(f64::NAN).is_nan());
    }

    #[test]
    fn number_density_decreases_monotonically() {
        let mut prev = f64::INFINITY;
        for k in -50..=860 {
            let n = number_density_m3(k as f64 * 100.0);
            assert!(n < prev, "at {} m", k * 100);
            prev = n;
        }
    }
}
