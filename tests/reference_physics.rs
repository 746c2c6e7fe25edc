//! The physics against references that do not call the code under test
//! (`tests/common/reference.rs`: formulas written from their sources, published tables,
//! quadrature written here). Each check is tight enough that a 1 % error in the formula
//! it covers fails it: ozone in T², the ozone cross-section, the ozone column, the range
//! weight `∫η/r² dr`, the sky light a polarization channel receives, the molecular
//! backscatter, the signal constant.

mod common;

use common::reference as r;
use common::{lidar, scenario};
use lidarsim::atmosphere::ozone;
use lidarsim::config::PlatformKind;
use lidarsim::scenario::Scenario;

fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// Ozone's one-way optical depth from the top of the atmosphere to each bin centre, as
/// the simulator's T² carries it (`T²_with / T²_without`), against the AFGL column
/// integrated here times the published cross-section, over `cos φ` on a flat Earth.
/// A 1 % error in σ or in the column moves τ by 1 %; the tolerance is 2e-3, and T²
/// without ozone in T² (τ = 0) fails by 100 %.
#[test]
fn ozone_in_the_two_way_transmission_is_the_afgl_column_times_the_cross_section() {
    for (off_nadir, wl) in [("0", "532"), ("20", "532"), ("0", "600"), ("0", "354.7")] {
        let over = |ozone: &str| {
            scenario(
                "paper/scenario1.toml",
                &[
                    &format!("atmosphere.ozone={ozone}"),
                    &format!("platform.off_nadir_deg={off_nadir}"),
                    "platform.earth_curvature=false",
                    &format!("instrument.wavelength_nm={wl}"),
                ],
            )
        };
        let (on, off) = (over("true"), over("false"));
        let (e_on, e_off) = (on.expected().unwrap(), off.expected().unwrap());
        let cfg = &on.loaded.config;
        // at 354.7 nm the Huggins band's [354, 355) nm bin (DBM, 228 K)
        let sigma = r::ozone_cross_section_m2(wl.parse().unwrap());
        let cos = (off_nadir.parse::<f64>().unwrap()).to_radians().cos();
        let mut checked = 0;
        for i in 0..e_on.n_bins() {
            let z = e_on.altitude_m[i];
            if !(0.0..60_000.0).contains(&z) || e_off.t2[i] < 1e-6 {
                continue;
            }
            // the bin centre's altitude from this test's own geometry
            let (a, b) = r::bins(cfg)[i];
            let z_ref = r::altitude_at_range(cfg, 0.5 * (a + b));
            assert!((z - z_ref).abs() < 1e-6, "bin {i}: {z} vs {z_ref}");
            let tau_sim = -0.5 * (e_on.t2[i] / e_off.t2[i]).ln();
            let tau_ref = sigma * r::ozone_column_m2(z_ref, 60_000.0) / cos;
            if tau_ref < 1e-6 {
                continue;
            }
            assert!(
                rel(tau_sim, tau_ref) < 2e-3,
                "{wl} nm, {off_nadir}°, bin {i} at {z:.0} m: τ_O3 {tau_sim} vs {tau_ref}"
            );
            checked += 1;
        }
        assert!(checked > 150, "{checked}");
        // the ozone's two-way transmission to the ground at 532 nm, nadir: about 0.95
        if wl == "532" && off_nadir == "0" {
            let t2 = (-2.0 * sigma * r::ozone_column_m2(0.0, 60_000.0)).exp();
            assert!((0.945..0.96).contains(&t2), "{t2}");
        }
    }
}

/// The total column of the embedded profile against this test's own quadrature of the
/// AFGL table (344 DU); the model's closed form within 1e-4.
#[test]
fn the_ozone_column_is_the_afgl_tables_column() {
    let du = r::ozone_column_m2(0.0, 60_000.0) / r::DOBSON_M2;
    assert!(
        rel(ozone::column_du(), du) < 1e-4,
        "{} vs {du}",
        ozone::column_du()
    );
    for (lo, hi) in [(0.0, 15_000.0), (15_000.0, 30_000.0), (22_000.0, 60_000.0)] {
        let col = r::ozone_column_m2(lo, hi);
        assert!(rel(ozone::column_m2(lo, hi), col) < 1e-4, "{lo}–{hi}");
    }
    for z in [0.0, 500.0, 9_700.0, 22_000.0, 33_333.0, 59_000.0] {
        assert!(
            rel(ozone::number_density_m3(z), r::ozone_number_density_m3(z)) < 1e-9,
            "{z}"
        );
    }
}

