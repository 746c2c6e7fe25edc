//! Multiple scattering that depends on the cloud and the field of view (issue 22,
//! docs/model.md §4j): the small-angle model's limits on whole scenarios, where the
//! answer is known without the model (single scattering; the whole forward lobe seen),
//! and its values against Hogan's own published implementation on his example inputs
//! (`validation/reports/multiple_scattering.md`).

mod common;

use common::scenario;
use lidarsim::atmosphere::multiple_scattering::{Footprint, Step, small_angle_ratios};
use lidarsim::scenario::ExpectedProfile;

const CIRRUS: &str = "ground/cirrus_small_angle.toml";

fn expected(rel: &str, overrides: &[&str]) -> ExpectedProfile {
    scenario(rel, overrides).expected().unwrap()
}

/// The shipped config's cirrus (9–11 km, ice) with another extinction and effective
/// radius, as a `--set` override.
fn cirrus(extinction_per_km: f64, effective_radius_um: f64) -> String {
    format!(
        "atmosphere.layers=[{{ kind = \"cloud\", phase = \"ice\", base_km = 9.0, top_km = 11.0, \
         extinction_per_km = {extinction_per_km}, lidar_ratio_sr = 25.0, depolarization = 0.4, \
         effective_radius_um = {effective_radius_um} }}]"
    )
}

/// The largest `|F − 1|` over the bins.
fn largest_departure(e: &ExpectedProfile) -> f64 {
    e.multiple_scattering
        .iter()
        .map(|m| (m.ratio - 1.0).abs())
        .fold(0.0, f64::max)
}

/// The bins inside the cloud (9–11 km) beyond its first 300 m, where the particle
/// optical depth above is at least 0.15.
fn deep_cloud_bins(e: &ExpectedProfile) -> Vec<usize> {
    (0..e.n_bins())
        .filter(|&i| e.altitude_m[i] > 9_300.0 && e.altitude_m[i] < 10_950.0)
        .collect()
}

/// Without particles the small-angle model is single scattering, bit for bit: the
/// same signal as the constant model with η = 1.
#[test]
fn clear_air_is_single_scattering() {
    let no_particles = [
        "atmosphere.layers=[]",
        "atmosphere.aerosol.visibility_km=1e4",
    ];
    let small = expected(CIRRUS, &no_particles);
    let mut constant_overrides = no_particles.to_vec();
    constant_overrides.push("multiple_scattering.model=\"constant\"");
    let constant = expected(CIRRUS, &constant_overrides);
    assert!(small.multiple_scattering.iter().all(|m| m.ratio == 1.0));
    assert_eq!(small.signal, constant.signal);
}

/// A vanishing optical depth: the ratio tends to 1 (within 1e-3 at τ = 1e-4), and the
/// effective η stays finite.
#[test]
fn vanishing_optical_depth_is_single_scattering() {
    let worst = largest_departure(&expected(CIRRUS, &[&cirrus(5e-5, 30.0)]));
    assert!(worst < 1e-3, "largest |ratio − 1| = {worst}");
    assert!(worst > 0.0, "the thin cirrus still scatters forward");
}

/// A vanishing field of view and beam: no forward-scattered photon stays inside, the
/// ratio is 1 within 1e-3 (with a finite beam it is not: the on-axis density of the
/// scattered photons over the unscattered beam's stays finite as the field of view
/// shrinks, docs/model.md §4j).
#[test]
fn vanishing_field_of_view_is_single_scattering() {
    let worst = largest_departure(&expected(
        CIRRUS,
        &[
            "instrument.fov_rad=2e-8",
            "instrument.beam_divergence_rad=1e-8",
        ],
    ));
    assert!(worst < 1e-3, "largest |ratio − 1| = {worst}");
}

