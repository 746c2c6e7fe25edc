//! The daylight sky from space (docs/model.md "Sky light from space by day",
//! `src/scene/sky.rs`): the sunlight reflected below *and* the air's own once-scattered
//! sunlight, the sun's path through a spherical atmosphere. The reference is
//! `validation/sky_reference.rs`, a single-scattering integration written apart from
//! lidarsim's sky code: its own U.S. Standard Atmosphere 1976 column times Bucholtz's
//! (1995) Rayleigh cross-section, the scene's aerosol profile as a Henyey–Greenstein
//! species of g = 0.7, exact spherical chords from every 10–50 m grid point, fine
//! (μ', φ') rules for the diffuse light (validation/reports/daylight_sky.md).

mod common;

#[path = "../validation/sky_reference.rs"]
#[allow(dead_code)]
mod sky_reference;

use std::path::PathBuf;

/// A space-borne 532 nm config (US76 molecules, no ozone, no layers, no night floor)
/// over a sea-level surface of albedo `albedo`; `extra` TOML appended. `aerosol`: the
/// background aerosol of 23 km visibility (`[atmosphere.aerosol]`) or none.
fn config(dir: &std::path::Path, albedo: f64, aerosol: bool, extra: &str) -> PathBuf {
    let aerosol = if aerosol {
        "[atmosphere.aerosol]\nvisibility_km = 23.0\nlidar_ratio_sr = 50.0\n"
    } else {
        ""
    };
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
{aerosol}
[surface]
kind = "ocean"
albedo = {albedo}
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

/// The reference column of a loaded scene: its own molecules, and the scene's
/// background aerosol profile (if any) as an HG species of g = 0.7.
fn reference(sc: &lidarsim::scenario::Scenario) -> sky_reference::Column {
    let none = |_: f64| 0.0;
    match &sc.atmosphere.aerosol {
        Some(a) => {
            let aer = |z: f64| a.extinction_per_m(z);
            sky_reference::Column::new(0.532, 0.0, &none, &[(0.7, &aer)])
        }
        None => sky_reference::Column::new(0.532, 0.0, &none, &[]),
    }
}

/// The sky radiance of a fixed-zenith scene from the deterministic model: its
/// background counts over the instrument's counts per unit radiance.
fn model_radiance(path: &std::path::Path, set: &[String]) -> f64 {
    let lidar = lidarsim::scenario::Lidar::load(path, set).unwrap();
    let sc = lidar.first();
    sc.expected().unwrap().background / sc.instrument.background_per_radiance
}

/// The issue's criterion: the daylight sky radiance (reflected + path) at θ_s = 60°
/// and 85° over the ocean (ρ = 0.05) and snow (ρ = 0.8), US76 molecules and the 23 km
/// background aerosol, agrees with the independent single-scattering integration
/// within 1 % (the issue asks 10 %; measured: ≤ 0.03 %, validation/reports/
/// daylight_sky.md). Today's main (reflected term only, plane-parallel, the ½ rule)
/// gives 0.32, 0.13, 0.75 and 0.94 of it and fails.
#[test]
fn the_daylight_sky_agrees_with_a_single_scattering_integration() {
    let dir = scratch("sky");
    let f = lidarsim::scene::sun::solar_spectral_irradiance_photons(532.0);
    for albedo in [0.05, 0.8] {
        let path = config(
            &dir,
            albedo,
            true,
            "[background]\nmodel = \"solar\"\nsolar_zenith_deg = 60\n",
        );
        let lidar = lidarsim::scenario::Lidar::load(&path, &[]).unwrap();
        let column = reference(lidar.first());
        for zenith in [60.0, 85.0] {
            let got = model_radiance(&path, &[format!("background.solar_zenith_deg={zenith}")]);
            let want = column.sky(albedo, f, zenith);
            let ratio = got / (want.reflected + want.path);
            eprintln!(
                "ρ = {albedo}, θ_s = {zenith}°: lidarsim {got:.4e}, reference {:.4e} \
                 (reflected {:.4e}, path {:.4e}), ratio {ratio:.4}",
                want.reflected + want.path,
                want.reflected,
                want.path
            );
            assert!((ratio - 1.0).abs() < 0.01, "ρ {albedo}, {zenith}°: {ratio}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Each part on its own, molecules only and with aerosol, at 30°–88°: the path
/// radiance and the reflected term of `SkyColumn::radiance` against the reference's
/// within 0.5 % (measured ≤ 0.12 %, at 88°), and
/// `background.path_radiance = false` leaves the reflected term alone.
#[test]
fn the_path_and_reflected_parts_each_agree() {
    use lidarsim::scene::sky::SkyColumn;
    let dir = scratch("parts");
    for aerosol in [false, true] {
        let path = config(
            &dir,
            0.8,
            aerosol,
            "[background]\nmodel = \"solar\"\nsolar_zenith_deg = 60\n",
        );
        let lidar = lidarsim::scenario::Lidar::load(&path, &[]).unwrap();
        let sc = lidar.first();
        let column = SkyColumn::above(&sc.atmosphere, 0.0);
        let reference = reference(sc);
        for zenith in [30.0, 60.0, 75.0, 85.0, 88.0] {
            let got = column.radiance(0.8, 1.0, zenith, true);
            let want = reference.sky(0.8, 1.0, zenith);
            let (rp, rr) = (got.path / want.path, got.reflected / want.reflected);
            eprintln!("aerosol {aerosol}, {zenith}°: path {rp:.4}, reflected {rr:.4}");
            assert!((rp - 1.0).abs() < 0.005, "{aerosol} {zenith}: path {rp}");
            assert!(
                (rr - 1.0).abs() < 0.005,
                "{aerosol} {zenith}: reflected {rr}"
            );
            let off = column.radiance(0.8, 1.0, zenith, false);
            assert_eq!((off.path, off.reflected), (0.0, got.reflected));
        }
        // the switch in the config
        let with = model_radiance(&path, &[]);
        let without = model_radiance(&path, &["background.path_radiance=false".into()]);
        let r = column.radiance(0.8, 1.0, 60.0, true);
        assert!((without / with - r.reflected / r.total()).abs() < 1e-6);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The spherical air mass. Kasten & Young (1989):
/// `AM = 1/(cos z + 0.50572·(96.07995 − z)^−1.6364)`, by hand 10.3058 at 85° and
/// 19.4332 at 88° (1.9943 at 60°): `kasten_young_air_mass` to 1e-5. The molecular air
/// mass of lidarsim's US76 column along its straight spherical solar path
/// (`molecular_air_mass`: 1.9931, 10.201, 18.822) against the reference's chords from
/// its 10 m grid (1.9932, 10.204, 18.835) within 0.2 %, and both against Kasten–Young
/// within 0.2 % at 60°, 1.5 % at 85° and 3.5 % at 88°: Kasten & Young integrate along
/// the refracted ray, which near the horizon stays longer in the dense air (+1.0 % at
/// 85°, +3.2 % at 88°); lidarsim's sun is geometric (no refraction, `scene/sun.rs`).
/// The plane-parallel 1/μ is 11 % high at 85° and 47 % at 88°. A 1 % error in either
/// formula fails.
#[test]
fn the_air_mass_is_spherical() {
    use lidarsim::scene::sky::{SkyColumn, kasten_young_air_mass};
    for (z, hand) in [(60.0, 1.99429), (85.0, 10.30579), (88.0, 19.43325)] {
        let ky = kasten_young_air_mass(z);
        assert!((ky / hand - 1.0).abs() < 1e-5, "{z}: {ky} vs {hand}");
    }
    let dir = scratch("airmass");
    let path = config(
        &dir,
        0.05,
        false,
        "[background]\nmodel = \"solar\"\nsolar_zenith_deg = 60\n",
    );
    let lidar = lidarsim::scenario::Lidar::load(&path, &[]).unwrap();
    let sc = lidar.first();
    let column = SkyColumn::above(&sc.atmosphere, 0.0);
    let reference = reference(sc);
    for (z, tol) in [(60.0, 0.002), (85.0, 0.015), (88.0, 0.035)] {
        let (got, own) = (
            column.molecular_air_mass(z),
            reference.molecular_air_mass(z),
        );
        let hand = 1.0 / (z.to_radians().cos() + 0.50572 * (96.07995 - z).powf(-1.6364));
        eprintln!("{z}°: lidarsim {got:.4}, reference {own:.4}, Kasten-Young {hand:.4}");
        assert!((got / hand - 1.0).abs() < tol, "{z}: {got} vs {hand}");
        assert!(
            (own / hand - 1.0).abs() < tol,
            "{z}: reference {own} vs {hand}"
        );
        assert!((got / own - 1.0).abs() < 0.002, "{z}: {got} vs {own}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Near the terminator the sky falls with the slant path, as the reference's does:
/// the ratio of the 85° to the 60° radiance over the ocean within 3 %; and below the
/// horizon it is 0.
#[test]
fn the_sky_drops_near_the_terminator() {
    let dir = scratch("drop");
    let path = config(
        &dir,
        0.05,
        true,
        "[background]\nmodel = \"solar\"\nsolar_zenith_deg = 60\n",
    );
    let at = |z: f64| model_radiance(&path, &[format!("background.solar_zenith_deg={z}")]);
    let lidar = lidarsim::scenario::Lidar::load(&path, &[]).unwrap();
    let column = reference(lidar.first());
    let sky = |z: f64| {
        let s = column.sky(0.05, 1.0, z);
        s.reflected + s.path
    };
    let ratio = at(85.0) / at(60.0);
    let want = sky(85.0) / sky(60.0);
    assert!((ratio / want - 1.0).abs() < 0.03, "{ratio} vs {want}");
    assert_eq!(at(90.0), 0.0);
    std::fs::remove_dir_all(&dir).ok();
}

/// Along an orbit the simulated file's `expected_background` of a daylit profile is the
/// reference's sky at that profile's own solar zenith angle (from the file's
/// latitude, longitude and time) and sun distance, within 3 %.
#[test]
fn an_orbit_run_sees_the_daylight_sky() {
    let dir = scratch("orbit");
    let path = config(
        &dir,
        0.05,
        false,
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
        common::h5::per_profile(&f, "expected_background"),
        read("altitude").len(),
    );
    let start = humantime::parse_rfc3339("2024-06-20T12:00:00Z").unwrap();
    let start_s = start
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64();
    let lidar = lidarsim::scenario::Lidar::load(&path, &[]).unwrap();
    let factor = lidar.first().instrument.background_per_radiance;
    let column = reference(lidar.first());
    let f532 = lidarsim::scene::sun::solar_spectral_irradiance_photons(532.0);
    for p in 0..4 {
        let unix = start_s + (p as f64 + 0.5) * 15.0 / 20.16;
        let zenith = lidarsim::scene::sun::solar_zenith_deg(unix, lat[p], lon[p]);
        assert!(zenith > 60.0 && zenith < 80.0, "{zenith}");
        let au = lidarsim::scene::sun::earth_sun_distance_au(unix);
        let sky = column.sky(0.05, f532 / (au * au), zenith);
        let want = (sky.reflected + sky.path) * factor;
        let got = bkg[p * n_bins];
        assert!(
            (got / want - 1.0).abs() < 0.03,
            "profile {p}: {got} vs {want}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
