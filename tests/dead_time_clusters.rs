//! The dead time's photon path with the clusters corrected (`detector::dead_time`,
//! `DeadTimedShots`, issue 41) against the exact counting law of a window of several bins
//! begun live: the window's count is the sum of its bins' recorded counts, so it is right
//! only if the dead time left by each bin is carried into the next.
//!
//! χ² over the count's values at 1, 30 and 300 MHz (τ = 3.5 ns), both models, in bins of
//! 2τ (the narrowest the photon path serves, where a bin's dead time most often crosses
//! into the next), fixed seeds; each check's false-alarm rate 1e-4 (the χ² quantile),
//! 1e-3 for the fifteen together. Power: with the dead time dropped at every bin edge
//! (each bin entered live; done once by hand in `clusters.rs`) every photon-path check at
//! 1, 30 and 300 MHz fails (see the commit message): at 1 MHz such a crossing changes
//! ~1e-4 of the shots, hence 3·10⁷ shots there. With τ 1 % too long in the photon path's
//! sweep the four photon-path checks at 300 MHz fail (χ² 111–194, limit 29.9; issue 41).

mod common;

use lidarsim::detector::dead_time::{DeadTimePath, DeadTimedShots};
use lidarsim::detector::{DeadTime, DeadTimeModel};
use lidarsim::sampling::ShotSampler;
use statrs::distribution::{ChiSquared, ContinuousCDF};

const TAU: f64 = 3.5e-9;
const FALSE_ALARM: f64 = 1e-4;

/// `P(Pois(μ) = j)` for j = 0..len, by the recurrence from `e^{−μ}` (μ ≤ ~30 here).
fn poisson_pmf(mu: f64, len: usize) -> Vec<f64> {
    let mut p = vec![0.0; len];
    let mut term = (-mu).exp();
    for (j, pj) in p.iter_mut().enumerate() {
        *pj = term;
        term *= mu / (j + 1) as f64;
    }
    p
}

/// The law of a non-paralyzable counter's count on a window `l` begun live (Müller 1973:
/// the k-th record at `(k−1)τ + Γ(k, n)`): `P(N ≥ k) = P(Pois(n(l − (k−1)τ)) ≥ k)`.
fn nonparalyzable_law(n: f64, l: f64, kmax: usize) -> Vec<f64> {
    let ge = |k: usize| -> f64 {
        if k == 0 {
            return 1.0;
        }
        let mu = n * (l - (k as f64 - 1.0) * TAU);
        if mu <= 0.0 {
            return 0.0;
        }
        let below: f64 = poisson_pmf(mu, k).iter().sum();
        (1.0 - below).max(0.0)
    };
    (0..kmax).map(|k| ge(k) - ge(k + 1)).collect()
}

/// The law of a paralyzable counter's count on a window `l` begun live: given M photons
/// uniform on it (M ~ Pois(nl)), the first is recorded and each later one whose spacing
/// from the one before is at least τ; `i` given spacings of the M + 1 all exceed τ with
/// probability `(1 − iτ/l)₊^M` (uniform spacings), so by inclusion–exclusion
/// `P(J = j | M) = Σ_{i ≥ j} (−1)^{i−j} C(i, j) C(M−1, i) (1 − iτ/l)₊^M` for J of the
/// M − 1 inner spacings above τ, and N = 1 + J.
fn paralyzable_law(n: f64, l: f64, kmax: usize) -> Vec<f64> {
    let binom = |a: usize, b: usize| -> f64 {
        (0..b).fold(1.0, |c, t| c * (a - t) as f64 / (t + 1) as f64)
    };
    let m_max = 80usize;
    let pm = poisson_pmf(n * l, m_max);
    let mut law = vec![0.0; kmax];
    law[0] = pm[0];
    for (m, &w) in pm.iter().enumerate().skip(1) {
        for j in 0..m {
            let mut p = 0.0;
            for i in j..m {
                let x = 1.0 - i as f64 * TAU / l;
                if x <= 0.0 {
                    break;
                }
                let sign = if (i - j) % 2 == 0 { 1.0 } else { -1.0 };
                p += sign * binom(i, j) * binom(m - 1, i) * x.powi(m as i32);
            }
            if j + 1 < kmax {
                law[j + 1] += w * p.max(0.0);
            }
        }
    }
    law
}

