//! The sun: its zenith angle at a time and place, the Earth–Sun distance, the
//! top-of-atmosphere solar spectrum and the daylight radiance a nadir view sees
//! (docs/model.md §4f).
//!
//! **Solar position.** The NOAA Solar Calculator equations (NOAA Global Monitoring
//! Laboratory, `NOAA_Solar_Calculations_day.xls`), which are the low-accuracy solar
//! coordinates of Meeus, *Astronomical Algorithms* (2nd ed., 1998), ch. 25, with the
//! equation of time of ch. 28. From the Julian century `T = (JD − 2451545)/36525`:
//! geometric mean longitude `L0` and mean anomaly `M` (polynomials in `T`), equation of
//! centre `C`, true longitude `L0 + C`, apparent longitude `λ` (nutation and aberration
//! terms), corrected obliquity `ε`, declination `δ = asin(sin ε · sin λ)`, equation of
//! time `E`, true solar time `t_s = UTC minutes + E + 4·longitude`, hour angle
//! `h = t_s/4 − 180°`, and `cos θ_s = sin φ·sin δ + cos φ·cos δ·cos h`.
//! Meeus gives 0.01° for the sun's apparent position; with the equation of time the
//! zenith angle is good to ~0.01–0.03° between 1900 and 2100 (UT is used for TT:
//! ΔT ≈ 70 s moves the sun by 0.0008°). The zenith angle is geometric and geocentric:
//! no atmospheric refraction (which lifts the apparent sun by 0.57° at the horizon and
//! 0.016° at 40° elevation) and no parallax (≤ 0.0024°).
//!
//! **Earth–Sun distance**, from the same equations:
//! `R = 1.000001018·(1 − e²)/(1 + e·cos ν)` AU (ν the true anomaly), 0.9833–1.0167 AU.
//!
//! **Solar spectrum.** [`solar_spectral_irradiance_photons`] interpolates a table of the
//! ASTM E-490-00a air-mass-zero spectrum (ASTM E490-00a (2019), *Standard Solar Constant
//! and Zero Air Mass Solar Spectral Irradiance Tables*, 1366.1 W m⁻² in total), averaged
//! here over 10 nm centred on each node (the Fraunhofer lines are smoothed out: the
//! 1-nm spectrum swings by ±10 % around these values), 300–2000 nm, at 1 AU.
//!
//! **Daylight radiance** seen looking down on a Lambertian reflector of albedo ρ
//! (docs/model.md §4f): through the modelled atmosphere, the reflected sunlight and the
//! air's own once-scattered sunlight, with the sun's path through a spherical
//! atmosphere ([`crate::scene::sky`]); with a stated two-way transmission T
//! (`background.transmission`) `L = ρ·F_λ·cos θ_s/π·T` and no path radiance. 0 when
//! the sun is below the horizon (θ_s ≥ 90°).

use crate::atmosphere::Atmosphere;
use crate::config::ScenarioConfig;
use crate::constants::{PLANCK_J_S, SPEED_OF_LIGHT_M_PER_S};
use crate::scene::sky::{SkyColumn, SkyRadiance};
use std::f64::consts::PI;

/// Julian date of the Unix epoch, 1970-01-01T00:00:00 UTC.
const UNIX_EPOCH_JD: f64 = 2_440_587.5;
/// Julian date of J2000.0.
const J2000_JD: f64 = 2_451_545.0;
/// Days per Julian century.
const DAYS_PER_JULIAN_CENTURY: f64 = 36_525.0;
/// Seconds per day.
const SECONDS_PER_DAY: f64 = 86_400.0;

/// The sun's declination and the equation of time at one instant.
#[derive(Debug, Clone, Copy)]
struct SolarCoordinates {
    /// Declination δ, rad.
    declination_rad: f64,
    /// Equation of time E (apparent minus mean solar time), minutes.
    equation_of_time_min: f64,
    /// Earth–Sun distance, AU.
    distance_au: f64,
}

/// Julian centuries since J2000.0 of a Unix time (UT taken for TT).
fn julian_century(unix_time_s: f64) -> f64 {
    (unix_time_s / SECONDS_PER_DAY + UNIX_EPOCH_JD - J2000_JD) / DAYS_PER_JULIAN_CENTURY
}

