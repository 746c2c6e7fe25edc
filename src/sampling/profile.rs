//! One profile's counts, shot by shot or aggregate, from its reproducible streams.

use rayon::prelude::*;

use super::aggregate::{AggregateSampler, add_aggregate};
use super::shot::ShotSampler;
use super::streams::{AGGREGATE_STREAM, SHOT_BLOCK, stream_rng};

/// Accumulate one profile of `shots` shots by the shot path into `acc`.
///
/// Shots are cut into blocks of [`SHOT_BLOCK`]; block `b` is drawn with
/// `stream_rng(seed, profile, b)` into its own buffer and the integer sums are
/// added, so the result is identical whatever the rayon thread count. Blocks
/// run in parallel (rayon) when there is more than one.
pub fn shot_profile(sampler: &ShotSampler, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
    assert_eq!(
        acc.len(),
        sampler.bins(),
        "accumulator length != number of bins"
    );
    let nblocks = shots.div_ceil(SHOT_BLOCK);
    let block_shots = |b: u64| SHOT_BLOCK.min(shots - b * SHOT_BLOCK);
    if nblocks <= 1 {
        if shots > 0 {
            sampler.add_shots(&mut stream_rng(seed, profile, 0), shots, acc);
        }
        return;
    }
    let bins = sampler.bins();
    let sum = (0..nblocks)
        .into_par_iter()
        .fold(
            || vec![0u64; bins],
            |mut part, b| {
                sampler.add_shots(&mut stream_rng(seed, profile, b), block_shots(b), &mut part);
                part
            },
        )
        .reduce_with(|mut x, y| {
            x.iter_mut().zip(&y).for_each(|(a, b)| *a += b);
            x
        })
        .expect("at least one block");
    acc.iter_mut().zip(&sum).for_each(|(a, b)| *a += b);
}

/// Accumulate one profile of `shots` shots by an [`AggregateSampler`] (samplers built
/// once for the fixed means) into `acc`, from `stream_rng(seed, profile, AGGREGATE_STREAM)`.
pub fn aggregate_profile_fixed(
    sampler: &AggregateSampler,
    seed: u64,
    profile: u64,
    shots: u64,
    acc: &mut [u64],
) {
    let mut rng = stream_rng(seed, profile, AGGREGATE_STREAM);
    sampler.add_profile(&mut rng, shots, acc);
}

/// Accumulate one profile of `shots` shots by [`add_aggregate`] (one exact
/// Poisson(`shots·λ_i`) per bin) into `acc`, from
/// `stream_rng(seed, profile, AGGREGATE_STREAM)`.
pub fn aggregate_profile(
    lambda_per_bin: &[f64],
    seed: u64,
    profile: u64,
    shots: u64,
    acc: &mut [u64],
) {
    let mut rng = stream_rng(seed, profile, AGGREGATE_STREAM);
    add_aggregate(&mut rng, lambda_per_bin, shots, acc);
}
