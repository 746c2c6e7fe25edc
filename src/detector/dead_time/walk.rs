//! The arrival walk ([`WalkShots`]): a shot's arrivals drawn in time order as a Poisson
//! process of piecewise-constant rate, the dead time applied as they come, without the
//! shot path's photons (issue 41).
//!
//! # Method
//!
//! With the rate constant within each bin, the cumulative mean `Λ(t)` is piecewise
//! linear (`Λ` at bin `b`'s start the sum of the means before it), and the arrivals of
//! the shot are `Λ⁻¹(Γ₁), Λ⁻¹(Γ₂), …`, `Γₖ` the partial sums of standard exponentials (the
//! time-change theorem of Poisson processes: Çinlar 1975, *Introduction to Stochastic
//! Processes*, §4.4; Devroye 1986, §VI.1.3). Each `Γ` step is one ziggurat exponential
//! (`counting::exp1`'s, Marsaglia & Tsang 2000), the bin holding
//! it found by stepping over the bins' cumulative means (one compare per bin passed, a
//! sentinel after the last), its time `b + (Γ − Λ_b)/λ_b` in bins. The bin is
//! found from a guide table over Λ (Chen & Asau 1974), about one compare per arrival:
//! empty bins cost nothing.
//!
//! * **Paralyzable**: every arrival restarts the dead time; it is recorded when the
//!   previous arrival is at least τ before it (the detector live at the window's
//!   start): a compare, no branch. O(arrivals) per shot.
//! * **Non-paralyzable**: a recorded arrival at t leaves the detector dead until t + τ,
//!   its arrivals lost whatever they are; by the memoryless property the next recorded
//!   arrival is at `Λ⁻¹(Λ(t + τ) + E)`, so only the recorded arrivals are drawn.
//!   O(recorded counts) per shot.
//!
//! Exact for any bin width (nothing assumes Δt ≥ 2τ), the dead time carried across bin
//! edges, to the `f64` rounding of `Λ` (relative 1e-16 of the run's total mean per shot,
//! far below τ/Δt). The photons are not those of the ideal detector's draw (none is
//! drawn): the recorded counts' law is the same, their seeded bytes not.
//!
//! # Cost
//!
//! Per arrival (paralyzable) or per recorded count (non-paralyzable): one exponential,
//! a guide-table look-up, a multiply-add and a compare; nothing per empty bin.
//! Measured by `benches/dead_time_rates.rs` (`validation/reports/dead_time_cost.md`):
//! see [`NS_PER_WALK_SHOT`] and [`NS_PER_WALK_ARRIVAL`].

use rand::Rng;

use super::model::{DeadTime, DeadTimeModel};
use super::record::ARRIVAL_STREAM;
use crate::detector::counting::{exp1_slow, ziggurat};
use crate::sampling::{SHOT_BLOCK, add_block_sums, stream_rng};

/// Cost of the walk per shot, ns, whatever its arrivals (measured, one thread,
/// `PATH_DT=walk cargo bench --bench dead_time_rates`, 200 bins of 2 µs, 2026-12-03:
/// 0.25–0.32 ns a bin at 0.01 photons a bin, two arrivals a shot).
pub const NS_PER_WALK_SHOT: f64 = 30.0;
/// Cost of the walk per arrival drawn (paralyzable) or recorded count (non-paralyzable),
/// ns (measured as [`NS_PER_WALK_SHOT`]: 14–17 ns at 0.2–1 photons a bin, where the
/// guide table's branch is mispredicted; 5–8 ns from 60 photons a bin on, where most
/// arrivals stay in the bin of the one before).
pub const NS_PER_WALK_ARRIVAL: f64 = 12.0;

/// The exponential ziggurat's layer ends (`counting::ziggurat`).
type Layers = [f64; 257];

