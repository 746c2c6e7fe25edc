//! Photon-count samplers (issue 3; docs/simulation.md).
//!
//! Per laser shot and range bin `i` the detected count is Poisson with mean
//! `λ_i = λ_sig,i + λ_bkg + λ_dc`, independent across bins and shots; a
//! profile accumulates `M` shots.
//!
//! * [`ShotSampler`]: exact draw of one shot, built once per set of means
//!   and reused for every shot. It mixes four exact paths per bin (dense
//!   table inversion, dense alias table over the PMF ([`PmfAlias`]), dense
//!   rejection from a step envelope over the PMF ([`PmfCells`]), dense
//!   Ahrens–Dieter, and the sparse "Poisson total + alias placement" path) by
//!   a measured cost model: see its docs and [`cost`].
//! * [`AggregateSampler`]: one Poisson(`M·λ_i`) draw per bin for fixed means,
//!   every bin's sampler built once (a [`ShotSampler`] over `M·λ_i`); exact
//!   when nothing varies from shot to shot and the detector is linear.
//! * [`add_aggregate`]: the same draw for means that change from profile to
//!   profile, computed on the fly (inversion or Ahrens–Dieter).
//! * [`stream_rng`], [`shot_profile`], [`aggregate_profile`]: reproducible
//!   streams. A profile's shots are cut into blocks of [`SHOT_BLOCK`] shots,
//!   block `b` of profile `p` drawn from `stream_rng(seed, p, b)`, and the
//!   integer block sums added: the result depends on the seed only, never on
//!   the rayon thread count or the schedule, and any profile, or any block of
//!   shots, can be regenerated alone.
//!
//! All counts are consumed through [`CountSink`] (`(bin, count)` events), so
//! the same sampler feeds accumulators (`[u64]`), per-shot buffers
//! ([`ShotCounts`]) or, later, a detector model.
//!
//! # Extension points
//!
//! Built since (see [`jitter`], and `src/detector/`, `src/onboard/` which use this
//! module, never the other way): per-shot varying means by thinning, the dead-time
//! detector wrapping a sampler, component colouring by separate streams, onboard sums
//! through [`ShotSampler::for_each_shot`].
//! The notes as first written:
//!
//! * **Per-shot varying means.** Pulse-energy jitter scales the signal part by
//!   `e_s` per shot: keep a sampler for the signal and one for background +
//!   dark (their sum has the same law). The sparse path's alias table depends
//!   only on the *shape* `λ_i/Σλ`, so a scaled shot only needs its total
//!   `N ~ Poisson(e_s·Λ)` redrawn ([`poisson_u64`]) and the same placement.
//!   Alternatively, exact thinning: build at the envelope `e_max·λ` and keep
//!   each count with probability `e_s/e_max` (per-shot binomial thinning of a
//!   Poisson is Poisson). A scene that changes along the track rebuilds the
//!   sampler per segment (O(n log n)) or thins against an envelope.
//! * **Detector stage (dead time, pile-up).** A sink receives each shot's
//!   `(bin, count)` events; given `k` counts in a bin, their arrival times are
//!   `k` i.i.d. draws from the within-bin rate profile (uniform for a
//!   constant rate), so a detector sink can draw times and apply dead time
//!   without any change here.
//! * **Component-resolved output.** Colour each count by its component with
//!   probabilities `λ_sig/λ`, `λ_bkg/λ`, `λ_dc/λ` (exact Poisson colouring),
//!   or run one sampler per component.
//! * **Onboard processing.** [`ShotSampler::for_each_shot`] hands every shot
//!   as a [`ShotCounts`] (dense counts plus the list of bins hit) to a
//!   closure, without allocating per shot.

mod aggregate;
pub(crate) mod alias;
pub mod approx;
pub mod jitter;
mod pmf_alias;
mod pmf_cells;
mod shot;
mod table;
#[cfg(test)]
mod tests;

pub use aggregate::{
    AGGREGATE_CHUNK, AGGREGATE_INVERSION_MAX, AGGREGATE_PREBUILT_MAX, AggregateSampler,
    add_aggregate, poisson_u64,
};
pub(crate) use alias::AliasTable;
pub use pmf_alias::{PmfAlias, pmf_alias_columns};
pub use pmf_cells::{CELLS_PER_SIGMA, PmfCells, pmf_cells_bytes};
pub use shot::{
    ALIAS_BUDGET_BYTES, DENSE_ALIAS_MAX, DENSE_TABLE_MAX, DenseMethod, PathChoice, ShotSampler,
    ShotStrategy, StrategyKind, TOTAL_TABLE_MAX, cost, table_bytes_bound,
};
pub(crate) use table::count_above;

use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;

/// Receiver of one shot's counts as `(bin, count)` events, `count ≥ 1`. A bin
/// may be reported more than once per shot (the sparse path reports one count
/// at a time); the shot's count in a bin is the sum of its events.
pub trait CountSink {
    fn add(&mut self, bin: usize, count: u32);

    /// A count that may be 0 (reported only when it is not, unless the sink can take a
    /// zero for free: an accumulator adds it without a branch that the draws of a bin
    /// with `P(K = 0)` near ½ would mispredict).
    #[inline(always)]
    fn add_any(&mut self, bin: usize, count: u32) {
        if count > 0 {
            self.add(bin, count);
        }
    }
}

/// Accumulator: adds every event into `acc[bin]`.
impl CountSink for [u64] {
    #[inline(always)]
    fn add(&mut self, bin: usize, count: u32) {
        self[bin] += u64::from(count);
    }

    #[inline(always)]
    fn add_any(&mut self, bin: usize, count: u32) {
        self[bin] += u64::from(count);
    }
}

/// One shot's counts: a dense `u32` per bin plus the list of bins hit, cleared
/// in O(bins hit). Capacity is reserved up front: no allocation per shot.
#[derive(Clone, Debug)]
pub struct ShotCounts {
    counts: Vec<u32>,
    hit: Vec<u32>,
}

impl ShotCounts {
    pub fn new(bins: usize) -> Self {
        ShotCounts {
            counts: vec![0; bins],
            hit: Vec::with_capacity(bins),
        }
    }

    /// Counts of every bin in this shot.
    pub fn counts(&self) -> &[u32] {
        &self.counts
    }

    /// Bins with a non-zero count, in first-hit order.
    pub fn hit_bins(&self) -> &[u32] {
        &self.hit
    }

    /// `(bin, count)` of the bins with a non-zero count, in first-hit order.
    pub fn nonzero(&self) -> impl Iterator<Item = (usize, u32)> + '_ {
        self.hit
            .iter()
            .map(|&b| (b as usize, self.counts[b as usize]))
    }

    /// Total number of counts in this shot.
    pub fn total(&self) -> u64 {
        self.nonzero().map(|(_, c)| u64::from(c)).sum()
    }

    /// Reset to zero counts (O(bins hit)).
    pub fn clear(&mut self) {
        for &b in &self.hit {
            self.counts[b as usize] = 0;
        }
        self.hit.clear();
    }
}

impl CountSink for ShotCounts {
    #[inline(always)]
    fn add(&mut self, bin: usize, count: u32) {
        let c = &mut self.counts[bin];
        if *c == 0 {
            self.hit.push(bin as u32);
        }
        *c += count;
    }
}

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
