//! One shot through the dead time ([`DeadTime::record_shot`]): each bin's count from its
//! counting distribution, or the photons' arrival times swept in time order.

use rand::Rng;

use super::model::{DeadTime, DeadTimeModel};
use crate::detector::counting::{self, Drawn, RateLaw};
use crate::sampling::ShotCounts;

/// Seed offset of the arrival-time streams.
pub const ARRIVAL_STREAM: u64 = 0xA441_7A1E_0000_0001;

impl DeadTime {
    /// Records one shot: `photons` holds the shot's true counts per bin (bins in time
    /// order); the recorded counts are added to `acc`. `scratch` holds reusable buffers.
    ///
    /// A lone photon between empty bins is recorded without drawing its time (an empty
    /// bin is at least τ long when Δt ≥ τ, so no other photon is within τ of it): that is
    /// most photons of a sparse shot, which so costs little more than without dead time.
    /// The other bins are swept in runs of adjacent bins, the detector live again after
    /// each empty bin.
    pub fn record_shot<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        photons: &ShotCounts,
        scratch: &mut Scratch,
        acc: &mut [u64],
    ) {
        if self.by_counts() {
            return self.record_by_counts(rng, photons, scratch, acc);
        }
        let counts = photons.counts();
        let independent_runs = self.tau_s <= self.bin_width_s;
        let empty = |b: usize| counts.get(b).is_none_or(|&c| c == 0);
        scratch.hit.clear();
        for &b in photons.hit_bins() {
            let i = b as usize;
            // a lone photon between empty bins meets no other within τ: recorded
            if independent_runs && counts[i] == 1 && (i == 0 || empty(i - 1)) && empty(i + 1) {
                acc[i] += 1;
            } else {
                scratch.hit.push(b);
            }
        }
        if !scratch.hit.is_sorted() {
            scratch.hit.sort_unstable();
        }
        let mut start = 0;
        while start < scratch.hit.len() {
            let mut end = start + 1;
            while end < scratch.hit.len()
                && (!independent_runs || scratch.hit[end] == scratch.hit[end - 1] + 1)
            {
                end += 1;
            }
            self.sweep(
                rng,
                counts,
                &scratch.hit[start..end],
                &mut scratch.times,
                acc,
            );
            start = end;
        }
    }

    /// Whether [`record_shot`](Self::record_shot) draws each bin's recorded count from
    /// its counting distribution ([`counting`]) rather than sweeping arrival times: a
    /// non-paralyzable detector on bins at least 2τ wide.
    pub fn by_counts(&self) -> bool {
        self.model == DeadTimeModel::Nonparalyzable && self.bin_width_s >= 2.0 * self.tau_s
    }

    /// [`record_shot`](Self::record_shot) by counting distributions.
    fn record_by_counts<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        photons: &ShotCounts,
        scratch: &mut Scratch,
        acc: &mut [u64],
    ) {
        self.record_runs(rng, photons, &NO_LAWS, scratch, acc);
    }

    /// Records one shot by counting distributions: the bins with a law in `bins` (by
    /// index; may be none) from [`RateLaw`] (their photons not drawn), the other
    /// hit bins given their photons ([`counting::Family`]). Each run of adjacent such
    /// bins in time order, the dead time left by a bin carried into the next (an empty
    /// bin, at least τ wide, ends it); the dense law bins' first draws all first, in bin
    /// order. A lone photon (one in its bin, none next to it) is recorded without a draw;
    /// a bin of more than [`counting::MAX_PHOTONS`] photons by its arrival times.
    pub(super) fn record_runs<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        photons: &ShotCounts,
        bins: &LawBins,
        scratch: &mut Scratch,
        acc: &mut [u64],
    ) {
        let (tau, dt) = (self.tau_s, self.bin_width_s);
        let LawBins {
            laws,
            starts,
            ends,
            dense,
        } = bins;
        let Scratch {
            times,
            hit: runs,
            family,
            drawn,
        } = scratch;
        if !family.as_ref().is_some_and(|f| f.is_for(tau, dt)) {
            *family = Some(counting::family(tau, dt));
        }
        let family = family.as_deref().expect("set above");
        let counts = photons.counts();
        let has_law = |i: usize| laws.get(i).is_some_and(Option::is_some);
        let active = |i: usize| counts.get(i).is_some_and(|&c| c > 0) || has_law(i);
        // lone photons at once (without branches on their outcome), the first bins of
        // the other runs kept
        let hits = photons.hit_bins();
        runs.clear();
        runs.resize(hits.len(), 0);
        let mut len = 0;
        for &b in hits {
            let i = b as usize;
            let prev = i > 0 && active(i - 1);
            let lone = (counts[i] == 1) & !prev & !active(i + 1);
            acc[i] += u64::from(lone);
            runs[len] = b;
            len += usize::from(!lone & !prev);
        }
        // every dense law bin's body first, in bin order (their table loads overlap)
        drawn.resize(laws.len(), Drawn::default());
        {
            for &i in dense {
                if let Some(law) = &laws[i as usize] {
                    drawn[i as usize] = law.draw_body(rng);
                }
            }
        }
        let first_law_bins = starts
            .iter()
            .filter(|&&a| a == 0 || !active(a as usize - 1));
        for &start in runs[..len].iter().chain(first_law_bins) {
            let (mut i, mut r) = (start as usize, 0.0);
            loop {
                if has_law(i) {
                    // a run of law bins (i is its first), in one loop
                    let end = ends[i] as usize;
                    for ((law, d), a) in laws[i..end]
                        .iter()
                        .zip(&drawn[i..end])
                        .zip(&mut acc[i..end])
                    {
                        let Some(law) = law else { continue };
                        let (k, left) = if law.dense {
                            law.finish(d, r)
                        } else {
                            law.record(rng, r)
                        };
                        *a += u64::from(k);
                        r = left;
                    }
                    if !active(end) {
                        break;
                    }
                    i = end;
                    continue;
                }
                let next = active(i + 1);
                let n = counts[i];
                let (k, left) = if n <= counting::MAX_PHOTONS {
                    family.record_bin(rng, n, r, next)
                } else {
                    self.sweep_bin(rng, n, r, times)
                };
                acc[i] += u64::from(k);
                if !next {
                    break;
                }
                r = left;
                i += 1;
            }
        }
    }

    /// One bin of `n` photons by its arrival times, entered dead for `r`
    /// (non-paralyzable): the recorded count and the dead time left at its end.
    fn sweep_bin<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        n: u32,
        r: f64,
        times: &mut Vec<f64>,
    ) -> (u32, f64) {
        sorted_uniform_times(rng, n, 0.0, self.bin_width_s, times);
        let (mut k, mut live_at) = (0u32, r);
        for &t in times.iter() {
            if t >= live_at {
                k += 1;
                live_at = t + self.tau_s;
            }
        }
        (k, (live_at - self.bin_width_s).max(0.0))
    }

    /// Draws the arrival times of the photons of `bins` (sorted, in time order), bin by
    /// bin (bins are ordered, so only a bin's own times need sorting), and records those
    /// that find the detector live; the detector is live at the first bin's start.
    fn sweep<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        counts: &[u32],
        bins: &[u32],
        times: &mut Vec<f64>,
        acc: &mut [u64],
    ) {
        let dt = self.bin_width_s;
        let mut live_at = f64::NEG_INFINITY;
        for &b in bins {
            sorted_uniform_times(rng, counts[b as usize], b as f64 * dt, dt, times);
            for &t in times.iter() {
                let live = t >= live_at;
                if live {
                    // dead time crosses bin edges, a count stays in the bin it arrived in
                    acc[b as usize] += 1;
                }
                if live || self.model == DeadTimeModel::Paralyzable {
                    live_at = t + self.tau_s;
                }
            }
        }
    }
}

