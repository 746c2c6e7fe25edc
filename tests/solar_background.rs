//! Sunlight through the atmosphere (docs/model.md "Sunlight from the
//! scene"): the solar background seen from above is `ρ·F_λ·μ/π·T(μ)` with, for a
//! molecules-only atmosphere (no absorber),
//! `T(μ) = exp(−τ)·[exp(−τ/μ) + ½·(1 − exp(−τ/μ))]`, μ = cos θ_s, τ the Rayleigh optical
//! depth above the reflector. τ is computed here independently of lidarsim: the Bucholtz
//! (1995, Appl. Opt. 34, 2765, Eq. 8 and Table 3) fit of the Rayleigh cross-section,
//! times the air column of a hydrostatic atmosphere, `p0/(m_air·g_eff)` (U.S. Standard
//! Atmosphere 1976: p0 = 101,325 Pa, M = 28.9644 g/mol; g_eff = g at the mass-weighted
//! mean altitude, ~8 km, 0.25 % below g0).

mod common;

use std::f64::consts::PI;
use std::path::PathBuf;

/// Bucholtz (1995) Eq. 8: σ(λ) = A·λ^−(B + C·λ + D/λ), λ in µm, σ in cm², with his
/// Table 3 coefficients for λ > 0.5 µm: A = 4.01061e-28, B = 3.99668, C = 1.10298e-3,
/// D = 2.71393e-2 (5.16e-27 cm² at 532 nm).
fn bucholtz_cross_section_m2(wavelength_um: f64) -> f64 {
    let (a, b, c, d) = (4.01061e-28, 3.99668, 1.10298e-3, 2.71393e-2);
    a * wavelength_um.powf(-(b + c * wavelength_um + d / wavelength_um)) * 1e-4
}

/// The air column above sea level, molecules m⁻² (hydrostatic).
fn air_column_m2() -> f64 {
    let (p0, molar_mass, avogadro) = (101_325.0, 0.028_964_4, 6.022_140_76e23);
    let g_eff = 9.806_65 * (6_356_766.0f64 / (6_356_766.0 + 8_000.0)).powi(2);
    p0 / (molar_mass / avogadro * g_eff)
}

/// The slant-path factor of the issue's formula, molecules only.
fn slant(tau: f64, mu: f64) -> f64 {
    (-tau).exp() * ((-tau / mu).exp() + 0.5 * (1.0 - (-tau / mu).exp()))
}

