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
