//! Calibrated per-bin intervals and multiple-testing checks for `validate`, so that
//! its verdicts keep their stated false-alarm rate at every size it accepts.
//!
//! **Why.** A per-bin z-score `(T − E T)/sd T` is outside its nominal 99 % interval with
//! probability 1 % only if `T` is normal. The sample variance `s²` of N counts of mean μ
//! is skewed and heavy-tailed at low counts (μ = 0.4, N = 1000: skewness 0.16); over
//! 1.3e6 such bins the excess of outside bins (1.02 % instead of 1 %) is many standard
//! deviations of the Binomial count. Likewise `x̄/s` is biased by O(1/N) at small N.
//!
//! **What.**
//! * [`sample_variance_shape`]: the skewness γ1 and excess kurtosis γ2 of `s²`, from
//!   the exact moments of `Y = (c − μ)²` under Poisson(μ) (a direct sum over the PMF for
//!   μ < 1000, the normal limit `Y/μ ~ χ²₁` above), with `s² ≈ mean of N Y`:
//!   γ1 = γ1(Y)/√N, γ2 = γ2(Y)/N (Kendall & Stuart, *Advanced Theory of Statistics*
//!   Vol. 1, §10.5; the replacement of μ by x̄ changes them by O(1/N)).
//! * [`outside_probability`]: the two-sided Edgeworth expansion of `P(|z| > z₀)` to order
//!   1/N, `2(1 − Φ(z₀)) + 2φ(z₀)[γ2·He₃(z₀)/24 + γ1²·He₅(z₀)/72]` (the γ1 term cancels
//!   between the tails; Hall 1992, *The Bootstrap and Edgeworth Expansion*, §2.2).
//!   [`EDGEWORTH_MAX_SKEWNESS`] bounds where it is trusted; beyond, a bin is not tested.
//! * [`snr_small_sample`]: for `x̄/s`, the normal-theory exact mean factor
//!   `E[σ/s] = √((N−1)/2)·Γ((N−2)/2)/Γ((N−1)/2)` and variance ratio (exact over delta
//!   method), applied to the model and to the delta-method variance.
//! * [`check`]: the count of outside bins against a Poisson law of mean `Σ p_i`
//!   (the Poisson–binomial law of independent bins, which the Poisson bounds from above
//!   in the upper tail: Hoeffding 1956), and `Σ z²` against a scaled χ² with the
//!   mean `K` and variance `Σ (2 + γ2,i)` (Satterthwaite 1946), at level
//!   [`CHECK_LEVEL`] each.

use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF, DiscreteCDF, Normal, Poisson};
use statrs::function::gamma::ln_gamma;

/// Level of each of the eight verdict checks (four statistics, two checks each): the
/// overall false-alarm rate is below 8 × 2.5e-4 = 2e-3.
pub const CHECK_LEVEL: f64 = 2.5e-4;
/// Per-bin nominal interval probability.
pub const BIN_INTERVAL: f64 = 0.99;
/// Largest skewness of a statistic for which its Edgeworth tail probability is used;
/// a bin whose statistic is more skewed than this is not tested.
pub const EDGEWORTH_MAX_SKEWNESS: f64 = 0.3;
/// Mean above which `Y = (c − μ)²` takes its normal-limit shape.
const NORMAL_LIMIT_MEAN: f64 = 1000.0;

/// The half-width of the nominal per-bin interval in units of sd (2.5758 for 99 %).
pub fn z_interval() -> f64 {
    Normal::standard().inverse_cdf(0.5 + BIN_INTERVAL / 2.0)
}

/// How a tested statistic is distributed under the model, for the checks.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Shape {
    /// Probability that |z| exceeds [`z_interval`] under the model.
    pub outside_probability: f64,
    /// Excess kurtosis of z (0 for a normal statistic).
    pub excess_kurtosis: f64,
}

impl Shape {
    /// A normal statistic.
    pub fn normal() -> Shape {
        Shape {
            outside_probability: 1.0 - BIN_INTERVAL,
            excess_kurtosis: 0.0,
        }
    }
}

