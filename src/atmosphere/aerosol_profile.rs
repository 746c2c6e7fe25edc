//! Background aerosol after the paper's Eq. 5–6 (Fochesatto et al. 2004).
//!
//! **Eq. 5** — near-surface extinction from the horizontal visibility V
//! (Koschmieder's 2 % contrast threshold as used by Middleton, with Kruse's
//! wavelength exponent):
//! `α_aer(0) = (3.91/V)·(0.55/λ_µm)^q` km⁻¹, `q = 0.585·V^(1/3)` for V < 6 km,
//! `q = 1.3` otherwise (docs/model.md §4; Kruse's third branch, q = 1.6 for
//! V > 50 km, is not part of the paper's model and is not used).
//!
//! **Eq. 6** — vertical shape `α_aer(z) = α_aer(0)·Np(z)/Np(0)`. The paper's
//! Fig. 1 uses a "typical" total aerosol concentration profile after Hinkley
//! (1976), which reproduces Elterman's standard aerosol model. The shape shipped
//! here is **Elterman (1968)**, "UV, visible, and IR attenuation for altitudes
//! to 50 km", AFCRL-68-0153 (see also Elterman, Wexler & Chang 1969,
//! Appl. Opt. 8, 893): aerosol attenuation coefficient at 1 km steps from 0 to
//! 50 km. The numbers are the 340 nm column of that model as embedded in NCAR's
//! TUV radiative-transfer code (S. Madronich), "Aerosol data from Elterman
//! (1968). These are vertical optical depths per km, in 1 km intervals from
//! 0 km to 50 km, at 340 nm", found identically in three public copies:
//! github.com/pb866/TUV_DSMACC `SRC/setaer.f`,
//! github.com/poissonconsulting/tuv-x `setaer.f`, and the CAMx TUV driver
//! github.com/bnmurphy/PMCAMx-UF `drvtuv.f` ("Total integrated OD is 0.38
//! (~0.23 at 550 nm)").
//!
//! Why an attenuation profile serves as the concentration shape Np(z)/Np(0):
//! Elterman's model uses one size distribution at all altitudes, so its
//! attenuation coefficients are proportional to the aerosol number density at
//! every wavelength ("Since the coefficients are proportional to aerosol number
//! density, the profiles yield information concerning aerosol stratification",
//! Elterman 1966, AFCRL-66-828, abstract); TUV accordingly applies the same
//! vertical shape at all wavelengths. Consistency checks on the numbers: the
//! sea-level value at 550 nm (0.240·340/550 ≈ 0.15 km⁻¹) matches Elterman's
//! 25 km sea-level visibility, the 0–50 km column is 0.38 at 340 nm, and above
//! 26 km successive values fall by a constant factor 0.765 per km, i.e. the
//! 3.75 km aerosol scale height Elterman et al. (1969) used to extrapolate to 50 km.
//!
//! Shape: steep boundary-layer decay (factor ≈ 24 from 0 to 4 km), a
//! free-tropospheric background (5–17 km, ≈ 2 % of the surface value) and a
//! weak stratospheric (Junge-layer) maximum at 18 km, then exponential decay.
//! Not verified against a scan of AFCRL-68-0153 itself.

/// Altitude step of [`ELTERMAN_1968_ATTENUATION_340NM_PER_KM`], m.
const STEP_M: f64 = 1_000.0;

/// Highest altitude of the tabulated shape, m; [`relative_concentration`] is 0 above.
pub const PROFILE_TOP_M: f64 = 50_000.0;

/// Elterman (1968) aerosol attenuation coefficient at 340 nm, km⁻¹, at
/// 0, 1, …, 50 km (as embedded in NCAR TUV `setaer.f`; see the module docs).
pub const ELTERMAN_1968_ATTENUATION_340NM_PER_KM: [f64; 51] = [
    2.40e-01, 1.06e-01, 4.56e-02, 1.91e-02, 1.01e-02, 7.63e-03, // 0–5 km
    5.38e-03, 5.00e-03, 5.15e-03, 4.94e-03, 4.82e-03, 4.51e-03, // 6–11 km
    4.74e-03, 4.37e-03, 4.28e-03, 4.03e-03, 3.83e-03, 3.78e-03, // 12–17 km
    3.88e-03, 3.08e-03, 2.26e-03, 1.64e-03, 1.23e-03, 9.45e-04, // 18–23 km
    7.49e-04, 6.30e-04, 5.50e-04, 4.21e-04, 3.22e-04, 2.48e-04, // 24–29 km
    1.90e-04, 1.45e-04, 1.11e-04, 8.51e-05, 6.52e-05, 5.00e-05, // 30–35 km
    3.83e-05, 2.93e-05, 2.25e-05, 1.72e-05, 1.32e-05, 1.01e-05, // 36–41 km
    7.72e-06, 5.91e-06, 4.53e-06, 3.46e-06, 2.66e-06, 2.04e-06, // 42–47 km
    1.56e-06, 1.19e-06, 9.14e-07, // 48–50 km
];

