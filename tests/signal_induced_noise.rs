//! Signal-induced noise (issue 21 item 4; docs/model.md §4b, `src/detector/induced.rs`):
//! the expected induced counts against a quadrature of the decay law written here, and
//! `validate` on counts that carry them.

mod common;

use lidarsim::simulate::ResolvedMethod;
use lidarsim::validate::{self, SimulatorSource};

/// The two-polarization ground lidar's parallel channel (no jitter, 250 shots a
/// profile) with signal-induced noise `sin` (a TOML inline table) and `dead_time_s`.
fn lidar_with(sin: &str, dead_time_s: f64) -> lidarsim::scenario::Lidar {
    let detector =
        format!("instrument.detector={{signal_induced_noise={sin}, dead_time_s={dead_time_s}}}");
    common::lidar(
        "ground/ground_532_depol.toml",
        &[
            "instrument.pulse_energy_jitter=0",
            "acquisition.accumulation_time_s=0.1",
            "instrument.channels=[{name=\"532_parallel\", polarization=\"parallel\"}]",
            &detector,
        ],
    )
}

/// `λ_SIN,b = a·Σ_b' λ_sig,b'·(1/Δt)∫_{bin b'} [G(t_b+1 − u) − G(t_b − u)] du`, by the
/// midpoint rule over 400 source positions per bin, with the CDF `cdf` of the delay.
fn reference(signal: &[f64], a: f64, dt: f64, cdf: impl Fn(f64) -> f64) -> Vec<f64> {
    let g = |t: f64| if t <= 0.0 { 0.0 } else { cdf(t) };
    let n = signal.len();
    let steps = 400;
    let mut out = vec![0.0; n];
    for (src, &s) in signal.iter().enumerate() {
        if s == 0.0 {
            continue;
        }
        for k in 0..steps {
            let u = (src as f64 + (k as f64 + 0.5) / steps as f64) * dt;
            for (b, o) in out.iter_mut().enumerate().skip(src) {
                let (lo, hi) = (b as f64 * dt, (b + 1) as f64 * dt);
                *o += a * s / steps as f64 * (g(hi - u) - g(lo - u));
            }
        }
    }
    out
}

/// Both decay laws: the file's expectation against the quadrature, to 1e-5 of the
/// largest induced count (the midpoint rule's error at 400 points is ~1e-6 here); the
/// induced counts are in `expected_counts` (total = signal + background + dark + them).
#[test]
fn the_induced_counts_are_the_signal_convolved_with_the_decay_law() {
    let exponential = |t: f64| 1.0 - (-t / 3e-6).exp();
    let power_law = |t: f64| 1.0 - (1.0 + t / 5e-7).powf(-0.7);
    let cases: [(&str, &dyn Fn(f64) -> f64); 2] = [
        (
            "{model=\"exponential\", fraction=2e-3, time_constant_s=3e-6}",
            &exponential,
        ),
        (
            "{model=\"power_law\", fraction=2e-3, time_constant_s=5e-7, exponent=1.7}",
            &power_law,
        ),
    ];
    for (sin, cdf) in cases {
        let lidar = lidar_with(sin, 0.0);
        let e = &lidar.expected().unwrap()[0];
        let dt = lidar.first().instrument.bin_width_s;
        let want = reference(&e.signal, 2e-3, dt, cdf);
        let top = want.iter().fold(0.0f64, |m, &x| m.max(x));
        assert!(top > 1e-3, "{sin}: {top}");
        for (b, (got, w)) in e.induced.iter().zip(&want).enumerate() {
            assert!((got - w).abs() < 1e-5 * top, "{sin} bin {b}: {got} vs {w}");
        }
        for (b, t) in e.total_per_shot().iter().enumerate() {
            let sum = e.signal[b] + e.background + e.dark + e.induced[b];
            assert!((t - sum).abs() <= 1e-12 * sum, "bin {b}");
        }
    }
}