/// σ_O3 at several wavelengths equals the published 10-nm bin averages (Serdyuchenko
/// et al. 2014, 233 K, as tabulated by Bruneton 2017: 4.672e-21 cm² at 570–580 nm, …)
/// and, from 350 to 360 nm, the 1-nm bin means of DBM at 228 K (Malicet et al. 1995:
/// 3.539e-23 cm² over [354, 355) nm); 1 % off anywhere fails.
#[test]
fn the_ozone_cross_section_is_the_published_table() {
    let published = [
        (350.0, 8.185e-27),   // [350, 351), the Huggins table's first bin
        (351.4, 2.544e-26),   // [351, 352): the band's peak at 351.4 nm
        (354.7, 3.539e-27),   // [354, 355): the Nd:YAG third harmonic
        (355.0, 3.955e-27),   // [355, 356)
        (359.999, 4.654e-27), // [359, 360), the last
        (400.0, 1.527e-27),   // [400, 410)
        (450.0, 2.316e-26),
        (500.0, 1.48e-25),
        (532.0, 2.755e-25), // [530, 540): 2.76e-21 cm², model.md ≈ 2.8e-21
        (575.0, 4.672e-25),
        (600.0, 5.019e-25), // the Chappuis maximum bin
        (650.0, 2.238e-25),
        (700.0, 7.455e-26),
        (750.0, 3.237e-26),
        (835.0, 7.105e-27), // the last bin
    ];
    for (wl, sigma) in published {
        assert!(
            rel(ozone::cross_section_m2(wl), sigma) < 1e-6,
            "{wl} nm: {} vs {sigma}",
            ozone::cross_section_m2(wl)
        );
        assert_eq!(r::ozone_cross_section_m2(wl), sigma, "the test's table");
    }
    assert_eq!(ozone::cross_section_m2(1064.0), 0.0);
}

/// The range weight alone, `∫_bin η(r)/r² dr`: for full overlap `1/a − 1/b` on this
/// test's own bin grid; for the biaxial ground lidar the midpoint rule at 5 mm on this
/// test's own circle–circle overlap. A 1 % error fails by 10×.
#[test]
fn the_range_weight_is_the_integral_of_the_overlap_over_r_squared() {
    let sc = scenario("paper/scenario1.toml", &[]);
    let e = sc.expected().unwrap();
    let bins = r::bins(&sc.loaded.config);
    assert_eq!(bins.len(), e.n_bins());
    for (i, (a, b)) in bins.iter().enumerate() {
        let exact = 1.0 / a - 1.0 / b;
        assert!(
            rel(e.range_weight[i], exact) < 1e-9,
            "bin {i}: {} vs {exact}",
            e.range_weight[i]
        );
    }
    let sc = scenario(
        "ground/ground_532_overlap.toml",
        &["acquisition.top_altitude_km=3"],
    );
    let e = sc.expected().unwrap();
    let cfg = &sc.loaded.config;
    let bins = r::bins(cfg);
    assert_eq!(bins.len(), e.n_bins());
    let mut nonzero = 0;
    for (i, &(a, b)) in bins.iter().enumerate() {
        let n = ((b - a) / 0.005).ceil() as usize;
        let h = (b - a) / n as f64;
        let w: f64 = (0..n)
            .map(|k| {
                let rr = a + (k as f64 + 0.5) * h;
                r::overlap(cfg, rr) / (rr * rr) * h
            })
            .sum();
        if w == 0.0 {
            assert_eq!(e.range_weight[i], 0.0, "bin {i}");
            continue;
        }
        nonzero += 1;
        assert!(
            rel(e.range_weight[i], w) < 1e-3,
            "bin {i}: {} vs {w}",
            e.range_weight[i]
        );
    }
    assert!(nonzero > 300, "{nonzero}");
}