/// Kruse exponent q of Eq. 5 for visibility `visibility_km` (km):
/// `0.585·V^(1/3)` below 6 km, 1.3 from 6 km up.
pub fn kruse_exponent(visibility_km: f64) -> f64 {
    if visibility_km < 6.0 {
        0.585 * visibility_km.cbrt()
    } else {
        1.3
    }
}

/// Eq. 5: near-surface aerosol extinction, m⁻¹, from the horizontal visibility
/// `visibility_km` (> 0, km) at `wavelength_nm` (> 0):
/// `(3.91/V)·(0.55/λ_µm)^q` km⁻¹ with q = [`kruse_exponent`]`(V)`.
pub fn surface_extinction_per_m(visibility_km: f64, wavelength_nm: f64) -> f64 {
    debug_assert!(visibility_km > 0.0 && wavelength_nm > 0.0);
    let q = kruse_exponent(visibility_km);
    let per_km = 3.91 / visibility_km * (550.0 / wavelength_nm).powf(q);
    per_km * 1e-3
}

/// Eq. 6 shape Np(z)/Np(0) at geometric altitude `altitude_m`: the Elterman
/// (1968) profile normalized to 1 at z = 0, log-linear between the 1 km table
/// altitudes; 1 below 0 m, 0 above [`PROFILE_TOP_M`]; NaN for NaN.
pub fn relative_concentration(altitude_m: f64) -> f64 {
    if altitude_m.is_nan() {
        return f64::NAN;
    }
    if altitude_m > PROFILE_TOP_M {
        return 0.0;
    }
    let t = &ELTERMAN_1968_ATTENUATION_340NM_PER_KM;
    if altitude_m <= 0.0 {
        return 1.0;
    }
    let x = altitude_m / STEP_M;
    let i = (x.floor() as usize).min(t.len() - 2);
    let f = x - i as f64;
    let ln = t[i].ln() + f * (t[i + 1].ln() - t[i].ln());
    ln.exp() / t[0]
}

/// Altitudes of [`BACKGROUND_STRATOSPHERE_532NM_PER_KM`], km.
pub const BACKGROUND_STRATOSPHERE_KM: [f64; 10] =
    [17.0, 20.0, 22.5, 25.0, 27.5, 30.0, 32.5, 35.0, 40.0, 50.0];

/// A present-day (non-volcanic, 2000s) background stratospheric aerosol extinction at
/// 532 nm, km⁻¹, at [`BACKGROUND_STRATOSPHERE_KM`]: a smooth mid-latitude profile
/// after the SAGE II / OSIRIS / CALIOP background climatologies (Thomason & Peter
/// (eds.) 2006, SPARC Assessment of Stratospheric Aerosol Properties, WCRP-124,
/// ch. 4; Vernier et al. 2011, Geophys. Res. Lett. 38, L12807, whose background
/// stratospheric optical depth is ~0.004–0.006 at 525–532 nm): ~3e-4 km⁻¹ at the
/// bottom of the stratosphere, ~1e-4 km⁻¹ at 20–25 km, then falling by about a decade
/// per 6 km (1e-5 at 30 km, 2.5e-7 at 40 km). Not a digitized table of either source:
/// its values are ASSUMED within their spread (a factor ~2). It leaves the
/// 30–34 km region that CALIOP's 532 nm calibration takes as molecular within 1 % of
/// the molecular backscatter (at a lidar ratio of 50 sr: 0.009 at 30 km, 0.004 at
/// 34 km), as CALIOP assumes, where Elterman's 1960s profile gives 0.12.
pub const BACKGROUND_STRATOSPHERE_532NM_PER_KM: [f64; 10] = [
    3.0e-4, 1.6e-4, 1.1e-4, 6.5e-5, 3.0e-5, 1.0e-5, 4.0e-6, 1.6e-6, 2.5e-7, 6.0e-9,
];

/// Ångström exponent of the background stratospheric aerosol, carrying
/// [`BACKGROUND_STRATOSPHERE_532NM_PER_KM`] to other wavelengths: 2, about the SAGE II
/// 525/1020 nm extinction ratio (~4) of the non-volcanic stratosphere (Thomason &
/// Peter 2006, ch. 4); ASSUMED.
pub const BACKGROUND_STRATOSPHERE_ANGSTROM: f64 = 2.0;

