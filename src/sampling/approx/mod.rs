//! The normal approximation to the aggregate Poisson draw, offered only with its
//! error bound (issue 4, item 4; docs/simulation.md: "approximations are allowed only with
//! their error measured and reported beside their speed").
//!
//! A bin of mean `μ = M·λ` may be drawn as `max(0, round(μ + √μ·g))`, `g` standard
//! normal, instead of an exact Poisson(μ). Its CDF at an integer `k ≥ 0` is
//! `Φ((k + ½ − μ)/√μ)` (the clamp puts all the mass below ½ at 0), so its
//! Kolmogorov–Smirnov distance to Poisson(μ) is
//!
//! ```text
//! KS(μ) = sup_{k ≥ 0} |F_Poisson(μ)(k) − Φ((k + ½ − μ)/√μ)|,
//! ```
//!
//! computed exactly by [`normal_approx_ks`]. For large μ the Edgeworth expansion
//! gives `F_Poisson(k) − Φ(z) ≈ −φ(z)(z² − 1)/(6√μ)` at `z = (k + ½ − μ)/√μ`, largest
//! at `z = 0`: `KS(μ) ≈ c/√μ` with `c =` [`KS_ASYMPTOTE`] `= 1/(6√(2π)) ≈ 0.0664904`.
//! Around it a lattice term of period 1 in μ: `(√μ·KS/c − 1)·μ` stays in
//! `[−0.2482, 0.1243]` (checked on a dense grid, with full periods resolved at
//! μ = 10, 10³, 10⁵, 10⁷; see `validation/speed_vs_error/` and its report). Hence the
//! bound [`normal_approx_ks_bound`]
//!
//! ```text
//! KS(μ) ≤ B(μ) = min(KS_SUP, c/√μ · (1 + KS_LATTICE/μ + KS_BOUND_SLACK))
//! ```
//!
//! with `KS_LATTICE = 1/8`, `KS_SUP = 0.10802 ≥ sup_μ KS(μ) = 0.108011` (at μ ≈ 0.44) and
//! `KS_BOUND_SLACK = 1e-6` for the f64 resolution of the check at μ = 10¹⁵. `B` is
//! decreasing in μ, so [`normal_threshold`]`(τ)`, the smallest μ with `B(μ) ≤ τ`,
//! guarantees `KS(μ) ≤ τ` for every μ at or above it; it is within a fraction of a percent
//! of the smallest such μ because the bound is tight (its terms are the measured envelope).
//!
//! | τ | μ* = `normal_threshold(τ)` |
//! |---|---|
//! | ≥ 0.10802 | 0 |
//! | 0.1 | 0.6337 |
//! | 1e-2 | 44.46 |
//! | 1e-3 | 4421.2 |
//! | 1e-4 | 4.4210e5 |
//! | 1e-5 | 4.4210e7 |
//! | 1e-6 | 4.4210e9 |
//!
//! [`add_aggregate_approx`] and [`aggregate_approx_profile`] draw a profile with exact
//! Poisson below the threshold ([`poisson_u64`], the same stream as
//! `aggregate_profile` (`sampling::profile`): with an infinite threshold the counts
//! are identical) and the normal approximation at or above it.
//!
//! The bound is on the KS distance only. Well above 1 the approximate law has mean μ
//! (to exponentially small terms) and variance μ + 1/12 (Sheppard), a relative bias
//! `1/(12μ)` (≤ 1.9e-3 for τ ≤ 0.01, μ* ≥ 44). For loose tolerances μ* is a few counts
//! and the clamp at 0 biases the moments: at μ* = 0.634 (τ = 0.1) the mean is 13 % high
//! and the variance 18 % low, at μ* = 2.0 (τ = 0.05) +2.3 % and −8.3 %
//! (`validation/reports/speed_vs_error.md` tabulates them); prefer τ ≤ 0.01.

use std::f64::consts::{PI, SQRT_2};
use std::sync::OnceLock;

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use statrs::function::erf::erfc;
use statrs::function::gamma::ln_gamma;

use super::poisson::poisson_u64;
use super::streams::{AGGREGATE_STREAM, stream_rng};

/// `c = 1/(6√(2π))`: `KS(μ)·√μ → c` as μ → ∞.
pub const KS_ASYMPTOTE: f64 = 0.066_490_380_066_905_46;

