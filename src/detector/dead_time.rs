//! Detector dead time (docs/model.md §4b): after a recorded count a photon counter is blind
//! for τ. Non-paralyzable: photons in the dead period are lost and do not extend it.
//! Paralyzable: every arriving photon, recorded or not, restarts it.
//!
//! **Sampler** ([`DeadTime::record_shot`], [`DeadTimedShots`]). The rate is taken
//! constant within a bin (as in the model below), dead time crosses bin edges, and the
//! detector is live at the start of the window. Three exact paths:
//!
//! * a non-paralyzable detector on bins at least 2τ wide ([`DeadTime::by_counts`]) draws
//!   each hit bin's recorded count from its counting distribution given the bin's photons
//!   (drawn by the shot path, exactly as without dead time), carrying the dead time
//!   left by a bin into the next ([`counting::Family`]): O(1) per hit bin, a lone photon
//!   without a draw;
//! * [`DeadTimedShots`] (fixed means, what `simulate`'s shot path runs) draws the bins
//!   of at least [`LAW_FROM_PHOTONS`] photons per shot from the counting law at their
//!   rate, without their photons ([`RateLaw`], tables built once per run), and the
//!   others as above;
//! * otherwise (paralyzable, narrow bins) each photon gets an arrival time uniform
//!   within its bin, the shot's arrivals are swept in time order, and a photon is
//!   recorded when the detector is live: O(photons · log photons) per shot.
//!
//! Nothing is drawn when τ = 0 (the scene then has no detector stage at all). Costs:
//! `benches/dead_time_rates.rs`, `validation/reports/dead_time_cost.md`.
//!
//! **Model** ([`DeadTime::recorded_means`]). With the rate n(t) piecewise constant per
//! bin, the mean recorded rate solves (Müller 1973, NIM 112, 47; docs/model.md §4b)
//!
//! ```text
//! non-paralyzable: m(t) = n(t)·(1 − ∫_{t−τ}^{t} m(s) ds)
//! paralyzable:     m(t) = n(t)·exp(−∫_{t−τ}^{t} n(s) ds)
//! ```
//!
//! solved on a grid of step h = min(τ, Δt)/64 by the midpoint rule (each step's rate at
//! its middle, the integral over the last τ a running sum of the earlier steps, the
//! oldest in part, plus half of the step itself, implicit in m), and integrated over each
//! bin. For a stationary rate it gives `n/(1+nτ)` and `n·e^{−nτ}` exactly, whatever τ/h;
//! at a step in the rate its error is O((h/τ)²) of the transient. A window whose grid
//! would exceed [`MAX_GRID_STEPS`] uses the stationary formulas per bin (error O(τ/Δt) at
//! the bin edges).
//!
//! **Variance** ([`DeadTime::recorded_mean_and_variance`]) of a bin's recorded count per
//! shot: non-paralyzable, exact given the dead time the solver carries into each bin
//! ([`super::dead_time_variance`]); paralyzable, the renewal-theory form
//! `mΔt·(1 − 2nτ·e^{−nτ})` at the bin's rate ([`DeadTime::recorded_variance`], whose
//! non-paralyzable `nΔt/(1+nτ)³` is the asymptote for bins much longer than the count's
//! correlation time, ~(nτ)²·τ: 11× too low at nτ = 40 in bins of 40τ).

use rand::Rng;

use super::counting::{self, Drawn, RateLaw};

use crate::sampling::{SHOT_BLOCK, ShotCounts, ShotSampler, add_block_sums, stream_rng};

/// Cost of recording one photon through the arrival-time path (the paralyzable
/// detector, bins narrower than 2τ), ns, for the duration estimate a run announces
/// ([`DeadTime::ns_per_shot`]): measured at 13–21 ns (one thread; 2,631 and 26,309 true
/// photons per shot: `configs/ground/ground_532_depol.toml` with
/// `--set instrument.pulse_energy_j=4e-4` and `4e-3`, `--profiles 1 --threads 1`, the
/// drawing time over shots × photons, on a machine shared with another build). Lone
/// photons cost less (recorded without drawing a time): the estimate errs long.
pub const NS_PER_PHOTON: f64 = 20.0;

