//! Each statistic of one bin against its model: the z-scores of the mean, the variance
//! and the S/N with their laws, and the verdict of each statistic over the bins.

use statrs::distribution::{DiscreteCDF, Poisson};

use super::calibration::{self, Check, Shape, check_calibrated};
use super::model::{BinModel, central_moments, snr_standard_error};
use super::report::{BinReport, Stat};

/// Smallest expected total count `N·κ1` for the variance and S/N tests.
pub const MIN_TOTAL_COUNTS: f64 = 100.0;
/// Smallest model S/N for the S/N tests.
pub const MIN_SNR: f64 = 0.1;

/// Mean and unbiased variance of a sample, from its exact sums.
#[derive(Debug, Clone, Copy)]
pub(super) struct MeanVar {
    mean: f64,
    variance: f64,
}

impl MeanVar {
    /// Of `n` values summing to `sum` with squares summing to `squares`, all divided by
    /// `scale`: the variance `(n·Σx² − (Σx)²)/(n(n−1))` in exact integers where they fit.
    pub(super) fn of(n: usize, sum: i128, squares: u128, scale: f64) -> MeanVar {
        let nf = n as f64;
        let mean = sum as f64 / nf / scale;
        if n < 2 {
            return MeanVar {
                mean,
                variance: 0.0,
            };
        }
        let exact = (n as u128)
            .checked_mul(squares)
            .zip(sum.unsigned_abs().checked_mul(sum.unsigned_abs()))
            .and_then(|(a, b)| a.checked_sub(b));
        let numerator = match exact {
            Some(x) => x as f64,
            None => (squares as f64 - (sum as f64) * (sum as f64) / nf) * nf,
        };
        MeanVar {
            mean,
            variance: numerator / (nf * (nf - 1.0)) / (scale * scale),
        }
    }
}

/// The mean's z-score `(T − Nκ1)/sd(T)` of the total `T` over `n` profiles, with its
/// law under the model where that departs from the normal.
///
/// Where the count is Poisson to 0.1 % in variance (κ2 = κ1: no jitter or dead time), `T`
/// is Poisson(μ = Nκ1) and `z = (T − μ)/√μ` is Pearson's: `E z² = 1` and the excess
/// kurtosis of z is `1/μ` exactly ([`poisson_pearson_shape`] gives its tail). So `Σz²`
/// has mean K and the Satterthwaite variance of [`calibration::check_calibrated`] at
/// every count. (A z taken from the two-sided
/// exact-test p-value instead has `E z² < 1` for a discrete law: 0.88 at μ = 40, 0.65 at
/// μ = 4; its `Σz²` p-values crowded towards 1, which a uniformity test of
/// `validation/reports/paper_scenarios.md` caught.) Elsewhere the normal z with the total's
/// variance `Nκ2`.
pub(super) fn mean_z(total: u128, n: f64, m: &BinModel) -> (Option<f64>, Option<Shape>) {
    let [k1, k2, ..] = m.cumulants;
    if k1 <= 0.0 {
        return ((total > 0).then_some(f64::INFINITY), None);
    }
    let mean = total as f64 / n;
    if (k2 - k1).abs() > 1e-3 * k1 {
        return (Some((mean - k1) / (k2 / n).sqrt()), None);
    }
    let mu = n * k1;
    let z = (total as f64 - mu) / mu.sqrt();
    (Some(z), Some(poisson_pearson_shape(mu)))
}

