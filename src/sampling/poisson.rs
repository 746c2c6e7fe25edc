//! One exact Poisson draw as a `u64`, for any mean a `u64` count can hold.

use rand::Rng;
use rand_distr::{Distribution, Poisson};

/// Means below this are drawn by on-the-fly inversion, above by Ahrens–Dieter.
pub const AGGREGATE_INVERSION_MAX: f64 = 12.0;

/// Largest mean given to one Ahrens–Dieter draw: `2^50 ≈ 1.126e15`. Larger
/// means are split into chunks (a sum of independent Poissons is Poisson).
pub const AGGREGATE_CHUNK: f64 = 1_125_899_906_842_624.0;

const TWO_POW_64: f64 = 18_446_744_073_709_551_616.0;

/// One Poisson(`mean`) draw as a `u64`, for any finite `mean >= 0` up to
/// about `1.8e19` (beyond that a `u64` cannot hold the count).
///
/// * `mean = 0` (or `1e-300`) gives 0, never NaN;
/// * `mean < 12`: inversion by sequential search (Devroye 1986, §X.3.3) with
///   the first step on 64-bit integers (`P(K ≥ 1) = -expm1(-mean)` realised
///   to `2^-64` absolute), the rest in f64 (cell errors ≤ ~1e-15·P(K ≥ 1));
/// * `mean ≥ 12`: `rand_distr::Poisson` (Ahrens & Dieter 1982, ACM TOMS 8(2),
///   163–179, exact rejection from a normal proposal; rand_distr ≥ 0.5, see
///   rand PR #1560, fixed the variance inflation of the previous algorithm at
///   large λ, rand issue #1515), on chunks of at most [`AGGREGATE_CHUNK`]
///   `= 2^50`. Precision: every integer up to `2^53` is an f64, and rounding
///   the normal proposal `λ + σz` to f64 moves the cell edges by at most
///   half an ulp, `≤ 1/8` count for a chunk `≤ 2^50` (below `4e-9 σ`); the
///   mean is off by at most that. Expected cost is O(1) per chunk (O(mean / 2^50) in all) and
///   cannot hang for finite mean (rand_distr caps λ at 1.844e19).
#[inline]
pub fn poisson_u64<R: Rng + ?Sized>(rng: &mut R, mean: f64) -> u64 {
    debug_assert!(
        mean.is_finite() && mean >= 0.0,
        "Poisson mean must be finite and >= 0, got {mean}"
    );
    if mean.is_nan() || mean <= 0.0 {
        return 0;
    }
    if mean < AGGREGATE_INVERSION_MAX {
        return poisson_small(rng, mean);
    }
    if mean <= AGGREGATE_CHUNK {
        return ahrens_dieter(rng, mean);
    }
    // Exact split: mean = n·2^50 + rem (both parts exact in f64).
    let n = (mean / AGGREGATE_CHUNK).floor();
    let rem = mean - n * AGGREGATE_CHUNK;
    let chunk = Poisson::new(AGGREGATE_CHUNK).unwrap();
    let mut total: u64 = 0;
    for _ in 0..n as u64 {
        total = total.saturating_add(chunk.sample(rng) as u64);
    }
    let tail = if rem <= 0.0 {
        0
    } else if rem < AGGREGATE_INVERSION_MAX {
        poisson_small(rng, rem)
    } else {
        ahrens_dieter(rng, rem)
    };
    total.saturating_add(tail)
}

#[inline]
fn ahrens_dieter<R: Rng + ?Sized>(rng: &mut R, mean: f64) -> u64 {
    let k: f64 = Poisson::new(mean).unwrap().sample(rng);
    k as u64
}

/// Inversion for `0 < mean < 12`, one `u64` per draw.
#[inline]
fn poisson_small<R: Rng + ?Sized>(rng: &mut R, mean: f64) -> u64 {
    let x = rng.next_u64();
    let q1 = -(-mean).exp_m1(); // P(K >= 1)
    if x >= (q1 * TWO_POW_64) as u64 {
        return 0;
    }
    // K >= 1. u is uniform on [0, q1) (64-bit x rounded to f64: relative 2^-53).
    let u = x as f64 * (1.0 / TWO_POW_64);
    let mut k: u64 = 1;
    let mut p = mean * (-mean).exp(); // P(K = 1)
    let mut tail = q1 - p; // P(K >= 2)
    // Stop also when the terms vanish (a rounding residue in `tail` must not loop forever).
    while u < tail && p > 0.0 {
        k += 1;
        p *= mean / k as f64;
        tail -= p;
    }
    k
}
