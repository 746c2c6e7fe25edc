//! Statistical validation of the Monte Carlo against the model (`lidarsim validate`).
//!
//! N independent profiles are drawn exactly as `simulate` draws them (same samplers,
//! seed and profile indices: `simulate --seed S --profiles N` writes the very counts
//! validated here). Per bin, four statistics are compared with their model values,
//! each turned into a z-score from its sampling distribution:
//!
//! * **mean** of the accumulated counts against `κ1 = M(λ_sig+λ_bkg+λ_dc)`: exact
//!   Poisson test on the total `Σ_p c_p ~ Poisson(N·κ1)` when shots are identical
//!   (two-sided p converted to a z-score), normal otherwise;
//! * **variance** (unbiased sample variance s²) against `κ2` (= κ1 for Poisson), with
//!   `Var(s²) = μ4/N − κ2²(N−3)/(N(N−1))`;
//! * **S/N with the background known** (paper Eq. 4): `x = c − M(λ_bkg+λ_dc)`,
//!   `SNR̂ = x̄/s_x` against `M·λ_sig/sqrt(κ2)`, with the delta-method variance
//!   `Var(SNR̂) ≈ [1 + m²(μ4−μ2²)/(4μ2³) − m·μ3/μ2²]/N`;
//! * **S/N with the background estimated** from `n_b` signal-free bins drawn in the
//!   same profile (model.md §2): `y = c − b̂`, model `M·λ_sig/sqrt(κ2 + M(λ_bkg+λ_dc)/n_b)`,
//!   same delta method with the cumulants of `y`.
//!
//! The cumulants of the accumulated count are those of a (mixed) Poisson: with
//! pulse-energy jitter σ, `κ1 = M(s+r)`, `κ2 = M(s+r+σ²s²)`, `κ3 = M(s+r+3σ²s²)`,
//! `κ4 = M(s+r+7σ²s²)` (s signal, r background + dark per shot; Stirling numbers of
//! the second kind on the cumulants of the shot's mean).
//!
//! **Verdict.** A statistic is tested in the bins where its approximation holds
//! (mean: every bin with κ1 > 0 — bins with κ1 = 0 must hold only zeros; the others:
//! `N·κ1 ≥ 100` and, for S/N, a model S/N ≥ 0.1). For each statistic two
//! multiple-testing-aware checks at level α = 2.5·10⁻⁴ each: the number of bins outside
//! their 99 % interval against its Binomial(K, 0.01) law, and `Σ z²` against χ²(K).
//! Eight checks at 2.5·10⁻⁴ give an overall false-alarm rate below 2·10⁻³.

use std::io::Write;
use std::path::PathBuf;

use rayon::prelude::*;
use serde::Serialize;
use statrs::distribution::{Binomial, ChiSquared, ContinuousCDF, DiscreteCDF, Normal, Poisson};

use crate::config::Method;
use crate::error::{Error, Result};
use crate::sampling::{self, poisson_u64, stream_rng};
use crate::scenario::{ExpectedProfile, Scenario};
use crate::simulate::{self, ResolvedMethod, StreamSampler};

/// Level of each of the eight verdict checks.
pub const CHECK_LEVEL: f64 = 2.5e-4;
/// Per-bin interval probability.
pub const BIN_INTERVAL: f64 = 0.99;
/// Smallest expected total count `N·κ1` for the variance and S/N tests.
pub const MIN_TOTAL_COUNTS: f64 = 100.0;
/// Smallest model S/N for the S/N tests.
pub const MIN_SNR: f64 = 0.1;
/// Seed offset of the background-estimation bins' stream.
const BACKGROUND_STREAM_SEED: u64 = 0x5EED_BAC6_0000_0001;

/// The model moments of one bin's accumulated count.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct BinModel {
    /// Expected signal per profile `M·λ_sig`.
    pub signal: f64,
    /// Expected background + dark per profile `M·(λ_bkg+λ_dc)`.
    pub rest: f64,
    /// Cumulants κ1..κ4 of the accumulated count.
    pub cumulants: [f64; 4],
}

