//! Depolarization calibration (issue 21, model.md §8 "Depolarization calibration",
//! `src/receiver/polarization.rs`): the Δ90 method (Freudenthaler 2016, Atmos. Meas.
//! Tech. 9, 4181), written here from its definition — the calibration constant is the
//! geometric mean of the perpendicular-to-parallel signal ratios of two runs with the
//! receiver's polarization plane rotated by +45° and −45°,
//!
//! ```text
//! η*_Δ90 = sqrt( [S_⊥/S_∥](+45°) · [S_⊥/S_∥](−45°) )
//! ```
//!
//! — applied to the expected signals of the two-polarization ground lidar with its
//! receiving optics' diattenuation and its splitter's cross-talk on, recovers the
//! configured gain ratio (the channels' quantum efficiencies, 0.3/0.2) in every bin.

mod common;

use std::path::{Path, PathBuf};

use common::cli::scratch;
use common::config_path;
use common::h5::{channel_rows, floats, simulate, strings, validate_consistent_both_ways};

/// The two-polarization lidar with diattenuation `d` and the receiver rotated by
/// `rotation_deg`, written into `dir`; 1,000 shots a profile (not 75,000: the expected
/// signals do not depend on it, and the dead-time path draws in seconds).
fn calibration_config(dir: &Path, d: f64, rotation_deg: f64) -> PathBuf {
    let base = std::fs::read_to_string(config_path("ground/ground_532_depol.toml")).unwrap();
    let (anchor, long) = ("wavelength_nm = 532.0\n", "accumulation_time_s = 30.0");
    assert!(base.contains(anchor) && base.contains(long));
    let text = base
        .replacen(
            anchor,
            &format!("{anchor}diattenuation = {d}\nreceiver_rotation_deg = {rotation_deg}\n"),
            1,
        )
        .replacen(long, "accumulation_time_s = 0.4", 1);
    let path = dir.join(format!("cal{rotation_deg}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// `[S_⊥/S_∥]` of each bin with a signal in the parallel channel, and the file's
/// calibration constant of the perpendicular channel.
fn ratios(dir: &Path, config: &Path, out: &str) -> (Vec<f64>, f64) {
    let f = simulate(dir, config, out, "1");
    let names = strings(&f, "channel_name");
    let k = |n: &str| names.iter().position(|c| c == n).unwrap();
    let (par, per) = (k("532_parallel"), k("532_perpendicular"));
    let signal = channel_rows(&f, "expected_signal", names.len());
    let r = signal[par]
        .iter()
        .zip(&signal[per])
        .map(|(p, s)| if *p > 0.0 { s / p } else { f64::NAN })
        .collect();
    (r, floats(&f, "polarization_calibration_constant")[per])
}

/// With D = 0.08 and cross-talk 0.01 on both channels, in every bin with a signal the
/// Δ90 constant is the configured gain ratio 1.5 (the perpendicular channel's quantum
/// efficiency 0.3 over the parallel one's 0.2, the rest of their lidar constants equal)
/// to 1e-12 — and the file's `polarization_calibration_constant` says 1.5. A calibrator
/// 0.5° off (+45.5°, −44.5°) still gives it within 1e-3 (the geometric mean cancels the
/// first order). Without the rotation (φ = 0) the ratio is the volume depolarization's,
/// far from 1.5. A diattenuation applied after the calibrator, or cross-talk on one
/// channel only, fails the 1e-12 check (checked by hand).
#[test]
fn the_delta90_calibration_recovers_the_gain_ratio() {
    let dir = scratch("delta90");
    let want = 0.3 / 0.2;
    let run = |phi: f64, name: &str| ratios(&dir, &calibration_config(&dir, 0.08, phi), name);
    let ((plus, truth), (minus, _)) = (run(45.0, "p.h5"), run(-45.0, "m.h5"));
    assert!((truth - want).abs() < 1e-12, "{truth}");
    let mut judged = 0;
    for (i, (a, b)) in plus.iter().zip(&minus).enumerate() {
        if a.is_nan() || b.is_nan() {
            continue;
        }
        let eta = (a * b).sqrt();
        assert!((eta / want - 1.0).abs() < 1e-12, "bin {i}: {eta}");
        judged += 1;
    }
    assert!(judged > 500, "{judged}");
    let ((plus, _), (minus, _)) = (run(45.5, "p2.h5"), run(-44.5, "m2.h5"));
    let worst = plus
        .iter()
        .zip(&minus)
        .filter(|(a, b)| !a.is_nan() && !b.is_nan())
        .map(|(a, b)| ((a * b).sqrt() / want - 1.0).abs())
        .fold(0.0f64, f64::max);
    assert!(worst < 1e-3, "0.5° off: {worst}");
    let (measured, _) = run(0.0, "z.h5");
    assert!(
        measured
            .iter()
            .filter(|r| !r.is_nan())
            .all(|r| (r / want - 1.0).abs() > 0.5)
    );
}

/// A calibration run is a run like any other: `validate` is CONSISTENT on the +45° run
/// at shot level (the preset's dead time makes the aggregate method inexact, which
/// `validate` refuses), and on the same run without dead time both ways of drawing.
#[test]
fn validate_is_consistent_on_a_calibration_run() {
    let dir = scratch("delta90-validate");
    let cfg = calibration_config(&dir, 0.08, 45.0);
    let o = common::cli::lidarsim(
        &dir,
        &["validate", cfg.to_str().unwrap(), "--method", "shot"],
        &[],
    );
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(out.contains("CONSISTENT"), "{out}");
    let text = std::fs::read_to_string(&cfg).unwrap();
    let dead = "detector = { dead_time_s = 3.5e-9, dead_time_model = \"nonparalyzable\" }\n";
    assert!(text.contains(dead));
    let ideal = dir.join("ideal.toml");
    std::fs::write(&ideal, text.replacen(dead, "", 1)).unwrap();
    validate_consistent_both_ways(&dir, &ideal);
}

/// The keys are checked, each error one line naming the key: a diattenuation outside
/// [−0.99, 0.99], a rotation outside [−90°, 90°].
#[test]
fn calibration_keys_are_checked() {
    let dir = scratch("delta90-keys");
    for (d, phi, key) in [
        (1.2, 45.0, "instrument.diattenuation"),
        (0.0, 135.0, "instrument.receiver_rotation_deg"),
    ] {
        let text = std::fs::read_to_string(calibration_config(&dir, d, phi)).unwrap();
        let e = common::refusal(&text, key);
        assert!(e.contains(key), "{e}");
    }
}

/// `simulate --calibration plus45|minus45` is the run with the receiver rotated by
/// ±45°: the file says so (`receiver_rotation`), and its expected signals are the
/// config key's.
#[test]
fn the_calibration_flag_rotates_the_receiver() {
    let dir = scratch("delta90-flag");
    let measured = calibration_config(&dir, 0.08, 0.0);
    for (flag, deg) in [("plus45", 45.0), ("minus45", -45.0)] {
        let out = format!("{flag}.h5");
        let args = [
            "simulate",
            measured.to_str().unwrap(),
            "-o",
            &out,
            "--profiles",
            "1",
            "--calibration",
            flag,
        ];
        common::cli::ok(common::cli::lidarsim(&dir, &args, &[]));
        let f = hdf5::File::open(dir.join(&out)).unwrap();
        assert!(floats(&f, "receiver_rotation").iter().all(|&r| r == deg));
        let keyed = simulate(&dir, &calibration_config(&dir, 0.08, deg), "k.h5", "1");
        assert_eq!(
            floats(&f, "expected_signal"),
            floats(&keyed, "expected_signal")
        );
    }
}

/// The total + cross layout (PollyXT): each perpendicular channel's η* is relative to the
/// total channel at its laser line, η* = η·T_R/T_T (docs/model.md §4c, Eq. 4c.1). By hand
/// from `pollyxt_like.toml`: the perpendicular and total channels at a line differ only in
/// `receiver_efficiency` (1e-4 and 3e-6 at 355 nm, 8e-5 and 3e-6 at 532 nm), so
/// η = 1e-4/3e-6 and 8e-5/3e-6; the cross channel's analyser passes on average 1/2
/// (`(1−x) + x` over two polarizations), the total channel's 1: η* = 16.67 and 13.33.
/// Independently of the formula, the Δ90 method applied to the ±45° runs' expected
/// signals (cross over total, geometric mean) gives the file's η* in every bin to 1e-12.
/// Before this fix the file said NaN for both.
#[test]
fn the_total_and_cross_layout_has_its_delta90_constant() {
    let dir = scratch("delta90-total-cross");
    let config = config_path("ground/pollyxt_like.toml");
    let run = |phi: f64, out: &str| {
        let rotation = format!("instrument.receiver_rotation_deg={phi}");
        let more = [
            "--set",
            "acquisition.accumulation_time_s=0.5",
            "--set",
            &rotation,
        ];
        common::h5::simulate_with(&dir, &config, out, "1", &more)
    };
    let (plus, minus) = (run(45.0, "p.h5"), run(-45.0, "m.h5"));
    let names = strings(&plus, "channel_name");
    let k = |n: &str| names.iter().position(|c| c == n).unwrap();
    let truth = floats(&plus, "polarization_calibration_constant");
    for (total, cross, by_hand) in [
        ("355_total", "355_perpendicular", 1e-4 / 3e-6 / 2.0),
        ("532_total", "532_perpendicular", 8e-5 / 3e-6 / 2.0),
    ] {
        let eta = truth[k(cross)];
        assert!(
            (eta / by_hand - 1.0).abs() < 1e-12,
            "{cross}: {eta}, by hand {by_hand}"
        );
        let ratio = |f: &hdf5::File| {
            let s = channel_rows(f, "expected_signal", names.len());
            let (t, c) = (s[k(total)].clone(), s[k(cross)].clone());
            t.iter().zip(c).map(|(t, c)| c / t).collect::<Vec<f64>>()
        };
        let mut judged = 0;
        for (a, b) in ratio(&plus).iter().zip(ratio(&minus)) {
            if a.is_finite() && b.is_finite() && *a > 0.0 {
                let delta90 = (a * b).sqrt();
                assert!(
                    (delta90 / eta - 1.0).abs() < 1e-12,
                    "{cross}: {delta90} vs {eta}"
                );
                judged += 1;
            }
        }
        assert!(judged > 1000, "{judged}");
        // the other channels have none
        assert!(truth[k(total)].is_nan());
    }
}

/// Every shipped config with a perpendicular channel (two-channel layouts: parallel +
/// perpendicular, total + cross, the HSRL's co- and cross-polar channels) writes a
/// finite, positive η* for each of its perpendicular channels.
#[test]
fn every_shipped_polarization_layout_has_a_finite_delta90_constant() {
    let dir = scratch("delta90-shipped");
    let root = config_path("");
    let mut configs = Vec::new();
    let mut stack = vec![root];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "toml")
                && std::fs::read_to_string(&p)
                    .unwrap()
                    .contains("polarization = \"perpendicular\"")
            {
                configs.push(p);
            }
        }
    }
    configs.sort();
    assert!(configs.len() >= 6, "{configs:?}");
    for (i, config) in configs.iter().enumerate() {
        let out = format!("shipped{i}.h5");
        let f = common::h5::simulate_with(
            &dir,
            config,
            &out,
            "1",
            &["--set", "acquisition.accumulation_time_s=0.2"],
        );
        let pol = strings(&f, "polarization");
        let eta = floats(&f, "polarization_calibration_constant");
        for (p, e) in pol.iter().zip(&eta) {
            if p == "perpendicular" {
                assert!(e.is_finite() && *e > 0.0, "{}: {e}", config.display());
            } else {
                assert!(e.is_nan(), "{}: {p} {e}", config.display());
            }
        }
        std::fs::remove_file(dir.join(&out)).ok();
    }
}