/// Coefficient `a` of the lattice correction in the bound `c/√μ·(1 + a/μ + ε)`.
pub const KS_LATTICE: f64 = 0.125;

/// Relative slack `ε` of the bound: the f64 resolution of its numerical check.
pub const KS_BOUND_SLACK: f64 = 1e-6;

/// An upper bound of `sup_{μ>0} KS(μ)` (= 0.108011 at μ ≈ 0.44): at or above this
/// tolerance every mean may be approximated.
pub const KS_SUP: f64 = 0.10802;

/// Largest tolerance (KS distance per bin) a run may ask for: 0.01, whose threshold
/// [`normal_threshold`] is μ* = 44.5 counts. Below ~40 counts the normal law, clipped at 0
/// and rounded, drifts from the Poisson mean (at `--tolerance 2` every mean is drawn
/// normally and means of 0.2 counts come out 21 % high), so larger tolerances buy
/// speed with bias, not with the shape error the tolerance states.
pub const MAX_TOLERANCE: f64 = 0.01;

/// [`normal_approx_ks`] sums over every integer up to this mean; above, it uses the
/// incomplete-gamma integral on a refined grid of k.
pub const KS_SUM_MAX: f64 = 1e6;

/// Above this mean (`2^52`) integers are too sparse in f64 for the exact computation:
/// [`normal_approx_ks`] returns the asymptote `c/√μ` (relative error below `1e-15`).
pub const KS_NUMERIC_MAX: f64 = 4_503_599_627_370_496.0;

/// Half-width of the window of k scanned, in standard deviations, plus [`WINDOW_PAD`]:
/// outside it both CDFs are within `e^-72` of 0 or 1 (Chernoff), far below any KS
/// distance at μ ≤ 2^52 (≥ 9.9e-10).
const WINDOW_SIGMAS: f64 = 12.0;
const WINDOW_PAD: f64 = 40.0;

/// Exact KS distance between Poisson(`mean`) and the clamped, rounded normal
/// `max(0, round(mean + √mean·g))` used by [`add_aggregate_approx`].
///
/// * `mean ≤ 0` gives 0 (both draw 0), NaN gives NaN;
/// * `mean ≤` [`KS_SUM_MAX`]: every integer k of `mean ± (12√mean + 40)` (clamped at 0),
///   the Poisson CDF by a compensated sum of the pmf in Loader's saddle-point form
///   (relative error ~1e-15 per term), Φ from `erfc`; exact to ~1e-15 absolute;
/// * up to [`KS_NUMERIC_MAX`]: `F(k) = Q(k+1, mean)`, the regularized upper incomplete
///   gamma, integrated by 16-point Gauss–Legendre over the gamma density; the
///   difference is smooth in k on the scale √mean, so it is evaluated on integers
///   spaced 0.05√mean over |z| ≤ 8 and its three largest local maxima refined by
///   golden-section search, then read at the neighbouring integers. Agrees with the
///   summation to ~1e-11 relative where both run (1e4–1e8); cost ~3–10 ms;
/// * above: the asymptote `c/√mean`.
pub fn normal_approx_ks(mean: f64) -> f64 {
    if mean.is_nan() {
        return f64::NAN;
    }
    if mean <= 0.0 || mean.is_infinite() {
        return 0.0;
    }
    if mean <= KS_SUM_MAX {
        ks_sum(mean).0
    } else if mean <= KS_NUMERIC_MAX {
        ks_smooth(mean).0
    } else {
        KS_ASYMPTOTE / mean.sqrt()
    }
}

/// The verified upper bound `B(μ) = min(KS_SUP, c/√μ·(1 + KS_LATTICE/μ + KS_BOUND_SLACK))`
/// of [`normal_approx_ks`] (0 for μ ≤ 0 and +∞; decreasing in μ > 0).
pub fn normal_approx_ks_bound(mean: f64) -> f64 {
    if mean.is_nan() {
        return f64::NAN;
    }
    if mean <= 0.0 || mean.is_infinite() {
        return 0.0;
    }
    let b = KS_ASYMPTOTE / mean.sqrt() * (1.0 + KS_LATTICE / mean + KS_BOUND_SLACK);
    b.min(KS_SUP)
}

