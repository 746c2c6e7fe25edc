//! The realizations' exact per-bin sums and their comparison with the model, bin by
//! bin: what `validate` draws, adds and tests.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::detector::DeadTime;
use crate::scenario::{ExpectedProfile, Lidar};
use crate::simulate::{self, ResolvedMethod, RunEnergy, StreamSampler};

use super::calibration::Check;
use super::exact;
use super::model::BinModel;
use super::model::central_moments;
use super::report::{BinReport, Stat};
use super::statistics::MIN_TOTAL_COUNTS;
use super::statistics::{MeanVar, mean_z, snr_stat, variance_stat, verdicts};

/// Fewest realizations `validate` accepts: below, the small-sample laws of `s²` and
/// `x̄/s` leave the stated false-alarm rate (measured: 84 of 100 seeds INCONSISTENT at
/// N = 10 before the corrections of [`calibration`]); see `validation/README.md`.
pub const MIN_REALIZATIONS: usize = 100;

/// Exact sums of one bin over realizations: of the count `c`, and of `u = n_b·c − B`
/// where `B` sums the channel's `n_b` signal-free bins of the same profile (the
/// estimated-background count is `y = c − B/n_b = u/n_b`). Integers, so that sums over
/// shards add up to the single run's exactly ([`exact`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct BinSums {
    /// Σc.
    #[serde(with = "exact::decimal")]
    pub(super) total: u128,
    /// Σc².
    #[serde(with = "exact::decimal")]
    pub(super) squares: u128,
    /// Σu.
    #[serde(with = "exact::decimal")]
    pub(super) u: i128,
    /// Σu².
    #[serde(with = "exact::decimal")]
    pub(super) u_squares: u128,
}

impl BinSums {
    /// One realization's count `c` and background sum `b` over `n_b` bins.
    pub(super) fn push(&mut self, c: u64, b: u64, n_b: usize) {
        let u = n_b as i128 * i128::from(c) - i128::from(b);
        self.total += u128::from(c);
        self.squares += u128::from(c) * u128::from(c);
        self.u += u;
        self.u_squares += u.unsigned_abs() * u.unsigned_abs();
    }

    /// The sums of both.
    pub(super) fn add(&mut self, o: &BinSums) {
        self.total += o.total;
        self.squares += o.squares;
        self.u += o.u;
        self.u_squares += o.u_squares;
    }
}

/// A source of realizations: per profile index, the window's counts. `validate` uses the
/// simulator's samplers; tests feed deliberately wrong ones.
pub trait RealizationSource: Sync {
    /// Counts of realization `p` into `counts` (zeroed).
    fn draw(&self, p: u64, counts: &mut [u64]);
}

/// The simulator's own realizations (what `simulate` writes for the same seed): every
/// channel's counts, channel-major.
pub struct SimulatorSource {
    pub(super) channels: Vec<(StreamSampler, u64)>,
    pub(super) shots: u64,
}

impl SimulatorSource {
    /// The sampler of `method` for the expectations `e`, pulse-energy `jitter` (one
    /// channel, ideal detector).
    pub fn new(
        e: &ExpectedProfile,
        method: ResolvedMethod,
        jitter: f64,
        seed: u64,
        shots: u64,
    ) -> Self {
        let rest = vec![e.background + e.dark; e.n_bins()];
        SimulatorSource {
            channels: vec![(
                StreamSampler::new(method, &e.photon_signal(), &rest, jitter),
                seed,
            )],
            shots,
        }
    }

    /// The same source with the detector's dead time applied (method `shot`).
    pub fn with_detector(mut self, dead: Option<DeadTime>) -> Self {
        self.channels = self
            .channels
            .into_iter()
            .map(|(s, seed)| (s.through_detector(dead), seed))
            .collect();
        self
    }

    /// Every channel of `lidar`, as `simulate` draws them.
    pub fn for_lidar(
        lidar: &Lidar,
        expected: &[ExpectedProfile],
        method: ResolvedMethod,
        energy: RunEnergy,
        seed: u64,
    ) -> Self {
        let channels = lidar
            .channels
            .iter()
            .zip(expected)
            .enumerate()
            .map(|(k, (c, e))| {
                let rest = vec![e.background + e.dark; e.n_bins()];
                let sampler = StreamSampler::with_energy(method, &e.photon_signal(), &rest, energy)
                    .through_detector(c.instrument.dead_time)
                    .every_photon(c.instrument.glued)
                    .through_analog(c.instrument.analog.as_ref())
                    .through_afterpulsing(c.instrument.afterpulsing.as_ref());
                (
                    sampler,
                    simulate::channel_seed(seed, lidar.photon_source(k)),
                )
            })
            .collect();
        SimulatorSource {
            channels,
            shots: lidar.first().shots_per_profile(),
        }
    }
}

impl RealizationSource for SimulatorSource {
    fn draw(&self, p: u64, counts: &mut [u64]) {
        let n = counts.len() / self.channels.len();
        for ((sampler, seed), part) in self.channels.iter().zip(counts.chunks_mut(n)) {
            sampler.profile_counts(*seed, p, self.shots, part);
        }
    }
}