impl BinModel {
    /// Mixed-Poisson cumulants for `shots` shots with signal `s`, rest `r` per shot and
    /// relative energy jitter `jitter`.
    pub fn new(s: f64, r: f64, shots: f64, jitter: f64) -> Self {
        let k1 = s + r;
        let v = jitter * jitter * s * s;
        BinModel {
            signal: shots * s,
            rest: shots * r,
            cumulants: [
                shots * k1,
                shots * (k1 + v),
                shots * (k1 + 3.0 * v),
                shots * (k1 + 7.0 * v),
            ],
        }
    }
}

/// Central moments (μ2, μ3, μ4) from cumulants (κ2, κ3, κ4).
fn central_moments(k2: f64, k3: f64, k4: f64) -> (f64, f64, f64) {
    (k2, k3, k4 + 3.0 * k2 * k2)
}

/// Delta-method standard error of `x̄/s_x` over `n` draws of a variable with mean `m`
/// and central moments μ2, μ3, μ4.
pub fn snr_standard_error(m: f64, mu2: f64, mu3: f64, mu4: f64, n: f64) -> f64 {
    let v = (1.0 + m * m * (mu4 - mu2 * mu2) / (4.0 * mu2.powi(3)) - m * mu3 / (mu2 * mu2)) / n;
    v.max(0.0).sqrt()
}

/// Streaming sums of one bin over the realizations.
#[derive(Debug, Clone, Default)]
struct BinSums {
    total: u128,
    x: Welford,
    y: Welford,
}

/// Welford's running mean and variance (numerically stable for counts up to 1e15).
#[derive(Debug, Clone, Copy, Default)]
struct Welford {
    n: f64,
    mean: f64,
    m2: f64,
}

impl Welford {
    fn push(&mut self, v: f64) {
        self.n += 1.0;
        let d = v - self.mean;
        self.mean += d / self.n;
        self.m2 += d * (v - self.mean);
    }
    fn variance(&self) -> f64 {
        if self.n > 1.0 {
            self.m2 / (self.n - 1.0)
        } else {
            0.0
        }
    }
}

/// The result of one statistic in one bin.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Stat {
    /// Empirical value.
    pub empirical: f64,
    /// Model value.
    pub model: f64,
    /// z-score from the statistic's sampling distribution (None: not tested here).
    pub z: Option<f64>,
}

/// Everything measured in one bin.
#[derive(Debug, Clone, Serialize)]
pub struct BinReport {
    /// Bin index.
    pub bin: usize,
    /// Bin-centre altitude, m.
    pub altitude_m: f64,
    /// Mean accumulated count.
    pub mean: Stat,
    /// Variance of the accumulated count.
    pub variance: Stat,
    /// S/N with the background known (Eq. 4).
    pub snr_known_background: Stat,
    /// S/N with the background estimated from `n_b` bins.
    pub snr_estimated_background: Stat,
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
    /// Largest `outside` consistent with Binomial(K, 0.01) at level [`CHECK_LEVEL`].
    pub outside_allowed: usize,
    /// `Σ z²` over the tested bins.
    pub chi_square: f64,
    /// Its p-value under χ²(K).
    pub chi_square_p: f64,
    /// Both checks passed.
    pub pass: bool,
}

/// The whole validation.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Scenario name.
    pub scenario: String,
    /// Method used.
    pub method: String,
    /// Seed.
    pub seed: u64,
    /// Realizations (profiles) drawn.
    pub realizations: usize,
    /// Shots per profile.
    pub shots_per_profile: u64,
    /// Signal-free bins used to estimate the background.
    pub background_bins: usize,
    /// Per-bin results.
    pub bins: Vec<BinReport>,
    /// Verdicts per statistic.
    pub checks: Vec<Check>,
    /// Whether every check passed.
    pub consistent: bool,
}

/// A source of realizations: per profile index, the window's counts and `n_b`
/// background-bin counts. `validate` uses the simulator's samplers; tests feed
/// deliberately wrong ones.
pub trait RealizationSource: Sync {
    /// Counts of realization `p` into `counts` (zeroed) and `background` (zeroed).
    fn draw(&self, p: u64, counts: &mut [u64], background: &mut [u64]);
}

/// The simulator's own realizations (what `simulate` writes for the same seed).
pub struct SimulatorSource {
    sampler: StreamSampler,
    seed: u64,
    shots: u64,
    background_mean: f64,
}