/// χ² of the observed window counts against `law` over cells of at least 5 expected
/// counts (the tails merged), and its degrees of freedom.
fn chi_square(observed: &[u64], law: &[f64], shots: u64) -> (f64, usize) {
    let total = shots as f64;
    let mut cells: Vec<(f64, f64)> = Vec::new();
    let (mut o, mut e) = (0.0, 0.0);
    for k in 0..law.len().max(observed.len()) {
        o += observed.get(k).copied().unwrap_or(0) as f64;
        e += law.get(k).copied().unwrap_or(0.0) * total;
        if e >= 5.0 {
            cells.push((o, e));
            (o, e) = (0.0, 0.0);
        }
    }
    if let Some(last) = cells.last_mut() {
        last.0 += o;
        last.1 += e;
    }
    let chi2 = cells.iter().map(|(o, e)| (o - e) * (o - e) / e).sum();
    (chi2, cells.len() - 1)
}

/// The window's recorded count, shot by shot, histogrammed.
fn window_counts(shots: &DeadTimedShots, seed: u64, n: u64) -> Vec<u64> {
    let mut hist = vec![0u64; 64];
    shots.for_each_shot(seed, 0, n, |acc| {
        let k = acc.iter().sum::<u64>() as usize;
        hist[k.min(63)] += 1;
    });
    hist
}

/// The χ² check of one case: `None` if it passes, else what failed.
fn check(model: DeadTimeModel, case: Case, every_photon: bool) -> Option<String> {
    let path = if every_photon {
        DeadTimePath::Photons
    } else {
        DeadTimePath::Auto
    };
    check_path(model, case, every_photon, path)
}

/// [`check`] with the path forced.
fn check_path(
    model: DeadTimeModel,
    (n, dt, bins, count): Case,
    every_photon: bool,
    path: DeadTimePath,
) -> Option<String> {
    let dead = detector(model, dt);
    let photons = ShotSampler::new(&vec![n * dt; bins]);
    let mut shots = DeadTimedShots::new(photons, dead).with_path(path);
    if every_photon {
        shots = shots.drawing_every_photon();
    }
    let l = bins as f64 * dt;
    let law = match model {
        DeadTimeModel::Nonparalyzable => nonparalyzable_law(n, l, 64),
        DeadTimeModel::Paralyzable => paralyzable_law(n, l, 64),
    };
    assert!(
        (law.iter().sum::<f64>() - 1.0).abs() < 1e-9,
        "the law sums to 1"
    );
    let hist = window_counts(&shots, 17, count);
    let (chi2, df) = chi_square(&hist, &law, count);
    let limit = ChiSquared::new(df as f64)
        .expect("df > 0")
        .inverse_cdf(1.0 - FALSE_ALARM);
    let line = format!(
        "{model:?} n = {n:e}, Δt = {dt:e}, every photon {every_photon}, {path:?}: χ² = {chi2:.1} \
         on {df} df (limit {limit:.1})"
    );
    println!("{line}");
    (chi2 >= limit).then_some(line)
}

/// A true rate, the bin width, the window's bins, the shots.
type Case = (f64, f64, usize, u64);

/// 1, 30 and 300 MHz in bins of 2τ: windows of 16 bins, of 4 at 300 MHz (whose
/// inclusion–exclusion then has at most 8 terms).
const CASES: [Case; 3] = [
    (1e6, 2.0 * TAU, 16, 30_000_000),
    (3e7, 2.0 * TAU, 16, 200_000),
    (3e8, 2.0 * TAU, 4, 200_000),
];

/// Wider bins, where most photons are placed without a look at their neighbours (their
/// time from the placement draw, flagged only within τ of an edge or second in their
/// bin): 30 MHz in bins of 8τ (0.84 photons a bin), 300 MHz in bins of 4τ.
const WIDE: [Case; 2] = [(3e7, 8.0 * TAU, 8, 200_000), (3e8, 4.0 * TAU, 2, 200_000)];

#[test]
fn the_paralyzable_window_count_follows_its_exact_law() {
    let failed: Vec<String> = CASES
        .into_iter()
        .chain(WIDE)
        .filter_map(|case| check(DeadTimeModel::Paralyzable, case, false))
        .collect();
    assert!(failed.is_empty(), "{failed:#?}");
}

