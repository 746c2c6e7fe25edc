//! The exact KS distance against brute force, the bound and threshold on grids, and the
//! approximate sampler's moments.

use super::*;
use rand_pcg::Pcg64Mcg;
use statrs::distribution::ContinuousCDF;
use statrs::distribution::{DiscreteCDF, Normal, Poisson};

/// Brute force with statrs' Poisson and normal CDFs over 0..μ+60σ+60.
fn ks_brute(mu: f64) -> f64 {
    let p = Poisson::new(mu).unwrap();
    let n = Normal::new(mu, mu.sqrt()).unwrap();
    let top = (mu + 60.0 * mu.sqrt() + 60.0) as u64;
    (0..=top)
        .map(|k| (p.cdf(k) - n.cdf(k as f64 + 0.5)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn ks_matches_brute_force() {
    for mu in [0.05, 0.44, 1.0, 3.7, 25.0, 200.5, 3000.0] {
        let a = normal_approx_ks(mu);
        let b = ks_brute(mu);
        assert!((a - b).abs() < 1e-10, "mu {mu}: {a} vs brute {b}");
    }
}

#[test]
fn ks_edge_cases() {
    assert_eq!(normal_approx_ks(0.0), 0.0);
    assert_eq!(normal_approx_ks(-1.0), 0.0);
    assert!(normal_approx_ks(f64::NAN).is_nan());
    assert_eq!(normal_approx_ks(f64::INFINITY), 0.0);
    // tiny mean: KS ≈ 1 − e^{−μ}
    let mu = 1e-6;
    assert!((normal_approx_ks(mu) - (-(-mu).exp_m1())).abs() < 1e-12);
}

#[test]
fn summation_and_gamma_integral_agree() {
    for mu in [2e4, 3.3e5, 1e6 + 0.37, 4.1e6] {
        let (a, ka) = ks_sum(mu);
        let (b, kb) = ks_smooth(mu);
        assert!(
            (a - b).abs() < 1e-10 * a,
            "mu {mu}: sum {a} vs integral {b}"
        );
        assert!((ka - kb).abs() <= 1.0, "mu {mu}: argmax {ka} vs {kb}");
    }
    // the CDF itself, both ways
    for (k, mu) in [(1_999_000u64, 2e6f64), (2_000_000, 2e6), (2_003_000, 2e6)] {
        let mut sum = Neumaier::default();
        let lo = (mu - 40.0 * mu.sqrt()) as u64;
        for j in lo..=k {
            sum.add(pmf(j as f64, mu));
        }
        let q = poisson_cdf(k, mu);
        assert!(
            (sum.value() - q).abs() < 1e-13,
            "F({k}; {mu}): {} vs {q}",
            sum.value()
        );
    }
}

#[test]
fn ks_falls_like_c_over_sqrt_mu() {
    assert!((KS_ASYMPTOTE - 1.0 / (6.0 * (2.0 * PI).sqrt())).abs() < 1e-16);
    for mu in [1e4, 1e8, 1e12, 1e15] {
        let r = normal_approx_ks(mu) * mu.sqrt() / KS_ASYMPTOTE;
        assert!(
            (r - 1.0).abs() < 0.3 / mu + 1e-6,
            "mu {mu}: sqrt(mu) KS / c = {r}"
        );
    }
    assert_eq!(normal_approx_ks(1e17), KS_ASYMPTOTE / 1e17f64.sqrt());
}

#[test]
fn bound_holds_on_a_grid() {
    let mut grid: Vec<f64> = (0..400)
        .map(|i| 10f64.powf(-4.0 + 10.0 * i as f64 / 400.0))
        .collect();
    grid.extend((0..100).map(|i| 10.0 + i as f64 / 100.0));
    grid.extend((0..40).map(|i| 0.3 + i as f64 / 100.0));
    for mu in grid {
        let ks = normal_approx_ks(mu);
        assert!(
            ks <= normal_approx_ks_bound(mu),
            "mu {mu}: KS {ks} above the bound"
        );
        assert!(ks <= KS_SUP);
    }
}

#[test]
fn threshold_is_monotone_and_consistent() {
    let tols = [
        0.5, KS_SUP, 0.1, 0.05, 1e-2, 3e-3, 1e-3, 1e-4, 1e-6, 1e-9, 1e-100, 1e-160,
    ];
    let th: Vec<f64> = tols.iter().map(|&t| normal_threshold(t)).collect();
    assert_eq!(th[0], 0.0);
    assert_eq!(th[1], 0.0);
    assert!(th.windows(2).all(|w| w[0] <= w[1]), "{th:?}");
    assert_eq!(th[th.len() - 1], f64::INFINITY);
    assert!(th[th.len() - 2].is_finite());
    assert_eq!(normal_threshold(0.0), f64::INFINITY);
    assert_eq!(normal_threshold(-1.0), f64::INFINITY);
    assert_eq!(normal_threshold(f64::NAN), f64::INFINITY);
    assert_eq!(normal_threshold(1.0), 0.0);
    for (&t, &m) in tols.iter().zip(&th).skip(2).take(6) {
        // the bound is met at μ* and every larger mean tried
        assert!(normal_approx_ks_bound(m) <= t);
        for f in [1.0, 1.003, 1.1, 1.7, 10.0, 1e3] {
            let ks = normal_approx_ks(m * f);
            assert!(ks <= t, "tol {t}: KS({}) = {ks}", m * f);
        }
        // and μ* is nearly the smallest: the true KS exceeds τ a little lower
        let below = (0..50)
            .map(|i| normal_approx_ks(m * (0.7 + 0.006 * i as f64)))
            .fold(0.0, f64::max);
        assert!(below > t, "tol {t}: mu* = {m} is not tight ({below})");
    }
    assert!((normal_threshold(1e-2) - 44.459).abs() < 0.01);
    assert!((normal_threshold(1e-3) / 4421.23 - 1.0).abs() < 1e-5);
}

/// Mean and variance of the normal draws at μ = 1e4 and 1e12 (20,000 draws, fixed
/// seed). Each check is at 5 standard deviations of its estimator: a false alarm
/// rate of 5.7e-7 per check for a random seed.
#[test]
fn approximate_sampler_moments() {
    let n = 20_000usize;
    for (mu, seed) in [(1e4, 1u64), (1e12, 2)] {
        let mut rng = Pcg64Mcg::new(0xA99 + u128::from(seed));
        let mut x = Vec::with_capacity(n);
        for _ in 0..n {
            let mut acc = [0u64];
            add_aggregate_approx(&mut rng, &[mu], 1, 0.0, &mut acc);
            x.push(acc[0] as f64);
        }
        let mean = x.iter().sum::<f64>() / n as f64;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let sd_mean = (mu / n as f64).sqrt();
        assert!((mean - mu).abs() < 5.0 * sd_mean, "mu {mu}: mean {mean}");
        let sd_var = (2.0 / n as f64).sqrt();
        assert!((var / mu - 1.0).abs() < 5.0 * sd_var, "mu {mu}: var {var}");
    }
}

#[test]
fn zero_means_and_exact_below_threshold() {
    let mut rng = Pcg64Mcg::new(7);
    let mut acc = [0u64; 3];
    add_aggregate_approx(&mut rng, &[0.0, 0.0, 0.0], 1000, 0.0, &mut acc);
    assert_eq!(acc, [0, 0, 0]);
    // infinite threshold: the same counts as the exact aggregate profile
    let lambda = [0.0, 0.3, 5.0, 80.0, 2e4];
    let (mut a, mut b) = ([0u64; 5], [0u64; 5]);
    for p in 0..20 {
        a.fill(0);
        b.fill(0);
        aggregate_approx_profile(&lambda, 11, p, 250, f64::INFINITY, &mut a);
        crate::sampling::aggregate_profile(&lambda, 11, p, 250, &mut b);
        assert_eq!(a, b);
    }
    // huge means convert to u64 without overflow
    let mut acc = [0u64; 2];
    add_aggregate_approx(&mut rng, &[1e18, 1e19], 1, 1.0, &mut acc);
    assert!((acc[0] as f64 / 1e18 - 1.0).abs() < 1e-6);
    assert!(acc[1] > 9_000_000_000_000_000_000);
}