impl SimulatorSource {
    /// The sampler of `method` for the expectations `e`, pulse-energy `jitter`.
    pub fn new(
        e: &ExpectedProfile,
        method: ResolvedMethod,
        jitter: f64,
        seed: u64,
        shots: u64,
    ) -> Self {
        let rest = vec![e.background + e.dark; e.n_bins()];
        SimulatorSource {
            sampler: StreamSampler::new(method, &e.signal, &rest, jitter),
            seed,
            shots,
            background_mean: shots as f64 * (e.background + e.dark),
        }
    }
}

impl RealizationSource for SimulatorSource {
    fn draw(&self, p: u64, counts: &mut [u64], background: &mut [u64]) {
        self.sampler
            .profile_counts(self.seed, p, self.shots, counts);
        let mut rng = stream_rng(
            self.seed ^ BACKGROUND_STREAM_SEED,
            p,
            sampling::AGGREGATE_STREAM,
        );
        for b in background.iter_mut() {
            *b = poisson_u64(&mut rng, self.background_mean);
        }
    }
}

/// Draws `n` realizations from `source` and accumulates the per-bin sums (in a fixed
/// order: the result does not depend on the thread count).
fn accumulate(source: &dyn RealizationSource, n: usize, bins: usize, n_b: usize) -> Vec<BinSums> {
    let mut sums = vec![BinSums::default(); bins];
    let batch = ((8 << 20) / (bins + n_b).max(1)).clamp(1, 4096);
    for first in (0..n).step_by(batch) {
        let last = (first + batch).min(n);
        let drawn: Vec<(Vec<u64>, f64)> = (first..last)
            .into_par_iter()
            .map(|p| {
                let mut c = vec![0u64; bins];
                let mut b = vec![0u64; n_b];
                source.draw(p as u64, &mut c, &mut b);
                let b_hat = if n_b > 0 {
                    b.iter().sum::<u64>() as f64 / n_b as f64
                } else {
                    0.0
                };
                (c, b_hat)
            })
            .collect();
        for (c, b_hat) in &drawn {
            for (s, &v) in sums.iter_mut().zip(c) {
                s.total += u128::from(v);
                s.x.push(v as f64);
                s.y.push(v as f64 - b_hat);
            }
        }
    }
    sums
}

fn z_from_two_sided_p(p: f64, sign: f64) -> f64 {
    let std = Normal::standard();
    let p = p.clamp(1e-300, 1.0);
    sign * std.inverse_cdf(1.0 - p / 2.0).max(0.0)
}

/// The mean's z-score: exact Poisson test when the count is Poisson (κ2 = κ1).
fn mean_z(total: u128, n: f64, m: &BinModel) -> Option<f64> {
    let [k1, k2, ..] = m.cumulants;
    if k1 <= 0.0 {
        return (total > 0).then_some(f64::INFINITY);
    }
    let mean = total as f64 / n;
    if (k2 - k1).abs() <= 1e-12 * k1 {
        let pois = Poisson::new(n * k1).ok()?;
        let t = total.min(u128::from(u64::MAX)) as u64;
        let lower = pois.cdf(t);
        let upper = if t == 0 { 1.0 } else { pois.sf(t - 1) };
        let p = (2.0 * lower.min(upper)).min(1.0);
        Some(z_from_two_sided_p(p, (mean - k1).signum()))
    } else {
        Some((mean - k1) / (k2 / n).sqrt())
    }
}