/// Photons above which a bin's arrival times are drawn already sorted (exponential
/// spacings) rather than drawn and sorted: measured crossover on this machine.
const SPACINGS_FROM: u32 = 24;

/// `n` arrival times uniform in `[start, start + width)`, in increasing order: drawn and
/// sorted for few photons, else as normalized cumulative sums of n + 1 standard
/// exponentials (the uniform order statistics; Devroye 1986, *Non-Uniform Random
/// Variate Generation*, §V.2), which costs O(n) instead of O(n log n).
pub(super) fn sorted_uniform_times<R: Rng + ?Sized>(
    rng: &mut R,
    n: u32,
    start: f64,
    width: f64,
    times: &mut Vec<f64>,
) {
    times.clear();
    if n < SPACINGS_FROM {
        times.extend((0..n).map(|_| start + width * unit_f64(rng.next_u64())));
        if n > 1 {
            times.sort_unstable_by(f64::total_cmp);
        }
        return;
    }
    let mut sum = 0.0;
    for _ in 0..n {
        sum -= (1.0 - unit_f64(rng.next_u64())).ln();
        times.push(sum);
    }
    sum -= (1.0 - unit_f64(rng.next_u64())).ln();
    let scale = width / sum;
    times.iter_mut().for_each(|t| *t = start + *t * scale);
}