/// `validate`'s law with the induced counts is CONSISTENT on both paths (false alarm <
/// 2e-3 per statistic, fixed seed); without them (the models of the same channel with
/// no signal-induced noise) the mean is rejected.
#[test]
fn validate_sees_the_induced_counts_and_rejects_their_absence() {
    let sin = "{model=\"exponential\", fraction=1e-2, time_constant_s=2e-5}";
    let energy = lidarsim::simulate::RunEnergy::jitter(0.0);
    // through a dead-time detector, shot by shot
    let lidar = lidar_with(sin, 3.5e-9);
    let expected = lidar.expected().unwrap();
    let e = &expected[0];
    let shots = lidar.first().shots_per_profile();
    let dead = lidar.channels[0].instrument.dead_time.unwrap();
    let laser = lidarsim::laser::PulseEnergy::from_config(&lidar.first().loaded.config.instrument);
    let without = lidarsim::scenario::ExpectedProfile {
        induced: Vec::new(),
        ..e.clone()
    };
    let source = SimulatorSource::for_lidar(&lidar, &expected, ResolvedMethod::Shot, energy, 3);
    let bg = &e.background_bin_indices;
    let right = validate::recorded_bin_models(e, shots, &dead, &laser);
    let (_, checks) = validate::validate_source(&source, &right, &e.altitude_m, 300, bg);
    assert!(checks.iter().all(|c| c.pass), "shot: {checks:#?}");
    let wrong = validate::recorded_bin_models(&without, shots, &dead, &laser);
    let (_, checks) = validate::validate_source(&source, &wrong, &e.altitude_m, 300, bg);
    let mean = checks.iter().find(|c| c.statistic == "mean").unwrap();
    assert!(!mean.pass, "shot: no SIN passes: {mean:#?}");
    // an ideal counter, aggregate path: the Poisson law with the induced counts
    let lidar = lidar_with(sin, 0.0);
    let expected = lidar.expected().unwrap();
    let e = &expected[0];
    let source =
        SimulatorSource::for_lidar(&lidar, &expected, ResolvedMethod::Aggregate, energy, 4);
    let bg = &e.background_bin_indices;
    let right = validate::bin_models(e, shots, 0.0);
    let (_, checks) = validate::validate_source(&source, &right, &e.altitude_m, 1000, bg);
    assert!(checks.iter().all(|c| c.pass), "aggregate: {checks:#?}");
    let without = lidarsim::scenario::ExpectedProfile {
        induced: Vec::new(),
        ..e.clone()
    };
    let wrong = validate::bin_models(&without, shots, 0.0);
    let (_, checks) = validate::validate_source(&source, &wrong, &e.altitude_m, 1000, bg);
    assert!(
        !checks[0].pass,
        "aggregate: no SIN passes: {:#?}",
        checks[0]
    );
}

/// The keys' limits, in one line naming the key.
#[test]
fn signal_induced_noise_keys_are_checked() {
    let base =
        std::fs::read_to_string(common::config_path("ground/ground_532_depol.toml")).unwrap();
    let detector = "detector = { dead_time_s = 3.5e-9, dead_time_model = \"nonparalyzable\" }";
    for (sin, key) in [
        (
            "{ model = \"exponential\", fraction = 0.5, time_constant_s = 1e-5 }",
            "fraction",
        ),
        (
            "{ model = \"exponential\", fraction = 1e-3, time_constant_s = 0 }",
            "time_constant_s",
        ),
        (
            "{ model = \"power_law\", fraction = 1e-3, time_constant_s = 1e-6, exponent = 1.0 }",
            "exponent",
        ),
    ] {
        let text = base.replacen(
            detector,
            &format!("detector = {{ signal_induced_noise = {sin} }}"),
            1,
        );
        let e = common::refusal(&text, sin);
        assert!(
            e.contains(&format!("instrument.detector.signal_induced_noise.{key}")),
            "{sin}: {e}"
        );
    }
}