/// Compares the accumulated sums with the model, bin by bin.
fn bin_reports(
    sums: &[BinSums],
    models: &[BinModel],
    altitudes: &[f64],
    n: usize,
    n_b: usize,
) -> Vec<BinReport> {
    let nf = n as f64;
    sums.iter()
        .zip(models)
        .enumerate()
        .map(|(i, (s, m))| {
            let [k1, k2, k3, k4] = m.cumulants;
            let enough = nf * k1 >= MIN_TOTAL_COUNTS;
            let mean = Stat {
                empirical: s.total as f64 / nf,
                model: k1,
                z: mean_z(s.total, nf, m),
            };
            let (mu2, mu3, mu4) = central_moments(k2, k3, k4);
            let var_s2 = mu4 / nf - k2 * k2 * (nf - 3.0) / (nf * (nf - 1.0));
            let variance = Stat {
                empirical: s.x.variance(),
                model: k2,
                z: (enough && var_s2 > 0.0).then(|| (s.x.variance() - k2) / var_s2.sqrt()),
            };
            let snr_stat = |w: &Welford, offset: f64, mu2: f64, mu3: f64, mu4: f64| {
                let model = if mu2 > 0.0 {
                    m.signal / mu2.sqrt()
                } else {
                    0.0
                };
                let sd = w.variance().sqrt();
                let empirical = if sd > 0.0 {
                    (w.mean - offset) / sd
                } else {
                    0.0
                };
                let se = snr_standard_error(m.signal, mu2, mu3, mu4, nf);
                Stat {
                    empirical,
                    model,
                    z: (enough && model >= MIN_SNR && se > 0.0).then(|| (empirical - model) / se),
                }
            };
            let snr_known = snr_stat(&s.x, m.rest, mu2, mu3, mu4);
            // y = c − b̂: cumulants of c plus (−1)^n those of b̂ (mean of n_b Poisson(rest))
            let snr_est = if n_b > 0 {
                let nb = n_b as f64;
                let (b2, b3, b4) = (m.rest / nb, -m.rest / (nb * nb), m.rest / (nb * nb * nb));
                let (y2, y3, y4) = central_moments(k2 + b2, k3 + b3, k4 + b4);
                snr_stat(&s.y, 0.0, y2, y3, y4)
            } else {
                Stat {
                    empirical: f64::NAN,
                    model: f64::NAN,
                    z: None,
                }
            };
            BinReport {
                bin: i,
                altitude_m: altitudes[i],
                mean,
                variance,
                snr_known_background: snr_known,
                snr_estimated_background: snr_est,
            }
        })
        .collect()
}

/// The two multiple-testing-aware checks of one statistic.
pub fn check(name: &str, zs: &[f64]) -> Check {
    let k = zs.len();
    let z99 = Normal::standard().inverse_cdf(0.5 + BIN_INTERVAL / 2.0);
    let outside = zs.iter().filter(|z| z.abs() > z99).count();
    let outside_allowed = match Binomial::new(1.0 - BIN_INTERVAL, k as u64) {
        Ok(b) => (0..=k as u64)
            .find(|&q| b.sf(q) <= CHECK_LEVEL)
            .unwrap_or(k as u64) as usize,
        Err(_) => k,
    };
    let chi_square: f64 = zs.iter().map(|z| z * z).sum();
    let chi_square_p = if k == 0 {
        1.0
    } else if !chi_square.is_finite() {
        0.0
    } else {
        ChiSquared::new(k as f64)
            .map(|c| c.sf(chi_square))
            .unwrap_or(0.0)
    };
    Check {
        statistic: name.into(),
        bins_tested: k,
        outside,
        outside_allowed,
        chi_square,
        chi_square_p,
        pass: outside <= outside_allowed && chi_square_p >= CHECK_LEVEL,
    }
}

/// The per-bin models of a scenario's expectations.
pub fn bin_models(e: &ExpectedProfile, shots: u64, jitter: f64) -> Vec<BinModel> {
    e.signal
        .iter()
        .map(|&s| BinModel::new(s, e.background + e.dark, shots as f64, jitter))
        .collect()
}

/// Validates `source` against `models`: the core of `lidarsim validate`, open to any sampler.
pub fn validate_source(
    source: &dyn RealizationSource,
    models: &[BinModel],
    altitudes: &[f64],
    realizations: usize,
    background_bins: usize,
) -> (Vec<BinReport>, Vec<Check>) {
    let sums = accumulate(source, realizations, models.len(), background_bins);
    let bins = bin_reports(&sums, models, altitudes, realizations, background_bins);
    let collect =
        |f: fn(&BinReport) -> Option<f64>| bins.iter().filter_map(f).collect::<Vec<f64>>();
    let checks = vec![
        check("mean", &collect(|b| b.mean.z)),
        check("variance", &collect(|b| b.variance.z)),
        check(
            "snr_known_background",
            &collect(|b| b.snr_known_background.z),
        ),
        check(
            "snr_estimated_background",
            &collect(|b| b.snr_estimated_background.z),
        ),
    ];
    (bins, checks)
}