/// Skewness and excess kurtosis of `Y = (c − μ)²` for c ~ Poisson(μ).
fn squared_deviation_shape(mu: f64) -> (f64, f64) {
    if mu >= NORMAL_LIMIT_MEAN {
        return (2.0 * std::f64::consts::SQRT_2, 12.0); // Y/μ ~ χ²₁
    }
    let sd = mu.sqrt();
    let lo = (mu - 15.0 * sd - 30.0).max(0.0) as u64;
    let hi = (mu + 15.0 * sd + 40.0) as u64;
    let ln_mu = mu.ln();
    let mut m = [0.0f64; 5]; // raw moments of Y, orders 0..4
    for k in lo..=hi {
        let p = (k as f64 * ln_mu - mu - ln_gamma(k as f64 + 1.0)).exp();
        let y = (k as f64 - mu).powi(2);
        let mut yj = 1.0;
        for mj in m.iter_mut() {
            *mj += p * yj;
            yj *= y;
        }
    }
    let mean = m[1] / m[0];
    let c2 = m[2] / m[0] - mean * mean;
    let c3 = m[3] / m[0] - 3.0 * mean * m[2] / m[0] + 2.0 * mean.powi(3);
    let c4 = m[4] / m[0] - 4.0 * mean * m[3] / m[0] + 6.0 * mean * mean * m[2] / m[0]
        - 3.0 * mean.powi(4);
    (c3 / c2.powf(1.5), c4 / (c2 * c2) - 3.0)
}

/// Skewness and excess kurtosis of the sample variance of `n` Poisson(μ) counts (see
/// the module docs; `poisson = false` — a mixed-Poisson count under pulse-energy jitter —
/// takes the normal-limit shape).
pub fn sample_variance_shape(mu: f64, n: f64, poisson: bool) -> (f64, f64) {
    let (g1, g2) = if poisson {
        squared_deviation_shape(mu)
    } else {
        (2.0 * std::f64::consts::SQRT_2, 12.0)
    };
    (g1 / n.sqrt(), g2 / n)
}

