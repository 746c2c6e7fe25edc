//! Statistical tests of the simulator (issue 4, item 2). Each has a fixed seed and states
//! its false-alarm rate (the chance that a correct simulator fails it); the power tests
//! show the same statistics reject deliberately wrong samplers.

mod common;
use common::scenario;
use lidarsim::config::Method;
use lidarsim::sampling::{ShotSampler, poisson_u64, stream_rng};
use lidarsim::scenario::ExpectedProfile;
use lidarsim::simulate::{ResolvedMethod, StreamSampler};
use lidarsim::validate::{self, BinModel, RealizationSource, SimulatorSource, ValidateOptions};
use rand_distr::{Distribution, Gamma, StandardNormal};
use statrs::distribution::{ChiSquared, ContinuousCDF, Discrete, DiscreteCDF, Poisson};

/// Chi-square goodness of fit of integer samples to Poisson(λ), cells pooled so every
/// expected count is ≥ 5 (the upper tail is one cell). Returns the p-value.
fn poisson_gof_p(samples: &[u64], lambda: f64) -> f64 {
    let n = samples.len() as f64;
    let pois = Poisson::new(lambda).unwrap();
    let max = *samples.iter().max().unwrap_or(&0) as usize;
    let mut observed = vec![0f64; max + 2];
    for &s in samples {
        observed[s as usize] += 1.0;
    }
    // cells [k] while expected ≥ 5, then the tail
    let (mut chi2, mut cells, mut k) = (0.0, 0usize, 0usize);
    let (mut obs_acc, mut exp_acc) = (0.0, 0.0);
    loop {
        obs_acc += observed.get(k).copied().unwrap_or(0.0);
        exp_acc += n * pois.pmf(k as u64);
        let tail_exp = n * pois.sf(k as u64);
        if exp_acc >= 5.0 && tail_exp >= 5.0 {
            chi2 += (obs_acc - exp_acc).powi(2) / exp_acc;
            cells += 1;
            obs_acc = 0.0;
            exp_acc = 0.0;
        } else if tail_exp < 5.0 {
            let obs_tail = obs_acc + observed.iter().skip(k + 1).sum::<f64>();
            let exp_tail = exp_acc + tail_exp;
            chi2 += (obs_tail - exp_tail).powi(2) / exp_tail;
            cells += 1;
            break;
        }
        k += 1;
    }
    if cells < 2 {
        return 1.0;
    }
    ChiSquared::new((cells - 1) as f64).unwrap().sf(chi2)
}

/// Single-shot counts of `bins` identical bins of mean λ over `shots` shots.
fn single_shot_samples(lambda: &[f64], shots: usize, seed: u64) -> Vec<u64> {
    let sampler = ShotSampler::new(lambda);
    let mut rng = stream_rng(seed, 0, 0);
    let mut out = Vec::with_capacity(shots * lambda.len());
    let mut acc = vec![0u64; lambda.len()];
    for _ in 0..shots {
        acc.iter_mut().for_each(|a| *a = 0);
        sampler.add_shot(&mut rng, &mut acc);
        out.extend_from_slice(&acc);
    }
    out
}

/// Per-shot counts are Poisson for λ from 1e-4 to 100 (chi-square GOF, 10⁶ samples each).
/// False-alarm rate: 7 tests at p < 1e-4 each, < 7e-4 in all.
#[test]
fn per_shot_counts_are_poisson_from_1e_4_to_100() {
    for (k, lambda) in [1e-4, 1e-2, 0.15, 1.0, 10.0, 30.5, 100.0]
        .into_iter()
        .enumerate()
    {
        let samples = single_shot_samples(&vec![lambda; 1000], 1000, 40 + k as u64);
        let p = poisson_gof_p(&samples, lambda);
        assert!(p > 1e-4, "λ = {lambda}: p = {p}");
    }
}

