//! One exact Poisson draw per bin for a whole profile.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use super::shot::ShotSampler;
use rand::Rng;

/// One exact Poisson(`shots`·λ_i) draw per bin, added into `acc`: exact when
/// nothing varies from shot to shot and the detector is linear (docs/simulation.md),
/// since a sum of `shots` independent Poisson(λ_i) is Poisson(`shots`·λ_i).
/// See [`poisson_u64`](super::poisson::poisson_u64) for the algorithms and their precision; O(bins).
pub fn add_aggregate<R: Rng + ?Sized>(
    rng: &mut R,
    lambda_per_bin: &[f64],
    shots: u64,
    acc: &mut [u64],
) {
    // the approximate sampler with an infinite threshold draws every bin exactly
    super::approx::add_aggregate_approx(rng, lambda_per_bin, shots, f64::INFINITY, acc);
}

/// Largest `M·λ` of a bin for which [`AggregateSampler`] prebuilds the profile's
/// samplers (a [`ShotSampler`] counts in `u32`: at `10^9` a count past `2^32` is
/// 10^5 standard deviations away); profiles with a larger mean are drawn by
/// [`add_aggregate`].
pub const AGGREGATE_PREBUILT_MAX: f64 = 1e9;

/// One exact Poisson(`M·λ_i`) draw per bin for fixed per-shot means `λ_i`, with every
/// bin's sampler built once per `M` (issue 11): the profile is one "shot" of a
/// [`ShotSampler`] over the means `M·λ_i`, which picks per bin the cheapest exact path
/// (table inversion, an alias table over the PMF, Ahrens–Dieter, or the sparse
/// Poisson-total-and-placement path for the faintest bins) by its measured cost model,
/// instead of [`add_aggregate`]'s `exp` and search per draw. The same law; the draws
/// depend on `(seed, profile, M)` only (the samplers for `M` are the same whenever they
/// are built), so any profile can be regenerated alone.
#[derive(Debug, Clone)]
pub struct AggregateSampler {
    lambda: Vec<f64>,
    /// The samplers built so far, by `M` (`None`: a mean past [`AGGREGATE_PREBUILT_MAX`]).
    built: Arc<Mutex<HashMap<u64, Arc<Option<ShotSampler>>>>>,
}

impl AggregateSampler {
    /// The sampler for per-shot means `lambda_per_bin` (finite, `≥ 0`).
    pub fn new(lambda_per_bin: &[f64]) -> Self {
        AggregateSampler {
            lambda: lambda_per_bin.to_vec(),
            built: Arc::default(),
        }
    }

    /// The samplers of the profile means `shots·λ_i`, built on first use.
    fn for_shots(&self, shots: u64) -> Arc<Option<ShotSampler>> {
        let mut built = self.built.lock().unwrap_or_else(|e| e.into_inner());
        built
            .entry(shots)
            .or_insert_with(|| {
                let m = shots as f64;
                let means: Vec<f64> = self.lambda.iter().map(|l| l * m).collect();
                let largest = means.iter().fold(0.0f64, |a, &b| a.max(b));
                Arc::new((largest <= AGGREGATE_PREBUILT_MAX).then(|| ShotSampler::new(&means)))
            })
            .clone()
    }

    /// Adds one profile of `shots` shots into `acc`, drawn from `rng`.
    pub fn add_profile<R: Rng + ?Sized>(&self, rng: &mut R, shots: u64, acc: &mut [u64]) {
        match self.for_shots(shots).as_ref() {
            Some(sampler) => sampler.add_shot(rng, acc),
            None => add_aggregate(rng, &self.lambda, shots, acc),
        }
    }
}