/// A standard exponential by the ziggurat (Marsaglia & Tsang 2000, as
/// `counting::exp1`), the generator kept in registers: the rare slow path gets a copy
/// by value and hands it back (a `&mut` to the walk's generator passed to a call that is
/// not inlined kept its state in memory, every draw a load and a store: measured, perf).
#[inline(always)]
fn exp_draw<R: Rng + Clone>(x: &Layers, rng: &mut R) -> f64 {
    let bits = rng.next_u64();
    let i = (bits & 0xff) as usize;
    let u = x[i] * ((bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64));
    if u < x[i + 1] {
        return u;
    }
    let (e, back) = exp_slow(i, u, rng.clone());
    *rng = back;
    e
}

/// [`exp_draw`]'s wedge and tail.
#[cold]
#[inline(never)]
fn exp_slow<R: Rng>(i: usize, u: f64, mut rng: R) -> (f64, R) {
    let e = exp1_slow(i, u, &mut rng);
    (e, rng)
}

/// Cells of the guide table per bin.
const GUIDE_PER_BIN: usize = 2;

/// The largest `f64` below 1: a time within its bin stays in it.
const BELOW_ONE: f64 = 1.0 - f64::EPSILON / 2.0;

/// Shots of fixed means through a dead time by the arrival walk (module docs).
#[derive(Debug, Clone)]
pub(super) struct WalkShots {
    /// Λ at each bin's start, then Λ at the window's end and `+∞` (the sentinel).
    starts: Vec<f64>,
    /// The bins' means λ_b (per shot).
    means: Vec<f64>,
    /// 1/λ_b (0 where λ_b = 0: no arrival is ever placed there).
    inv: Vec<f64>,
    /// Per cell `j` of [`GUIDE_PER_BIN`]·bins equal cells of the window's total mean,
    /// the first bin ending past the cell's start (Chen & Asau 1974's guide table;
    /// Devroye 1986, §III.2.4): the bin of an arrival at Λ = g is found from
    /// `guide[⌊g·scale⌋]` in about one step, whatever the bins' means.
    guide: Vec<u32>,
    /// Cells per unit of Λ.
    scale: f64,
    /// The window's total mean Λ (per shot).
    total: f64,
    /// τ/Δt.
    tau: f64,
    paralyzable: bool,
}

impl WalkShots {
    /// The walk of the means `lambda` per bin and shot through `dead` (one pixel).
    pub(super) fn new(lambda: &[f64], dead: &DeadTime) -> WalkShots {
        let mut starts = Vec::with_capacity(lambda.len() + 2);
        let mut sum = 0.0;
        for &l in lambda {
            starts.push(sum);
            sum += l.max(0.0);
        }
        starts.extend([sum, f64::INFINITY]);
        let cells = (GUIDE_PER_BIN * lambda.len()).max(1);
        let scale = if sum > 0.0 { cells as f64 / sum } else { 0.0 };
        let mut b = 0usize;
        let guide = (0..cells)
            .map(|j| {
                let at = j as f64 / scale;
                while b < lambda.len() && starts[b + 1] <= at {
                    b += 1;
                }
                b as u32
            })
            .collect();
        WalkShots {
            guide,
            scale,
            total: sum,
            starts,
            means: lambda.iter().map(|l| l.max(0.0)).collect(),
            inv: lambda
                .iter()
                .map(|&l| if l > 0.0 { 1.0 / l } else { 0.0 })
                .collect(),
            tau: dead.tau_s / dead.bin_width_s,
            paralyzable: dead.model == DeadTimeModel::Paralyzable,
        }
    }

    /// Estimated cost of one shot, ns ([`NS_PER_WALK_SHOT`], [`NS_PER_WALK_ARRIVAL`]): per
    /// arrival (paralyzable) or per recorded count (non-paralyzable, the stationary
    /// `λ/(1 + nτ)` per bin).
    pub(super) fn ns_per_shot(lambda: &[f64], dead: &DeadTime) -> f64 {
        let x = dead.tau_s / dead.bin_width_s;
        let draws: f64 = match dead.model {
            DeadTimeModel::Paralyzable => lambda.iter().sum(),
            DeadTimeModel::Nonparalyzable => lambda.iter().map(|&l| l / (1.0 + l * x)).sum(),
        };
        NS_PER_WALK_SHOT + draws * NS_PER_WALK_ARRIVAL
    }