/// Power: the same GOF test rejects the right sampler judged against a mean 1 % off
/// (λ = 10 and 100, 10⁶ samples: the expected χ² excess is ≫ the 1e-4 critical value).
#[test]
fn per_shot_gof_rejects_a_mean_off_by_one_percent() {
    for lambda in [10.0, 100.0] {
        let samples = single_shot_samples(&vec![lambda; 1000], 1000, 7);
        assert!(
            poisson_gof_p(&samples, lambda * 1.01) < 1e-4,
            "λ = {lambda}"
        );
    }
}

fn validate_paper(n: usize, radiance: &str, method: Method) -> validate::Report {
    let sc = common::lidar(
        &format!("paper/scenario{n}.toml"),
        &[&format!("background.radiance={radiance}")],
    );
    let opts = ValidateOptions {
        realizations: 1000,
        method: Some(method),
        seed: Some(99),
        json: None,
    };
    validate::run(&sc, &opts).unwrap()
}

/// Accumulated profiles of scenarios 1 and 4, day and night, both methods: mean, variance
/// (dispersion index 1) and Eq. 4 S/N agree with the model. False-alarm rate: < 2e-3 per
/// validation (see `validate`), 8 validations: < 1.6e-2 in all (fixed seed: it passes).
#[test]
fn paper_scenarios_1_and_4_day_and_night_are_consistent() {
    for n in [1, 4] {
        for radiance in ["1.1e10", "1.1e15"] {
            for method in [Method::Aggregate, Method::Shot] {
                let r = validate_paper(n, radiance, method);
                assert!(
                    r.consistent,
                    "scenario {n}, {radiance}, {method:?}: {:#?}",
                    r.checks
                );
                // the dispersion index (variance/mean) is 1 within its sampling noise
                let di: Vec<f64> = r
                    .bins
                    .iter()
                    .filter(|b| b.variance.z.is_some())
                    .map(|b| b.variance.empirical / b.mean.empirical)
                    .collect();
                let mean_di = di.iter().sum::<f64>() / di.len() as f64;
                assert!(
                    (mean_di - 1.0).abs() < 0.02,
                    "mean dispersion index {mean_di}"
                );
            }
        }
    }
}

/// A deliberately wrong source: draws each bin from a transformed law.
struct Wrong<F: Fn(&mut rand_pcg::Pcg64Mcg, f64) -> u64 + Sync> {
    means: Vec<f64>,
    draw: F,
}

impl<F: Fn(&mut rand_pcg::Pcg64Mcg, f64) -> u64 + Sync> RealizationSource for Wrong<F> {
    fn draw(&self, p: u64, counts: &mut [u64]) {
        let mut rng = stream_rng(5, p, 0);
        for (c, &m) in counts.iter_mut().zip(&self.means) {
            *c = (self.draw)(&mut rng, m);
        }
    }
}

fn scenario1_model() -> (ExpectedProfile, Vec<BinModel>, u64) {
    let sc = scenario("paper/scenario1.toml", &[]);
    let e = sc.expected().unwrap();
    let shots = sc.shots_per_profile();
    let models = validate::bin_models(&e, shots, 0.0);
    (e, models, shots)
}

fn verdict(
    source: &dyn RealizationSource,
    e: &ExpectedProfile,
    models: &[BinModel],
) -> Vec<(String, bool)> {
    let (_, checks) = validate::validate_source(
        source,
        models,
        &e.altitude_m,
        1000,
        &e.background_bin_indices,
    );
    checks.into_iter().map(|c| (c.statistic, c.pass)).collect()
}

