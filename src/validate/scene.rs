//! `validate` for a scene that changes along the track (segments, broken cloud, a solar
//! background): every profile has its own law, so the statistics compare each profile's
//! counts with its own expectation μ_p (`simulate`'s per-profile truth:
//! `M·(expected_signal + expected_background + expected_dark)`), and the S/N (defined for
//! identical profiles) is not tested.
//!
//! Per bin, over N profiles (an ideal detector without jitter: counts are Poisson(μ_p)):
//!
//! * **mean**: the total `Σ_p c_p ~ Poisson(Σ_p μ_p)`, an exact two-sided test;
//! * **variance**: `V = Σ_p (c_p − μ_p)²` against `E[V] = Σμ_p`, with the exact
//!   cumulants of `Y = (c − μ)²` for a Poisson count (from its central moments
//!   μ2 = μ, μ4 = μ + 3μ², μ6 = μ + 25μ² + 15μ³, μ8 = μ + 119μ² + 490μ³ + 105μ⁴):
//!   `Var Y = μ + 2μ²`, `κ3(Y) = μ + 22μ² + 8μ³`, `κ4(Y) = μ + 112μ² + 384μ³ + 48μ⁴`,
//!   summed over the profiles and turned into an Edgeworth-calibrated interval
//!   ([`super::calibration`]) where `ΣE[c] ≥ 100`.
//!
//! The verdicts are those of [`super::bins::validate_channels`]: per statistic the outside
//! count and Σz², each at level 2.5·10⁻⁴.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::calibration;
use super::calibration::Check;
use super::exact::ExactSum;
use super::model::BinModel;
use super::report::{BinReport, Stat};
use super::statistics::{MIN_TOTAL_COUNTS, mean_z, verdicts};

/// Per-bin sums over the profiles: the count's exactly, the floating-point ones in
/// [`ExactSum`]s, so that sums over shards add up to the single run's bit for bit.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Sums {
    /// Σc.
    #[serde(with = "super::exact::decimal")]
    total: u128,
    /// Σμ.
    mu: ExactSum,
    /// Σ(c − μ)².
    v: ExactSum,
    /// Σ Var Y.
    var: ExactSum,
    /// Σ κ3(Y).
    k3: ExactSum,
    /// Σ κ4(Y).
    k4: ExactSum,
}

impl Sums {
    fn push(&mut self, c: u64, mu: f64) {
        let d = c as f64 - mu;
        self.total += u128::from(c);
        self.mu.add(mu);
        self.v.add(d * d);
        self.var.add(mu + 2.0 * mu * mu);
        self.k3.add(mu + 22.0 * mu * mu + 8.0 * mu.powi(3));
        self.k4
            .add(mu + 112.0 * mu * mu + 384.0 * mu.powi(3) + 48.0 * mu.powi(4));
    }

    /// Why these cannot be sums of counts and of their laws' cumulants (a damaged or
    /// edited partial): the field (`mu`, `v`, `var`, `k3`, `k4`) that is not finite or
    /// negative (each sums terms ≥ 0); `None` when they can be.
    pub fn impossible(&self) -> Option<String> {
        let fields = [
            ("mu", &self.mu),
            ("v", &self.v),
            ("var", &self.var),
            ("k3", &self.k3),
            ("k4", &self.k4),
        ];
        fields.into_iter().find_map(|(name, s)| {
            let x = s.value();
            if !s.is_finite() || !x.is_finite() {
                Some(format!("`{name}` is not finite"))
            } else if x < 0.0 {
                Some(format!(
                    "`{name}` = {x:e} is negative, but it sums terms that are not"
                ))
            } else {
                None
            }
        })
    }

    /// The sums of both.
    pub fn add(&mut self, o: &Sums) {
        self.total += o.total;
        for (a, b) in [
            (&mut self.mu, &o.mu),
            (&mut self.v, &o.v),
            (&mut self.var, &o.var),
            (&mut self.k3, &o.k3),
            (&mut self.k4, &o.k4),
        ] {
            a.merge(b);
        }
    }
}

/// One realization: the counts and their expectations, channel-major.
pub type Realization = (Vec<u64>, Vec<f64>);