/// Cost of one photon recorded given its bin's photons by the counting tables
/// ([`counting::Family`]), and of one bin drawn from its counting law ([`RateLaw`],
/// below and above 64 MHz at τ = 3.5 ns), ns, for the same estimate: measured by
/// `benches/dead_time_rates.rs` (one thread; 0.2 photons per bin: 3.3 ns a bin; 2–20
/// photons: 4.5–7 ns a bin; 100–600: 19–22 ns), the ideal detector's share included.
pub const NS_PER_GIVEN_PHOTON: f64 = 16.0;
/// See [`NS_PER_GIVEN_PHOTON`].
pub const NS_PER_LAW_BIN: f64 = 7.0;
/// See [`NS_PER_GIVEN_PHOTON`].
pub const NS_PER_DENSE_LAW_BIN: f64 = 22.0;

/// Seed offset of the arrival-time streams.
pub const ARRIVAL_STREAM: u64 = 0xA441_7A1E_0000_0001;
/// Most grid steps of the mean-rate solver; beyond, the stationary formulas per bin.
pub const MAX_GRID_STEPS: f64 = 5e7;
/// Grid steps per dead time (and at least per bin).
const STEPS_PER_TAU: f64 = 64.0;

/// How the dead period behaves (a config key's type, so it lives in the config).
pub use crate::config::DeadTimeModel;

/// A photon counter's dead time on a window of bins of equal width.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeadTime {
    /// τ, s (> 0).
    pub tau_s: f64,
    /// Non-paralyzable or paralyzable.
    pub model: DeadTimeModel,
    /// Δt of a bin, s.
    pub bin_width_s: f64,
}

impl DeadTime {
    /// Estimated cost of recording one shot of true means `lambda` per bin, ns (for the
    /// duration a run announces): per photon on the arrival-time path, per bin or photon
    /// by the counting distributions ([`NS_PER_GIVEN_PHOTON`]).
    pub fn ns_per_shot(&self, lambda: &[f64]) -> f64 {
        if !self.by_counts() {
            return lambda.iter().sum::<f64>() * NS_PER_PHOTON;
        }
        lambda
            .iter()
            .map(|&l| {
                if l < LAW_FROM_PHOTONS {
                    l * NS_PER_GIVEN_PHOTON
                } else if counting::is_dense(l / self.bin_width_s, self.tau_s) {
                    NS_PER_DENSE_LAW_BIN
                } else {
                    NS_PER_LAW_BIN
                }
            })
            .sum()
    }

    /// Stationary recorded rate for a true rate `n` (s⁻¹): `n/(1+nτ)` or `n·e^{−nτ}`.
    pub fn stationary_rate(&self, n: f64) -> f64 {
        match self.model {
            DeadTimeModel::Nonparalyzable => n / (1.0 + n * self.tau_s),
            DeadTimeModel::Paralyzable => n * (-n * self.tau_s).exp(),
        }
    }

    /// Mean recorded counts per shot per bin for true means `lambda` per bin (see the
    /// module docs).
    pub fn recorded_means(&self, lambda: &[f64]) -> Vec<f64> {
        self.solve(lambda, |_, _| {})
    }

