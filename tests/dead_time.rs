//! Detector dead time (docs/model.md §4b): the shot-level sampler against the stationary
//! formulas, the solver against the sampler where the rate changes, and `validate`.

mod common;

use lidarsim::detector::{DeadTime, DeadTimeModel};
use lidarsim::sampling::{ShotSampler, stream_rng};
use lidarsim::simulate::ResolvedMethod;
use lidarsim::validate::{self, SimulatorSource};

const TAU: f64 = 3.5e-9;
const DT: f64 = 2e-6;
const BINS: usize = 20;

/// Per-bin recorded counts of `shots` shots of constant true rate `n` (s⁻¹): the mean
/// and variance per shot of bins 1.. (bin 0 starts live), pooled.
fn simulate_stationary(model: DeadTimeModel, n: f64, shots: u64, seed: u64) -> (f64, f64) {
    let dead = DeadTime {
        tau_s: TAU,
        model,
        bin_width_s: DT,
    };
    let photons = ShotSampler::new(&[n * DT; BINS]);
    let mut rng = stream_rng(seed, 0, 0);
    let mut arrivals = stream_rng(seed, 1, 0);
    let mut scratch = lidarsim::detector::dead_time::Scratch::default();
    let (mut sum, mut sum2, mut k) = (0.0f64, 0.0f64, 0.0f64);
    let mut acc = vec![0u64; BINS];
    photons.for_each_shot(&mut rng, shots, |shot| {
        acc.iter_mut().for_each(|a| *a = 0);
        dead.record_shot(&mut arrivals, shot, &mut scratch, &mut acc);
        for &c in &acc[1..] {
            let c = c as f64;
            sum += c;
            sum2 += c * c;
            k += 1.0;
        }
    });
    let mean = sum / k;
    (mean, sum2 / k - mean * mean)
}

/// The mean recorded count per bin matches `n/(1+nτ)` and `n·e^{−nτ}` within 0.5 % and
/// within 5 sd of its sampling noise (false alarm 6e-7 per rate), from 1 kHz to 200 MHz
/// (paralyzable: up to 1/τ, its maximum); the variance matches the renewal-theory form
/// within 5 % (above 100 kHz, where there are enough counts to see it) — these forms are
/// asymptotic in Δt/τ, and Δt/τ = 571 here.
#[test]
fn recorded_rates_follow_the_dead_time_formulas() {
    for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
        let dead = DeadTime {
            tau_s: TAU,
            model,
            bin_width_s: DT,
        };
        for n in [1e3, 1e5, 1e7, 5e7, 1.0 / TAU, 2e8] {
            if model == DeadTimeModel::Paralyzable && n > 1.0 / TAU {
                continue;
            }
            let lambda = n * DT;
            let shots = ((4e5 / (lambda * BINS as f64)) as u64).clamp(300, 2_000_000);
            let (mean, var) = simulate_stationary(model, n, shots, 7);
            let want = dead.stationary_rate(n) * DT;
            let want_var = dead.recorded_variance(lambda);
            let sd = (want_var / (shots as f64 * (BINS - 1) as f64)).sqrt();
            assert!(
                (mean / want - 1.0).abs() < 5e-3 && (mean - want).abs() < 5.0 * sd.max(1e-12),
                "{model:?} n = {n:e}: mean {mean} vs {want} (sd {sd})"
            );
            if n >= 1e5 {
                assert!(
                    (var / want_var - 1.0).abs() < 0.05,
                    "{model:?} n = {n:e}: variance {var} vs {want_var}"
                );
            }
        }
    }
}

