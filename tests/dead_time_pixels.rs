//! A photon counter of several pixels (`instrument.detector.pixels`, issue 42): the
//! photons split evenly over k pixels, each with its own non-paralyzable dead time.
//!
//! Reference, written here from renewal theory and not from the code under test: one
//! pixel at the stationary rate n/k records (n/k)/(1 + (n/k)·τ) (Müller 1973, NIM 112,
//! 47), so k pixels record k times that. Judged as the issue states it: the recorded rate
//! of a 16-pixel detector at 100 MHz total within 0.5 % of 16 × one pixel's at 6.25 MHz
//! (the statistical error of the run is 1.6e-4 of it, so 0.5 % is 30σ: no false alarm;
//! a one-pixel detector at the whole rate records 24 % less and fails it). The variance
//! of the 16 pixels' sum equals 16 × that of one pixel run alone at the 16th of the rate
//! (independent pixels add their variances), within 5 % (the pooled estimates' error is
//! ~1 %): pixels that shared their photons' draws (one seed for all) would give 16× it.

mod common;

use common::cli::scratch;
use common::config_path;
use common::h5::{floats, simulate_with};

const TAU_S: f64 = 3.2e-9;
const BIN_S: f64 = 2e-8;
const TOTAL_HZ: f64 = 1e8;
const PROFILES: usize = 10;
/// Bins skipped at the window's start (the detector starts live: a transient of a few τ).
const SKIP: usize = 10;

/// The ICESat-2-like preset made a constant-rate source: no signal to speak of
/// (1e-12 J: 5e-8 photons a shot), no sky, `dark_hz` of dark counts.
fn run(dir: &std::path::Path, out: &str, dark_hz: f64, pixels: u32) -> Vec<Vec<f64>> {
    let sets = [
        format!("instrument.dark_count_rate_hz={dark_hz}"),
        "instrument.pulse_energy_j=1e-12".to_string(),
        "background.radiance=0".to_string(),
        format!("instrument.detector.pixels={pixels}"),
    ];
    let mut more = vec![];
    for s in &sets {
        more.push("--set");
        more.push(s.as_str());
    }
    let f = simulate_with(
        dir,
        &config_path("instruments/icesat2_like.toml"),
        out,
        &PROFILES.to_string(),
        &more,
    );
    let counts = floats(&f, "counts");
    let bins = counts.len() / PROFILES;
    counts.chunks(bins).map(|p| p[SKIP..].to_vec()).collect()
}

/// Mean per bin and profile, and the pooled variance over profiles of each bin's count.
fn mean_and_pooled_variance(profiles: &[Vec<f64>]) -> (f64, f64) {
    let (p, bins) = (profiles.len() as f64, profiles[0].len());
    let mut mean_sum = 0.0;
    let mut var_sum = 0.0;
    for b in 0..bins {
        let m = profiles.iter().map(|r| r[b]).sum::<f64>() / p;
        let v = profiles.iter().map(|r| (r[b] - m).powi(2)).sum::<f64>() / (p - 1.0);
        mean_sum += m;
        var_sum += v;
    }
    (mean_sum / bins as f64, var_sum / bins as f64)
}

#[test]
fn sixteen_pixels_record_sixteen_times_one_pixel_at_a_sixteenth_of_the_rate() {
    let dir = scratch("dead_time_pixels");
    let shots = 400.0;
    let pixel_hz = TOTAL_HZ / 16.0;
    let renewal = 16.0 * pixel_hz / (1.0 + pixel_hz * TAU_S) * BIN_S * shots;

    let sixteen = run(&dir, "sixteen.h5", TOTAL_HZ, 16);
    let (mean, var) = mean_and_pooled_variance(&sixteen);
    let n = (sixteen.len() * sixteen[0].len()) as f64;
    let sigma = (var / n).sqrt() / renewal;
    assert!(sigma < 5e-4, "statistical error {sigma}");
    assert!(
        (mean / renewal - 1.0).abs() < 5e-3,
        "16 pixels at 100 MHz record {mean} per bin and profile, renewal theory {renewal}"
    );

    // the whole rate on one pixel loses 24 %: the law above tells them apart
    let one = run(&dir, "one.h5", TOTAL_HZ, 1);
    let (mean_one, _) = mean_and_pooled_variance(&one);
    assert!(mean_one / renewal < 0.8, "{mean_one} vs {renewal}");

    // independent pixels: the variances add
    let single = run(&dir, "single.h5", pixel_hz, 1);
    let (mean_single, var_single) = mean_and_pooled_variance(&single);
    assert!((16.0 * mean_single / renewal - 1.0).abs() < 5e-3);
    assert!(
        (var / (16.0 * var_single) - 1.0).abs() < 0.05,
        "variance of 16 pixels {var}, 16 × one pixel's {}",
        16.0 * var_single
    );
}

/// The file says how many pixels each channel has, and `validate --file` judges the
/// counts by the 16-pixel law.
#[test]
fn the_file_records_the_pixels_and_validate_reads_them() {
    let dir = scratch("dead_time_pixels_file");
    let f = simulate_with(
        &dir,
        &config_path("instruments/icesat2_like.toml"),
        "is2.h5",
        "5",
        &[],
    );
    assert_eq!(floats(&f, "detector_pixels"), vec![16.0]);
    let o = common::cli::lidarsim(&dir, &["validate", "--file", "is2.h5"], &[]);
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}