/// Counts minus their expectation over the shots, in units of the Poisson sd, of every
/// bin of every channel; NaN where the expected count over the shots is 20 or less.
fn standardized_residuals(f: &hdf5::File) -> Vec<f64> {
    let n = floats(f, "n_shots")[0];
    let mean = floats(f, "expected_counts");
    let counts = f.dataset("counts").unwrap().read_raw::<u64>().unwrap();
    counts
        .iter()
        .zip(&mean)
        .map(|(c, m)| {
            if m * n > 20.0 {
                (*c as f64 - m * n) / (m * n).sqrt()
            } else {
                f64::NAN
            }
        })
        .collect()
}

/// Pearson's correlation of two series over the bins where both are finite, and how
/// many those are.
fn correlation(a: &[f64], b: &[f64]) -> (f64, usize) {
    let pairs: Vec<(f64, f64)> = a
        .iter()
        .zip(b)
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(x, y)| (*x, *y))
        .collect();
    let n = pairs.len() as f64;
    let ma = pairs.iter().map(|p| p.0).sum::<f64>() / n;
    let mb = pairs.iter().map(|p| p.1).sum::<f64>() / n;
    let cov: f64 = pairs.iter().map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = pairs.iter().map(|(x, _)| (x - ma).powi(2)).sum();
    let vb: f64 = pairs.iter().map(|(_, y)| (y - mb).powi(2)).sum();
    (cov / (va * vb).sqrt(), pairs.len())
}

