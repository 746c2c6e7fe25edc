//! Poisson sampling by table inversion with 64-bit integer thresholds.
//!
//! # Method
//!
//! Inversion by sequential search (Devroye 1986, *Non-Uniform Random Variate
//! Generation*, §X.3.3), written on tail probabilities: with
//! `T_j = ⌊P(K ≥ j) · 2^64⌋` for `j = 1, 2, …` and `x` a uniform `u64`,
//!
//! ```text
//! K = #{ j ≥ 1 : x < T_j }        so that   P(K ≥ j) = T_j / 2^64  exactly.
//! ```
//!
//! One `u64` per draw. `T_1` is usually the only threshold a small-λ draw
//! looks at, so the common case `K = 0` costs one uniform and one compare;
//! on `x < T_1` the remaining thresholds above `x` are counted branch-free.
//!
//! # Precision
//!
//! The PMF is built by the forward recurrence `p_{i+1} = p_i λ/(i+1)` from
//! `p_0 = e^{-λ}`, tails are summed from the smallest term up, and
//! `P(K ≥ 1) = -expm1(-λ)` directly, so every tail carries a relative error of
//! a few ulps (≤ ~1e-15) before the `2^-64` floor. The table stops once the
//! PMF falls below `2^-72` past the mode, so the law is truncated by less than
//! `2^-70`. A tail below `2^-64` (e.g. `λ < 5.4e-20` for `K ≥ 1`) becomes a
//! zero threshold: λ = 0 and λ = 1e-300 give `K = 0` always, never NaN.
//! Valid for `0 ≤ λ ≤` [`TABLE_LAMBDA_LIMIT`] (where `e^{-λ}` is still a normal
//! f64).

/// Largest mean accepted by [`tail_thresholds`] (`e^{-600} ≈ 2.6e-261`: no underflow).
pub(crate) const TABLE_LAMBDA_LIMIT: f64 = 600.0;

const TWO_POW_64: f64 = 18_446_744_073_709_551_616.0;
/// The PMF recurrence stops past the mode once a term is below this.
const PMF_CUTOFF: f64 = 1.0 / (1u128 << 72) as f64; // 2^-72

/// Poisson(λ) PMF `p_0, …, p_kmax` (forward recurrence from `e^{-λ}`),
/// stopped past the mode once a term is below `2^-72`; empty for `λ = 0`.
pub(crate) fn poisson_pmf(lambda: f64) -> Vec<f64> {
    debug_assert!(
        lambda.is_finite() && (0.0..=TABLE_LAMBDA_LIMIT).contains(&lambda),
        "table inversion needs 0 <= lambda <= {TABLE_LAMBDA_LIMIT}, got {lambda}"
    );
    if lambda.is_nan() || lambda <= 0.0 {
        return Vec::new();
    }
    let mut pmf = Vec::with_capacity(16);
    let mut p = (-lambda).exp();
    let mut i = 0usize;
    loop {
        pmf.push(p);
        i += 1;
        p = p * lambda / i as f64;
        if p == 0.0 || (i as f64 > lambda && p < PMF_CUTOFF) {
            break;
        }
    }
    pmf
}

/// Thresholds `T_1, T_2, …, T_kmax` (non-increasing, all > 0, no sentinel).
pub(crate) fn tail_thresholds(lambda: f64) -> Vec<u64> {
    let pmf = poisson_pmf(lambda);
    if pmf.is_empty() {
        return Vec::new();
    }
    // tails[j] = P(K >= j), summed from the small end; P(K >= 1) = -expm1(-λ)
    // directly (the PMF may stop at p_0 for tiny λ).
    let mut tails = vec![0.0f64; pmf.len().max(2)];
    let mut s = 0.0;
    for j in (1..pmf.len()).rev() {
        s += pmf[j];
        tails[j] = s;
    }
    tails[1] = -(-lambda).exp_m1();
    let mut out = Vec::with_capacity(pmf.len());
    let mut prev = u64::MAX;
    for &tail in &tails[1..] {
        // `as` saturates: a tail that rounds to 1.0 gives u64::MAX (error 2^-64).
        let t = ((tail * TWO_POW_64) as u64).min(prev);
        if t == 0 {
            break;
        }
        out.push(t);
        prev = t;
    }
    out
}

/// Number of thresholds above `x` (branch-free; `thr` non-increasing, no sentinel).
#[inline(always)]
pub(crate) fn count_above(thr: &[u64], x: u64) -> u32 {
    thr.iter().map(|&t| u32::from(x < t)).sum()
}