/// Validates `n` profiles drawn by `draw(p)` (counts and expectations of profile p)
/// against their own expectations; `names` and `altitudes` label the bins (channel-major,
/// `n_bins` per channel).
pub fn validate_profiles(
    draw: &(dyn Fn(u64) -> Realization + Sync),
    n: usize,
    names: &[String],
    altitudes: &[f64],
) -> (Vec<BinReport>, Vec<Check>) {
    let sums = accumulate(draw, 0..n, altitudes.len());
    reports(&sums, n, names, altitudes)
}

/// The per-bin sums of profiles `rows` drawn by `draw`, over `bins` bins.
pub fn accumulate(
    draw: &(dyn Fn(u64) -> Realization + Sync),
    rows: std::ops::Range<usize>,
    bins: usize,
) -> Vec<Sums> {
    let mut sums = vec![Sums::default(); bins];
    let batch = ((8 << 20) / bins.max(1)).clamp(1, 4096);
    for first in rows.clone().step_by(batch) {
        let last = (first + batch).min(rows.end);
        let drawn: Vec<Realization> = (first..last)
            .into_par_iter()
            .map(|p| draw(p as u64))
            .collect();
        for (c, mu) in &drawn {
            for ((s, &c), &mu) in sums.iter_mut().zip(c).zip(mu) {
                s.push(c, mu);
            }
        }
    }
    sums
}

/// The bins' statistics and verdicts from the sums of `n` profiles.
pub fn reports(
    sums: &[Sums],
    n: usize,
    names: &[String],
    altitudes: &[f64],
) -> (Vec<BinReport>, Vec<Check>) {
    let per_channel = altitudes.len() / names.len().max(1);
    let reports: Vec<BinReport> = sums
        .iter()
        .enumerate()
        .map(|(i, s)| bin_report(s, n, &names[i / per_channel], i % per_channel, altitudes[i]))
        .collect();
    let checks = verdicts(&reports);
    (reports, checks)
}

/// The sums' values.
struct Values {
    total: u128,
    mu: f64,
    v: f64,
    var: f64,
    k3: f64,
    k4: f64,
}

/// One bin's statistics.
fn bin_report(sums: &Sums, n: usize, channel: &str, bin: usize, altitude_m: f64) -> BinReport {
    let nf = n as f64;
    let s = Values {
        total: sums.total,
        mu: sums.mu.value(),
        v: sums.v.value(),
        var: sums.var.value(),
        k3: sums.k3.value(),
        k4: sums.k4.value(),
    };
    let model = BinModel::new(0.0, s.mu / nf, nf, 0.0);
    let (z, mean_shape) = mean_z(s.total, 1.0, &BinModel::new(0.0, s.mu, 1.0, 0.0));
    let mean = Stat {
        empirical: s.total as f64 / nf,
        model: s.mu / nf,
        z,
        shape: mean_shape,
    };
    let enough = model.cumulants[0] >= MIN_TOTAL_COUNTS && s.var > 0.0;
    let variance = variance_stat(s.v, s.mu, [s.var, s.k3, s.k4], enough, nf);
    mean_and_variance(channel, bin, altitude_m, mean, variance)
}

/// The variance check of a bin over `nf` profiles: the sum of squared deviations
/// `v` against its model `model_v`, whose own variance and third and fourth cumulants
/// are `[var, k3, k4]` (the calibrated Edgeworth tail; no z unless `enough`).
pub(crate) fn variance_stat(
    v: f64,
    model_v: f64,
    [var, k3, k4]: [f64; 3],
    enough: bool,
    nf: f64,
) -> Stat {
    let shape = calibration::outside_probability(k3 / var.powf(1.5), k4 / (var * var));
    Stat {
        empirical: v / nf,
        model: model_v / nf,
        z: (enough && shape.is_some()).then(|| (v - model_v) / var.sqrt()),
        shape,
    }
}

/// A bin's report with the mean and variance checks only (no S/N).
pub(crate) fn mean_and_variance(
    channel: &str,
    bin: usize,
    altitude_m: f64,
    mean: Stat,
    variance: Stat,
) -> BinReport {
    BinReport {
        channel: channel.to_string(),
        bin,
        altitude_m,
        mean,
        variance,
        snr_known_background: Stat::untested(),
        snr_estimated_background: Stat::untested(),
    }
}
