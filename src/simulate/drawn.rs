//! One drawn profile of every channel, as the file stores it, and the draw of a static
//! scene's profile.

use super::energy::RunEnergy;
use super::sampler::StreamSampler;

/// One profile of every channel, channel-major, as the file stores it.
pub struct DrawnProfile {
    /// Recorded counts, channel-major.
    pub counts: Vec<u64>,
    pub(super) components: Option<[Vec<u64>; 3]>,
    /// Sum of the shots' energy factors (the energy monitor's reading × M / E0).
    pub(super) energy_sum: f64,
    /// The rows of the per-profile variables (a changing scene's truth: expected signal,
    /// background, recorded counts per shot, S/N, attenuated backscatter).
    pub values: Vec<Vec<f64>>,
    /// The columns the profile's shots saw and their shares (`profile_column`,
    /// `profile_column_weight`), padded to the file's slots; `None` in a static scene
    /// (its one column, [`STATIC_COLUMN`]).
    pub columns: Option<(Vec<i32>, Vec<f64>)>,
}

/// Index in [`DrawnProfile::values`] of a changing scene's expected recorded counts per shot.
pub const RECORDED_ROW: usize = 2;

/// Draws profile `p` of every channel's streams.
pub fn draw_profile(
    channels: &[Vec<(StreamSampler, u64)>],
    p: u64,
    shots: u64,
    n_bins: usize,
    components: bool,
    energy: &RunEnergy,
) -> DrawnProfile {
    let len = channels.len() * n_bins;
    let mut counts = vec![0u64; len];
    let mut parts: Option<[Vec<u64>; 3]> =
        components.then(|| std::array::from_fn(|_| vec![0; len]));
    for (k, streams) in channels.iter().enumerate() {
        let bins = k * n_bins..(k + 1) * n_bins;
        for (c, (sampler, stream_seed)) in streams.iter().enumerate() {
            match parts.as_mut() {
                // component c of channel k, added into the channel's counts too
                Some(parts) => {
                    let part = &mut parts[c][bins.clone()];
                    sampler.profile_counts(*stream_seed, p, shots, part);
                    let acc = &mut counts[bins.clone()];
                    acc.iter_mut().zip(part.iter()).for_each(|(a, x)| *a += x);
                }
                None => sampler.profile_counts(*stream_seed, p, shots, &mut counts[bins.clone()]),
            }
        }
    }
    let energy_seed = energy.seed.unwrap_or_default();
    DrawnProfile {
        counts,
        components: parts,
        energy_sum: energy.law.profile_sum(energy_seed, p, shots),
        values: Vec::new(),
        columns: None,
    }
}

impl DrawnProfile {
    /// Sum of the shots' energy factors (relative to the nominal energy).
    pub fn energy_sum(&self) -> f64 {
        self.energy_sum
    }
}

/// The columns of every profile of a static scene: its one column, all the shots.
pub const STATIC_COLUMN: (&[i32], &[f64]) = (&[0], &[1.0]);

/// The distinct columns of a profile's `runs` (column, shots) in the order first seen,
/// with the share of the shots that saw each, padded with (−1, 0) to `slots`.
pub fn profile_columns(runs: &[(usize, u64)], slots: usize) -> (Vec<i32>, Vec<f64>) {
    let shots: u64 = runs.iter().map(|r| r.1).sum();
    let mut columns: Vec<i32> = Vec::with_capacity(slots);
    let mut counts: Vec<u64> = Vec::with_capacity(slots);
    for &(col, n) in runs {
        let col = col as i32;
        match columns.iter().position(|&c| c == col) {
            Some(j) => counts[j] += n,
            None => {
                columns.push(col);
                counts.push(n);
            }
        }
    }
    let mut weights: Vec<f64> = counts.iter().map(|&n| n as f64 / shots as f64).collect();
    columns.resize(slots.max(columns.len()), -1);
    weights.resize(columns.len(), 0.0);
    (columns, weights)
}
