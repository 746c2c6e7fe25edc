//! The mean statistic's law under the model, against sums written here from the Poisson
//! PMF, and the mean check's false-alarm rate and power on counts drawn by `rand_distr`.

use rand::SeedableRng;
use rand_distr::{Distribution, Gamma, Poisson as PoissonDraw};
use rand_pcg::Pcg64Mcg;

use super::BinModel;
use super::calibration::{CHECK_LEVEL, check_calibrated, z_interval};
use super::statistics::mean_z;

/// Poisson(μ) PMF over 0..=k_max by the recursion p(k) = p(k−1)·μ/k, from the mode in
/// log space so that large μ does not underflow.
fn poisson_pmf(mu: f64, k_max: u64) -> Vec<f64> {
    let mode = mu.floor() as u64;
    let ln_fact = |k: u64| (1..=k).map(|i| (i as f64).ln()).sum::<f64>();
    let p_mode = (mode as f64 * mu.ln() - mu - ln_fact(mode)).exp();
    let mut p = vec![0.0; k_max as usize + 1];
    p[mode as usize] = p_mode;
    for k in mode + 1..=k_max {
        p[k as usize] = p[k as usize - 1] * mu / k as f64;
    }
    for k in (0..mode).rev() {
        p[k as usize] = p[k as usize + 1] * (k + 1) as f64 / mu;
    }
    p
}

#[test]
fn the_mean_z_is_standardized_at_every_count_and_its_tail_is_exact() {
    let z0 = z_interval();
    for mu in [0.5_f64, 4.0, 40.0, 400.0, 3000.0, 20_000.5] {
        let k_max = (mu + 40.0 * mu.sqrt() + 40.0) as u64;
        let pmf = poisson_pmf(mu, k_max);
        let model = BinModel::new(0.0, mu, 1.0, 0.0);
        let (mut m2, mut m4, mut outside) = (0.0, 0.0, 0.0);
        let mut shape = None;
        for (t, p) in pmf.iter().enumerate() {
            let (z, s) = mean_z(t as u128, 1.0, &model);
            let z = z.unwrap();
            shape = s;
            m2 += p * z * z;
            m4 += p * z.powi(4);
            if z.abs() > z0 {
                outside += p;
            }
        }
        let shape = shape.expect("a Poisson bin has its own law");
        assert!((m2 - 1.0).abs() < 1e-9, "μ = {mu}: E z² = {m2}");
        assert!(
            (m4 - 3.0 - shape.excess_kurtosis).abs() < 1e-8 * m4,
            "μ = {mu}: E z⁴ = {m4}, shape kurtosis {}",
            shape.excess_kurtosis
        );
        assert!(
            (outside - shape.outside_probability).abs() < 1e-9,
            "μ = {mu}: P(|z| > z₀) = {outside}, shape says {}",
            shape.outside_probability
        );
    }
}

/// Totals of `bins` bins over Poisson means spread over 2..60 (faint bins, where a
/// discrete law departs most from the normal), drawn by `draw`; the mean check's verdict.
fn mean_check_passes(seed: u64, draw: impl Fn(f64, &mut Pcg64Mcg) -> f64) -> (bool, f64) {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let bins = 20_000;
    let (mut zs, mut shapes) = (Vec::new(), Vec::new());
    for i in 0..bins {
        let mu = 2.0 + 58.0 * i as f64 / bins as f64;
        let total = draw(mu, &mut rng) as u128;
        let (z, shape) = mean_z(total, 1.0, &BinModel::new(0.0, mu, 1.0, 0.0));
        zs.push(z.unwrap());
        shapes.push(shape.unwrap());
    }
    let c = check_calibrated("mean", &zs, &shapes);
    (c.pass, c.chi_square_p)
}

/// False-alarm rate: the check passes exact Poisson totals (each of its two parts at
/// level [`CHECK_LEVEL`] = 2.5e-4, so this fixed-seed test fails with probability below
/// 5e-4), and its Σz² p-value is not pushed to either end (not below 1e-3, not above
/// 0.999: a z from the exact test's two-sided p-value gives Σz² ≈ 0.85 K here, a p-value of 1).
/// Power: totals with 10 % more variance than Poisson (Gamma–Poisson) are rejected.
#[test]
fn the_mean_check_keeps_its_rate_and_rejects_a_ten_percent_variance_excess() {
    let poisson = |mu: f64, rng: &mut Pcg64Mcg| PoissonDraw::new(mu).unwrap().sample(rng);
    let (pass, p) = mean_check_passes(2025, poisson);
    assert!(
        pass && p > 1e-3 && p < 0.999,
        "exact Poisson totals: pass {pass}, p = {p}"
    );
    // Var = μ(1 + μ/k) = 1.1 μ with k = 10 μ: a Poisson law whose mean is Gamma(k, μ/k)
    let overdispersed = |mu: f64, rng: &mut Pcg64Mcg| {
        let lambda = Gamma::new(10.0 * mu, 0.1).unwrap().sample(rng);
        PoissonDraw::new(lambda).unwrap().sample(rng)
    };
    let (pass, p) = mean_check_passes(2025, overdispersed);
    assert!(
        !pass && p < CHECK_LEVEL,
        "10 % variance excess accepted: p = {p}"
    );
}

/// Power against a 1 % bias of the mean, at totals that resolve it (μ_T = 10⁶: the bias
/// is 10 standard deviations per bin).
#[test]
fn the_mean_check_rejects_a_one_percent_bias_at_large_totals() {
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    let mu = 1e6;
    let model = BinModel::new(0.0, mu, 1.0, 0.0);
    let (zs, shapes): (Vec<f64>, Vec<_>) = (0..200)
        .map(|_| {
            let total = PoissonDraw::new(1.01 * mu).unwrap().sample(&mut rng) as u128;
            let (z, shape) = mean_z(total, 1.0, &model);
            (z.unwrap(), shape.unwrap())
        })
        .unzip();
    assert!(!check_calibrated("mean", &zs, &shapes).pass);
}