    /// Draws `shots` shots (blocks of [`SHOT_BLOCK`] from `stream_rng(seed ^
    /// ARRIVAL_STREAM, profile, block)`, summed in integers) into `acc`.
    pub(super) fn profile(&self, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
        let bins = acc.len();
        add_block_sums(acc, shots.div_ceil(SHOT_BLOCK), |b| {
            let mut part = vec![0u64; bins];
            let n = SHOT_BLOCK.min(shots - b * SHOT_BLOCK);
            let mut rng = stream_rng(seed ^ ARRIVAL_STREAM, profile, b);
            for _ in 0..n {
                self.shot(&mut rng, &mut part);
            }
            part
        });
    }

    /// [`profile`](Self::profile)'s draws (one stream, block 0), each shot's recorded
    /// counts handed to `f`.
    pub(super) fn for_each_shot(
        &self,
        seed: u64,
        profile: u64,
        shots: u64,
        mut f: impl FnMut(&[u64]),
    ) {
        let mut acc = vec![0u64; self.means.len()];
        let mut rng = stream_rng(seed ^ ARRIVAL_STREAM, profile, 0);
        for _ in 0..shots {
            acc.iter_mut().for_each(|a| *a = 0);
            self.shot(&mut rng, &mut acc);
            f(&acc);
        }
    }

    /// [`profile`](Self::profile)'s draws replayed, the same blocks and streams, each
    /// recorded arrival handed to `f(shot, bin, place in the bin)`: the histogram of what
    /// `f` gets is `profile`'s counts, bit for bit (the photon file, `crate::photons`).
    pub(super) fn registrations(
        &self,
        seed: u64,
        profile: u64,
        shots: u64,
        mut f: impl FnMut(u64, usize, f64),
    ) {
        for b in 0..shots.div_ceil(SHOT_BLOCK) {
            let n = SHOT_BLOCK.min(shots - b * SHOT_BLOCK);
            let mut rng = stream_rng(seed ^ ARRIVAL_STREAM, profile, b);
            for i in 0..n {
                let shot = b * SHOT_BLOCK + i;
                let mut emit = |bin: usize, t: f64| f(shot, bin, t - bin as f64);
                if self.paralyzable {
                    self.paralyzable_events(&mut rng, &mut emit);
                } else {
                    self.nonparalyzable_events(&mut rng, &mut emit);
                }
            }
        }
    }

    /// [`paralyzable_walk`](Self::paralyzable_walk)'s recorded arrivals, each one's bin
    /// and time (in bins) handed to `emit`.
    fn paralyzable_events<R: Rng + Clone>(&self, rng: &mut R, emit: &mut impl FnMut(usize, f64)) {
        self.paralyzable_walk(rng, |b, t, recorded| {
            if recorded {
                emit(b, t)
            }
        });
    }

    /// [`nonparalyzable_walk`](Self::nonparalyzable_walk)'s recorded arrivals, each one's
    /// bin and time (in bins) handed to `emit`.
    fn nonparalyzable_events<R: Rng + Clone>(
        &self,
        rng: &mut R,
        emit: &mut impl FnMut(usize, f64),
    ) {
        self.nonparalyzable_walk(rng, |b, g| emit(b, self.time(b, g)));
    }

    /// One shot's recorded counts added to `acc` (the generator a local copy: kept in
    /// registers through the loop).
    #[inline(never)]
    fn shot<R: Rng + Clone>(&self, rng: &mut R, acc: &mut [u64]) {
        let mut local = rng.clone();
        if self.paralyzable {
            self.paralyzable_shot(&mut local, acc);
        } else {
            self.nonparalyzable_shot(&mut local, acc);
        }
        *rng = local;
    }