/// The smallest mean μ* with `normal_approx_ks_bound(μ*) ≤ tolerance`: every bin of
/// mean ≥ μ* drawn by the normal approximation has a KS distance ≤ `tolerance` to its
/// exact Poisson law (see the module docs for how "every" is guaranteed).
///
/// `+∞` (never approximate) when `tolerance` is NaN, ≤ 0, or so small that μ* would
/// not be a finite f64 (below ~6e-156); 0 (approximate every mean) when `tolerance ≥`
/// [`KS_SUP`]. Else `μ* ≈ (c/τ)²·(1 + …)`: 44.46 at τ = 0.01, 4421 at 1e-3, 4.42e5 at 1e-4.
pub fn normal_threshold(tolerance: f64) -> f64 {
    if tolerance.is_nan() || tolerance <= 0.0 {
        return f64::INFINITY;
    }
    if tolerance >= KS_SUP {
        return 0.0;
    }
    let b = |mu: f64| KS_ASYMPTOTE / mu.sqrt() * (1.0 + KS_LATTICE / mu + KS_BOUND_SLACK);
    if b(f64::MAX) > tolerance {
        return f64::INFINITY;
    }
    // bisection on ln μ: b is decreasing; keep b(hi) ≤ tolerance < b(lo)
    let (mut lo, mut hi) = ((1e-12f64).ln(), f64::MAX.ln());
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if b(mid.exp()) <= tolerance {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let mu = hi.exp();
    if mu.is_finite() { mu } else { f64::MAX }
}

/// Exact Poisson(`mean`) probability of `k` (Loader's saddle-point form: relative error
/// ~1e-15 for every k and mean).
pub fn poisson_pmf(k: u64, mean: f64) -> f64 {
    if mean <= 0.0 {
        return if k == 0 { 1.0 } else { 0.0 };
    }
    pmf(k as f64, mean)
}

/// Exact Poisson(`mean`) CDF at `k` (absolute error ~1e-15; exactly 0 or 1 more than
/// `40√mean + 40` from the mean, where the true value is within `e^-800` of it).
pub fn poisson_cdf(k: u64, mean: f64) -> f64 {
    if mean.is_nan() || mean <= 0.0 {
        return 1.0;
    }
    let kf = k as f64;
    let s = mean.sqrt();
    if kf < mean - 40.0 * s - WINDOW_PAD {
        return 0.0;
    }
    if kf > mean + 40.0 * s + WINDOW_PAD {
        return 1.0;
    }
    if mean <= KS_SUM_MAX || kf <= 15.0 {
        let lo = (mean - 40.0 * s - WINDOW_PAD).floor().max(0.0);
        let hi = (mean + 40.0 * s + WINDOW_PAD).ceil();
        if kf <= mean {
            let mut sum = Neumaier::default();
            let mut j = lo;
            while j <= kf {
                sum.add(pmf(j, mean));
                j += 1.0;
            }
            sum.value()
        } else {
            let mut sum = Neumaier::default();
            let mut j = kf + 1.0;
            while j <= hi {
                sum.add(pmf(j, mean));
                j += 1.0;
            }
            1.0 - sum.value()
        }
    } else {
        gamma_q(kf, mean)
    }
}

/// Adds one profile of `shots` shots into `acc`: per bin, mean `shots·λ_i`; exact
/// Poisson ([`poisson_u64`]) below `threshold`, the normal approximation
/// `max(0, round(mean + √mean·g))` at or above it (`g` from
/// [`rand_distr::StandardNormal`]; saturates at `u64::MAX`, exact in f64 up to
/// `2^53`). `threshold = +∞` (or NaN) is exactly `add_aggregate` (`sampling::aggregate`);
/// take it from [`normal_threshold`].
pub fn add_aggregate_approx<R: Rng + ?Sized>(
    rng: &mut R,
    lambda_per_bin: &[f64],
    shots: u64,
    threshold: f64,
    acc: &mut [u64],
) {
    assert_eq!(
        acc.len(),
        lambda_per_bin.len(),
        "accumulator length != number of bins"
    );
    let m = shots as f64;
    for (a, &l) in acc.iter_mut().zip(lambda_per_bin) {
        let mean = l * m;
        let k = if mean >= threshold && mean > 0.0 {
            normal_count(rng, mean)
        } else {
            poisson_u64(rng, mean)
        };
        *a = a.saturating_add(k);
    }
}

/// [`add_aggregate_approx`] for profile `profile`, from
/// `stream_rng(seed, profile, AGGREGATE_STREAM)` like
/// `aggregate_profile` (`sampling::profile`).
pub fn aggregate_approx_profile(
    lambda_per_bin: &[f64],
    seed: u64,
    profile: u64,
    shots: u64,
    threshold: f64,
    acc: &mut [u64],
) {
    let mut rng = stream_rng(seed, profile, AGGREGATE_STREAM);
    add_aggregate_approx(&mut rng, lambda_per_bin, shots, threshold, acc);
}

#[inline]
fn normal_count<R: Rng + ?Sized>(rng: &mut R, mean: f64) -> u64 {
    let g: f64 = StandardNormal.sample(rng);
    let x = (mean + mean.sqrt() * g).round();
    if x > 0.0 { x as u64 } else { 0 }
}

// ---------------------------------------------------------------------------
// Numerics
// ---------------------------------------------------------------------------

const SQRT_2PI: f64 = 2.506_628_274_631_000_5;

/// Compensated (Neumaier) sum.
#[derive(Default)]
struct Neumaier {
    sum: f64,
    comp: f64,
}

impl Neumaier {
    #[inline]
    fn add(&mut self, x: f64) {
        let t = self.sum + x;
        if self.sum.abs() >= x.abs() {
            self.comp += (self.sum - t) + x;
        } else {
            self.comp += (x - t) + self.sum;
        }
        self.sum = t;
    }

    fn value(&self) -> f64 {
        self.sum + self.comp
    }
}

/// Standard normal CDF.
fn phi(z: f64) -> f64 {
    0.5 * erfc(-z / SQRT_2)
}

/// `ln Γ(n+1) − [(n+½)ln n − n + ½ln(2π)]`, the error of Stirling's formula (n ≥ 1).
fn stirlerr(n: f64) -> f64 {
    if n <= 15.0 {
        ln_gamma(n + 1.0) - (n + 0.5) * n.ln() + n - (SQRT_2PI).ln()
    } else {
        const S0: f64 = 1.0 / 12.0;
        const S1: f64 = 1.0 / 360.0;
        const S2: f64 = 1.0 / 1260.0;
        const S3: f64 = 1.0 / 1680.0;
        const S4: f64 = 1.0 / 1188.0;
        let nn = n * n;
        (S0 - (S1 - (S2 - (S3 - S4 / nn) / nn) / nn) / nn) / n
    }
}

/// `x ln(x/np) + np − x`, without cancellation (Loader 2000, "Fast and accurate
/// computation of binomial probabilities").
fn bd0(x: f64, np: f64) -> f64 {
    if (x - np).abs() < 0.1 * (x + np) {
        let v = (x - np) / (x + np);
        let mut s = (x - np) * v;
        let mut ej = 2.0 * x * v;
        let v2 = v * v;
        for j in 1..200 {
            ej *= v2;
            let s1 = s + ej / (2 * j + 1) as f64;
            if s1 == s {
                return s1;
            }
            s = s1;
        }
        s
    } else {
        x * (x / np).ln() + np - x
    }
}

/// Poisson pmf at (real) `k ≥ 0`, mean `mu > 0`: `exp(−stirlerr(k) − bd0(k, μ))/√(2πk)`.
fn pmf(k: f64, mu: f64) -> f64 {
    if k == 0.0 {
        (-mu).exp()
    } else {
        (-stirlerr(k) - bd0(k, mu)).exp() / (2.0 * PI * k).sqrt()
    }
}

/// `(KS, argmax k)` by summation over every integer of the window.
fn ks_sum(mu: f64) -> (f64, f64) {
    let s = mu.sqrt();
    let k_lo = (mu - WINDOW_SIGMAS * s - WINDOW_PAD).floor().max(0.0);
    let k_hi = (mu + WINDOW_SIGMAS * s + WINDOW_PAD).ceil();
    // F(k_lo − 1) < e^-72 (Chernoff): started at 0
    let mut f = Neumaier::default();
    let mut best = (0.0, k_lo);
    let mut k = k_lo;
    while k <= k_hi {
        f.add(pmf(k, mu));
        let d = (f.value() - phi((k + 0.5 - mu) / s)).abs();
        if d > best.0 {
            best = (d, k);
        }
        k += 1.0;
    }
    best
}

fn gl16() -> &'static [(f64, f64)] {
    static NODES: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    NODES.get_or_init(|| gauss_legendre(16))
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on the Legendre recurrence).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 1..=n {
        let mut x = (PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for j in 2..=n {
                let p2 = ((2 * j - 1) as f64 * x * p1 - (j - 1) as f64 * p0) / j as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

/// `κ·(−ln(1 − y) − y)`, `y = d/κ`: `bd0(κ, κ − d)` from the offset `d` (no rounding of
/// `κ − d` to the f64 grid of huge means).
fn bd0_shift(kappa: f64, d: f64) -> f64 {
    let y = d / kappa;
    if y.abs() < 0.1 {
        let mut term = y * y;
        let mut s = 0.5 * term;
        for j in 3..100 {
            term *= y;
            let s1 = s + term / j as f64;
            if s1 == s {
                break;
            }
            s = s1;
        }
        kappa * s
    } else {
        kappa * (-(-y).ln_1p() - y)
    }
}

/// `Q(κ+1, x) = P(Poisson(x) ≤ κ) = ∫_x^∞ t^κ e^{−t}/Γ(κ+1) dt` for real κ > 15:
/// 16-point Gauss–Legendre on panels of width √κ from x up to `max(x, κ) + 14√κ`
/// (the rest is below e^-98 of the peak), in the offset `u = t − x`.
fn gamma_q(kappa: f64, x: f64) -> f64 {
    let sk = kappa.sqrt();
    let h = sk;
    let d0 = kappa - x; // κ − t = d0 − u
    let top = d0.max(0.0) + 14.0 * sk;
    let panels = (top / h).ceil().max(1.0) as usize;
    let nodes = gl16();
    let norm = -stirlerr(kappa);
    let mut sum = Neumaier::default();
    for p in 0..panels {
        let mid = (p as f64 + 0.5) * h;
        let mut part = 0.0;
        for &(v, w) in nodes {
            let u = mid + 0.5 * h * v;
            part += w * (norm - bd0_shift(kappa, d0 - u)).exp();
        }
        sum.add(0.5 * h * part);
    }
    sum.value() / (2.0 * PI * kappa).sqrt()
}

/// `(KS, argmax k)` for large μ, from [`gamma_q`] on a refined grid of k.
fn ks_smooth(mu: f64) -> (f64, f64) {
    let s = mu.sqrt();
    let d = |k: f64| (gamma_q(k, mu) - phi((k + 0.5 - mu) / s)).abs();
    let n = 320usize;
    let ks: Vec<f64> = (0..=n)
        .map(|j| (mu - 0.5 + (-8.0 + 16.0 * j as f64 / n as f64) * s).round())
        .collect();
    let vals: Vec<f64> = ks.iter().map(|&k| d(k)).collect();
    let mut best = (0.0, ks[0]);
    for (&k, &v) in ks.iter().zip(&vals) {
        if v > best.0 {
            best = (v, k);
        }
    }
    let mut peaks: Vec<usize> = (1..n)
        .filter(|&j| vals[j] >= vals[j - 1] && vals[j] >= vals[j + 1])
        .collect();
    peaks.sort_by(|&a, &b| vals[b].total_cmp(&vals[a]));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for &j in peaks.iter().take(3) {
        let (mut a, mut b) = (ks[j - 1], ks[j + 1]);
        let mut c = b - g * (b - a);
        let mut e = a + g * (b - a);
        let (mut fc, mut fe) = (d(c), d(e));
        while b - a > 0.5 {
            if fc > fe {
                b = e;
                e = c;
                fe = fc;
                c = b - g * (b - a);
                fc = d(c);
            } else {
                a = c;
                c = e;
                fc = fe;
                e = a + g * (b - a);
                fe = d(e);
            }
        }
        let m = 0.5 * (a + b);
        for k in [m.floor() - 1.0, m.floor(), m.ceil(), m.ceil() + 1.0] {
            let v = d(k);
            if v > best.0 {
                best = (v, k);
            }
        }
    }
    best
}

#[cfg(test)]
mod tests;
