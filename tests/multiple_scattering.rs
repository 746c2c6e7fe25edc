//! Multiple scattering that depends on the cloud and the field of view (issue 22,
//! docs/model.md §4j): the small-angle model's limits on whole scenarios, where the
//! answer is known without the model (single scattering; the whole forward lobe seen),
//! and its values against Hogan's own published implementation on his example inputs
//! (`validation/reports/multiple_scattering.md`).

mod common;

use common::scenario;
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
    let e = expected(CIRRUS, &[&cirrus(5e-5, 30.0)]);
    let worst = e
        .multiple_scattering
        .iter()
        .map(|m| (m.ratio - 1.0).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-3, "largest |ratio − 1| = {worst}");
    assert!(worst > 0.0, "the thin cirrus still scatters forward");
}

/// A vanishing field of view and beam: no forward-scattered photon stays inside, the
/// ratio is 1 within 1e-3 (with a finite beam it is not: the on-axis density of the
/// scattered photons over the unscattered beam's stays finite as the field of view
/// shrinks, docs/model.md §4j).
#[test]
fn vanishing_field_of_view_is_single_scattering() {
    let e = expected(
        CIRRUS,
        &[
            "instrument.fov_rad=2e-8",
            "instrument.beam_divergence_rad=1e-8",
        ],
    );
    let worst = e
        .multiple_scattering
        .iter()
        .map(|m| (m.ratio - 1.0).abs())
        .fold(0.0, f64::max);
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
        let r = small.multiple_scattering_at(i).ratio;
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
