//! Poisson draws for a fixed mean by an alias table over the PMF: one `u64` per draw,
//! whatever the mean.
//!
//! # Method
//!
//! The PMF is laid out around the mode `m = ⌊μ⌋` without normalisation: `w_m = 1`,
//! `w_{k+1} = w_k·μ/(k+1)` upwards and `w_{k-1} = w_k·k/μ` downwards, each side stopped
//! once a weight falls below `2^-72` (relative to the mode, so the law is truncated by
//! less than `2^-72` per side: the mode's probability is below 1). No `exp` or
//! log-gamma is needed and nothing underflows at any mean: the alias table
//! ([`AliasTable`]) normalises the weights to integers summing to exactly `2^64`
//! (Walker 1977; Vose 1991), so a common scale factor does not matter.
//!
//! # Precision
//!
//! Each weight carries the rounding of `|k − m|` multiplications, a relative error of at
//! most `|k − m|·2^-53` (≤ ~2e-13 at ten standard deviations of `μ = 10^6`); the table
//! then realises every cell to within `(n+1)·2^-64` absolute. The same precision as the
//! tail thresholds of [`super::table`], for any mean.
//!
//! # Cost
//!
//! One `u64`, one column load and a compare per draw (measured in
//! `cost` (`sampling::shot`)); the table takes 16 bytes per column, `≈ 2^⌈log2(19.2·√μ)⌉`
//! columns for large means (`μ = 100`: 256 columns, 4 KiB), which is what limits it
//! (the shot sampler's `DENSE_ALIAS_MAX` and alias budget).

use super::alias::AliasTable;

/// Weights below this, relative to the mode, end the PMF on each side (`2^-72`).
const PMF_CUTOFF: f64 = 1.0 / (1u128 << 72) as f64;

/// The PMF of Poisson(`mean`) up to a common factor, from `k0` on: `(k0, weights)`,
/// truncated at `2^-72` of the mode's weight on both sides; empty for `mean ≤ 0`.
pub(crate) fn pmf_window(mean: f64) -> (u32, Vec<f64>) {
    debug_assert!(mean.is_finite() && mean < 4e9, "PMF window of mean {mean}");
    if mean.is_nan() || mean <= 0.0 {
        return (0, Vec::new());
    }
    let mode = mean.floor();
    let mut below = Vec::new();
    let (mut w, mut k) = (1.0f64, mode);
    while k > 0.0 {
        w *= k / mean;
        k -= 1.0;
        if w < PMF_CUTOFF {
            break;
        }
        below.push(w);
    }
    let k0 = mode as u32 - below.len() as u32;
    let mut weights: Vec<f64> = below.into_iter().rev().collect();
    weights.push(1.0);
    let (mut w, mut k) = (1.0f64, mode);
    loop {
        k += 1.0;
        w *= mean / k;
        if w < PMF_CUTOFF {
            break;
        }
        weights.push(w);
    }
    (k0, weights)
}

/// Columns of the alias table [`PmfAlias::new`] builds for `mean` (for cost models),
/// without building it.
pub fn pmf_alias_columns(mean: f64) -> usize {
    if mean <= 0.0 {
        return 0;
    }
    // the window spans ~±10 standard deviations, at least the few terms of a small mean
    let entries = 2.0 * 10.0 * mean.sqrt() + 8.0;
    (entries.ceil() as usize).next_power_of_two().max(2)
}

/// An exact Poisson(`μ`) sampler for one fixed mean: an alias table over the PMF window.
#[derive(Clone, Debug)]
pub struct PmfAlias {
    table: AliasTable,
}

impl PmfAlias {
    /// The sampler of Poisson(`mean`), `0 < mean < 4e9` (finite; its table has
    /// [`pmf_alias_columns`]`(mean)` columns).
    pub fn new(mean: f64) -> PmfAlias {
        let (k0, w) = pmf_window(mean);
        assert!(!w.is_empty(), "PmfAlias needs a positive mean, got {mean}");
        let ks: Vec<u32> = (0..w.len() as u32).map(|i| k0 + i).collect();
        PmfAlias {
            table: AliasTable::new(&w, &ks),
        }
    }

    /// The count for the uniform `u64` `x`.
    #[inline(always)]
    pub fn count_for(&self, x: u64) -> u32 {
        self.table.bin_for(x) as u32
    }

    /// Realised probability of each count `0..len` (tests).
    #[cfg(test)]
    pub(crate) fn probabilities(&self, len: usize) -> Vec<f64> {
        self.table.probabilities(len)
    }
}