/// The NOAA / Meeus ch. 25 low-accuracy solar coordinates at Julian century `t`.
fn solar_coordinates(t: f64) -> SolarCoordinates {
    let l0 = (280.46646 + t * (36000.76983 + t * 0.000_303_2)).rem_euclid(360.0);
    let m = 357.52911 + t * (35999.05029 - 0.000_153_7 * t);
    let e = 0.016_708_634 - t * (0.000_042_037 + 0.000_000_126_7 * t);
    let mr = m.to_radians();
    let c = mr.sin() * (1.914_602 - t * (0.004_817 + 0.000_014 * t))
        + (2.0 * mr).sin() * (0.019_993 - 0.000_101 * t)
        + (3.0 * mr).sin() * 0.000_289;
    let true_anomaly = (m + c).to_radians();
    let distance_au = 1.000_001_018 * (1.0 - e * e) / (1.0 + e * true_anomaly.cos());
    let omega = (125.04 - 1934.136 * t).to_radians();
    let apparent_longitude = (l0 + c - 0.005_69 - 0.004_78 * omega.sin()).to_radians();
    let mean_obliquity =
        23.0 + (26.0 + (21.448 - t * (46.815 + t * (0.000_59 - t * 0.001_813))) / 60.0) / 60.0;
    let obliquity = (mean_obliquity + 0.002_56 * omega.cos()).to_radians();
    let declination_rad = (obliquity.sin() * apparent_longitude.sin()).asin();
    SolarCoordinates {
        declination_rad,
        equation_of_time_min: equation_of_time_min(obliquity, l0.to_radians(), mr, e),
        distance_au,
    }
}

/// Equation of time, minutes (Meeus Eq. 28.3 in the form of the NOAA calculator),
/// from the obliquity ε, mean longitude L0 and mean anomaly M (rad) and eccentricity e.
fn equation_of_time_min(obliquity: f64, l0: f64, m: f64, e: f64) -> f64 {
    let y = (obliquity / 2.0).tan().powi(2);
    let rad = y * (2.0 * l0).sin() - 2.0 * e * m.sin() + 4.0 * e * y * m.sin() * (2.0 * l0).cos()
        - 0.5 * y * y * (4.0 * l0).sin()
        - 1.25 * e * e * (2.0 * m).sin();
    4.0 * rad.to_degrees()
}

/// Solar zenith angle θ_s, degrees in [0, 180], at `unix_time_s` (seconds since
/// 1970-01-01T00:00:00 UTC, leap seconds ignored as in Unix time) seen from latitude
/// `latitude_deg` (north positive) and longitude `longitude_deg` (east positive).
/// Geometric (no refraction), geocentric; accurate to ~0.01–0.03° (module docs).
/// Above 90° the sun is below the horizon.
pub fn solar_zenith_deg(unix_time_s: f64, latitude_deg: f64, longitude_deg: f64) -> f64 {
    let sun = solar_coordinates(julian_century(unix_time_s));
    let utc_minutes = unix_time_s.rem_euclid(SECONDS_PER_DAY) / 60.0;
    let true_solar_time_min = utc_minutes + sun.equation_of_time_min + 4.0 * longitude_deg;
    let hour_angle = (true_solar_time_min / 4.0 - 180.0).to_radians();
    let lat = latitude_deg.to_radians();
    let cos_zenith = lat.sin() * sun.declination_rad.sin()
        + lat.cos() * sun.declination_rad.cos() * hour_angle.cos();
    cos_zenith.clamp(-1.0, 1.0).acos().to_degrees()
}

/// Earth–Sun distance at `unix_time_s`, AU (0.9833 in early January to 1.0167 in early
/// July). The solar irradiance at the Earth is the 1-AU value divided by its square.
pub fn earth_sun_distance_au(unix_time_s: f64) -> f64 {
    solar_coordinates(julian_century(unix_time_s)).distance_au
}

/// How sunlight reaches a reflector and comes back to a nadir view (module docs).
#[derive(Debug, Clone, PartialEq)]
pub enum SunlightPath {
    /// A stated two-way transmission (`background.transmission`), whatever the angle.
    Fixed(f64),
    /// Through the modelled atmosphere above the reflector ([`SkyColumn`]).
    Sky {
        /// The column above the reflector at the channel's wavelength.
        column: SkyColumn,
        /// Whether the air's scattered sunlight is added (`background.path_radiance`).
        path_radiance: bool,
    },
}

impl SunlightPath {
    /// The path of a config's sunlight to a reflector at `reflector_m`: the stated
    /// `background.transmission` if given, else the column above it in `atmosphere`.
    pub fn of(cfg: &ScenarioConfig, atmosphere: &Atmosphere, reflector_m: f64) -> SunlightPath {
        match cfg.background.transmission {
            Some(t) => SunlightPath::Fixed(t),
            None => SunlightPath::Sky {
                column: SkyColumn::above(atmosphere, reflector_m),
                path_radiance: cfg.background.path_radiance.unwrap_or(true),
            },
        }
    }