/// The law of Pearson's `z = (T − μ)/√μ` for `T ~ Poisson(μ)`: its excess kurtosis `1/μ`
/// and its probability outside the nominal interval, the Poisson law's own tail (statrs'
/// CDF: a few µs a bin, 0.15 ms at μ = 10⁸). Above μ = 10⁸ Edgeworth's tail with
/// γ1 = μ^(−1/2), γ2 = 1/μ, which misses the lattice term: measured 6e-5 off at μ = 2·10⁴
/// (why it is not used lower), below 1e-6 at 10⁷–10⁸, shrinking as μ^(−1/2).
fn poisson_pearson_shape(mu: f64) -> Shape {
    let excess_kurtosis = 1.0 / mu;
    let exact = Poisson::new(mu).ok().filter(|_| mu < 1e8);
    let Some(law) = exact else {
        return calibration::outside_probability(mu.sqrt().recip(), excess_kurtosis)
            .unwrap_or_else(Shape::normal);
    };
    let half_width = calibration::z_interval() * mu.sqrt();
    // |T − μ| > half_width: T ≤ t_low (the largest integer below μ − half_width, none
    // when that is negative) or T > μ + half_width
    let t_low = (mu - half_width).ceil() - 1.0;
    let lower = if t_low >= 0.0 {
        law.cdf(t_low as u64)
    } else {
        0.0
    };
    let upper = law.sf((mu + half_width).floor() as u64);
    Shape {
        outside_probability: (lower + upper).clamp(0.0, 1.0),
        excess_kurtosis,
    }
}

/// The sample variance against κ2, with `Var(s²) = μ4/N − κ2²(N−3)/(N(N−1))` and its
/// Edgeworth-calibrated interval; untested where the Edgeworth expansion is not trusted.
pub(super) fn variance_stat(x: &MeanVar, m: &BinModel, nf: f64, enough: bool) -> Stat {
    let [k1, k2, k3, k4] = m.cumulants;
    let (_, _, mu4) = central_moments(k2, k3, k4);
    let var_s2 = mu4 / nf - k2 * k2 * (nf - 3.0) / (nf * (nf - 1.0));
    let poisson = !m.recorded && (k2 - k1).abs() <= 1e-12 * k1;
    let (g1, g2) = calibration::sample_variance_shape(k1, nf, poisson);
    let shape = calibration::outside_probability(g1, g2);
    Stat {
        empirical: x.variance,
        model: k2,
        z: (enough && var_s2 > 0.0 && shape.is_some()).then(|| (x.variance - k2) / var_s2.sqrt()),
        shape,
    }
}

/// `w.mean − offset` over `w`'s sd against the model S/N `signal/√μ2`, corrected for the
/// small-sample bias of `x̄/s` and with its delta-method variance so corrected.
pub(super) fn snr_stat(
    w: &MeanVar,
    m: &BinModel,
    offset: f64,
    (mu2, mu3, mu4): (f64, f64, f64),
    nf: f64,
    enough: bool,
) -> Stat {
    let model = if mu2 > 0.0 {
        m.signal / mu2.sqrt()
    } else {
        0.0
    };
    let sd = w.variance.sqrt();
    let empirical = if sd > 0.0 {
        (w.mean - offset) / sd
    } else {
        0.0
    };
    let (bias, variance_ratio) = calibration::snr_small_sample(model, nf);
    let se = snr_standard_error(m.signal, mu2, mu3, mu4, nf) * variance_ratio.sqrt();
    Stat {
        empirical,
        model,
        z: (enough && !m.recorded && model >= MIN_SNR && se > 0.0)
            .then(|| (empirical - model * bias) / se),
        shape: None,
    }
}

/// The verdict of each statistic over the bins where it was tested: the outside count
/// and Σz², each at [`CHECK_LEVEL`](calibration::CHECK_LEVEL) (with the bins' calibrated
/// shapes).
pub(super) fn verdicts(bins: &[BinReport]) -> Vec<Check> {
    let verdict = |name: &str, f: fn(&BinReport) -> &Stat| {
        let (zs, shapes): (Vec<f64>, Vec<Shape>) = bins
            .iter()
            .map(f)
            .filter_map(|s| s.z.map(|z| (z, s.shape.unwrap_or_else(Shape::normal))))
            .unzip();
        check_calibrated(name, &zs, &shapes)
    };
    vec![
        verdict("mean", |b| &b.mean),
        verdict("variance", |b| &b.variance),
        verdict("snr_known_background", |b| &b.snr_known_background),
        verdict("snr_estimated_background", |b| &b.snr_estimated_background),
    ]
}