/// The two calibration runs with the config's seed are two measurements: at ±45° their
/// expected counts are the same (both splitter axes see half the light whatever the
/// rotation's sign, D = 0), and their noises are independent. Over the N > 400 bins
/// with more than 20 expected counts (no pulse-energy jitter, so that no factor common to
/// a run's bins correlates them) the correlation of the standardized residuals of two
/// independent runs has sd 1/√N: |ρ|·√N < 4 has a false-alarm rate of 6e-5 per pair
/// (fixed seeds; three pairs). Identical noise — today's `--calibration` with one seed,
/// and what `--same-noise` asks for — gives ρ = 1 and fails it; the measurement's (φ = 0)
/// noise is independent of either run's as well.
#[test]
fn the_two_calibration_runs_do_not_share_their_noise() {
    let dir = scratch("delta90-noise");
    let measured = calibration_config(&dir, 0.0, 0.0);
    let run = |out: &str, more: &[&str]| {
        let mut args = vec!["--set", "instrument.pulse_energy_jitter=0"];
        args.extend_from_slice(more);
        common::h5::simulate_with(&dir, &measured, out, "1", &args)
    };
    let plus = run("p.h5", &["--calibration", "plus45"]);
    let minus = run("m.h5", &["--calibration", "minus45"]);
    let zero = run("z.h5", &[]);
    assert_eq!(
        floats(&plus, "expected_counts"),
        floats(&minus, "expected_counts")
    );
    let z = |f: &hdf5::File| standardized_residuals(f);
    for (name, a, b) in [
        ("plus45 and minus45", z(&plus), z(&minus)),
        ("plus45 and the measurement", z(&plus), z(&zero)),
        ("minus45 and the measurement", z(&minus), z(&zero)),
    ] {
        let (rho, n) = correlation(&a, &b);
        assert!(n > 400, "{name}: {n}");
        assert!(
            rho.abs() * (n as f64).sqrt() < 4.0,
            "{name} share their noise: ρ = {rho} over {n} bins"
        );
    }
    // asked for with --same-noise: the seed itself, the same noise, the same counts
    let counts = |f: &hdf5::File| f.dataset("counts").unwrap().read_raw::<u64>().unwrap();
    let same_minus = run("sm.h5", &["--calibration", "minus45", "--same-noise"]);
    let same_plus = run("sp.h5", &["--calibration", "plus45", "--same-noise"]);
    assert_eq!(counts(&same_minus), counts(&same_plus));
    assert_ne!(counts(&plus), counts(&same_plus));
}

/// `--calibration` on an instrument without a polarization channel is refused: one line
/// naming the config and the key, exit 2, nothing written.
#[test]
fn calibration_without_a_polarization_channel_is_refused() {
    let dir = scratch("delta90-no-polarization");
    let config = config_path("ground/ground_532_overlap.toml");
    for flag in ["plus45", "minus45"] {
        let args = [
            "simulate",
            config.to_str().unwrap(),
            "-o",
            "out.h5",
            "--calibration",
            flag,
        ];
        common::cli::refused(
            &dir,
            &args,
            &[
                "ground_532_overlap.toml",
                "instrument.polarization",
                "--calibration",
            ],
            "out.h5",
        );
    }
}