    /// The daylight radiance over a reflector of albedo `albedo` under the
    /// top-of-atmosphere irradiance `irradiance` at solar zenith `zenith_deg`
    /// (module docs), photons m⁻² s⁻¹ sr⁻¹ nm⁻¹, split into its reflected and path parts.
    pub fn radiance(&self, albedo: f64, irradiance: f64, zenith_deg: f64) -> SkyRadiance {
        match self {
            SunlightPath::Fixed(t) => SkyRadiance {
                reflected: reflected_radiance(albedo, irradiance, zenith_deg, *t),
                path: 0.0,
            },
            SunlightPath::Sky {
                column,
                path_radiance,
            } => column.radiance(albedo, irradiance, zenith_deg, *path_radiance),
        }
    }

    /// An upper bound of [`SunlightPath::radiance`]'s total at any angle: the albedo
    /// under an overhead sun with no atmosphere (or the stated transmission), plus the
    /// path radiance's bound.
    pub fn brightest(&self, albedo: f64, irradiance: f64) -> f64 {
        match self {
            SunlightPath::Fixed(t) => reflected_radiance(albedo, irradiance, 0.0, *t),
            SunlightPath::Sky {
                column,
                path_radiance,
            } => {
                reflected_radiance(albedo, irradiance, 0.0, 1.0)
                    + if *path_radiance {
                        column.path_radiance_bound(irradiance)
                    } else {
                        0.0
                    }
            }
        }
    }
}

/// Daylight radiance seen looking down on a Lambertian reflector (docs/model.md §4f),
/// photons m⁻² s⁻¹ sr⁻¹ nm⁻¹ (the unit of the irradiance, per steradian), through a
/// stated two-way transmission `transmission`:
/// `L = ρ·F_λ·cos θ_s/π·T` for |θ_s| < 90°, 0 otherwise (NaN for a NaN angle).
///
/// `albedo` is ρ, `solar_irradiance_photons_m2_s_nm` the top-of-atmosphere F_λ (for the
/// day of year: [`solar_spectral_irradiance_photons`] divided by
/// [`earth_sun_distance_au`]²).
pub fn reflected_radiance(
    albedo: f64,
    solar_irradiance_photons_m2_s_nm: f64,
    solar_zenith_deg: f64,
    transmission: f64,
) -> f64 {
    if solar_zenith_deg.abs() >= 90.0 {
        return 0.0;
    }
    let cos_zenith = solar_zenith_deg.to_radians().cos();
    albedo * solar_irradiance_photons_m2_s_nm * cos_zenith / PI * transmission
}

/// ASTM E-490-00a at 1 AU averaged over 10 nm around each node: (nm, W m⁻² nm⁻¹).
/// Each value is the mean of the E-490 entries within ±5 nm of the node (1-nm
/// entries below 630 nm, 2-nm entries above; 5 nm at 850 includes the Ca II lines).
const SOLAR_SPECTRUM_W_M2_NM: [(f64, f64); 32] = [
    (300.0, 0.511),
    (325.0, 0.840),
    (350.0, 0.964),
    (375.0, 1.101),
    (400.0, 1.483),
    (425.0, 1.664),
    (450.0, 1.993),
    (475.0, 2.011),
    (500.0, 1.916),
    (532.0, 1.897),
    (550.0, 1.873),
    (575.0, 1.837),
    (600.0, 1.768),
    (625.0, 1.686),
    (650.0, 1.587),
    (700.0, 1.411),
    (750.0, 1.268),
    (800.0, 1.135),
    (850.0, 0.978),
    (900.0, 0.922),
    (1000.0, 0.745),
    (1064.0, 0.640),
    (1100.0, 0.598),
    (1200.0, 0.501),
    (1300.0, 0.417),
    (1400.0, 0.345),
    (1500.0, 0.294),
    (1550.0, 0.272),
    (1600.0, 0.251),
    (1700.0, 0.207),
    (1800.0, 0.169),
    (2000.0, 0.116),
];