/// A very wide field of view sees the whole forward lobe: the photons it keeps are half
/// the extinction, so the apparent optical depth is halved, η = 0.5 (within 2 %), and
/// the ratio is `e^{τ_p}`, computed here from the layer's own extinction.
#[test]
fn wide_field_of_view_sees_the_whole_forward_lobe() {
    let e = expected(
        CIRRUS,
        &[
            "instrument.fov_rad=0.1",
            &cirrus(0.5, 200.0),
            "atmosphere.aerosol.visibility_km=1e4",
        ],
    );
    let bins = deep_cloud_bins(&e);
    assert!(bins.len() > 50);
    for i in bins {
        let m = e.multiple_scattering[i];
        let eta = m.effective_factor();
        assert!((eta - 0.5).abs() < 0.01, "bin {i}: η = {eta}");
        // the cloud's optical depth from its base at 9 km to the bin centre (the thin
        // aerosol of a 10,000 km visibility adds < 1e-3)
        let tau = 0.5e-3 * (e.altitude_m[i] - 9_000.0);
        assert!(
            (m.particle_optical_depth - tau).abs() < 1e-3,
            "bin {i}: τ_p {} against {tau}",
            m.particle_optical_depth
        );
        let whole_lobe = m.particle_optical_depth.exp();
        assert!(
            (m.ratio / whole_lobe - 1.0).abs() < 0.02,
            "bin {i}: ratio {} against {whole_lobe}",
            m.ratio
        );
    }
}

/// The ratio is already in the signal: the file's single-scattering truth times the
/// ratio is the apparent attenuated backscatter, and the model's single scattering is
/// the constant model's with η = 1.
#[test]
fn single_scattering_truth_is_the_constant_model_without_eta() {
    let small = expected(CIRRUS, &[]);
    let constant = expected(CIRRUS, &["multiple_scattering.model=\"constant\""]);
    let mut enhanced = 0;
    for i in 0..small.n_bins() {
        let r = small.multiple_scattering_at(i).channel_ratio();
        assert!(r >= 1.0 - 1e-12, "bin {i}: ratio {r}");
        let single = small.attenuated_backscatter[i] / r;
        let c = constant.attenuated_backscatter[i];
        assert!(
            (single - c).abs() <= 1e-12 * c.abs(),
            "bin {i}: {single} vs {c}"
        );
        enhanced += usize::from(r > 1.01);
    }
    assert!(enhanced > 100, "{enhanced} bins enhanced by over 1 %");
}

/// One of Hogan's example inputs as this model's steps: gates of `width_m` from
/// `start_range_m` on (the instrument's side of the first gate), each gate's particle
/// extinction (m⁻¹), equivalent-area radius (m) and air extinction (m⁻¹).
fn steps(wavelength_m: f64, width_m: f64, gates: &[(f64, f64, f64)]) -> Vec<Step> {
    gates
        .iter()
        .map(|&(alpha, radius_m, alpha_air)| {
            let theta = wavelength_m / (std::f64::consts::PI * radius_m);
            Step {
                width_m,
                alpha_particle_per_m: alpha,
                alpha_theta2_per_m: alpha * theta * theta,
                alpha_air_per_m: alpha_air,
            }
        })
        .collect()
}

/// The air of Hogan's examples: `1.34041e-5·e^{−z/8000 m}` m⁻¹.
fn air(z_m: f64) -> f64 {
    1.34041e-5 * (-z_m / 8000.0).exp()
}

/// Each gate's ratio within `tol` of the reference's.
fn assert_close(ours: &[f64], reference: &[f64], tol: f64, case: &str) {
    assert_eq!(ours.len(), reference.len(), "{case}");
    for (k, (o, r)) in ours.iter().zip(reference).enumerate() {
        assert!(
            (o / r - 1.0).abs() < tol,
            "{case}, gate {k}: {o} against {r}"
        );
    }
}

/// Reference ratios (apparent over single-scattering backscatter of each gate) from
/// Hogan's own implementation, `multiscatter` 1.2.10 (LGPL; built outside this
/// repository from the copy in github.com/mgrecu35/gmp_combined,
/// `Code/multiscatter-1.2.10`), run as `multiscatter -algorithms fast none` and
/// `-algorithms single none` on the inputs described in each test, which are those of
/// its `examples/` files (`validation/reports/multiple_scattering.md`). Printed to six
/// digits: 1e-5 is the comparison's resolution; a 1 % change of any coefficient of the
/// moment equations moves some gate by more.
const PRINTED: f64 = 1e-5;