/// Top of the troposphere whose aerosol keeps Elterman's shape under a background
/// stratosphere, m: between it and the table's first altitude (17 km) the extinction
/// goes log-linearly from Elterman's value to the table's.
pub const TROPOSPHERE_TOP_M: f64 = 12_000.0;

/// The background stratospheric aerosol's extinction at `wavelength_nm` and altitude
/// `altitude_m`, m⁻¹: [`BACKGROUND_STRATOSPHERE_532NM_PER_KM`] log-linear between its
/// altitudes, times `(532/λ)^2`; 0 above 50 km; below 17 km the table's first value
/// (the caller joins it to the troposphere).
pub fn background_stratosphere_per_m(altitude_m: f64, wavelength_nm: f64) -> f64 {
    let (z, t) = (
        &BACKGROUND_STRATOSPHERE_KM,
        &BACKGROUND_STRATOSPHERE_532NM_PER_KM,
    );
    let km = altitude_m / 1e3;
    if km > z[z.len() - 1] {
        return 0.0;
    }
    let per_km = if km <= z[0] {
        t[0]
    } else {
        let i = z.partition_point(|&x| x <= km).clamp(1, z.len() - 1);
        let f = (km - z[i - 1]) / (z[i] - z[i - 1]);
        (t[i - 1].ln() + f * (t[i].ln() - t[i - 1].ln())).exp()
    };
    per_km * 1e-3 * (532.0 / wavelength_nm).powf(BACKGROUND_STRATOSPHERE_ANGSTROM)
}

