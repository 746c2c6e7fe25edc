//! Reproducible random streams: one generator per (seed, profile, block of shots), and
//! the integer sums of blocks drawn in parallel.

use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;

/// Shots per block in [`shot_profile`]: block `b` covers shots
/// `[b·SHOT_BLOCK, (b+1)·SHOT_BLOCK)` and has its own [`stream_rng`].
pub const SHOT_BLOCK: u64 = 1 << 16;

/// Block index of the stream used by [`aggregate_profile`] (never reached by
/// shot blocks, which stay below `2^48`).
pub const AGGREGATE_STREAM: u64 = u64::MAX;

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function (Steele, Lea & Flood 2014, "Fast splittable
/// pseudorandom number generators", OOPSLA; constants of Stafford's Mix13):
/// a bijection of `u64` with full avalanche.
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Deterministic generator for `(seed, profile, block)`.
///
/// `Pcg64Mcg` (O'Neill 2014, "PCG: a family of simple fast space-efficient
/// statistically good algorithms for random number generation", HMC-CS-2014-0905;
/// 128-bit MCG, XSL-RR output) whose state is the three numbers absorbed one
/// after the other by SplitMix64's mixer: `h = mix(mix(mix(seed+γ) ^
/// mix(profile+2γ)) ^ mix(block+3γ))`, state `= h·2^64 + mix(h+4γ)`. For a
/// fixed `(seed, profile)` distinct blocks always give distinct states (the
/// chain is a bijection of `block`); any two other triples collide with
/// probability `2^-64`. Streams start at effectively random points of the
/// `2^126` period, so overlaps are negligible.
pub fn stream_rng(seed: u64, profile: u64, block: u64) -> Pcg64Mcg {
    let a = mix64(seed.wrapping_add(GOLDEN));
    let b = mix64(a ^ mix64(profile.wrapping_add(GOLDEN.wrapping_mul(2))));
    let h = mix64(b ^ mix64(block.wrapping_add(GOLDEN.wrapping_mul(3))));
    let lo = mix64(h.wrapping_add(GOLDEN.wrapping_mul(4)));
    Pcg64Mcg::new((u128::from(h) << 64) | u128::from(lo))
}

/// Adds into `acc` the counts of blocks `0..nblocks`, each drawn by `block` into a
/// buffer of its own (of `acc.len()` bins), the blocks in parallel (rayon): integer sums,
/// so the result does not depend on the thread count.
pub fn add_block_sums(
    acc: &mut [u64],
    nblocks: u64,
    block: impl Fn(u64) -> Vec<u64> + Sync + Send,
) {
    if nblocks <= 1 {
        // one block (a profile of up to SHOT_BLOCK shots): drawn here, not handed to
        // the pool (a cross-thread round trip of microseconds), the same sums
        if nblocks == 1 {
            acc.iter_mut().zip(&block(0)).for_each(|(a, s)| *a += s);
        }
        return;
    }
    let bins = acc.len();
    let sum = (0..nblocks).into_par_iter().map(block).reduce(
        || vec![0u64; bins],
        |mut x, y| {
            x.iter_mut().zip(&y).for_each(|(a, b)| *a += b);
            x
        },
    );
    acc.iter_mut().zip(&sum).for_each(|(a, s)| *a += s);
}