/// Power of `validate`: a mean 1 % high, a variance 10 % high (negative binomial with the
/// right mean) and correlated shots (every shot of a profile shares a 2 % energy
/// fluctuation) are each rejected; the exact sampler under the same seed passes (the
/// control's false-alarm rate: `validate`'s, < 2e-3).
#[test]
fn validate_rejects_deliberately_wrong_samplers() {
    let (e, models, shots) = scenario1_model();
    let means: Vec<f64> = models.iter().map(|m| m.cumulants[0]).collect();
    let background = shots as f64 * (e.background + e.dark);
    let failed = |v: Vec<(String, bool)>| {
        v.into_iter()
            .filter(|(_, pass)| !pass)
            .map(|(s, _)| s)
            .collect::<Vec<_>>()
    };

    let right = Wrong {
        means: means.clone(),
        draw: |r: &mut rand_pcg::Pcg64Mcg, m: f64| poisson_u64(r, m),
    };
    assert!(failed(verdict(&right, &e, &models)).is_empty(), "control");

    let mean_high = Wrong {
        means: means.clone(),
        draw: |r: &mut rand_pcg::Pcg64Mcg, m: f64| poisson_u64(r, 1.01 * m),
    };
    assert!(failed(verdict(&mean_high, &e, &models)).contains(&"mean".to_string()));

    // Poisson(m·G), G ~ Gamma(k, 1/k) with m/k = 0.1: variance 1.1·m, mean m
    let var_high = Wrong {
        means: means.clone(),
        draw: |r: &mut rand_pcg::Pcg64Mcg, m: f64| {
            if m <= 0.0 {
                return 0;
            }
            let k = 10.0 * m;
            let g = Gamma::new(k, 1.0 / k).unwrap().sample(r);
            poisson_u64(r, m * g)
        },
    };
    assert!(failed(verdict(&var_high, &e, &models)).contains(&"variance".to_string()));

    // correlated shots: one energy factor per profile, shared by all its shots and bins
    struct Correlated(Vec<f64>, Vec<f64>);
    impl RealizationSource for Correlated {
        fn draw(&self, p: u64, counts: &mut [u64]) {
            let mut rng = stream_rng(6, p, 0);
            let g: f64 = StandardNormal.sample(&mut rng);
            let f = 1.0 + 0.02 * g;
            for ((c, &s), &r) in counts.iter_mut().zip(&self.0).zip(&self.1) {
                *c = poisson_u64(&mut rng, f * s + r);
            }
        }
    }
    let signal: Vec<f64> = e.signal.iter().map(|s| s * shots as f64).collect();
    let rest = vec![background; signal.len()];
    let bad = failed(verdict(&Correlated(signal, rest), &e, &models));
    assert!(bad.contains(&"variance".to_string()), "{bad:?}");
}