/// A space-borne 532 nm config over the ocean (ρ = 0.05, at sea level), molecules
/// only (US76, no aerosol, no ozone, no layers), no night floor; `extra` TOML appended.
fn config(dir: &std::path::Path, extra: &str) -> PathBuf {
    let text = format!(
        r#"name = "solar background test"
[instrument]
wavelength_nm = 532.0
pulse_energy_j = 0.110
rep_rate_hz = 20.16
telescope_area_m2 = 0.785
optical_efficiency = 1.0
receiver_efficiency = 0.7
filter_transmission = 0.85
quantum_efficiency = 0.12
fov_rad = 130e-6
filter_width_nm = 0.037
dark_count_rate_hz = 100.0
bin_width_s = 2e-7
[platform]
kind = "spaceborne"
altitude_km = 705.0
[acquisition]
accumulation_time_s = 0.744
top_altitude_km = 100.0
bottom_altitude_km = -0.5
profiles = 4
start_time = "2024-06-20T12:00:00Z"
[atmosphere]
ozone = false
[atmosphere.molecular]
model = "us76"
[surface]
kind = "ocean"
[simulation]
seed = 1
{extra}
"#
    );
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("solar.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("lidarsim-solar-{name}-{}", std::process::id()))
}

/// The deterministic model's background (fixed zenith angle) at θ_s = 60° and 85°
/// equals `ρ·F·μ/π·T(μ)·factor` with T from the independent τ, within 0.5 % (the
/// issue's criterion is 2 %); the atmosphere's factor T alone (against a stated
/// transmission of 1) too. A 1 % error in the background, or the old constant 0.8
/// (20 % off at 60°), fails.
#[test]
fn solar_background_follows_the_slant_path_at_60_and_85_degrees() {
    let dir = scratch("fixed");
    let tau = bucholtz_cross_section_m2(0.532) * air_column_m2();
    // the Rayleigh optical depth of a standard atmosphere at 532 nm is ~0.11
    assert!((tau - 0.111).abs() < 0.002, "τ = {tau}");
    let f = lidarsim::scene::sun::solar_spectral_irradiance_photons(532.0);
    for zenith in [60.0f64, 85.0] {
        let path = config(
            &dir,
            &format!("[background]\nmodel = \"solar\"\nsolar_zenith_deg = {zenith}\n"),
        );
        let lidar = lidarsim::scenario::Lidar::load(&path, &[]).unwrap();
        let sc = lidar.first();
        let got = sc.expected().unwrap().background;
        let mu = zenith.to_radians().cos();
        let factor = sc.instrument.background_per_radiance;
        let want = 0.05 * f * mu / PI * slant(tau, mu) * factor;
        assert!(
            (got / want - 1.0).abs() < 0.005,
            "θ_s = {zenith}: {got} vs {want}"
        );
        // the atmosphere's share alone, against a stated transmission of 1
        let bare = lidarsim::scenario::Lidar::load(&path, &["background.transmission=1".into()])
            .unwrap()
            .first()
            .expected()
            .unwrap()
            .background;
        let t = got / bare;
        eprintln!(
            "θ_s = {zenith}: τ = {tau:.5}, background {got:.6e} vs {want:.6e} ({:+.3} %), T = {t:.5}",
            (got / want - 1.0) * 100.0
        );
        assert!(
            (t / slant(tau, mu) - 1.0).abs() < 0.005,
            "θ_s = {zenith}: T = {t} vs {}",
            slant(tau, mu)
        );
    }
    // below the horizon: nothing
    let path = config(
        &dir,
        "[background]\nmodel = \"solar\"\nsolar_zenith_deg = 90\n",
    );
    let lidar = lidarsim::scenario::Lidar::load(&path, &[]).unwrap();
    assert_eq!(lidar.first().expected().unwrap().background, 0.0);
    std::fs::remove_dir_all(&dir).ok();
}

/// Near the terminator the background falls with the slant path, far below a
/// constant transmission: at 85° T(μ) is 0.62 of its 60° value (0.8 held constant
/// would keep it), and the drop from 60° to 89° of `μ·T(μ)` exceeds the drop of μ alone.
#[test]
fn the_background_drops_near_the_terminator() {
    let tau = bucholtz_cross_section_m2(0.532) * air_column_m2();
    let (t60, t85) = (slant(tau, 0.5), slant(tau, 85f64.to_radians().cos()));
    assert!(t85 / t60 < 0.85, "{t85} / {t60}");
    let dir = scratch("drop");
    let path = config(
        &dir,
        "[background]\nmodel = \"solar\"\nsolar_zenith_deg = 60\n",
    );
    let at = |z: f64| {
        lidarsim::scenario::Lidar::load(&path, &[format!("background.solar_zenith_deg={z}")])
            .unwrap()
            .first()
            .expected()
            .unwrap()
            .background
    };
    let ratio = at(85.0) / at(60.0);
    let want = 85f64.to_radians().cos() / 0.5 * t85 / t60;
    assert!((ratio / want - 1.0).abs() < 0.005, "{ratio} vs {want}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Along an orbit the simulated file's `expected_background` of a daylit profile is the
/// slant-path formula at that profile's own solar zenith angle (from the file's
/// latitude, longitude and time), within 0.5 %.
#[test]
fn an_orbit_run_uses_the_slant_path() {
    let dir = scratch("orbit");
    let path = config(
        &dir,
        "[background]\nmodel = \"solar\"\n[orbit]\ninclination_deg = 98.2\n\
         start_latitude_deg = -50.0\nstart_longitude_deg = 0.0\nascending = false\n",
    );
    let out = dir.join("run.h5");
    common::cli::ok(common::cli::lidarsim(
        &dir,
        &[
            "simulate",
            path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        &[],
    ));
    let f = hdf5::File::open(&out).unwrap();
    let read = |n: &str| -> Vec<f64> { f.dataset(n).unwrap().read_raw().unwrap() };
    let (lat, lon, bkg, n_bins) = (
        read("latitude"),
        read("longitude"),
        read("expected_background"),
        read("altitude").len(),
    );
    let tau = bucholtz_cross_section_m2(0.532) * air_column_m2();
    let start = humantime::parse_rfc3339("2024-06-20T12:00:00Z").unwrap();
    let start_s = start
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64();
    let factor = lidarsim::scenario::Lidar::load(&path, &[])
        .unwrap()
        .first()
        .instrument
        .background_per_radiance;
    let f532 = lidarsim::scene::sun::solar_spectral_irradiance_photons(532.0);
    for p in 0..4 {
        let unix = start_s + (p as f64 + 0.5) * 15.0 / 20.16;
        let zenith = lidarsim::scene::sun::solar_zenith_deg(unix, lat[p], lon[p]);
        assert!(zenith > 60.0 && zenith < 80.0, "{zenith}");
        let au = lidarsim::scene::sun::earth_sun_distance_au(unix);
        let mu = zenith.to_radians().cos();
        let want = 0.05 * f532 / (au * au) * mu / PI * slant(tau, mu) * factor;
        let got = bkg[p * n_bins];
        assert!(
            (got / want - 1.0).abs() < 0.005,
            "profile {p}: {got} vs {want}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