/// Options of `lidarsim validate`.
#[derive(Debug, Clone)]
pub struct ValidateOptions {
    /// Profiles to draw.
    pub realizations: usize,
    /// Method (`simulation.method` when None).
    pub method: Option<Method>,
    /// Seed (`simulation.seed` when None).
    pub seed: Option<u64>,
    /// Write the full report as JSON.
    pub json: Option<PathBuf>,
}

/// Runs the validation of a scenario.
pub fn run(sc: &Scenario, opts: &ValidateOptions) -> Result<Report> {
    if opts.realizations < 10 {
        return Err(Error::Unsupported(
            "--realizations must be at least 10".into(),
        ));
    }
    let cfg = &sc.loaded.config;
    let seed = opts.seed.unwrap_or(cfg.simulation.seed);
    let method = simulate::resolve_method(opts.method.unwrap_or(cfg.simulation.method), sc)?;
    let e = sc.expected()?;
    let shots = sc.shots_per_profile();
    let jitter = sc.instrument.pulse_energy_jitter;
    let source = SimulatorSource::new(&e, method, jitter, seed, shots);
    let models = bin_models(&e, shots, jitter);
    let (bins, checks) = validate_source(
        &source,
        &models,
        &e.altitude_m,
        opts.realizations,
        e.background_bins,
    );
    let consistent = checks.iter().all(|c| c.pass);
    Ok(Report {
        scenario: cfg.name.clone(),
        method: method.name().into(),
        seed,
        realizations: opts.realizations,
        shots_per_profile: shots,
        background_bins: e.background_bins,
        bins,
        checks,
        consistent,
    })
}

/// A table for a person: the verdicts, then the bins that fell outside their interval.
pub fn write_table(w: &mut dyn Write, r: &Report) -> std::io::Result<()> {
    writeln!(
        w,
        "{} — {} realizations of {} shots, method {}, seed {}, {} background bins",
        r.scenario, r.realizations, r.shots_per_profile, r.method, r.seed, r.background_bins
    )?;
    writeln!(w)?;
    writeln!(
        w,
        "{:<26} {:>6} {:>8} {:>8} {:>12} {:>10}  verdict",
        "statistic", "bins", "outside", "allowed", "sum z^2", "p"
    )?;
    for c in &r.checks {
        writeln!(
            w,
            "{:<26} {:>6} {:>8} {:>8} {:>12.1} {:>10.3e}  {}",
            c.statistic,
            c.bins_tested,
            c.outside,
            c.outside_allowed,
            c.chi_square,
            c.chi_square_p,
            if c.pass { "ok" } else { "INCONSISTENT" }
        )?;
    }
    writeln!(w)?;
    writeln!(
        w,
        "{:>9} {:>12} {:>12} {:>8} {:>12} {:>8} {:>9} {:>9} {:>7}",
        "alt (km)", "mean", "model", "z", "variance", "z", "S/N", "Eq. 4", "z"
    )?;
    let z = |s: &Stat| {
        s.z.map(|z| format!("{z:8.2}"))
            .unwrap_or_else(|| format!("{:>8}", "-"))
    };
    let step = (r.bins.len() / 40).max(1);
    for b in r.bins.iter().step_by(step) {
        writeln!(
            w,
            "{:9.3} {:12.5e} {:12.5e} {} {:12.5e} {} {:9.3} {:9.3} {}",
            b.altitude_m / 1e3,
            b.mean.empirical,
            b.mean.model,
            z(&b.mean),
            b.variance.empirical,
            z(&b.variance),
            b.snr_known_background.empirical,
            b.snr_known_background.model,
            z(&b.snr_known_background)
        )?;
    }
    if step > 1 {
        writeln!(w, "(every {step}th bin shown; --json has all)")?;
    }
    writeln!(w)?;
    writeln!(
        w,
        "{}",
        if r.consistent {
            "CONSISTENT: the simulated counts agree with the Poisson model and Eq. 4."
        } else {
            "INCONSISTENT: at least one statistic departs from the model (false-alarm rate < 2e-3)."
        }
    )
}