    /// The bin holding the arrival at cumulative mean `g < total`, at or after `b`: `b`
    /// itself without a look-up where it holds it (most arrivals at high rates).
    #[inline(always)]
    fn bin_from(&self, b: usize, g: f64) -> usize {
        if g < self.starts[b + 1] {
            b
        } else {
            self.bin_of(g)
        }
    }

    /// The bin holding the arrival at cumulative mean `g < total`.
    #[inline(always)]
    fn bin_of(&self, g: f64) -> usize {
        let cell = ((g * self.scale) as usize).min(self.guide.len() - 1);
        let mut b = self.guide[cell] as usize;
        // (a cell's start and `g·scale` round apart by an ulp at most)
        while b > 0 && self.starts[b] > g {
            b -= 1;
        }
        while self.starts[b + 1] <= g {
            b += 1;
        }
        b
    }

    /// The time, in bins, of the arrival at cumulative mean `g` in bin `b`.
    #[inline(always)]
    fn time(&self, b: usize, g: f64) -> f64 {
        b as f64 + ((g - self.starts[b]) * self.inv[b]).min(BELOW_ONE)
    }

    /// Paralyzable: every arrival drawn, recorded when the one before is τ or more away.
    fn paralyzable_shot<R: Rng + Clone>(&self, rng: &mut R, acc: &mut [u64]) {
        self.paralyzable_walk(rng, |b, _, recorded| acc[b] += u64::from(recorded));
    }

    /// The paralyzable walk of one shot: each arrival's bin, time (in bins) and whether
    /// it is recorded (the one before τ or more away) handed to `arrival` (inlined into
    /// both callers: the counts' path computes no more than it did alone).
    #[inline(always)]
    fn paralyzable_walk<R: Rng + Clone>(
        &self,
        rng: &mut R,
        mut arrival: impl FnMut(usize, f64, bool),
    ) {
        let x = &ziggurat().0;
        let (mut b, mut last) = (0usize, f64::NEG_INFINITY);
        let mut g = exp_draw(x, rng);
        while g < self.total {
            b = self.bin_from(b, g);
            let t = self.time(b, g);
            arrival(b, t, t - last >= self.tau);
            last = t;
            g += exp_draw(x, rng);
        }
    }

    /// Non-paralyzable: only the recorded arrivals drawn, each the first after the dead
    /// time of the one before.
    fn nonparalyzable_shot<R: Rng + Clone>(&self, rng: &mut R, acc: &mut [u64]) {
        self.nonparalyzable_walk(rng, |b, _| acc[b] += 1);
    }

    /// The non-paralyzable walk of one shot: each recorded arrival's bin and cumulative
    /// mean Λ handed to `recorded` (its time is [`time`](Self::time)`(b, Λ)`, computed
    /// only by a caller that needs it).
    #[inline(always)]
    fn nonparalyzable_walk<R: Rng + Clone>(
        &self,
        rng: &mut R,
        mut recorded: impl FnMut(usize, f64),
    ) {
        let x = &ziggurat().0;
        let bins = self.means.len();
        let mut b = 0usize;
        let mut g = exp_draw(x, rng);
        while g < self.total {
            b = self.bin_from(b, g);
            recorded(b, g);
            // the dead time ends in the same bin (most counts at high rates): Λ moves
            // by τ·λ_b, no time computed
            let live_g = g + self.tau * self.means[b];
            if live_g < self.starts[b + 1] {
                g = live_g + exp_draw(x, rng);
                continue;
            }
            // Λ at the end of its dead time, then the next arrival after it
            let live = self.time(b, g) + self.tau;
            let lb = live as usize;
            if lb >= bins {
                return;
            }
            b = lb;
            g = self.starts[lb] + (live - lb as f64) * self.means[lb] + exp_draw(x, rng);
        }
    }
}
