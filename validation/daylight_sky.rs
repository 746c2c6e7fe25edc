//! The daylight sky from space against an independent single-scattering integration,
//! and the error of the single-scattering order (validation/reports/daylight_sky.md).
//!
//!     cargo run --release --example daylight_sky
//!
//! (its output is the body of the report, below a summary written by hand).
//!
//! 1. lidarsim's sky (`SkyColumn::radiance`, and the deterministic model's background
//!    over the instrument's factor) against `validation/sky_reference.rs` at 60° and
//!    85° over ocean (ρ = 0.05) and snow (0.8), US76 + the 23 km background aerosol;
//!    the former model (reflected only, plane-parallel, the ½ diffuse rule) beside it.
//! 2. The molecular air mass against Kasten & Young (1989).
//! 3. The order of scattering: a second-order computation for a homogeneous
//!    plane-parallel layer of the same optical depths (molecules alone, and mixed with
//!    the aerosol), and the atmosphere's spherical albedo from below, which sets the
//!    ground–air coupling `1/(1 − ρ·s)` left out by single scattering.
//! 4. The cost: building a column's sky and evaluating it.

#[path = "sky_reference.rs"]
mod sky_reference;

use lidarsim::scene::sky::{SkyColumn, kasten_young_air_mass};
use std::f64::consts::PI;

const CONFIG: &str = r#"name = "daylight sky validation"
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
[atmosphere]
ozone = false
[atmosphere.molecular]
model = "us76"
AEROSOL
[surface]
kind = "ocean"
[background]
model = "solar"
solar_zenith_deg = 60
"#;