/// Where the rate jumps from 0 to 100 MHz mid-window and back, the solver's recorded
/// means (the file's `expected_counts`) agree with the sampler's bin by bin within 5 sd
/// (false alarm 40 × 6e-7): dead time crossing bin edges is modelled, not ignored.
#[test]
fn the_recorded_mean_model_follows_a_rate_step() {
    for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
        // 5 ns bins: a dead time is most of a bin
        let dead = DeadTime {
            tau_s: TAU,
            model,
            bin_width_s: 5e-9,
        };
        let mut lambda = vec![0.0; 40];
        lambda[10..30].iter_mut().for_each(|l| *l = 1e8 * 5e-9);
        let want = dead.recorded_means(&lambda);
        let photons = ShotSampler::new(&lambda);
        let shots = 200_000u64;
        let mut acc = vec![0u64; 40];
        let mut rng = stream_rng(3, 0, 0);
        let mut arrivals = stream_rng(3, 1, 0);
        let mut scratch = lidarsim::detector::dead_time::Scratch::default();
        photons.for_each_shot(&mut rng, shots, |shot| {
            dead.record_shot(&mut arrivals, shot, &mut scratch, &mut acc)
        });
        for i in 0..40 {
            let mean = acc[i] as f64 / shots as f64;
            let sd = (lambda[i] / shots as f64).sqrt();
            assert!(
                (mean - want[i]).abs() <= 5.0 * sd + 1e-3 * want[i],
                "{model:?} bin {i}: {mean} vs {}",
                want[i]
            );
        }
        // the step matters: the first bin of the pulse records more than the stationary
        assert!(want[10] > want[20] * 1.02, "{} vs {}", want[10], want[20]);
    }
}

/// `validate` with dead time (paper scenario 1 at 1 J: ~350 MHz at the cloud top):
/// the simulator's recorded counts are CONSISTENT with the dead-time model (false alarm
/// < 2e-3), and the ideal Poisson expectation is rejected on the mean.
#[test]
fn validate_checks_recorded_counts_and_rejects_the_ideal_model() {
    let sc = common::scenario(
        "paper/scenario1.toml",
        &[
            "instrument.detector.dead_time_s=3.5e-9",
            "acquisition.accumulation_time_s=1",
        ],
    );
    let e = sc.expected().unwrap();
    let shots = sc.shots_per_profile();
    let dead = sc.instrument.dead_time.unwrap();
    let source =
        SimulatorSource::new(&e, ResolvedMethod::Shot, 0.0, 5, shots).with_detector(Some(dead));
    let bg = &e.background_bin_indices;
    let laser = lidarsim::laser::PulseEnergy::from_config(&sc.loaded.config.instrument);
    let right = validate::recorded_bin_models(&e, shots, &dead, &laser);
    let (_, checks) = validate::validate_source(&source, &right, &e.altitude_m, 400, bg);
    assert!(checks.iter().all(|c| c.pass), "{checks:#?}");
    let ideal = validate::bin_models(&e, shots, 0.0);
    let (_, checks) = validate::validate_source(&source, &ideal, &e.altitude_m, 400, bg);
    let mean = checks.iter().find(|c| c.statistic == "mean").unwrap();
    assert!(!mean.pass, "{mean:#?}");
}

/// Dead time makes `aggregate` inexact (refused, `auto` draws shots); component counts
/// are refused in one line; jitter combines with dead time.
#[test]
fn dead_time_refuses_what_it_cannot_do() {
    let sc = common::lidar(
        "paper/scenario1.toml",
        &["instrument.detector.dead_time_s=3.5e-9"],
    );
    let e = lidarsim::simulate::resolve_method(lidarsim::config::Method::Aggregate, &sc);
    assert!(e.unwrap_err().to_string().contains("dead time"));
    assert_eq!(
        lidarsim::simulate::resolve_method(lidarsim::config::Method::Auto, &sc).unwrap(),
        ResolvedMethod::Shot
    );
    assert!(lidarsim::simulate::check_detector(&sc, true).is_err());
    let jittered = common::lidar(
        "paper/scenario1.toml",
        &[
            "instrument.detector.dead_time_s=3.5e-9",
            "instrument.pulse_energy_jitter=0.05",
        ],
    );
    assert!(lidarsim::simulate::check_detector(&jittered, false).is_ok());
}

/// Without dead time, a bin beyond a photon counter's linear range is named in a
/// one-line warning after the run; with dead time there is none.
#[test]
fn rates_beyond_the_linear_range_are_warned_of() {
    let cfg = common::config_path("paper/scenario1.toml");
    let run = |extra: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_lidarsim"))
            .arg("expect")
            .arg(&cfg)
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success());
        String::from_utf8(o.stderr).unwrap()
    };
    let w = run(&[]);
    assert!(
        w.contains("warning: bin 294") && w.contains("350 MHz"),
        "{w}"
    );
    assert_eq!(w.lines().count(), 1);
    assert!(run(&["--set", "instrument.detector.dead_time_s=3.5e-9"]).is_empty());
    assert!(run(&["--set", "instrument.pulse_energy_j=0.01"]).is_empty());
}