    /// The mean-rate solver of [`recorded_means`](Self::recorded_means); before each bin
    /// of the grid it hands `entering(bin, last)` the recorded counts of the last steps
    /// before the bin, newest first, each `m·h` of a step of `h` (non-paralyzable: the
    /// detector's dead state entering the bin, [`super::dead_time_variance`]), or `None`
    /// where the grid is too long and the stationary formulas are used.
    pub(crate) fn solve(
        &self,
        lambda: &[f64],
        mut entering: impl FnMut(usize, Option<(&[f64], f64)>),
    ) -> Vec<f64> {
        let dt = self.bin_width_s;
        let h = self.tau_s.min(dt) / STEPS_PER_TAU;
        let per_bin = (dt / h).ceil().max(1.0);
        if per_bin * lambda.len() as f64 > MAX_GRID_STEPS {
            return lambda
                .iter()
                .enumerate()
                .map(|(b, &l)| {
                    entering(b, None);
                    self.stationary_rate(l / dt) * dt
                })
                .collect();
        }
        let per_bin = per_bin as usize;
        let h = dt / per_bin as f64;
        // each step is evaluated at its midpoint t: the last τ before t is half of the
        // step itself and `past` = τ/h − 1/2 earlier steps, the oldest of them in part
        let past = self.tau_s / h - 0.5;
        let lag = past.ceil().max(1.0) as usize;
        let oldest_share = past - (lag as f64 - 1.0);
        // ring buffer of the last `lag` steps: m·h (non-paralyzable) or n·h (paralyzable)
        let mut ring = vec![0.0f64; lag];
        let mut newest_first = Vec::new();
        let (mut pos, mut window) = (0usize, 0.0f64);
        lambda
            .iter()
            .enumerate()
            .map(|(b, &l)| {
                newest_first.clear();
                newest_first.extend((1..=lag).map(|k| ring[(pos + lag - k) % lag]));
                entering(b, Some((&newest_first, h)));
                let n = l / dt;
                let mut recorded = 0.0;
                for _ in 0..per_bin {
                    let before = window - (1.0 - oldest_share) * ring[pos];
                    let (m, pushed) = match self.model {
                        // m = n·(1 − before − m·h/2)
                        DeadTimeModel::Nonparalyzable => {
                            let m = n * (1.0 - before).max(0.0) / (1.0 + 0.5 * n * h);
                            (m, m * h)
                        }
                        DeadTimeModel::Paralyzable => (n * (-(before + 0.5 * n * h)).exp(), n * h),
                    };
                    recorded += m * h;
                    window += pushed - ring[pos];
                    ring[pos] = pushed;
                    pos = (pos + 1) % lag;
                }
                recorded
            })
            .collect()
    }

    /// Mean and variance of each bin's recorded count per shot when the signal varies
    /// from shot to shot with the laser's jitter (`energy`, drift excluded): by the law
    /// of total variance over the shot's energy factor f,
    /// `E[m(f)]` and `E[v(f)] + Var[m(f)]`, with m from [`recorded_means`](Self::recorded_means)
    /// and v from [`recorded_mean_and_variance`](Self::recorded_mean_and_variance) at
    /// `f·signal + rest`.
    pub fn recorded_moments(
        &self,
        signal: &[f64],
        rest: f64,
        energy: &crate::laser::PulseEnergy,
    ) -> (Vec<f64>, Vec<f64>) {
        let n = signal.len();
        let m = energy.jitter_expectation(|f| {
            let lambda: Vec<f64> = signal.iter().map(|s| f * s + rest).collect();
            let (mean, var) = self.recorded_mean_and_variance(&lambda);
            let square = mean.iter().map(|x| x * x).collect::<Vec<f64>>();
            mean.iter().copied().chain(var).chain(square).collect()
        });
        let mean = m[..n].to_vec();
        let var = (0..n)
            .map(|i| m[n + i] + (m[2 * n + i] - m[i] * m[i]).max(0.0))
            .collect();
        (mean, var)
    }