/// Hogan (2008) Fig. 8's input (`examples/hogan2008fig8.in`): CALIPSO-like at 700 km,
/// beam 5 µrad, field of view 71.429 µrad (1/e and top-hat half-widths), 532 nm, 200 m
/// gates from 8 km down: an ice cloud of 6e-4 m⁻¹ and 50 µm from 7 to 4.2 km and a water
/// cloud of 3e-3 m⁻¹ and 10 µm from 2 to 1.2 km (gate centres).
#[test]
fn hogan_2008_figure_8_case() {
    let gates: Vec<(f64, f64, f64)> = (0..41)
        .map(|k| {
            let z = 8000.0 - 200.0 * k as f64;
            let (alpha, radius) = match z {
                z if (4200.0..=7000.0).contains(&z) => (6e-4, 50e-6),
                z if (1200.0..=2000.0).contains(&z) => (3e-3, 10e-6),
                _ => (0.0, 100e-6),
            };
            (alpha, radius, air(z))
        })
        .collect();
    let fp = Footprint {
        divergence_rad: 5e-6,
        fov_half_angle_rad: 7.1429e-6,
    };
    let ours = small_angle_ratios(fp, 700e3 - 8000.0 - 100.0, &steps(532e-9, 200.0, &gates));
    let reference = [
        1.0, 1.0, 1.0, 1.0, 1.0, 1.05966, 1.19257, 1.33657, 1.48759, 1.64001, 1.78729, 1.92317,
        2.0218, 2.08452, 2.17299, 2.29713, 2.42396, 2.54695, 2.66423, 2.77535, 2.71694, 2.51284,
        2.34017, 2.18646, 2.05094, 1.93237, 1.82916, 1.73956, 1.66185, 1.59441, 1.94649, 2.90603,
        3.65401, 4.56596, 5.82991, 5.79007, 4.38762, 3.50909, 2.91975, 2.50886, 2.21306,
    ];
    assert_close(&ours, &reference, PRINTED, "Hogan (2008) Fig. 8");
}

/// `examples/ground_based_cirrus_example.in`: a zenith lidar 100 m below the first
/// gate, beam 0.5 mrad, field of view 0.75 mrad, 532 nm, 200 m gates from 0 to 8 km;
/// cirrus of 100 µm particles, 2e-3 m⁻¹ from 3.2 to 4 km, 5e-4 to 5 km, 1e-4 to 6 km,
/// 5e-4 to 7 km.
#[test]
fn ground_based_cirrus_case() {
    let gates: Vec<(f64, f64, f64)> = (0..41)
        .map(|k| {
            let z = 200.0 * k as f64;
            let alpha = match z {
                z if (3200.0..=4000.0).contains(&z) => 2e-3,
                z if (4200.0..=5000.0).contains(&z) => 5e-4,
                z if (5200.0..=6000.0).contains(&z) => 1e-4,
                z if (6200.0..=7000.0).contains(&z) => 5e-4,
                _ => 0.0,
            };
            (alpha, 100e-6, air(z))
        })
        .collect();
    let fp = Footprint {
        divergence_rad: 5e-4,
        fov_half_angle_rad: 7.5e-4,
    };
    let ours = small_angle_ratios(fp, 0.0, &steps(532e-9, 200.0, &gates));
    let reference = [
        1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.19645,
        1.77632, 2.61199, 3.7883, 5.40623, 6.64662, 6.8272, 6.86397, 6.79871, 6.93988, 7.03277,
        6.87664, 6.7388, 6.60484, 6.47651, 6.61229, 7.03022, 7.46605, 7.93519, 8.4405, 8.5508,
        8.24795, 7.9771, 7.72502, 7.49054,
    ];
    assert_close(&ours, &reference, PRINTED, "ground-based cirrus");
}

/// The I3RC lidar case of `examples/i3rc_lidar_exp4.in` (Intercomparison of 3D
/// Radiation Codes, phase 3; Hogan 2008 §5): 1,000 km away, beam 2.5 nrad, field of
/// view 2.5 mrad (a 2.5 km footprint), 532 nm, 15 m gates of a cloud of 0.04 m⁻¹ and
/// 1.22517 µm, no air: the first 33 gates, to an optical depth of 19.8.
#[test]
fn i3rc_lidar_case() {
    let gates = vec![(0.04, 1.22517e-6, 0.0); 33];
    let fp = Footprint {
        divergence_rad: 2.5e-9,
        fov_half_angle_rad: 2.5e-3,
    };
    let ours = small_angle_ratios(fp, 1e6, &steps(532e-9, 15.0, &gates));
    let reference = [
        1.29131, 2.35292, 4.28731, 7.81199, 14.2344, 25.9367, 47.2598, 86.1129, 156.908, 285.905,
        520.953, 949.238, 1729.62, 3151.58, 5742.55, 10463.6, 19065.9, 34740.4, 63301.2, 115342.0,
        210167.0, 382950.0, 697780.0, 1.27144e6, 2.31671e6, 4.22132e6, 7.69175e6, 1.40153e7,
        2.55375e7, 4.65324e7, 8.47875e7, 1.54493e8, 2.81505e8,
    ];
    assert_close(&ours, &reference, PRINTED, "I3RC");
}