/// Top-of-atmosphere solar spectral irradiance at 1 AU, W m⁻² nm⁻¹: ASTM E-490
/// smoothed over 10 nm, linear between the nodes; NaN outside [300, 2000] nm.
/// 1.90 at 532 nm (model.md quotes 1.86), 0.64 at 1064 nm.
pub fn solar_spectral_irradiance_w_m2_nm(wavelength_nm: f64) -> f64 {
    let table = &SOLAR_SPECTRUM_W_M2_NM;
    let (first, last) = (table[0].0, table[table.len() - 1].0);
    if !(first..=last).contains(&wavelength_nm) {
        return f64::NAN;
    }
    let k = table
        .windows(2)
        .position(|w| wavelength_nm <= w[1].0)
        .unwrap_or(table.len() - 2);
    let ((x0, y0), (x1, y1)) = (table[k], table[k + 1]);
    y0 + (y1 - y0) * (wavelength_nm - x0) / (x1 - x0)
}

/// Top-of-atmosphere solar spectral photon irradiance at 1 AU, photons s⁻¹ m⁻² nm⁻¹:
/// [`solar_spectral_irradiance_w_m2_nm`] divided by the photon energy `h·c/λ`
/// (≈ 5.1e18 at 532 nm, 3.4e18 at 1064 nm); NaN outside [300, 2000] nm.
pub fn solar_spectral_irradiance_photons(wavelength_nm: f64) -> f64 {
    let photon_energy_j = PLANCK_J_S * SPEED_OF_LIGHT_M_PER_S / (wavelength_nm * 1e-9);
    solar_spectral_irradiance_w_m2_nm(wavelength_nm) / photon_energy_j
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2024-01-01T00:00:00Z.
    const UNIX_2024: f64 = 1_704_067_200.0;

    /// Independent check: Spencer (1971, Search 2, 172) Fourier series for the
    /// declination and the equation of time, as restated in NOAA's "General Solar
    /// Position Calculations" (fractional year γ over 365 days). Against the Meeus
    /// equations it is off by up to 0.24° in declination and 0.6 min (0.15°) in the
    /// equation of time over 2024, hence the 0.5° tolerance.
    fn spencer_zenith_deg(unix_time_s: f64, lat_deg: f64, lon_deg: f64) -> f64 {
        let day = (unix_time_s - UNIX_2024) / SECONDS_PER_DAY; // 0 at Jan 1, 0h
        let hour = day.fract() * 24.0;
        let g = 2.0 * PI / 365.0 * (day.floor() + (hour - 12.0) / 24.0);
        let decl = 0.006918 - 0.399912 * g.cos() + 0.070257 * g.sin() - 0.006758 * (2.0 * g).cos()
            + 0.000907 * (2.0 * g).sin()
            - 0.002697 * (3.0 * g).cos()
            + 0.00148 * (3.0 * g).sin();
        let eot = 229.18
            * (0.000075 + 0.001868 * g.cos()
                - 0.032077 * g.sin()
                - 0.014615 * (2.0 * g).cos()
                - 0.040849 * (2.0 * g).sin());
        let ha = ((hour * 60.0 + eot + 4.0 * lon_deg) / 4.0 - 180.0).to_radians();
        let lat = lat_deg.to_radians();
        (lat.sin() * decl.sin() + lat.cos() * decl.cos() * ha.cos())
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }

    #[test]
    fn spa_reference_case() {
        // Reda & Andreas (2004, Solar Energy 76, 577; NREL/TP-560-34302), Table A5.1:
        // 2003-10-17 12:30:30 local (UTC−7), 39.742476° N, 105.1786° W: topocentric
        // zenith 50.11162° including refraction (820 hPa, 11 °C: 0.0163°) and parallax
        // (−0.0019°), i.e. a geometric geocentric zenith of 50.1261°.
        let z = solar_zenith_deg(1_066_419_030.0, 39.742476, -105.1786);
        assert!((z - 50.1261).abs() < 0.02, "{z}");
    }

    #[test]
    fn equinox_sun_overhead_at_the_equator() {
        // March equinox 2024-03-20 03:06 UTC: declination 0
        let t = 1_710_903_960.0;
        let sun = solar_coordinates(julian_century(t));
        assert!(sun.declination_rad.to_degrees().abs() < 0.01);
        // the sub-solar point is on the equator: the minimum zenith there is ≈ 0
        let min = (0..36_000)
            .map(|k| solar_zenith_deg(t, 0.0, -180.0 + k as f64 * 0.01))
            .fold(f64::INFINITY, f64::min);
        assert!(min < 0.02, "{min}");
        // ... and the poles see the sun on the horizon
        assert!((solar_zenith_deg(t, 90.0, 0.0) - 90.0).abs() < 0.02);
    }

    #[test]
    fn solstice_noon_zenith_is_latitude_minus_obliquity() {
        // June solstice 2024-06-20 20:51 UTC: δ = +23.44°
        let t = 1_718_916_660.0;
        let sun = solar_coordinates(julian_century(t));
        assert!((sun.declination_rad.to_degrees() - 23.44).abs() < 0.01);
    }

    #[test]
    fn agrees_with_spencer_series() {
        let mut worst = 0.0f64;
        for day in (0..366).step_by(7) {
            for hour in [0.0, 5.5, 11.0, 14.25, 20.0] {
                let t = UNIX_2024 + day as f64 * SECONDS_PER_DAY + hour * 3600.0;
                for (lat, lon) in [(0.0, 0.0), (45.0, 7.0), (-33.9, 151.2), (70.0, -150.0)] {
                    let d = solar_zenith_deg(t, lat, lon) - spencer_zenith_deg(t, lat, lon);
                    worst = worst.max(d.abs());
                }
            }
        }
        assert!(worst < 0.5, "worst difference {worst}°");
    }

    #[test]
    fn night_is_below_the_horizon() {
        // midnight UTC at Greenwich on the equator, any season
        for day in [0.0, 90.0, 180.0, 270.0] {
            let t = UNIX_2024 + day * SECONDS_PER_DAY;
            assert!(solar_zenith_deg(t, 0.0, 0.0) > 150.0);
            // and noon at 180° E is the same instant
            assert!(solar_zenith_deg(t, 0.0, 180.0) < 30.0);
        }
    }

    #[test]
    fn earth_sun_distance_at_perihelion_and_aphelion() {
        // 2024 perihelion Jan 3 00:39 UTC 0.983 AU, aphelion Jul 5 05:06 UTC 1.017 AU
        let peri = earth_sun_distance_au(1_704_242_340.0);
        let aph = earth_sun_distance_au(1_720_155_960.0);
        assert!((peri - 0.98331).abs() < 1e-4, "{peri}");
        assert!((aph - 1.01673).abs() < 1e-4, "{aph}");
    }

    #[test]
    fn irradiance_at_laser_lines() {
        let w532 = solar_spectral_irradiance_w_m2_nm(532.0);
        assert!((w532 / 1.86 - 1.0).abs() < 0.03, "{w532}");
        let p532 = solar_spectral_irradiance_photons(532.0);
        assert!((p532 / 5.0e18 - 1.0).abs() < 0.03, "{p532}");
        let w1064 = solar_spectral_irradiance_w_m2_nm(1064.0);
        assert!((w1064 - 0.64).abs() < 0.01, "{w1064}");
        assert!((solar_spectral_irradiance_w_m2_nm(355.0) - 0.99).abs() < 0.05);
        assert!(solar_spectral_irradiance_photons(299.0).is_nan());
        assert!(solar_spectral_irradiance_photons(2001.0).is_nan());
        assert!(solar_spectral_irradiance_photons(2000.0).is_finite());
    }

    #[test]
    fn table_integral_is_near_the_solar_constant_share() {
        // E-490 totals 1366.1 W m⁻²; about 11 W m⁻² lie below 300 nm and 78 W m⁻²
        // beyond 2000 nm (its tail ≈ 117 W m⁻² µm⁻¹ at 2 µm falling as λ⁻⁴), so
        // ∫ 300–2000 nm ≈ 1277 W m⁻²
        let mut sum = 0.0;
        let mut l = 300.0;
        while l < 2000.0 {
            sum += solar_spectral_irradiance_w_m2_nm(l + 0.5);
            l += 1.0;
        }
        assert!((sum - 1277.0).abs() < 15.0, "{sum}");
    }

    #[test]
    fn radiance_follows_lambert_and_is_zero_at_night() {
        let f = 5.0e18;
        let l = reflected_radiance(0.3, f, 60.0, 0.8);
        assert!((l - 0.3 * f * 0.5 / PI * 0.8).abs() < 1e-6 * l);
        // model.md: ~1e17–1e18 for land and cloud at moderate sun
        assert!(l > 1e17 && l < 1e18);
        assert_eq!(reflected_radiance(0.3, f, 90.0, 0.8), 0.0);
        assert_eq!(reflected_radiance(0.3, f, 120.0, 0.8), 0.0);
        assert!((reflected_radiance(1.0, PI, 0.0, 1.0) - 1.0).abs() < 1e-12);
    }
}