/// `shot` and `aggregate` give the same distribution: per bin, two-sample z-tests of the
/// means and variances of 1000 profiles each (scenario 4, day), combined by the same
/// multiple-testing-aware checks as `validate` (false-alarm rate < 1e-3). Power: the
/// mean statistic tells shot draws from draws of 1.01·λ, the variance statistic from
/// draws whose variance is 10 % high.
#[test]
fn shot_and_aggregate_have_the_same_law() {
    let sc = scenario("paper/scenario4.toml", &["background.radiance=1.1e15"]);
    let e = sc.expected().unwrap();
    let shots = sc.shots_per_profile();
    let rest = vec![e.background + e.dark; e.n_bins()];
    let draws = |method: ResolvedMethod, seed: u64| -> Vec<Vec<u64>> {
        let s = StreamSampler::new(method, &e.signal, &rest, 0.0);
        (0..1000u64)
            .map(|p| {
                let mut acc = vec![0u64; e.n_bins()];
                s.profile_counts(seed, p, shots, &mut acc);
                acc
            })
            .collect()
    };
    let (a, b) = (
        draws(ResolvedMethod::Shot, 1),
        draws(ResolvedMethod::Aggregate, 2),
    );
    let moments = |x: &[Vec<u64>], i: usize| {
        let n = x.len() as f64;
        let m = x.iter().map(|r| r[i] as f64).sum::<f64>() / n;
        let v = x.iter().map(|r| (r[i] as f64 - m).powi(2)).sum::<f64>() / (n - 1.0);
        (m, v)
    };
    let n = 1000.0;
    let (mut zm, mut zv) = (vec![], vec![]);
    for i in 0..e.n_bins() {
        let ((ma, va), (mb, vb)) = (moments(&a, i), moments(&b, i));
        let mu = (ma + mb) / 2.0;
        if mu * n < 100.0 {
            continue;
        }
        zm.push((ma - mb) / ((va + vb) / n).sqrt());
        // Var(s²) for Poisson(μ): (μ + 2μ²)/n
        zv.push((va - vb) / (2.0 * (mu + 2.0 * mu * mu) / n).sqrt());
    }
    let (cm, cv) = (
        validate::check("mean", &zm),
        validate::check("variance", &zv),
    );
    assert!(cm.pass && cv.pass, "{cm:?} {cv:?}");
    // power: the same statistic tells shot draws from draws of 1.01·λ
    let rest_hi = vec![1.01 * (e.background + e.dark); e.n_bins()];
    let sig_hi: Vec<f64> = e.signal.iter().map(|s| 1.01 * s).collect();
    let hi = StreamSampler::new(ResolvedMethod::Aggregate, &sig_hi, &rest_hi, 0.0);
    let c: Vec<Vec<u64>> = (0..1000u64)
        .map(|p| {
            let mut acc = vec![0u64; e.n_bins()];
            hi.profile_counts(3, p, shots, &mut acc);
            acc
        })
        .collect();
    let zh: Vec<f64> = (0..e.n_bins())
        .map(|i| {
            let ((ma, va), (mb, vb)) = (moments(&a, i), moments(&c, i));
            (ma - mb) / ((va + vb) / n).sqrt()
        })
        .collect();
    assert!(!validate::check("mean", &zh).pass);
    // and the variance statistic tells shot draws from draws whose variance is 10 % high
    // (Poisson of a gamma-distributed mean m·G, Var = m + 0.1·m: shape k = 10·m)
    let wide: Vec<Vec<u64>> = (0..1000u64)
        .map(|p| {
            let mut rng = stream_rng(4, p, 0);
            (0..e.n_bins())
                .map(|i| {
                    let m = shots as f64 * (e.signal[i] + e.background + e.dark);
                    let k = 10.0 * m;
                    let g = Gamma::new(k, 1.0 / k).unwrap().sample(&mut rng);
                    poisson_u64(&mut rng, m * g)
                })
                .collect()
        })
        .collect();
    let zw: Vec<f64> = (0..e.n_bins())
        .filter_map(|i| {
            let ((ma, va), (mb, vb)) = (moments(&a, i), moments(&wide, i));
            let mu = (ma + mb) / 2.0;
            (mu * n >= 100.0).then(|| (va - vb) / (2.0 * (mu + 2.0 * mu * mu) / n).sqrt())
        })
        .collect();
    assert!(!validate::check("variance", &zw).pass);
}

/// The simulator source under jitter: validate uses the mixed-Poisson model and passes;
/// the plain-Poisson model (no jitter term) is rejected on the variance.
#[test]
fn jitter_is_validated_against_its_own_model() {
    let sc = scenario(
        "paper/scenario4.toml",
        &["instrument.pulse_energy_jitter=0.05"],
    );
    let e = sc.expected().unwrap();
    let shots = sc.shots_per_profile();
    let source = SimulatorSource::new(&e, ResolvedMethod::Shot, 0.05, 11, shots);
    let right = validate::bin_models(&e, shots, 0.05);
    let (_, checks) = validate::validate_source(
        &source,
        &right,
        &e.altitude_m,
        1000,
        &e.background_bin_indices,
    );
    assert!(checks.iter().all(|c| c.pass), "{checks:#?}");
    let poisson = validate::bin_models(&e, shots, 0.0);
    let (_, checks) = validate::validate_source(
        &source,
        &poisson,
        &e.altitude_m,
        1000,
        &e.background_bin_indices,
    );
    assert!(checks.iter().any(|c| c.statistic == "variance" && !c.pass));
}