/// The background aerosol's extinction under a present-day stratosphere, m⁻¹:
/// `surface_per_m · Np(z)/Np(0)` (Elterman's shape) up to [`TROPOSPHERE_TOP_M`], the
/// background stratosphere ([`background_stratosphere_per_m`]) from 17 km up, and
/// log-linear between the two in 12–17 km.
pub fn with_background_stratosphere_per_m(
    surface_per_m: f64,
    altitude_m: f64,
    wavelength_nm: f64,
) -> f64 {
    let bottom_m = BACKGROUND_STRATOSPHERE_KM[0] * 1e3;
    if altitude_m <= TROPOSPHERE_TOP_M || altitude_m.is_nan() {
        return surface_per_m * relative_concentration(altitude_m);
    }
    let high = background_stratosphere_per_m(altitude_m.max(bottom_m), wavelength_nm);
    if altitude_m >= bottom_m {
        return high;
    }
    let low = surface_per_m * relative_concentration(TROPOSPHERE_TOP_M);
    if low <= 0.0 || high <= 0.0 {
        return 0.0;
    }
    let f = (altitude_m - TROPOSPHERE_TOP_M) / (bottom_m - TROPOSPHERE_TOP_M);
    (low.ln() + f * (high.ln() - low.ln())).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        (a / b - 1.0).abs()
    }

    #[test]
    fn eq5_hand_values() {
        // V = 20 km, 532 nm: (3.91/20)·(550/532)^1.3 = 0.2041 km⁻¹.
        let a = surface_extinction_per_m(20.0, 532.0);
        assert!(rel(a, 0.204e-3) < 5e-3, "{a}");
        assert!(rel(a, 0.195_5 * (550.0_f64 / 532.0).powf(1.3) * 1e-3) < 1e-12);
        // V = 5 km: q = 0.585·5^(1/3) = 1.000336.
        let q = kruse_exponent(5.0);
        assert!((q - 1.000_336).abs() < 1e-6, "{q}");
        let a5 = surface_extinction_per_m(5.0, 532.0);
        assert!(rel(a5, 3.91 / 5.0 * (550.0_f64 / 532.0).powf(q) * 1e-3) < 1e-12);
        assert!(rel(a5, 0.808_5e-3) < 1e-3, "{a5}");
        // At 550 nm the wavelength factor is 1: Koschmieder 3.91/V.
        assert!(rel(surface_extinction_per_m(23.0, 550.0), 3.91 / 23.0 * 1e-3) < 1e-12);
    }

    #[test]
    fn kruse_branches() {
        assert_eq!(kruse_exponent(6.0), 1.3);
        assert_eq!(kruse_exponent(100.0), 1.3);
        assert!((kruse_exponent(1.0) - 0.585).abs() < 1e-12);
        // The paper's two branches are discontinuous at 6 km (1.063 → 1.3).
        assert!((kruse_exponent(5.999) - 1.0628).abs() < 1e-3);
    }

    #[test]
    fn shape_normalized_and_bounded() {
        assert_eq!(relative_concentration(0.0), 1.0);
        assert_eq!(relative_concentration(-100.0), 1.0);
        assert_eq!(relative_concentration(PROFILE_TOP_M + 1.0), 0.0);
        assert!(relative_concentration(PROFILE_TOP_M) > 0.0);
        assert!(relative_concentration(f64::NAN).is_nan());
        let t = &ELTERMAN_1968_ATTENUATION_340NM_PER_KM;
        for (k, v) in t.iter().enumerate() {
            assert!(rel(relative_concentration(k as f64 * 1000.0), v / t[0]) < 1e-12);
        }
    }

    #[test]
    fn log_linear_between_table_points() {
        let mid = relative_concentration(500.0);
        assert!(rel(mid, (1.0_f64 * 0.106 / 0.240).sqrt()) < 1e-12);
    }

    #[test]
    fn monotone_decay_through_boundary_layer() {
        let mut prev = relative_concentration(0.0);
        for k in 1..=500 {
            let v = relative_concentration(k as f64 * 10.0);
            assert!(v < prev, "at {} m", k * 10);
            prev = v;
        }
        assert!(relative_concentration(5_000.0) < 0.05);
    }

    #[test]
    fn stratospheric_maximum() {
        // A local maximum between 15 and 25 km (Elterman's is at 18 km).
        let f = |km: f64| relative_concentration(km * 1000.0);
        let peaks: Vec<f64> = (15..=25)
            .map(f64::from)
            .filter(|&z| f(z) > f(z - 1.0) && f(z) > f(z + 1.0))
            .collect();
        assert_eq!(peaks, vec![18.0]);
    }

    /// The background stratosphere by hand: the table's values at its altitudes, the
    /// geometric mean halfway (log-linear), (532/1064)² = 1/4 at 1064 nm, continuity
    /// at 12 and 17 km and 0 above 50 km; its optical depth above 17 km at 532 nm is
    /// ~0.0015 (trapezoid of the table: about 1.5e-3).
    #[test]
    fn background_stratosphere_hand_values() {
        let (z, t) = (
            &BACKGROUND_STRATOSPHERE_KM,
            &BACKGROUND_STRATOSPHERE_532NM_PER_KM,
        );
        for k in 0..z.len() {
            let got = background_stratosphere_per_m(z[k] * 1e3, 532.0);
            assert!(rel(got, t[k] * 1e-3) < 1e-12, "{} km", z[k]);
        }
        let mid = background_stratosphere_per_m(28_750.0, 532.0);
        assert!(rel(mid, (3.0e-5f64 * 1.0e-5).sqrt() * 1e-3) < 1e-12);
        let ir = background_stratosphere_per_m(30_000.0, 1064.0);
        assert!(rel(ir, 1.0e-5 / 4.0 * 1e-3) < 1e-12);
        assert_eq!(background_stratosphere_per_m(50_001.0, 532.0), 0.0);
        let s = 1.776e-4; // V = 23 km at 532 nm, m⁻¹
        let at = |z: f64| with_background_stratosphere_per_m(s, z, 532.0);
        assert_eq!(at(5_000.0), s * relative_concentration(5_000.0));
        assert!(rel(at(12_000.0 + 1e-6), at(12_000.0)) < 1e-6);
        assert!(rel(at(17_000.0 - 1e-6), 3.0e-7) < 1e-6);
        assert!(at(14_000.0) < at(13_000.0) && at(14_000.0) > 3.0e-7);
        let column: f64 = t
            .windows(2)
            .zip(z.windows(2))
            .map(|(v, h)| 0.5 * (v[0] + v[1]) * (h[1] - h[0]))
            .sum();
        assert!((column - 1.5e-3).abs() < 0.2e-3, "{column}");
    }

    #[test]
    fn column_and_scale_height_consistent_with_elterman() {
        let t = &ELTERMAN_1968_ATTENUATION_340NM_PER_KM;
        // Trapezoid column at 340 nm: TUV/CAMx quote 0.38.
        let column: f64 = t.windows(2).map(|w| 0.5 * (w[0] + w[1])).sum();
        assert!((column - 0.38).abs() < 0.01, "{column}");
        // Above 26 km: 3.75 km scale height (Elterman, Wexler & Chang 1969).
        for k in 27..t.len() {
            let h = 1.0 / (t[k - 1] / t[k]).ln();
            assert!((h - 3.75).abs() < 0.15, "scale height {h} km at {k} km");
        }
    }
}
