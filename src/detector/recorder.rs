//! The detector stage of the shot path ([`ShotRecorder`]) and one profile recorded
//! through it, shot for shot ([`recorded_profile`]).

use rand::Rng;

use crate::sampling::{SHOT_BLOCK, ShotCounts, ShotSampler, add_block_sums, stream_rng};

/// A detector stage that records each shot's photons (dead time, the analog chain):
/// its own random draws come from streams of their own, so that the photons are those
/// of the shot path without it, shot for shot.
pub trait ShotRecorder: Sync {
    /// Reusable buffers of one block of shots.
    type Scratch: Default;
    /// Seed offset of the stage's streams (`stream_rng(seed ^ STREAM, profile, block)`).
    const STREAM: u64;
    /// Records one shot whose photons per bin are `photons`, adding into `acc`.
    fn record_shot<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        photons: &ShotCounts,
        scratch: &mut Self::Scratch,
        acc: &mut [u64],
    );
}

/// Accumulates one profile of `shots` shots through `detector` into `acc`: the photons
/// of each shot drawn by `photons` (the shot path) from `stream_rng(seed, profile,
/// block)`, the detector's draws from its own stream; blocks of [`SHOT_BLOCK`] shots
/// summed in integers, so the record does not depend on the thread count.
pub fn recorded_profile<D: ShotRecorder>(
    photons: &ShotSampler,
    detector: &D,
    seed: u64,
    profile: u64,
    shots: u64,
    acc: &mut [u64],
) {
    let bins = acc.len();
    add_block_sums(acc, shots.div_ceil(SHOT_BLOCK), |b| {
        let mut part = vec![0u64; bins];
        let mut scratch = D::Scratch::default();
        let n = SHOT_BLOCK.min(shots - b * SHOT_BLOCK);
        let mut own = stream_rng(seed ^ D::STREAM, profile, b);
        photons.for_each_shot(&mut stream_rng(seed, profile, b), n, |shot| {
            detector.record_shot(&mut own, shot, &mut scratch, &mut part)
        });
        part
    });
}