/// Unpolarized sky light: each polarization channel receives half of
/// `Lλ·A·Ω·Δλ·TF·Δt·TR·Q` (Eq. 3, Ω = πθ²/4), whatever its cross-talk (the cross-talk
/// exchanges halves of equal size); the total channel all of it.
#[test]
fn sky_light_is_halved_in_each_polarization_channel() {
    for overrides in [
        vec![],
        vec![
            "instrument.channels.0.crosstalk=0.2",
            "instrument.channels.1.crosstalk=0.2",
        ],
    ] {
        let l = lidar("instruments/caliop_3ch.toml", &overrides);
        let mut seen = vec![];
        for sc in &l.channels {
            let i = &sc.loaded.config.instrument;
            let radiance = sc.loaded.config.background.radiance.unwrap();
            let omega = std::f64::consts::PI / 4.0 * i.fov_rad * i.fov_rad;
            let full = radiance
                * i.telescope_area_m2
                * omega
                * i.filter_width_nm
                * i.filter_transmission
                * i.bin_width_s
                * i.receiver_efficiency
                * i.quantum_efficiency;
            let name = sc.instrument.channel.name();
            let share = if name == "total" { 1.0 } else { 0.5 };
            assert!(
                rel(sc.instrument.background_per_bin, share * full) < 1e-12,
                "{}: {} vs {}",
                sc.channel_name,
                sc.instrument.background_per_bin,
                share * full
            );
            seen.push(name);
        }
        assert_eq!(seen, ["parallel", "perpendicular", "total"]);
    }
}

/// The signal constant `C = K·E0·(λ/hc)·A·TR·TF·Q` and the molecular backscatter
/// `β_mol = N_US76·σ_Bucholtz/S_mol` at bin centres, from this test's formulas, for
/// 355, 532 and 1064 nm (whole Rayleigh line) and 532 nm through a narrow filter
/// (Cabannes line); the 532/1064 ratio is ≈ 16.7 (λ⁻⁴·⁰⁸), here to 1e-4.
#[test]
fn signal_constant_and_molecular_backscatter_follow_their_formulas() {
    for (wl, filter) in [
        ("355", "0.5"),
        ("532", "0.5"),
        ("1064", "0.5"),
        ("532", "0.1"),
    ] {
        let sc = scenario(
            "paper/scenario6.toml",
            &[
                &format!("instrument.wavelength_nm={wl}"),
                &format!("instrument.filter_width_nm={filter}"),
                "atmosphere.molecular.model=us76",
            ],
        );
        let cfg = &sc.loaded.config;
        assert!(rel(sc.instrument.signal_constant, r::signal_constant(cfg)) < 1e-12);
        let e = sc.expected().unwrap();
        let wl_nm: f64 = wl.parse().unwrap();
        let (s_mol, _) =
            r::molecular_lidar_ratio_and_depolarization(r::rayleigh_rho_n(wl_nm), filter == "0.1");
        for i in (0..e.n_bins()).step_by(7) {
            let z = e.altitude_m[i];
            if !(0.0..86_000.0).contains(&z) {
                continue;
            }
            let beta = r::us76_number_density_m3(z) * r::rayleigh_cross_section_m2(wl_nm) / s_mol;
            assert!(
                rel(e.point[i].beta_mol, beta) < 1e-4,
                "{wl} nm, filter {filter}, z {z}: {} vs {beta}",
                e.point[i].beta_mol
            );
        }
    }
    // Bucholtz (1995) Table 2 values: σ(532) = 5.167e-27 cm², σ(1064) = 3.127e-28 cm²
    // (US-standard air at 288.15 K, 1013.25 hPa) — the test's fit within 0.1 %
    assert!(rel(r::rayleigh_cross_section_m2(532.0), 5.162e-31) < 1e-3);
    assert!(rel(r::rayleigh_cross_section_m2(1064.0), 3.125e-32) < 1e-3);
}

/// This test's US76 against the Standard's Table I (number density 2.5470e25 m⁻³ at
/// sea level, 8.5976e24 at 10 km... computed as N_A·P/(R*T) of the printed P, T).
#[test]
fn the_reference_us76_reproduces_the_published_table() {
    for (z, p, t) in [
        (0.0, 1.01325e5, 288.150),
        (5_000.0, 5.4048e4, 255.676),
        (11_000.0, 2.2700e4, 216.774),
        (20_000.0, 5.5293e3, 216.650),
        (32_000.0, 8.8906e2, 228.490),
        (47_000.0, 1.1585e2, 269.684),
        (71_000.0, 4.4796e0, 216.846),
        (86_000.0, 3.7338e-1, 186.870),
    ] {
        let (tt, pp) = r::us76_t_p(z);
        assert!(rel(pp, p) < 1e-4, "P at {z}: {pp} vs {p}");
        assert!(rel(tt, t) < 1e-4, "T at {z}: {tt} vs {t}");
        let sim = lidarsim::atmosphere::us76::number_density_m3(z);
        assert!(rel(sim, r::us76_number_density_m3(z)) < 1e-4, "N at {z}");
    }
}