/// The bins of one channel within the concatenated profile, and the signal-free bins
/// (absolute indices) its background is estimated from.
#[derive(Debug, Clone)]
pub struct ChannelBins {
    /// The channel's name.
    pub name: String,
    /// Its bins, `offset..offset + n_bins` of the concatenated profile.
    pub bins: std::ops::Range<usize>,
    /// Its signal-free bins, absolute indices.
    pub background: Vec<usize>,
}

impl ChannelBins {
    /// One channel holding every bin.
    pub fn single(n_bins: usize, background: &[usize]) -> Vec<ChannelBins> {
        vec![ChannelBins {
            name: String::new(),
            bins: 0..n_bins,
            background: background.to_vec(),
        }]
    }
}

/// Draws realizations `rows` from `source` and accumulates the per-bin sums (exact: the
/// result does not depend on the thread count, nor on how the realizations are cut into
/// shards). The background estimate of a profile is, per channel, the mean of its own
/// counts in the channel's signal-free bins (as a retrieval would take them from the file).
pub(super) fn accumulate(
    source: &dyn RealizationSource,
    rows: std::ops::Range<usize>,
    bins: usize,
    channels: &[ChannelBins],
) -> Vec<BinSums> {
    let mut sums = vec![BinSums::default(); bins];
    let batch = ((8 << 20) / bins.max(1)).clamp(1, 4096);
    for first in rows.clone().step_by(batch) {
        let last = (first + batch).min(rows.end);
        let drawn: Vec<Vec<u64>> = (first..last)
            .into_par_iter()
            .map(|p| {
                let mut c = vec![0u64; bins];
                source.draw(p as u64, &mut c);
                c
            })
            .collect();
        for c in &drawn {
            for ch in channels {
                let b: u64 = ch.background.iter().map(|&i| c[i]).sum();
                for i in ch.bins.clone() {
                    sums[i].push(c[i], b, ch.background.len());
                }
            }
        }
    }
    sums
}

/// Compares the accumulated sums with the model, bin by bin; each channel's signal-free
/// bins are not tested for the estimated-background S/N.
pub(super) fn bin_reports(
    sums: &[BinSums],
    models: &[BinModel],
    altitudes: &[f64],
    n: usize,
    channels: &[ChannelBins],
) -> Vec<BinReport> {
    let nf = n as f64;
    channels
        .iter()
        .flat_map(|ch| ch.bins.clone().map(move |i| (ch, i)))
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|(ch, i)| {
            let (s, m) = (&sums[i], &models[i]);
            let [k1, k2, k3, k4] = m.cumulants;
            let enough = nf * k1 >= MIN_TOTAL_COUNTS;
            let (z, shape) = mean_z(s.total, nf, m);
            let mean = Stat {
                empirical: s.total as f64 / nf,
                model: k1,
                z,
                shape,
            };
            let (mu2, mu3, mu4) = central_moments(k2, k3, k4);
            let x = MeanVar::of(n, s.total as i128, s.squares, 1.0);
            let variance = variance_stat(&x, m, nf, enough);
            let snr_known = snr_stat(&x, m, m.rest, (mu2, mu3, mu4), nf, enough);
            // y = c − b̂: cumulants of c plus (−1)^n those of b̂ (mean of n_b Poisson(rest))
            let n_b = ch.background.len();
            let snr_est = if n_b > 0 && !ch.background.contains(&i) {
                let nb = n_b as f64;
                let (b2, b3, b4) = (m.rest / nb, -m.rest / (nb * nb), m.rest / (nb * nb * nb));
                let y = central_moments(k2 + b2, k3 + b3, k4 + b4);
                let sample = MeanVar::of(n, s.u, s.u_squares, nb);
                snr_stat(&sample, m, 0.0, y, nf, enough)
            } else {
                Stat {
                    empirical: f64::NAN,
                    model: f64::NAN,
                    z: None,
                    shape: None,
                }
            };
            BinReport {
                channel: ch.name.clone(),
                bin: i - ch.bins.start,
                altitude_m: altitudes[i],
                mean,
                variance,
                snr_known_background: snr_known,
                snr_estimated_background: snr_est,
            }
        })
        .collect()
}

/// Validates `source` against `models`: the core of `lidarsim validate`, open to any
/// sampler. `background` are the signal-free bins the background is estimated from.
pub fn validate_source(
    source: &dyn RealizationSource,
    models: &[BinModel],
    altitudes: &[f64],
    realizations: usize,
    background: &[usize],
) -> (Vec<BinReport>, Vec<Check>) {
    let channels = ChannelBins::single(models.len(), background);
    validate_channels(source, models, altitudes, realizations, &channels)
}

/// As [`validate_source`] for profiles of several channels: `models` and `altitudes`
/// are concatenated channel by channel as `channels` lays them out.
pub fn validate_channels(
    source: &dyn RealizationSource,
    models: &[BinModel],
    altitudes: &[f64],
    realizations: usize,
    channels: &[ChannelBins],
) -> (Vec<BinReport>, Vec<Check>) {
    let sums = accumulate(source, 0..realizations, models.len(), channels);
    let bins = bin_reports(&sums, models, altitudes, realizations, channels);
    let checks = verdicts(&bins);
    (bins, checks)
}