    /// Variance of a bin's recorded count per shot (renewal theory, module docs), for the
    /// bin's true mean `lambda` per shot.
    pub fn recorded_variance(&self, lambda: f64) -> f64 {
        let dt = self.bin_width_s;
        let n = lambda / dt;
        let x = n * self.tau_s;
        match self.model {
            DeadTimeModel::Nonparalyzable => lambda / (1.0 + x).powi(3),
            DeadTimeModel::Paralyzable => {
                let m = lambda * (-x).exp();
                m * (1.0 - 2.0 * x * (-x).exp())
            }
        }
    }

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
    fn record_runs<R: Rng + ?Sized>(
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
fn sorted_uniform_times<R: Rng + ?Sized>(
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

/// One profile through the dead time, every photon drawn ([`super::recorded_profile`];
/// the detector's draws from the arrival stream `seed ^ ARRIVAL_STREAM`).
pub use super::recorded_profile;

impl super::ShotRecorder for DeadTime {
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

/// Fewest expected photons per shot for a bin to be drawn from its counting law
/// ([`RateLaw`], its photons not drawn) rather than given its photons: measured
/// (`benches/dead_time_rates.rs`), the photon path costs more from about here on.
pub const LAW_FROM_PHOTONS: f64 = 0.5;

/// Most bytes of [`RateLaw`] tables one run keeps; bins past it are recorded given
/// their photons.
pub const LAW_BUDGET_BYTES: usize = 32 << 20;

/// Shots of fixed means recorded through a dead-time detector: what `simulate --method
/// shot` draws for a channel with dead time and without jitter.
///
/// A non-paralyzable detector ([`DeadTime::by_counts`]) draws each bin of at least
/// [`LAW_FROM_PHOTONS`] photons per shot from its counting law ([`RateLaw`], built once
/// for the run) without drawing its photons, and the other bins' photons by a
/// [`ShotSampler`] over them, recorded given those photons; otherwise
/// ([`recorded_profile`]) every photon is drawn and recorded.
#[derive(Debug, Clone)]
pub struct DeadTimedShots {
    photons: ShotSampler,
    dead: DeadTime,
    split: std::sync::OnceLock<Split>,
    /// Every bin's photons drawn by `photons` and recorded given them, none from its law:
    /// the photons are then the shot path's own, shot for shot (a `both` detector's
    /// photon-counting half records the analog half's photons).
    every_photon: bool,
}

/// The bins drawn by their law and the sampler of the others.
#[derive(Debug, Clone)]
struct Split {
    others: ShotSampler,
    laws: LawBins,
}

/// The bins drawn from their counting law.
#[derive(Debug, Clone)]
struct LawBins {
    /// Per bin, its law if it has one (empty: none has).
    laws: Vec<Option<RateLaw>>,
    /// The first bins of the runs of law bins.
    starts: Vec<u32>,
    /// At the first bin of each such run, the bin past its end.
    ends: Vec<u32>,
    /// The bins of dense laws ([`RateLaw::dense`]).
    dense: Vec<u32>,
}

/// No bin drawn from its law.
static NO_LAWS: LawBins = LawBins {
    laws: Vec::new(),
    starts: Vec::new(),
    ends: Vec::new(),
    dense: Vec::new(),
};

impl DeadTimedShots {
    /// The shots of `photons` through `dead`.
    pub fn new(photons: ShotSampler, dead: DeadTime) -> Self {
        DeadTimedShots {
            photons,
            dead,
            split: std::sync::OnceLock::new(),
            every_photon: false,
        }
    }

    /// The same shots with every bin's photons drawn (no bin from its counting law), so
    /// that they are the shot path's photons, shot for shot; slower at high rates.
    pub fn drawing_every_photon(mut self) -> Self {
        self.every_photon = true;
        self
    }

    /// The sampler of every bin's photons.
    pub fn photons(&self) -> &ShotSampler {
        &self.photons
    }

    /// The detector.
    pub fn dead(&self) -> &DeadTime {
        &self.dead
    }

    fn split(&self) -> &Split {
        self.split.get_or_init(|| {
            let (tau, dt) = (self.dead.tau_s, self.dead.bin_width_s);
            let means = self.photons.means();
            let mut spent = 0usize;
            let laws: Vec<Option<RateLaw>> = means
                .iter()
                .map(|&l| {
                    (l >= LAW_FROM_PHOTONS && spent < LAW_BUDGET_BYTES).then(|| {
                        let law = RateLaw::new(l / dt, tau, dt);
                        spent += counting::rate_law_bytes(&law);
                        law
                    })
                })
                .collect();
            let others: Vec<f64> = means
                .iter()
                .zip(&laws)
                .map(|(&l, law)| if law.is_some() { 0.0 } else { l })
                .collect();
            let starts: Vec<u32> = (0..laws.len())
                .filter(|&i| laws[i].is_some() && (i == 0 || laws[i - 1].is_none()))
                .map(|i| i as u32)
                .collect();
            let mut ends = vec![0u32; laws.len()];
            for &a in &starts {
                let mut e = a as usize;
                while e < laws.len() && laws[e].is_some() {
                    e += 1;
                }
                ends[a as usize] = e as u32;
            }
            let dense = (0..laws.len() as u32)
                .filter(|&i| laws[i as usize].as_ref().is_some_and(|l| l.dense))
                .collect();
            Split {
                others: ShotSampler::new(&others),
                laws: LawBins {
                    // without law bins, none to look up
                    laws: if starts.is_empty() { Vec::new() } else { laws },
                    starts,
                    ends,
                    dense,
                },
            }
        })
    }

    /// Draws `shots` shots from `stream_rng(seed, profile, 0)` and its arrival stream and
    /// hands each one's recorded counts to `f` (per-shot consumers: tests, onboard sums).
    pub fn for_each_shot(&self, seed: u64, profile: u64, shots: u64, mut f: impl FnMut(&[u64])) {
        let bins = self.photons.bins();
        let mut acc = vec![0u64; bins];
        let mut scratch = Scratch::default();
        let mut arrivals = stream_rng(seed ^ ARRIVAL_STREAM, profile, 0);
        let mut rng = stream_rng(seed, profile, 0);
        if !self.dead.by_counts() || self.every_photon {
            return self.photons.for_each_shot(&mut rng, shots, |shot| {
                acc.iter_mut().for_each(|a| *a = 0);
                self.dead
                    .record_shot(&mut arrivals, shot, &mut scratch, &mut acc);
                f(&acc);
            });
        }
        let split = self.split();
        split.others.for_each_shot(&mut rng, shots, |shot| {
            acc.iter_mut().for_each(|a| *a = 0);
            self.dead
                .record_runs(&mut arrivals, shot, &split.laws, &mut scratch, &mut acc);
            f(&acc);
        });
    }

    /// Accumulates one profile of `shots` shots into `acc`, by blocks of [`SHOT_BLOCK`]
    /// shots from `stream_rng(seed, profile, block)` (photons) and its arrival stream
    /// (the detector's draws), summed in integers: independent of the thread count.
    pub fn profile(&self, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
        if !self.dead.by_counts() || self.every_photon {
            return recorded_profile(&self.photons, &self.dead, seed, profile, shots, acc);
        }
        let split = self.split();
        let bins = acc.len();
        add_block_sums(acc, shots.div_ceil(SHOT_BLOCK), |b| {
            let mut part = vec![0u64; bins];
            let mut scratch = Scratch::default();
            let n = SHOT_BLOCK.min(shots - b * SHOT_BLOCK);
            let mut arrivals = stream_rng(seed ^ ARRIVAL_STREAM, profile, b);
            split
                .others
                .for_each_shot(&mut stream_rng(seed, profile, b), n, |shot| {
                    self.dead
                        .record_runs(&mut arrivals, shot, &split.laws, &mut scratch, &mut part)
                });
            part
        });
    }
}

/// A uniform in [0, 1) from the top 53 bits of `x`.
fn unit_f64(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dead(model: DeadTimeModel) -> DeadTime {
        DeadTime {
            tau_s: 3.5e-9,
            model,
            bin_width_s: 2e-6,
        }
    }

    #[test]
    fn the_solver_meets_the_stationary_formulas() {
        for model in [DeadTimeModel::Nonparalyzable, DeadTimeModel::Paralyzable] {
            let d = dead(model);
            for n in [1e3, 1e6, 5e7, 2e8] {
                let lambda = vec![n * d.bin_width_s; 40];
                let m = d.recorded_means(&lambda);
                let want = d.stationary_rate(n) * d.bin_width_s;
                // past the first bin the rate is stationary
                assert!(
                    (m[20] / want - 1.0).abs() < 1e-3,
                    "{model:?} n={n}: {} vs {want}",
                    m[20]
                );
                // the first bin starts live: at least the stationary count
                assert!(m[0] >= want * (1.0 - 1e-9));
            }
        }
    }

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

    #[test]
    fn no_rate_no_count_and_low_rates_are_poisson() {
        let d = dead(DeadTimeModel::Nonparalyzable);
        assert_eq!(d.recorded_means(&[0.0, 0.0]), vec![0.0, 0.0]);
        let m = d.recorded_means(&[1e-3; 3]);
        // n = 500 Hz: m/n = 1/(1 + nτ) = 1 − 1.75e-6
        assert!((m[1] / 1e-3 - 1.0 + 1.75e-6).abs() < 1e-8);
        // variance 1/(1 + nτ)³ = 1 − 5.25e-6 of the Poisson value
        assert!((d.recorded_variance(1e-3) / 1e-3 - 1.0 + 5.25e-6).abs() < 1e-8);
    }
}