#[test]
fn the_nonparalyzable_window_count_follows_its_exact_law() {
    let mut failed = Vec::new();
    for case in WIDE {
        failed.extend(check(DeadTimeModel::Nonparalyzable, case, true));
    }
    for case in CASES {
        // every photon drawn: the photon path with the clusters corrected
        failed.extend(check(DeadTimeModel::Nonparalyzable, case, true));
        // the default: the same below 0.5 photons a bin, the counting law above
        failed.extend(check(DeadTimeModel::Nonparalyzable, case, false));
    }
    // the counting law at 1.5 photons a bin, and the photon path at 0.2, in 2 µs bins
    failed.extend(check(
        DeadTimeModel::Nonparalyzable,
        (1e6, 1.5e-6, 4, 200_000),
        false,
    ));
    failed.extend(check(
        DeadTimeModel::Nonparalyzable,
        (1e5, 2e-6, 4, 200_000),
        false,
    ));
    assert!(failed.is_empty(), "{failed:#?}");
}

/// The laws written here are those of a window: the paralyzable one by inclusion–exclusion
/// and Müller's agree at low rates, where at most one photon is lost (τ/l small), and the
/// paralyzable mean matches `nl·e^{−nτ}` up to the window's start (begun live: higher).
#[test]
fn the_reference_laws_are_sound() {
    let (n, l) = (1e6, 6e-6);
    let a = nonparalyzable_law(n, l, 64);
    let b = paralyzable_law(n, l, 64);
    for k in 0..20 {
        assert!((a[k] - b[k]).abs() < 2e-4, "k {k}: {} vs {}", a[k], b[k]);
    }
    let (n, l) = (3e8, 8.0 * TAU);
    let mean: f64 = paralyzable_law(n, l, 64)
        .iter()
        .enumerate()
        .map(|(k, p)| k as f64 * p)
        .sum();
    let stationary = n * l * (-n * TAU).exp();
    assert!(
        mean > stationary && mean < stationary + 1.0,
        "{mean} vs {stationary}"
    );
}