/// Reusable buffers of [`DeadTime::record_shot`]: no allocation per shot.
#[derive(Debug, Default, Clone)]
pub struct Scratch {
    times: Vec<f64>,
    hit: Vec<u32>,
    /// The counting tables of the last (τ, Δt) recorded.
    family: Option<std::sync::Arc<counting::Family>>,
    /// Per law bin, its body drawn.
    drawn: Vec<Drawn>,
}

impl crate::detector::recorder::ShotRecorder for DeadTime {
    type Scratch = Scratch;
    const STREAM: u64 = ARRIVAL_STREAM;

    fn record_shot<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        photons: &ShotCounts,
        scratch: &mut Scratch,
        acc: &mut [u64],
    ) {
        DeadTime::record_shot(self, rng, photons, scratch, acc)
    }
}

/// The bins drawn from their counting law.
#[derive(Debug, Clone)]
pub(super) struct LawBins {
    /// Per bin, its law if it has one (empty: none has).
    pub(super) laws: Vec<Option<RateLaw>>,
    /// The first bins of the runs of law bins.
    pub(super) starts: Vec<u32>,
    /// At the first bin of each such run, the bin past its end.
    pub(super) ends: Vec<u32>,
    /// The bins of dense laws ([`RateLaw::dense`]).
    pub(super) dense: Vec<u32>,
}

/// No bin drawn from its law.
static NO_LAWS: LawBins = LawBins {
    laws: Vec::new(),
    starts: Vec::new(),
    ends: Vec::new(),
    dense: Vec::new(),
};

/// A uniform in [0, 1) from the top 53 bits of `x`.
fn unit_f64(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sorted_times_are_uniform_order_statistics_on_both_paths() {
        // the k-th of n sorted uniforms has mean k/(n+1); both paths, 20,000 draws
        for n in [5u32, 100] {
            let mut rng = crate::sampling::stream_rng(9, n as u64, 0);
            let mut times = Vec::new();
            let mut mean = vec![0.0; n as usize];
            for _ in 0..20_000 {
                sorted_uniform_times(&mut rng, n, 10.0, 2.0, &mut times);
                assert!(times.windows(2).all(|w| w[0] <= w[1]));
                assert!(times.iter().all(|t| (10.0..12.0).contains(t)));
                times
                    .iter()
                    .zip(&mut mean)
                    .for_each(|(t, m)| *m += (t - 10.0) / 2.0 / 20_000.0);
            }
            for (k, m) in mean.iter().enumerate() {
                let want = (k + 1) as f64 / (n + 1) as f64;
                // sd of the mean of U_(k): sqrt(want(1-want)/(n+2)/20000) <= 0.0025
                assert!((m - want).abs() < 0.0125, "n={n} k={k}: {m} vs {want}");
            }
        }
    }
}