/// The point optics every bin integral is built on: attenuating extinction (molecules,
/// ozone, background aerosol, layers × η_ms), the extinction and backscatter by species
/// (the file's truth), and the backscatter each channel sees
/// (molecular line share, lidar ratios, each species' depolarization split by the
/// channel's polarization and cross-talk), against tests/common/reference.rs's own
/// formulas, every 25 m from the ground to 30 km, to 1e-6 (the code's molecules come from
/// its US76 on a grid), for paper scenario 2 (aerosol and two cirrus, total channel) and
/// the three CALIOP-like channels (parallel and perpendicular with cross-talk 0.2, a
/// smoke layer, 1064 nm with Ångström exponents), molecules through the whole line and
/// the Cabannes line, with η_ms = 0.6 on the layers.
#[test]
fn point_optics_match_the_reference_in_every_channel() {
    let mut checked = 0;
    for (config, overrides) in [
        (
            "paper/scenario2.toml",
            vec!["atmosphere.layers.0.multiple_scattering=0.6"],
        ),
        (
            "instruments/caliop_3ch.toml",
            vec![
                "instrument.channels.0.crosstalk=0.2",
                "instrument.channels.1.crosstalk=0.2",
                "atmosphere.layers.0.multiple_scattering=0.6",
            ],
        ),
        (
            "instruments/caliop_3ch.toml",
            vec!["atmosphere.molecular.line=\"rayleigh\""],
        ),
    ] {
        for sc in &lidar(config, &overrides).channels {
            let reference = r::RefAtmosphere::new(sc);
            for k in 0..=1200 {
                let z = 25.0 * k as f64;
                let (got, want) = (sc.atmosphere.optics_at(z), reference.at(z));
                let what = format!("{config} {overrides:?}, {}, {z} m", sc.channel_name);
                assert!(
                    rel(got.alpha_effective, want.alpha) < 1e-6,
                    "{what}: α {} vs {}",
                    got.alpha_effective,
                    want.alpha
                );
                assert!(
                    rel(got.beta_channel, want.beta) < 1e-6,
                    "{what}: β {} vs {}",
                    got.beta_channel,
                    want.beta
                );
                // the truth by species the file carries
                for (name, g, w) in [
                    ("α_total", got.alpha_total, want.alpha_total),
                    ("β_mol", got.beta_mol, want.beta_mol),
                    ("β_aer", got.beta_aer, want.beta_aer),
                    ("β_cld", got.beta_cld, want.beta_cld),
                ] {
                    assert!(
                        (g - w).abs() <= 1e-6 * w.abs() + 1e-30,
                        "{what}: {name} {g} vs {w}"
                    );
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 7 * 1201);
}

/// The beam's path on a sphere (docs/model.md §3): altitude at range and range at altitude
/// against the reference's law of cosines, the local incidence against the law of sines
/// `sin θ_z = (R + H)·sin φ/(R + z)` written here, and the bins' edges against the
/// reference's grid, to 1e-9 — space-borne 30° off nadir, a ground beam 60° off zenith,
/// flat and nadir beams, every 1 km of altitude.
#[test]
fn the_beam_geometry_matches_the_reference_on_a_sphere() {
    for (config, overrides) in [
        (
            "instruments/caliop_532.toml",
            vec!["platform.off_nadir_deg=30"],
        ),
        (
            "instruments/caliop_532.toml",
            vec![
                "platform.off_nadir_deg=30",
                "platform.earth_curvature=false",
            ],
        ),
        ("instruments/caliop_532.toml", vec![]),
        ("paper/scenario6.toml", vec![]),
        (
            "ground/profile_file_example.toml",
            vec!["platform.off_nadir_deg=60"],
        ),
    ] {
        let sc = scenario(config, &overrides);
        let (g, cfg) = (&sc.geometry, &sc.loaded.config);
        let p = &cfg.platform;
        let what = format!("{config} {overrides:?}");
        // a ground beam from its station up, a space-borne one from the ground
        let z0 = if p.kind == PlatformKind::Ground {
            p.altitude_km * 1e3
        } else {
            0.0
        };
        for km in 0..=40 {
            let z = z0 + km as f64 * 1e3;
            let r = r::range_at_altitude(cfg, z);
            assert!(
                (g.range_at_altitude(z) - r).abs() <= 1e-9 * r.abs().max(1.0),
                "{what}: range at {z}"
            );
            assert!(
                (g.altitude_at_range(r) - r::altitude_at_range(cfg, r)).abs() < 1e-6,
                "{what}: altitude at {r}"
            );
            let sin_phi = p.off_nadir_deg.to_radians().sin();
            let want_cos = if p.earth_curvature {
                let s =
                    (r::EARTH_RADIUS_M + p.altitude_km * 1e3) * sin_phi / (r::EARTH_RADIUS_M + z);
                (1.0 - s * s).sqrt()
            } else {
                p.off_nadir_deg.to_radians().cos()
            };
            assert!(
                rel(g.local_cos_at(z), want_cos) < 1e-9,
                "{what}: cos at {z}"
            );
        }
        let bins = r::bins(cfg);
        assert_eq!(g.n_bins, bins.len(), "{what}");
        for (i, (a, b)) in bins.iter().enumerate().step_by(97) {
            let (ga, gb) = g.bin_range_bounds(i);
            let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * y.abs().max(1.0);
            assert!(close(ga, *a) && close(gb, *b), "{what}: bin {i}");
        }
    }
}

/// Every bin's expected signal `C·∫ηβT²/r² dr` against the reference's brute-force
/// quadrature (own geometry, optics and T², midpoint rule at 0.5 m split at every jump of
/// the optics) within 1e-3. The others differ by less than 1e-4; the bins holding the
/// ground by up to 5e-4, the model's own approximation (docs/model.md: optics constant
/// on `grid_m` = 10 m slabs at their mid-altitude, and a ground bin holds only the lowest
/// few metres of its slab, where the aerosol changes fastest): paper scenario 2
/// (aerosol and two cirrus, total channel) and the three CALIOP-like channels
/// (polarization shares with cross-talk, 1064 nm). The same check at 5 cm and 1e-3 over
/// all six paper scenarios is `tests/bin_integral.rs`; this one is fast enough to run
/// for every mutant (validation/reports/mutants.md: `bin_integral → Ok(1.0)` survived
/// without it).
#[test]
fn every_bin_signal_is_the_brute_force_integral() {
    let check = |sc: &Scenario, step_m: f64, what: &str| {
        let e = sc.expected().unwrap();
        let brute = common::brute_force_signal(sc, step_m);
        let mut checked = 0;
        for (i, (got, want)) in e.signal.iter().zip(&brute).enumerate() {
            if got.abs().max(want.abs()) < 1e-12 {
                continue;
            }
            assert!(rel(*got, *want) < 1e-3, "{what}: bin {i}: {got} vs {want}");
            checked += 1;
        }
        assert!(checked > 250, "{what}: only {checked} bins with signal");
    };
    check(&scenario("paper/scenario2.toml", &[]), 0.5, "scenario 2");
    for sc in &lidar(
        "instruments/caliop_3ch.toml",
        &[
            "instrument.channels.0.crosstalk=0.2",
            "instrument.channels.1.crosstalk=0.2",
        ],
    )
    .channels
    {
        check(sc, 0.5, &sc.channel_name);
    }
}

/// The surface bin's expected signal is `C·(ρ cos θ/π)·T²(r_s)/r_s²` plus the air of the
/// bin above the surface, within 1e-4, at nadir and 30° off nadir (spherical Earth, cos θ
/// the local incidence): everything on the right from tests/common/reference.rs (own
/// geometry, optics, Eq. 2 constant, T² marched from 100 km) and the law of sines, none
/// from lidarsim. The beam sees nothing below the surface; the ocean preset's albedo is 0.05.
#[test]
fn the_surface_echo_follows_the_lambertian_law() {
    use common::reference as r;
    for angle in ["0", "30"] {
        let set = |surface: bool| {
            let mut v = vec![format!("platform.off_nadir_deg={angle}")];
            if surface {
                v.push("surface.altitude_km=0.2".into());
                v.push("surface.albedo=0.3".into());
            }
            v
        };
        let load = |surface: bool| {
            let v = set(surface);
            scenario(
                "instruments/caliop_532.toml",
                &v.iter().map(String::as_str).collect::<Vec<_>>(),
            )
        };
        let sc = load(true);
        // the reference optics know no surface: the same atmosphere without one (its
        // optics above 200 m, all the march visits, do not depend on the surface)
        let air = load(false);
        let cfg = &sc.loaded.config;
        let optics = r::RefAtmosphere::new(&air);
        let r_s = r::range_at_altitude(cfg, 200.0);
        let (bin, &(a, _)) = r::bins(cfg)
            .iter()
            .enumerate()
            .find(|(_, (a, b))| r_s >= *a && r_s < *b)
            .unwrap();
        // T² to r_s and the air's part of the bin, midpoint rule at 0.5 m (0.01 m in the bin)
        let (tau, air_part) = r::march(
            cfg,
            &optics,
            &[
                (r::range_at_altitude(cfg, 100_000.0), a, 0.5, false),
                (a, r_s, 0.01, true),
            ],
        );
        // local incidence: sin θ_i = (R + H)/(R + z)·sin θ (law of sines)
        let big = r::EARTH_RADIUS_M + cfg.platform.altitude_km * 1e3;
        let sin_i =
            big / (r::EARTH_RADIUS_M + 200.0) * cfg.platform.off_nadir_deg.to_radians().sin();
        let cos = (1.0 - sin_i * sin_i).sqrt();
        let surface_part = 0.3 * cos / std::f64::consts::PI * (-2.0 * tau).exp() / (r_s * r_s);
        let want = r::signal_constant(cfg) * (surface_part + air_part);
        let e = sc.expected().unwrap();
        let got = e.signal[bin];
        assert!((got / want - 1.0).abs() < 1e-4, "{angle}°: {got} vs {want}");
        assert!(
            e.signal[bin + 1..].iter().all(|&s| s == 0.0),
            "{angle}°: light below the surface"
        );
        assert!(e.signal[bin] > 100.0 * e.signal[bin - 1]);
    }
    let ocean = scenario("instruments/caliop_532.toml", &["surface.kind=\"ocean\""]);
    let land = scenario("instruments/caliop_532.toml", &["surface.kind=\"land\""]);
    let peak = |sc: &Scenario| {
        sc.expected()
            .unwrap()
            .signal
            .iter()
            .fold(0.0f64, |m, &s| m.max(s))
    };
    assert!((peak(&land) / peak(&ocean) - 3.0).abs() < 0.05);
    let e = Scenario::load(
        &common::config_path("ground/ground_532_overlap.toml"),
        &["surface.albedo=0.3".to_string()],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("surface") && e.contains("ground"), "{e}");
}

/// The solar position (`src/scene/sun.rs`, docs/model.md §4f) against Meeus's low-accuracy
/// solar coordinates and equation of time, transcribed in tests/common/reference.rs. First
/// the transcription against Meeus's worked examples for 1992 October 13.0 (JD 2448908.5):
/// Example 25.a, apparent declination δ = −7.78507° and R = 0.99766 AU; Example 28.b,
/// E = +0.059825 rad (13m42.7s). Then the simulator at that instant through its public
/// functions, against the same printed values: δ = 90° − θ_s at the North Pole; E from θ_s
/// at the equator at 90° E (hour angle E − 90°, so cos θ_s = cos δ·sin E); R from
/// `earth_sun_distance_au`. Last, cos θ_s and R against the transcription to 1e-11 at
/// 1,200 instants and places from 1900 to 2100 (T = −1…1, where the T² terms are largest:
/// a T² coefficient of the equation of centre with its sign flipped moves θ_s by 1e-5°).
/// (cargo-mutants survivors in `solar_coordinates`: R with ν = M − C, 1e-3 AU off where
/// sin M is large, which the perihelion and aphelion checks cannot see; Ω = 125.04 −
/// (1934.136 + T), δ 6e-4° off; the sign of 0.000014·T².)
#[test]
fn the_sun_is_where_meeus_puts_it() {
    use lidarsim::scene::sun::{earth_sun_distance_au, solar_zenith_deg};
    // the transcription against the printed examples (their last digit ± rounding)
    let (delta, eot, au) = r::meeus_sun(2_448_908.5);
    assert!((delta + 7.785_07).abs() < 1e-5, "δ {delta}");
    assert!((au - 0.997_66).abs() < 1e-5, "R {au}");
    assert!((eot - 0.059_825).abs() < 1e-6, "E {eot}");
    // the simulator at 1992-10-13T00:00:00Z
    let t = 718_934_400.0;
    let delta = 90.0 - solar_zenith_deg(t, 90.0, 0.0);
    assert!((delta + 7.785_07).abs() < 2e-5, "simulator δ {delta}");
    let cos_zenith = solar_zenith_deg(t, 0.0, 90.0).to_radians().cos();
    let eot = (cos_zenith / delta.to_radians().cos()).asin();
    assert!((eot - 0.059_825).abs() < 1e-6, "simulator E {eot} rad");
    let au = earth_sun_distance_au(t);
    assert!((au - 0.997_66).abs() < 1e-5, "simulator R {au}");
    // term for term, 1900–2100
    let j2000 = 946_728_000.0; // 2000-01-01T12:00:00Z
    let mut checked = 0;
    for years in [-100.0, -50.0, 0.0, 50.0, 100.0] {
        for month in 0..12 {
            for hours in [0.0, 5.5, 11.0, 14.25, 20.0] {
                let t = j2000 + (years * 365.25 + month as f64 * 30.4) * 86_400.0 + hours * 3_600.0;
                for (lat, lon) in [(0.0, 0.0), (45.0, 7.0), (-33.9, 151.2), (70.0, -150.0)] {
                    let got = solar_zenith_deg(t, lat, lon).to_radians().cos();
                    let want = r::cos_solar_zenith(t, lat, lon);
                    assert!(
                        (got - want).abs() < 1e-11,
                        "{t} s, ({lat}, {lon}): cos θ_s {got} vs {want}"
                    );
                    checked += 1;
                }
                let (_, _, want) = r::meeus_sun(2_440_587.5 + t / 86_400.0);
                let got = earth_sun_distance_au(t);
                assert!(rel(got, want) < 1e-12, "{t} s: R {got} vs {want}");
            }
        }
    }
    assert_eq!(checked, 1_200);
}

/// The sunlight's optical depths above a reflector (docs/model.md §4f,
/// `SkyColumn::above`): τ_sca = ∫ (α_total − α_O3) dz, everything but ozone, and
/// τ_abs = σ_O3·∫ n_O3 dz, from the reflector to the top, against the reference's point
/// optics and AFGL ozone integrated here by the midpoint rule at 1 m, to 1e-4: paper
/// scenario 2 with ozone (US76 molecules, the background aerosol, cirrus at 9–11 and
/// 16–17 km) from the ground, inside the lower cirrus and between the two; above the
/// atmosphere both are 0. (The radiance through these depths is checked against an
/// independent single-scattering integration in `tests/solar_background.rs`.)
#[test]
fn the_sunlight_path_is_the_optical_depth_above_the_reflector() {
    use lidarsim::scene::sky::SkyColumn;
    let sc = scenario("paper/scenario2.toml", &["atmosphere.ozone=true"]);
    let reference = r::RefAtmosphere::new(&sc);
    let sigma_o3 = r::ozone_cross_section_m2(532.0);
    let depths = |z: f64| SkyColumn::above(&sc.atmosphere, z).vertical_depths();
    for reflector in [0.0, 9_500.0, 13_000.0] {
        let steps = (100_000.0 - reflector) as usize; // 1 m each, to 100 km
        let scattering: f64 = (0..steps)
            .map(|k| {
                let z = reflector + k as f64 + 0.5;
                reference.at(z).alpha_total - sigma_o3 * r::ozone_number_density_m3(z)
            })
            .sum();
        let absorbing = sigma_o3 * r::ozone_column_m2(reflector, 60_000.0);
        let (sca, abs) = depths(reflector);
        assert!(
            rel(sca, scattering) < 1e-4,
            "{reflector} m: τ_sca {sca} vs {scattering}"
        );
        assert!(
            rel(abs, absorbing) < 1e-4,
            "{reflector} m: τ_abs {abs} vs {absorbing}"
        );
    }
    // the ground's τ_sca holds the cirrus (0.4 + 0.025) and ~0.11 of molecules
    assert!(depths(0.0).0 > 0.5);
    assert_eq!(depths(100_000.0), (0.0, 0.0));
}