/// `validate` on the shipped small-angle preset: the counts every sampler draws follow
/// the expectation with multiple scattering in it (false-alarm rate: `validate`'s own,
/// fixed seed).
#[test]
fn validate_is_consistent_on_the_small_angle_preset() {
    let dir = std::env::temp_dir().join(format!("lidarsim-ms-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    common::h5::validate_preset_consistent(
        &dir,
        &common::config_path(CIRRUS),
        "acquisition.accumulation_time_s=0.5",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// What the model needs and does not take is refused in one line naming the key.
#[test]
fn refusals_name_the_key() {
    let load = |overrides: &[&str]| {
        let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        lidarsim::scenario::Scenario::load(&common::config_path(CIRRUS), &ov)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    let cases: [(&[&str], &str); 5] = [
        (
            &["instrument.beam_divergence_rad=0"],
            "instrument.beam_divergence_rad",
        ),
        (
            &[
                "atmosphere.layers=[{ kind = \"cloud\", base_km = 1.0, top_km = 2.0, \
               extinction_per_km = 1.0, lidar_ratio_sr = 18.0, asymmetry_factor = 1.0 }]",
            ],
            "within [0, 0.99], got 1",
        ),
        (
            &["multiple_scattering.wide_angle_cutoff_rad=-1"],
            "multiple_scattering.wide_angle_cutoff_rad",
        ),
        (
            &["atmosphere.aerosol.effective_radius_um=1e9"],
            "atmosphere.aerosol.effective_radius_um",
        ),
        (
            &[
                "atmosphere.layers=[{ kind = \"aerosol\", phase = \"ice\", base_km = 1.0, \
               top_km = 2.0, extinction_per_km = 0.1, lidar_ratio_sr = 50.0 }]",
            ],
            "an aerosol layer has none",
        ),
    ];
    for (overrides, needle) in cases {
        let e = load(overrides);
        assert!(e.contains(needle), "{overrides:?}: {e}");
        assert_eq!(e.lines().count(), 1, "{e}");
    }
    // a config without the beam's divergence: which key to set
    let text = std::fs::read_to_string(common::config_path(CIRRUS)).unwrap();
    let without: String = text
        .lines()
        .filter(|l| !l.starts_with("beam_divergence_rad"))
        .collect::<Vec<_>>()
        .join("\n");
    let e = lidarsim::loaded::load_str(&without, std::path::Path::new("c.toml"), &[])
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        e.contains("instrument.beam_divergence_rad") && e.contains("small_angle"),
        "{e}"
    );
}

/// Water cloud seen from space through the CALIOP-like ∥/⊥ pair: the layer-integrated
/// depolarization δ of the two channels' apparent returns (cross-talk undone) and the
/// layer's multiple-scattering factor η, solved here from the analytic integral of a
/// homogeneous layer, `∫β e^{−2ητ} = β(1 − e^{−2ητ_L})/(2ηα)` against single
/// scattering's, follow Hu et al. (2006): `η = ((1 − δ)/(1 + δ))²`. Their Monte Carlo
/// points scatter about the relation by ~0.05 in δ; the model follows it by
/// construction, so the check is tight (the bins' discretization and the air's return:
/// 0.004 in η; a 1 % change of the relation's exponent moves it by 0.005).
#[test]
fn water_cloud_depolarization_follows_hu() {
    let lidar = common::lidar(
        "instruments/caliop_3ch.toml",
        &[
            "multiple_scattering.model=\"small_angle\"",
            "instrument.beam_divergence_rad=5e-5",
            "instrument.bin_width_s=1.25e-8",
            "acquisition.top_altitude_km=3",
            "acquisition.bottom_altitude_km=0.5",
            "atmosphere.layers=[{ kind = \"cloud\", base_km = 0.8, top_km = 1.5, \
             extinction_per_km = 8.0, lidar_ratio_sr = 18.0 }]",
        ],
    );
    let e = lidar.expected().unwrap();
    let (par, perp) = (&e[0], &e[1]);
    let x = 0.005; // the preset's cross-talk
    let cloud: Vec<usize> = (0..par.n_bins())
        .filter(|&i| par.point[i].alpha_cld > 0.0)
        .collect();
    let (mut sum_par, mut sum_perp, mut sum_single) = (0.0, 0.0, 0.0);
    for &i in &cloud {
        let (p, s) = (
            par.attenuated_backscatter[i],
            perp.attenuated_backscatter[i],
        );
        sum_par += ((1.0 - x) * p - x * s) / (1.0 - 2.0 * x);
        sum_perp += ((1.0 - x) * s - x * p) / (1.0 - 2.0 * x);
        // the droplets depolarize nothing singly: the ∥ channel sees (1 − x) of it
        let single = par.attenuated_backscatter[i] / par.multiple_scattering[i].channel_ratio();
        sum_single += single / (1.0 - x);
    }
    let delta = sum_perp / sum_par;
    // the layer's η: (1 − e^{−2ητ})/η = ratio·(1 − e^{−2τ}), τ = 5.6 (bisection)
    let tau: f64 = 8.0 * 0.7;
    let target = (sum_par + sum_perp) / sum_single * -(-2.0 * tau).exp_m1();
    let (mut lo, mut hi) = (1e-6, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if -(-2.0 * mid * tau).exp_m1() / mid > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let eta = 0.5 * (lo + hi);
    let hu = ((1.0 - delta) / (1.0 + delta)).powi(2);
    assert!(delta > 0.05 && eta < 0.9, "δ = {delta}, η = {eta}");
    assert!(
        (hu - eta).abs() < 0.004,
        "Hu's η {hu} against the layer's {eta} (δ = {delta})"
    );
    // the depolarization rises from the cloud's top with the multiply scattered share
    let d: Vec<f64> = cloud
        .iter()
        .map(|&i| par.multiple_scattering[i].water_depolarization)
        .collect();
    assert!(d[0] < 0.05 && d[d.len() / 2] > 2.0 * d[0], "{:?}", &d[..5]);
}

/// A bin's ratio weights its steps by their single-scattering signal: the apparent
/// signal of a 30 m bin through a stratocumulus (0.24 optical depth per bin) equals the
/// sum of its sixteen 1.875 m bins' (within 3e-3: the 0.05 steps), as single
/// scattering's exact bin integrals add up (1e-6: the air's slabs follow the bin width).
/// Weighting the steps without their T² fails it; a 1 % change of the weights'
/// attenuation moves a bin's ratio by ~1e-4 (the ratio varies by e^{0.24} across a bin),
/// below the steps' own 1.5e-3, and is not caught.
#[test]
fn coarse_bins_are_the_sum_of_fine_ones() {
    let run = |bin_width: &str, model: &str| {
        let e = expected(
            "instruments/caliop_532.toml",
            &[
                &format!("multiple_scattering.model=\"{model}\""),
                "instrument.beam_divergence_rad=5e-5",
                &format!("instrument.bin_width_s={bin_width}"),
                "acquisition.top_altitude_km=2.0",
                "acquisition.bottom_altitude_km=0.5",
                "atmosphere.layers=[{ kind = \"cloud\", base_km = 0.8, top_km = 1.5, \
                 extinction_per_km = 8.0, lidar_ratio_sr = 18.0 }]",
            ],
        );
        e.signal
    };
    for (model, tol) in [("constant", 1e-6), ("small_angle", 3e-3)] {
        let coarse = run("2e-7", model);
        let fine = run("1.25e-8", model);
        let mut checked = 0;
        for (k, c) in coarse.iter().enumerate() {
            let Some(parts) = fine.get(16 * k..16 * (k + 1)) else {
                break;
            };
            let sum: f64 = parts.iter().sum();
            if *c > 1e-6 {
                assert!(
                    (sum / c - 1.0).abs() < tol,
                    "{model}, bin {k}: {sum} against {c}"
                );
                checked += 1;
            }
        }
        assert!(checked > 30, "{model}: {checked} bins");
    }
}

/// An opaque cloud (optical depth 1.8e5): every value finite, and the steps stop where
/// T² underflows (the run takes as few steps as an optical depth of 400 needs).
#[test]
fn opaque_cloud_stays_finite() {
    let e = expected(
        CIRRUS,
        &[
            "atmosphere.layers=[{ kind = \"cloud\", base_km = 1.0, top_km = 19.0, \
           extinction_per_km = 1e4, lidar_ratio_sr = 18.0 }]",
        ],
    );
    for i in 0..e.n_bins() {
        let m = e.multiple_scattering_at(i);
        assert!(e.signal[i].is_finite() && m.ratio.is_finite(), "bin {i}");
        assert!(m.effective_factor().is_finite(), "bin {i}");
    }
}