fn load(aerosol: bool, set: &[String]) -> lidarsim::scenario::Lidar {
    let dir = std::env::temp_dir().join(format!("lidarsim-daylight-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("sky.toml");
    let aer = if aerosol {
        "[atmosphere.aerosol]\nvisibility_km = 23.0\nlidar_ratio_sr = 50.0"
    } else {
        ""
    };
    std::fs::write(&path, CONFIG.replace("AEROSOL", aer)).unwrap();
    let lidar = lidarsim::scenario::Lidar::load(&path, set).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    lidar
}

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

/// The former model (main before issue 36): `ρ·F·μ/π·e^{−τ}[e^{−τ/μ} + ½(1 − e^{−τ/μ})]`.
fn former(albedo: f64, f: f64, zenith: f64, tau: f64) -> f64 {
    let mu = zenith.to_radians().cos();
    albedo * f * mu / PI * (-tau).exp() * ((-tau / mu).exp() + 0.5 * (1.0 - (-tau / mu).exp()))
}

fn main() {
    let f = lidarsim::scene::sun::solar_spectral_irradiance_photons(532.0);
    println!(
        "Made by `cargo run --release --example daylight_sky` \
         (`validation/daylight_sky.rs`; the reference is `validation/sky_reference.rs`, also \
         used by `tests/solar_background.rs`). 532 nm, F = {f:.4e} photons m⁻² s⁻¹ nm⁻¹ \
         (1 AU), nadir view, US76 molecules, ozone off; radiances in photons m⁻² s⁻¹ sr⁻¹ nm⁻¹.\n"
    );
    for aerosol in [true, false] {
        let lidar = load(aerosol, &[]);
        let sc = lidar.first();
        let column = SkyColumn::above(&sc.atmosphere, 0.0);
        let refc = reference(sc);
        let (tau_sca, _) = column.vertical_depths();
        println!(
            "## 1{}. {} (τ = {tau_sca:.4} above the surface; reference's Rayleigh τ = {:.4})\n",
            if aerosol { "a" } else { "b" },
            if aerosol {
                "US76 + background aerosol (visibility 23 km, Elterman profile, HG g = 0.7)"
            } else {
                "US76 molecules alone"
            },
            refc.molecular_depth()
        );
        println!(
            "| surface | θ_s | lidarsim reflected | lidarsim path | lidarsim total | `expect` total | \
             reference reflected | reference path | reference total | lidarsim / reference | \
             path / reflected | former model | former / reference |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        for (name, albedo) in [("ocean", 0.05), ("snow", 0.8)] {
            for zenith in [60.0, 85.0] {
                let got = column.radiance(albedo, f, zenith, true);
                let model = {
                    let l = load(
                        aerosol,
                        &[
                            format!("background.solar_zenith_deg={zenith}"),
                            format!("surface.albedo={albedo}"),
                        ],
                    );
                    let s = l.first();
                    s.expected().unwrap().background / s.instrument.background_per_radiance
                };
                let want = refc.sky(albedo, f, zenith);
                let total = want.reflected + want.path;
                let old = former(albedo, f, zenith, tau_sca);
                println!(
                    "| {name} ({albedo}) | {zenith}° | {:.4e} | {:.4e} | {:.4e} | {model:.4e} | \
                     {:.4e} | {:.4e} | {total:.4e} | {:.4} | {:.2} | {old:.4e} | {:.3} |",
                    got.reflected,
                    got.path,
                    got.total(),
                    want.reflected,
                    want.path,
                    got.total() / total,
                    want.path / want.reflected,
                    old / total
                );
            }
        }
        println!();
        println!("Each part separately, ρ = 0.8 (lidarsim / reference):\n");
        println!("| θ_s | path | reflected |");
        println!("|---|---|---|");
        for zenith in [30.0, 60.0, 75.0, 80.0, 85.0, 88.0] {
            let got = column.radiance(0.8, 1.0, zenith, true);
            let want = refc.sky(0.8, 1.0, zenith);
            println!(
                "| {zenith}° | {:.4} | {:.4} |",
                got.path / want.path,
                got.reflected / want.reflected
            );
        }
        println!();
    }

    println!("## 2. The air mass\n");
    println!(
        "Kasten & Young (1989): `AM = 1/(cos z + 0.50572·(96.07995 − z_deg)^−1.6364)`. The \
         molecular air mass is the US76 column's slant Rayleigh depth over its vertical one \
         along the straight (unrefracted) spherical path.\n"
    );
    println!("| θ_s | lidarsim | reference (10 m chords) | Kasten–Young | lidarsim / KY | 1/μ |");
    println!("|---|---|---|---|---|---|");
    {
        let lidar = load(false, &[]);
        let column = SkyColumn::above(&lidar.first().atmosphere, 0.0);
        let refc = reference(lidar.first());
        for z in [60.0, 80.0, 85.0, 88.0, 89.5] {
            let got = column.molecular_air_mass(z);
            let ky = kasten_young_air_mass(z);
            println!(
                "| {z}° | {got:.4} | {:.4} | {ky:.4} | {:.4} | {:.3} |",
                refc.molecular_air_mass(z),
                got / ky,
                1.0 / z.to_radians().cos()
            );
        }
    }
    println!();

    println!("## 3. The order of scattering\n");
    let lidar = load(true, &[]);
    let a = lidar.first().atmosphere.aerosol.clone().unwrap();
    let tau_r = reference(load(false, &[]).first()).molecular_depth();
    let tau_a: f64 = (0..100_000)
        .map(|k| a.extinction_per_m(k as f64 + 0.5))
        .sum();
    println!(
        "Homogeneous plane-parallel layers, black surface, nadir view (scalar, no polarization): \
         the second-order path radiance I₂ over the first I₁ (`second_order` below: the \
         first-order field in every direction integrated analytically in depth, the \
         second scattering by a 200 × 200 × 72 rule in (τ, μ', φ')). The solar beam's \
         attenuation uses the air mass s (1/μ at 60°, the spherical 10.2 at 85°). τ_R = \
         {tau_r:.4}, τ_aer = {tau_a:.4}.\n"
    );
    println!("| layer | θ_s | I₂/I₁ | successive orders 1/(1 − I₂/I₁) − 1 |");
    println!("|---|---|---|---|");
    for (name, tr, ta) in [
        ("molecules", tau_r, 0.0),
        ("molecules + aerosol", tau_r, tau_a),
    ] {
        for (zenith, s) in [(60.0, 2.0), (85.0, 10.2)] {
            let r = second_order(tr, ta, 0.7, zenith, s);
            println!(
                "| {name} | {zenith}° | {r:.4} | {:.4} |",
                1.0 / (1.0 - r) - 1.0
            );
        }
    }
    println!();
    for (name, tr, ta) in [
        ("molecules", tau_r, 0.0),
        ("molecules + aerosol", tau_r, tau_a),
    ] {
        let s = spherical_albedo(tr, ta, 0.7);
        println!(
            "Spherical albedo from below (single scattering), {name}: s = {s:.4}; coupling \
             1/(1 − ρs) − 1 = {:+.2} % (ocean), {:+.2} % (snow) of the reflected term.\n",
            100.0 * (1.0 / (1.0 - 0.05 * s) - 1.0),
            100.0 * (1.0 / (1.0 - 0.8 * s) - 1.0)
        );
    }

    shipped();

    println!("## 4. Cost\n");
    let sc = lidar.first();
    let t0 = std::time::Instant::now();
    let n_build = 20;
    let mut column = SkyColumn::above(&sc.atmosphere, 0.0);
    for _ in 1..n_build {
        column = SkyColumn::above(&sc.atmosphere, 0.0);
    }
    let build = t0.elapsed().as_secs_f64() / n_build as f64;
    let t0 = std::time::Instant::now();
    let n_eval = 2_000;
    let mut sum = 0.0;
    for k in 0..n_eval {
        sum += column
            .radiance(0.05, f, 40.0 + 45.0 * k as f64 / n_eval as f64, true)
            .total();
    }
    let eval = t0.elapsed().as_secs_f64() / n_eval as f64;
    println!(
        "One column of US76 + aerosol at 7.5 m slabs (CALIOP's grid), {} sky layers: built in {:.2} ms, \
         evaluated in {:.1} µs per solar angle (once per profile, channel and column seen; \
         mean {:.3e}). A night or fixed-background scene builds none. (One machine, 2 cores \
         shared; indicative.)",
        column.n_layers(),
        build * 1e3,
        eval * 1e6,
        sum / n_eval as f64
    );
}

/// The shipped daytime orbit presets: per profile the sky radiance (the run's
/// shot-weighted background over the instrument's factor, less the night floor) with
/// and without the path radiance.
fn shipped() {
    println!("## 5. Shipped configs whose outputs change\n");
    println!(
        "`expected_background` (and so the counts) of every daylit profile of the presets \
         with `background.model = \"solar\"`. The sky radiance L (photons m⁻² s⁻¹ sr⁻¹ nm⁻¹) \
         at a few profiles, with `background.path_radiance = false` beside it (the reflected \
         term alone, itself changed by the spherical path and the single-scattered diffuse \
         light down and up); the former model's reflected term was 0.13–0.94 of the \
         reference's total in §1.\n"
    );
    println!("| config | profile | θ_s | L | reflected only | L / reflected |");
    println!("|---|---|---|---|---|---|");
    for name in ["caliop_orbit.toml", "caliop_orbit_wide_angle.toml"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("configs/instruments")
            .join(name);
        let sky = |set: &[String]| -> (Vec<f64>, Vec<f64>) {
            let lidar = lidarsim::scenario::Lidar::load(&path, set).unwrap();
            let profiles = lidar.first().loaded.config.acquisition.profiles as u64;
            let energy = lidarsim::simulate::run_energy(&lidar, 1, 0.0).unwrap();
            let model = lidarsim::simulate::scene::SceneModel::new(
                &lidar,
                1,
                profiles,
                lidarsim::simulate::ResolvedMethod::Aggregate,
                energy,
            )
            .unwrap();
            let factor = lidar.first().instrument.background_per_radiance;
            let floor = lidar
                .first()
                .loaded
                .config
                .background
                .radiance
                .unwrap_or(0.0);
            let sunlight = model.sunlight().unwrap();
            (0..profiles)
                .map(|p| {
                    let runs = model.runs(p);
                    let b = model.run_backgrounds(0, p, &runs);
                    let shots: u64 = runs.iter().map(|r| r.1).sum();
                    let mean: f64 = runs
                        .iter()
                        .zip(&b)
                        .map(|(r, b)| r.1 as f64 * b)
                        .sum::<f64>()
                        / shots as f64;
                    ((mean / factor - floor).max(0.0), sunlight.sun_at(p).0)
                })
                .unzip()
        };
        let (with, zenith) = sky(&[]);
        let (without, _) = sky(&["background.path_radiance=false".into()]);
        for p in [0usize, 25, 50, 60, 100, 130, 150, 165, 170, 175] {
            if p >= with.len() {
                continue;
            }
            println!(
                "| {name} | {p} | {:.2}° | {:.4e} | {:.4e} | {:.2} |",
                zenith[p],
                with[p],
                without[p],
                if without[p] > 0.0 {
                    with[p] / without[p]
                } else {
                    f64::NAN
                }
            );
        }
    }
    println!();
}

/// Mixed phase function of molecules (τ_r) and HG particles (τ_a, g).
fn mixed_phase(cos_theta: f64, tr: f64, ta: f64, g: f64) -> f64 {
    let r = 0.75 * (1.0 + cos_theta * cos_theta);
    let h = (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_theta).powf(1.5);
    (tr * r + ta * h) / (tr + ta)
}

/// I₂/I₁ of the path radiance at the top, nadir, for a homogeneous conservative layer
/// of depth τ_r + τ_a over a black surface, sun at `zenith` with beam air mass `s`.
fn second_order(tr: f64, ta: f64, g: f64, zenith: f64, s: f64) -> f64 {
    let tau0 = tr + ta;
    let mu_s = zenith.to_radians().cos();
    let sin_s = (1.0 - mu_s * mu_s).sqrt();
    let (nt, nm, np) = (200, 200, 72);
    // the φ'-average of the first scattering's phase function per μ' node
    let mus: Vec<f64> = (0..nm)
        .map(|j| -1.0 + (j as f64 + 0.5) * 2.0 / nm as f64)
        .collect();
    let avg: Vec<f64> = mus
        .iter()
        .map(|&m| {
            let sm = (1.0 - m * m).sqrt();
            (0..np)
                .map(|q| {
                    let phi = (q as f64 + 0.5) * 2.0 * PI / np as f64;
                    mixed_phase(sin_s * sm * phi.cos() - mu_s * m, tr, ta, g)
                })
                .sum::<f64>()
                / np as f64
        })
        .collect();
    let d_mu = 2.0 / nm as f64;
    let d_t = tau0 / nt as f64;
    let mut i2 = 0.0;
    for k in 0..nt {
        let t = (k as f64 + 0.5) * d_t;
        let mut j2 = 0.0;
        for (j, &m) in mus.iter().enumerate() {
            let geom = if m < 0.0 {
                let u = -m;
                let d = s * u - 1.0;
                if d.abs() < 1e-9 {
                    t * (-t * s).exp() / u
                } else {
                    ((-t / u).exp() - (-t * s).exp()) / d
                }
            } else {
                ((-t * s).exp() - (-tau0 * s - (tau0 - t) / m).exp()) / (s * m + 1.0)
            };
            // second scattering from direction μ' into the nadir-up view: cos Θ = μ'
            j2 += mixed_phase(m, tr, ta, g) * avg[j] * geom * d_mu;
        }
        i2 += 0.5 * j2 * (-t).exp() * d_t;
    }
    // both carry F/(4π); first order at the top, nadir
    let i1 = mixed_phase(-mu_s, tr, ta, g) * (1.0 - (-tau0 * (s + 1.0)).exp()) / (s + 1.0);
    i2 / i1
}

/// The single-scattering spherical albedo of a homogeneous layer lit from below by an
/// isotropic radiance: downward irradiance scattered back once over the upward one.
fn spherical_albedo(tr: f64, ta: f64, g: f64) -> f64 {
    let tau0 = tr + ta;
    let (nt, nm, np) = (100, 48, 36);
    let mu: Vec<f64> = (0..nm).map(|j| (j as f64 + 0.5) / nm as f64).collect();
    let (d_t, d_mu, d_phi) = (tau0 / nt as f64, 1.0 / nm as f64, 2.0 * PI / np as f64);
    let mut e = 0.0;
    for k in 0..nt {
        let t = (k as f64 + 0.5) * d_t;
        for &a in &mu {
            for &b in &mu {
                let (sa, sb) = ((1.0 - a * a).sqrt(), (1.0 - b * b).sqrt());
                // up (a) scattered into down (b): cos Θ = −a·b + sa·sb·cos Δφ
                let p: f64 = (0..np)
                    .map(|q| {
                        mixed_phase(
                            -a * b + sa * sb * ((q as f64 + 0.5) * d_phi).cos(),
                            tr,
                            ta,
                            g,
                        )
                    })
                    .sum::<f64>()
                    * d_phi;
                // incoming radiance 1 at slant t/a; into 2π·d_mu of up directions; out to
                // the bottom at slant t/b, irradiance weight b·(1/b) path factor
                e +=
                    p / (4.0 * PI) * (-t / a).exp() * (-t / b).exp() * 2.0 * PI * d_mu * d_mu * d_t;
            }
        }
    }
    e / PI
}