/// The arrival walk (`walk.rs`, issue 41) at 1, 30 and 300 MHz in bins of 2τ, and at 300
/// MHz in bins of τ/2 (narrower than the photon path serves), both models. Power: with
/// the dead time dropped at every bin edge (each bin's walk begun live; done once by hand
/// in `walk.rs`) the checks fail (see the commit message and
/// `validation/reports/dead_time_cost.md`).
#[test]
fn the_arrival_walk_follows_the_exact_laws() {
    let mut failed = Vec::new();
    let narrow = (3e8, 0.5 * TAU, 16, 200_000);
    for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
        for case in CASES.into_iter().chain([narrow]) {
            // the 1 MHz case needs its many shots only for the photon path's rare edges
            let case = if case.0 == 1e6 {
                (1e6, 2.0 * TAU, 16, 3_000_000)
            } else {
                case
            };
            failed.extend(check_path(model, case, false, DeadTimePath::Walk));
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}

/// A single-pixel detector of dead time [`TAU`] on bins of `dt`.
fn detector(model: DeadTimeModel, dt: f64) -> DeadTime {
    DeadTime {
        tau_s: TAU,
        model,
        bin_width_s: dt,
        pixels: 1,
    }
}

/// The stationary mean of a bin's recorded count (`nT/(1+nτ)`, `nT·e^{−nτ}`) and its
/// renewal window variance, T the bin width `dt`.
fn renewal_mean_and_variance(model: DeadTimeModel, n: f64, dt: f64) -> (f64, f64) {
    match model {
        DeadTimeModel::Nonparalyzable => (
            n * dt / (1.0 + n * TAU),
            common::reference::nonparalyzable_window_variance(n, TAU, dt),
        ),
        DeadTimeModel::Paralyzable => (
            n * dt * (-n * TAU).exp(),
            paralyzable_window_variance(n, TAU, dt),
        ),
    }
}

/// The stationary variance of a paralyzable counter's count in a window T ≥ τ: a record
/// at s is an arrival with none in (s − τ, s), so records at u < v have the product
/// density `n²e^{−2nτ}` for v − u > τ and 0 below (disjoint empty intervals), whence
/// `Var N(T) = mT + m²(T − τ)² − (mT)² = mT − m²(2Tτ − τ²)`, m = n·e^{−nτ}.
fn paralyzable_window_variance(n: f64, tau: f64, t: f64) -> f64 {
    let m = n * (-n * tau).exp();
    m * t - m * m * (2.0 * t * tau - tau * tau)
}

/// The walk's recorded counts, deep in a long window of constant rate (so that a
/// residual dead time enters each bin, in its stationary law), have the stationary mean
/// (`nT/(1+nτ)`, `nT·e^{−nτ}`) and the window variance of renewal theory within 0.5 %,
/// from 100 kHz to 300 MHz, both models. Bins of 20τ (several records a bin at high
/// rates, where the dead time matters most); the first 8 bins (160τ) left out. Fixed
/// seed; ≥ 10⁶ bin counts per rate: the variance's relative standard error ≤ 0.15 %, so
/// 0.5 % is > 3σ (together with the mean's, false alarm ~1e-3 for the 16 checks). With
/// τ 1 % too long in the walk the paralyzable variance at 300 MHz moves by ~3 %.
#[test]
fn the_arrival_walk_has_the_renewal_mean_and_variance() {
    let dt = 20.0 * TAU;
    let (bins, skip) = (108usize, 8usize);
    let mut failed = Vec::new();
    for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
        let dead = detector(model, dt);
        for n in [1e5, 1e7, 1e8, 3e8] {
            // at 100 kHz a bin holds 0.007 photons: more shots for the same precision
            let shots: u64 = if n < 1e6 { 2_000_000 } else { 20_000 };
            let photons = ShotSampler::new(&vec![n * dt; bins]);
            let walk = DeadTimedShots::new(photons, dead).with_path(DeadTimePath::Walk);
            let (mut s1, mut s2, mut count) = (0.0, 0.0, 0.0);
            walk.for_each_shot(23, 0, shots, |acc| {
                for &k in &acc[skip..] {
                    let k = k as f64;
                    s1 += k;
                    s2 += k * k;
                    count += 1.0;
                }
            });
            let mean = s1 / count;
            let var = s2 / count - mean * mean;
            let (want_mean, want_var) = renewal_mean_and_variance(model, n, dt);
            let line = format!(
                "{model:?} n = {n:e}: mean {mean:.5} vs {want_mean:.5}, variance {var:.5} vs \
                 {want_var:.5}"
            );
            println!("{line}");
            if (mean / want_mean - 1.0).abs() > 5e-3 || (var / want_var - 1.0).abs() > 5e-3 {
                failed.push(line);
            }
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}

/// The law of the sum of `shots` independent counts of law `law` (convolved).
fn convolved(law: &[f64], shots: usize) -> Vec<f64> {
    let mut sum = vec![1.0];
    for _ in 0..shots {
        let mut next = vec![0.0; sum.len() + law.len() - 1];
        for (a, pa) in sum.iter().enumerate() {
            for (b, pb) in law.iter().enumerate() {
                next[a + b] += pa * pb;
            }
        }
        sum = next;
    }
    sum
}

/// The column path (`columns.rs`: a block's shots drawn bin by bin as counts of shots,
/// profiles only) against the exact law: the window's count summed over the `S` shots of
/// a profile follows the S-fold convolution of the window's law. Profiles of 3 shots (so
/// that the block's binomials and its shots carried dead from bin to bin both count), of
/// 1 shot and of 40 (the hits skipped to, the binomials by inversion); the cases of the
/// photon path and 0.2 and 1.5 photons a bin in 2 µs bins, both models; false alarm 1e-4
/// per check. Power (by hand, see validation/reports/dead_time_cost.md): each bin entered
/// live (the carried dead time dropped), τ 1 % too long, and the level share
/// `P(K = k | K ≥ k)` 1 % too large (fails at 1e5 and 7.5e5 Hz in 2 µs bins and 3e7 Hz
/// in 28 ns bins, all three profile sizes at 7.5e5 Hz).
#[test]
fn the_column_path_follows_the_exact_laws() {
    let mut failed = Vec::new();
    let cases = CASES
        .into_iter()
        .map(|(n, dt, bins, count)| (n, dt, bins, count.min(3_000_000)))
        .chain(WIDE)
        .chain([(1e5, 2e-6, 4, 200_000), (7.5e5, 2e-6, 4, 200_000)]);
    for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
        for (n, dt, bins, count) in cases.clone() {
            for per_profile in [3u64, 1, 40] {
                let dead = detector(model, dt);
                let photons = ShotSampler::new(&vec![n * dt; bins]);
                let path = DeadTimedShots::new(photons, dead).with_path(DeadTimePath::Columns);
                let l = bins as f64 * dt;
                let law = match model {
                    DeadTimeModel::Nonparalyzable => nonparalyzable_law(n, l, 64),
                    DeadTimeModel::Paralyzable => paralyzable_law(n, l, 64),
                };
                let law = convolved(&law, per_profile as usize);
                let profiles = count / per_profile;
                let mut hist = vec![0u64; law.len()];
                let mut acc = vec![0u64; bins];
                for p in 0..profiles {
                    acc.iter_mut().for_each(|a| *a = 0);
                    path.profile(29, p, per_profile, &mut acc);
                    let k = acc.iter().sum::<u64>() as usize;
                    hist[k.min(law.len() - 1)] += 1;
                }
                let (chi2, df) = chi_square(&hist, &law, profiles);
                let limit = ChiSquared::new(df as f64)
                    .expect("df > 0")
                    .inverse_cdf(1.0 - FALSE_ALARM);
                let line = format!(
                    "{model:?} n = {n:e}, Δt = {dt:e}, columns, {per_profile} shots a profile: \
                     χ² = {chi2:.1} on {df} df (limit {limit:.1})"
                );
                println!("{line}");
                if chi2 >= limit {
                    failed.push(line);
                }
            }
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}

/// The column path's recorded counts deep in a long window of constant rate have the
/// stationary mean and the renewal window variance within 0.5 %, as the walk's above
/// (same rates, bins of 20τ, first 8 bins left out), from profiles of 4 shots: a bin's
/// sum over a profile has 4 × the shot's mean and variance (independent shots). Fixed
/// seed; 10⁶ bin sums per rate or more (the variance's relative standard error ≤ 0.15 %).
/// The mean also from one profile of many blocks (2·10⁵ shots, 2·10⁶ at 100 kHz), within
/// 0.3 % (its standard error 0.03 % from 10 MHz on, 0.09 % at 100 kHz).
#[test]
fn the_column_path_has_the_renewal_mean_and_variance() {
    let dt = 20.0 * TAU;
    let (bins, skip, per_profile) = (108usize, 8usize, 4u64);
    let mut failed = Vec::new();
    for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
        let dead = detector(model, dt);
        for n in [1e5, 1e7, 1e8, 3e8] {
            let shots: u64 = if n < 1e6 { 2_000_000 } else { 40_000 };
            let photons = ShotSampler::new(&vec![n * dt; bins]);
            let path = DeadTimedShots::new(photons, dead).with_path(DeadTimePath::Columns);
            let (mut s1, mut s2, mut count) = (0.0, 0.0, 0.0);
            let mut acc = vec![0u64; bins];
            for p in 0..shots / per_profile {
                acc.iter_mut().for_each(|a| *a = 0);
                path.profile(31, p, per_profile, &mut acc);
                for &k in &acc[skip..] {
                    let k = k as f64;
                    s1 += k;
                    s2 += k * k;
                    count += 1.0;
                }
            }
            let mean = s1 / count;
            let var = (s2 / count - mean * mean) / per_profile as f64;
            let mean = mean / per_profile as f64;
            let (want_mean, want_var) = renewal_mean_and_variance(model, n, dt);
            // and one profile of several blocks (the binomials of large n)
            acc.iter_mut().for_each(|a| *a = 0);
            let big: u64 = if n < 1e6 { 2_000_000 } else { 200_000 };
            path.profile(41, 0, big, &mut acc);
            let big_mean =
                acc[skip..].iter().sum::<u64>() as f64 / ((bins - skip) as u64 * big) as f64;
            if (big_mean / want_mean - 1.0).abs() > 3e-3 {
                failed.push(format!("{model:?} n = {n:e}, one profile of {big} shots: mean {big_mean:.5} vs {want_mean:.5}"));
            }
            let line = format!(
                "{model:?} n = {n:e}, columns: mean {mean:.5} vs {want_mean:.5} ({big_mean:.5} \
                 in one profile), variance {var:.5} vs {want_var:.5}"
            );
            println!("{line}");
            if (mean / want_mean - 1.0).abs() > 5e-3 || (var / want_var - 1.0).abs() > 5e-3 {
                failed.push(line);
            }
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}