/// Two-sided Edgeworth tail `P(|z| > z₀)` for a standardized statistic of skewness `g1`
/// and excess kurtosis `g2`; `None` where the expansion is not trusted.
pub fn outside_probability(g1: f64, g2: f64) -> Option<Shape> {
    let trusted = g1.abs() <= EDGEWORTH_MAX_SKEWNESS && g2.abs() <= 2.0 * EDGEWORTH_MAX_SKEWNESS;
    if !trusted {
        return None; // also for NaN
    }
    let z = z_interval();
    let phi = (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let he3 = z.powi(3) - 3.0 * z;
    let he5 = z.powi(5) - 10.0 * z.powi(3) + 15.0 * z;
    let p = (1.0 - BIN_INTERVAL) + 2.0 * phi * (g2 * he3 / 24.0 + g1 * g1 * he5 / 72.0);
    Some(Shape {
        outside_probability: p.clamp(0.0, 1.0),
        excess_kurtosis: g2,
    })
}

/// Small-sample corrections of `x̄/s` over `n` draws for a model S/N `snr`
/// (normal theory): the factor on its mean, `E[σ/s]`, and the ratio of its exact
/// variance to the delta-method variance `(1 + snr²/2)/n`. `n` must exceed 3.
pub fn snr_small_sample(snr: f64, n: f64) -> (f64, f64) {
    let b =
        ((n - 1.0) / 2.0).sqrt() * (ln_gamma((n - 2.0) / 2.0) - ln_gamma((n - 1.0) / 2.0)).exp();
    let exact = (snr * snr + 1.0 / n) * (n - 1.0) / (n - 3.0) - snr * snr * b * b;
    let delta = (1.0 + 0.5 * snr * snr) / n;
    (b, (exact / delta).max(1.0))
}

/// One multiple-testing-aware verdict over the bins.
#[derive(Debug, Clone, Serialize)]
pub struct Check {
    /// Statistic name.
    pub statistic: String,
    /// Bins tested.
    pub bins_tested: usize,
    /// Bins outside their 99 % interval.
    pub outside: usize,
    /// Expected number outside, `Σ p_i`.
    pub outside_expected: f64,
    /// Largest `outside` consistent with the model at level [`CHECK_LEVEL`].
    pub outside_allowed: usize,
    /// `Σ z²` over the tested bins.
    pub chi_square: f64,
    /// Its p-value under the scaled χ² of the module docs.
    pub chi_square_p: f64,
    /// Both checks passed.
    pub pass: bool,
}

/// The two checks of one statistic, every bin normal (nominal 1 % outside).
pub fn check(name: &str, zs: &[f64]) -> Check {
    let shapes = vec![Shape::normal(); zs.len()];
    check_calibrated(name, zs, &shapes)
}

/// The two checks of one statistic with each bin's own [`Shape`].
pub fn check_calibrated(name: &str, zs: &[f64], shapes: &[Shape]) -> Check {
    let k = zs.len();
    let z0 = z_interval();
    let outside = zs.iter().filter(|z| z.abs() > z0).count();
    let expected: f64 = shapes.iter().map(|s| s.outside_probability).sum();
    let outside_allowed = match Poisson::new(expected) {
        Ok(p) => p.inverse_cdf(1.0 - CHECK_LEVEL) as usize,
        Err(_) => 0,
    };
    let chi_square: f64 = zs.iter().map(|z| z * z).sum::<f64>() + 0.0; // no -0.0
    let variance: f64 = shapes
        .iter()
        .map(|s| (2.0 + s.excess_kurtosis).max(0.5))
        .sum();
    let chi_square_p = if k == 0 {
        1.0
    } else if !chi_square.is_finite() {
        0.0
    } else {
        // a·χ²(ν) with mean a·ν = K and variance 2a²ν = Σ(2 + γ2)
        let a = variance / (2.0 * k as f64);
        ChiSquared::new(k as f64 / a)
            .map(|c| c.sf(chi_square / a))
            .unwrap_or(0.0)
    };
    Check {
        statistic: name.into(),
        bins_tested: k,
        outside,
        outside_expected: expected,
        outside_allowed,
        chi_square,
        chi_square_p,
        pass: outside <= outside_allowed && chi_square_p >= CHECK_LEVEL,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn squared_deviation_matches_its_limits() {
        // large μ: the χ²₁ shape
        let (g1, g2) = squared_deviation_shape(999.0);
        assert!(
            (g1 - 2.828).abs() < 0.05 && (g2 - 12.0).abs() < 0.5,
            "{g1} {g2}"
        );
        // μ = 0.4 by hand: Y ∈ {0.16, 0.36, 2.56, 6.76, ...}: strongly skewed
        let (g1, _) = squared_deviation_shape(0.4);
        assert!(g1 > 4.0, "{g1}");
    }

    #[test]
    fn edgeworth_reduces_to_the_normal_and_grows_with_kurtosis() {
        let p0 = outside_probability(0.0, 0.0).unwrap().outside_probability;
        assert!((p0 - 0.01).abs() < 1e-12);
        let p = outside_probability(0.1, 0.05).unwrap().outside_probability;
        assert!(p > 0.01 && p < 0.0105, "{p}");
        assert!(outside_probability(0.5, 0.0).is_none());
    }

    #[test]
    fn snr_corrections_vanish_for_large_samples() {
        let (b, r) = snr_small_sample(10.0, 1e6);
        assert!((b - 1.0).abs() < 1e-5 && (r - 1.0).abs() < 1e-3, "{b} {r}");
        let (b, r) = snr_small_sample(10.0, 30.0);
        // E[σ/s] ≈ 1 + 3/(4(N−1)) for moderate N
        assert!((b - (1.0 + 0.75 / 29.0)).abs() < 3e-3, "{b}");
        assert!(r > 1.0, "{r}");
    }

    #[test]
    fn the_count_check_follows_the_expected_outside_count() {
        let zs = vec![0.0; 1000];
        let c = check("x", &zs);
        assert!(c.pass && c.outside_allowed >= 10);
        let mut zs = vec![0.0; 1000];
        zs.iter_mut().take(30).for_each(|z| *z = 3.0);
        assert!(!check("x", &zs).pass);
    }
}
