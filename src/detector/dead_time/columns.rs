//! The column path of the dead time ([`ColumnShots`]): a block of shots drawn bin by bin
//! across all its shots at once, as counts of shots; a shot's photons are given times
//! only where the dead time can act on them (issue 41: "at low rates a bin's arrivals
//! are mostly 0 or 1 and the residual dead time from the previous bin is mostly 0").
//!
//! # Method
//!
//! With bins at least 2τ wide (as the clusters path), a shot's state at a bin's start is
//! the dead time left by the bin before, `r ∈ [0, τ)`; its photons in the bin are
//! Poisson(λᵢ), uniform in it, independent of everything before. Shots entering a bin
//! live (`r = 0`) are therefore exchangeable and need no identity; only the few entering
//! it dead are kept, each with its `r`. Per bin of a block of S shots:
//!
//! * each shot entering dead: its count Poisson(λᵢ), its photons' times, the sweep (every
//!   photon restarting the dead time, paralyzable, or only a recorded one,
//!   non-paralyzable), and the dead time it leaves;
//! * of the others, `Bin(S − dead, 1 − e^{−λᵢ})` hold a photon or more; level by level of
//!   the count k, `Bin(left, P(K = k | K ≥ k))` of those left hold k photons, and of them
//!   `Bin(·, (1 − kτ)^k)` are *plain*: each photon at least τ after the one before and
//!   the last at least τ before the bin's end (the spacings of k uniform points, `D₀` the
//!   first time and `D_k` the distance from the last to the end, are uniform on the
//!   simplex, so `P(D₁ … D_k ≥ τ) = (1 − kτ)^k`, τ in bins). A plain shot records all k
//!   and leaves nothing; the others are drawn given that they are not plain
//!   ([`ColumnShots::not_plain`]), swept, and join the shots entering the next bin dead
//!   if they leave it dead.
//!
//! Each step draws the law of the block's independent shots given what is known, so the
//! block's sums have exactly the law of S independent shots through the detector (the
//! rate constant within a bin). The shots holding a photon: under 3 expected, by skipping
//! from one to the next (each gap `⌊E/λ⌋` shots, E ~ Exp(1), geometric; Devroye 1986,
//! §X.2), else as the other binomials. Binomials of up to 6 trials trial by trial (a
//! `u64` against `⌊p·2^64⌋`), of a smaller side's mean under 10 by sequential inversion
//! (Kachitvichyanukul & Schmeiser 1988's BINV, started from `(1 − p)^n`), above by
//! `rand_distr::Binomial` (BTPE). The level probabilities `P(K = k | K ≥ k)` and the plain
//! shares tabled per bin when the path is built (up to 64 levels; `counting::pois_pmf` and
//! `counting::pois_tails`: Loader's saddle-point form, tails summed from the smaller
//! side); a dead shot's count by inversion from `e^{−λ}` (`rand_distr::Poisson` above
//! λ = 30).
//!
//! # Precision
//!
//! Exact in law to the `f64` rounding of its probabilities (relative ~1e-15) and the 53
//! bits of its uniforms (2^-64 for a trial). `tests/dead_time_clusters.rs` checks it
//! against the exact window laws (χ², profiles of 1, 3 and 40 shots) and the renewal mean
//! and variance; the unit tests here check each binomial regime against statrs' pmf.
//!
//! # Cost
//!
//! Per bin and block, whatever its shots: [`COLUMN_NS_PER_BIN`], and two binomials per
//! level of the count its shots reach ([`COLUMN_NS_PER_LEVEL`]); per shot and bin, nothing
//! for a plain shot and a drawn bin ([`COLUMN_NS_PER_DRAWN_BIN`]) for the others, a share
//! of about `τ(λ + λ²)` of the shot-bins (and `λτ` entering dead). Nothing per photon: on
//! blocks of 10⁴ shots or more it costs less than the ideal detector up to ~2 photons a
//! bin at τ/Δt = 1/571 (0.05–0.7×; the ideal detector places or draws every photon), and
//! more from there on, the drawn share growing as λ². On profiles of 100 shots a bin's
//! levels are no longer spread over many shots: 2.7–5× the ideal detector from 0.1 to 2
//! photons a bin (39 ns a bin and block at 0.01 photons, 256 at 0.48, 800 at 2), taken by
//! `DeadTimePath::Auto` where that beats the photon paths (about 0.3 to 1.5 photons a
//! bin, the daylight background of a space lidar). Measured by `benches/dead_time_rates.rs`
//! (`validation/reports/dead_time_cost.md`). It draws profiles only: per-shot consumers
//! (`DeadTimedShots::for_each_shot`) take the photon paths.

use rand::Rng;
use rand_distr::{Binomial, Distribution, Exp1, Poisson};

use super::model::{DeadTime, DeadTimeModel};
use crate::detector::counting::{pois_pmf, pois_tails};
use crate::sampling::{SHOT_BLOCK, add_block_sums, stream_rng};

/// Cost of a bin per block of shots, ns, besides its levels: fitted to
/// `SHOTS=… PATH_DT=columns cargo bench --bench dead_time_rates` (2026-12-05, one thread,
/// blocks of 30 to 65,536 shots, 0.01 to 2 photons a bin: 39 ns a bin at 0.01 photons and
/// 100 shots, 256 at 0.48, 796 at 2).
pub const COLUMN_NS_PER_BIN: f64 = 20.0;
/// Cost of one level of a bin's count reached by a block (two binomials), ns, plus
/// [`COLUMN_NS_PER_LEVEL_HIT`] per shot holding a photon (up to 20): fitted as
/// [`COLUMN_NS_PER_BIN`].
pub const COLUMN_NS_PER_LEVEL: f64 = 40.0;
/// See [`COLUMN_NS_PER_LEVEL`].
pub const COLUMN_NS_PER_LEVEL_HIT: f64 = 1.0;
/// Cost of one drawn bin (a shot entering dead, or one not plain), ns, plus
/// [`COLUMN_NS_PER_DRAWN_PHOTON`] per photon in it: fitted as [`COLUMN_NS_PER_LEVEL`]
/// (1.6 ns a shot-bin at 2 photons a bin, 13 at 6).
pub const COLUMN_NS_PER_DRAWN_BIN: f64 = 80.0;
/// See [`COLUMN_NS_PER_DRAWN_BIN`].
pub const COLUMN_NS_PER_DRAWN_PHOTON: f64 = 12.0;

/// Above this mean a bin's conditioned count is drawn by rejection from
/// `rand_distr::Poisson` (the inversion's terms would underflow far above it).
const INVERSION_MAX: f64 = 30.0;

/// Shots of fixed means through a dead time, drawn bin by bin across a block of shots
/// (see the module docs): bins at least 2τ wide, either model, profiles only.
#[derive(Debug, Clone)]
pub(super) struct ColumnShots {
    /// Each bin's mean photons per shot, λ.
    lambda: Vec<f64>,
    /// `P(K ≥ 1) = 1 − e^{−λ}`.
    occupied: Vec<f64>,
    /// `P(K = 0) = e^{−λ}`.
    zero: Vec<f64>,
    /// Per bin, from `level_start[i]`: the level probabilities of its count,
    /// `(P(K = k | K ≥ k), (1 − kτ)^k, P(K ≥ k))` for k = 1, 2, … while `P(K ≥ k) > 0`,
    /// at most [`MAX_TABLED_LEVELS`] (the rest computed where reached).
    levels: Vec<(f64, f64, f64)>,
    level_start: Vec<usize>,
    /// τ/Δt.
    tau: f64,
    paralyzable: bool,
}

/// The most levels of a bin's count [`ColumnShots::new`] tables (a bin of λ ≤ 30 needs
/// fewer than 64 before `P(K ≥ k)` falls below 1e-20; the path is not taken far above).
const MAX_TABLED_LEVELS: u32 = 64;

/// `P(K = k | K ≥ k)` for K ~ Poisson(λ) (1 where `P(K ≥ k)` underflows), given
/// `tail = P(K ≥ k)`.
fn level_share(k: u32, lambda: f64, tail: f64) -> f64 {
    if tail > 0.0 {
        (pois_pmf(k, lambda) / tail).min(1.0)
    } else {
        1.0
    }
}

/// `P(K ≥ k)` for K ~ Poisson(λ), `occupied = P(K ≥ 1)`.
fn level_tail(k: u32, lambda: f64, occupied: f64) -> f64 {
    if k == 1 {
        occupied
    } else {
        pois_tails(k, lambda).0
    }
}

/// A bin of one shot drawn: its recorded count, the dead time it leaves in the next bin
/// (in bins).
struct Drawn {
    recorded: u64,
    left: f64,
}

impl ColumnShots {
    /// The path over `lambda` through `dead` (bins at least 2τ wide).
    pub(super) fn new(lambda: &[f64], dead: &DeadTime) -> ColumnShots {
        let occupied: Vec<f64> = lambda.iter().map(|&l| -(-l).exp_m1()).collect();
        let tau = dead.tau_s / dead.bin_width_s;
        let (mut levels, mut level_start) = (Vec::new(), Vec::with_capacity(lambda.len() + 1));
        for (&l, &occ) in lambda.iter().zip(&occupied) {
            level_start.push(levels.len());
            for k in 1..=MAX_TABLED_LEVELS {
                let tail = level_tail(k, l, occ);
                if tail.is_nan() || tail <= 0.0 {
                    break;
                }
                levels.push((level_share(k, l, tail), plain_share(k, tau), tail));
            }
        }
        level_start.push(levels.len());
        ColumnShots {
            lambda: lambda.to_vec(),
            zero: lambda.iter().map(|&l| (-l).exp()).collect(),
            occupied,
            levels,
            level_start,
            tau,
            paralyzable: dead.model == DeadTimeModel::Paralyzable,
        }
    }

    /// Estimated cost of a profile of `shots` shots on this path, ns: per bin and block
    /// [`COLUMN_NS_PER_BIN`] and per level of the count its shots reach (those k with
    /// `S·P(K ≥ k) ≥ 0.05`, S the block's shots) [`COLUMN_NS_PER_LEVEL`], plus
    /// [`COLUMN_NS_PER_LEVEL_HIT`] per hit shot up to 20 (the binomials' cost grows with
    /// their n); per shot-bin its drawn share ([`COLUMN_NS_PER_DRAWN_BIN`]).
    pub(super) fn ns_per_profile(&self, shots: u64) -> f64 {
        let full = shots / SHOT_BLOCK;
        let rest = shots % SHOT_BLOCK;
        let mut total = 0.0;
        for (i, (&l, &p)) in self.lambda.iter().zip(&self.occupied).enumerate() {
            if p <= 0.0 {
                continue;
            }
            let tabled = &self.levels[self.level_start[i]..self.level_start[i + 1]];
            let block = |s: u64| {
                let s = s as f64;
                let levels = tabled.iter().take_while(|t| s * t.2 >= 0.05).count() as f64;
                let per_level = COLUMN_NS_PER_LEVEL + COLUMN_NS_PER_LEVEL_HIT * (s * p).min(20.0);
                COLUMN_NS_PER_BIN + levels * per_level
            };
            total += full as f64 * block(SHOT_BLOCK) + if rest > 0 { block(rest) } else { 0.0 };
            let drawn = (self.tau * (2.0 * l + l * l)).min(1.0);
            total +=
                shots as f64 * drawn * (COLUMN_NS_PER_DRAWN_BIN + l * COLUMN_NS_PER_DRAWN_PHOTON);
        }
        total
    }

    /// Draws `shots` shots (blocks of [`SHOT_BLOCK`] from `stream_rng(seed, profile,
    /// block)`, summed in integers: independent of the thread count) into `acc`.
    pub(super) fn profile(&self, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
        let bins = acc.len();
        add_block_sums(acc, shots.div_ceil(SHOT_BLOCK), |b| {
            let mut part = vec![0u64; bins];
            let n = SHOT_BLOCK.min(shots - b * SHOT_BLOCK);
            self.block(&mut stream_rng(seed, profile, b), n, &mut part);
            part
        });
    }

    /// One block of `shots` shots into `acc` (see the module docs).
    fn block<R: Rng>(&self, rng: &mut R, shots: u64, acc: &mut [u64]) {
        // the shots entering the bin dead: the dead time each has left
        let mut dead: Vec<f64> = Vec::new();
        let mut next: Vec<f64> = Vec::new();
        let mut times: Vec<f64> = Vec::new();
        for i in 0..self.lambda.len() {
            next.clear();
            if self.occupied[i] <= 0.0 {
                std::mem::swap(&mut dead, &mut next);
                continue; // an empty bin leaves every shot live (Δt ≥ τ)
            }
            for &r in &dead {
                let k = self.count(rng, i);
                let d = self.draw_bin(rng, k, r, &mut times);
                acc[i] += d.recorded;
                if d.left > 0.0 {
                    next.push(d.left);
                }
            }
            let live = shots - dead.len() as u64;
            let hit = self.hits(rng, i, live);
            self.live_shots(rng, i, hit, &mut times, &mut next, acc);
            std::mem::swap(&mut dead, &mut next);
        }
    }

    /// The `hit` shots entering bin `i` live with a photon or more, level by level of
    /// their count k: `Bin(·, P(K = k | K ≥ k))` of them hold k photons, of which
    /// `Bin(·, (1 − kτ)^k)` are *plain* (each photon at least τ after the one before, the
    /// last at least τ before the bin's end: all recorded, nothing left), the others drawn
    /// given that they are not ([`not_plain`](Self::not_plain)) and swept.
    fn live_shots<R: Rng>(
        &self,
        rng: &mut R,
        i: usize,
        hit: u64,
        times: &mut Vec<f64>,
        next: &mut Vec<f64>,
        acc: &mut [u64],
    ) {
        let l = self.lambda[i];
        let tabled = &self.levels[self.level_start[i]..self.level_start[i + 1]];
        let (mut left, mut k) = (hit, 1u32);
        while left > 0 {
            let (share, plain) = match tabled.get(k as usize - 1) {
                Some(&(share, plain, _)) => (share, plain),
                None => (
                    level_share(k, l, level_tail(k, l, self.occupied[i])),
                    plain_share(k, self.tau),
                ),
            };
            let at_k = binomial(rng, left, share);
            left -= at_k;
            if at_k > 0 {
                let plain = binomial(rng, at_k, plain);
                acc[i] += u64::from(k) * plain;
                for _ in plain..at_k {
                    self.not_plain(rng, k, times);
                    let d = self.sweep(0.0, times);
                    acc[i] += d.recorded;
                    if d.left > 0.0 {
                        next.push(d.left);
                    }
                }
            }
            k += 1;
        }
    }

    /// How many of `live` shots hold a photon or more in bin `i`, `Bin(live, 1 − e^{−λ})`:
    /// where under [`SKIP_MAX_HITS`] are expected, by the trials skipped between them,
    /// each gap `⌊E/λ⌋` (E ~ Exp(1): `P(⌊E/λ⌋ ≥ g) = e^{−λg}`, the geometric law of the
    /// shots missed; Devroye 1986, §X.2), a ziggurat exponential per hit; else
    /// [`binomial`].
    fn hits<R: Rng>(&self, rng: &mut R, i: usize, live: u64) -> u64 {
        let p = self.occupied[i];
        if live as f64 * p >= SKIP_MAX_HITS {
            return binomial(rng, live, p);
        }
        let inv_l = 1.0 / self.lambda[i];
        let (mut hits, mut at) = (0u64, 0f64);
        loop {
            at += (Distribution::<f64>::sample(&Exp1, rng) * inv_l).floor() + 1.0;
            if at > live as f64 {
                return hits;
            }
            hits += 1;
        }
    }

    /// The times of `k` photons uniform in a bin (in bins) given that they are not plain
    /// (some photon within τ after the one before, or the last within τ of the end), into
    /// `times`, sorted. With the spacings `D₀ … D_k` (`D₀` the first time, `D_k` the
    /// last's distance to the end; uniform on the simplex), the first `j ≥ 1` with
    /// `D_j < τ` has `P(J = j) = (1 − (j−1)τ)^k − (1 − jτ)^k`; given it, the spacings
    /// with `D₁ … D_{j−1}` less τ are uniform on the simplex of total `1 − (j−1)τ`
    /// conditioned on `D_j < τ`: `D_j` by inversion of its Beta(1, k) law below τ, the
    /// others the rest shared by normalised exponentials (Devroye 1986, §V.2.2).
    fn not_plain<R: Rng>(&self, rng: &mut R, k: u32, times: &mut Vec<f64>) {
        let tau = self.tau;
        let kk = f64::from(k);
        let survive = |j: u32| (1.0 - f64::from(j) * tau).max(0.0).powi(k as i32);
        let mut target = unit_f64(rng.next_u64()) * (1.0 - survive(k));
        let mut j = 1u32;
        while j < k {
            let p = survive(j - 1) - survive(j);
            if target < p {
                break;
            }
            target -= p;
            j += 1;
        }
        let total = 1.0 - f64::from(j - 1) * tau;
        let below = -(kk * (-tau / total).ln_1p()).exp_m1(); // P(D_j < τ)
        let u = unit_f64(rng.next_u64());
        let d_j = total * -((-u * below).ln_1p() / kk).exp_m1();
        // the other k spacings share the rest as k normalised exponentials: first their
        // running sums over D₀ … D_m (D_j skipped), then the times
        times.clear();
        let mut sum = 0.0;
        for m in 0..k {
            if m != j {
                sum += Distribution::<f64>::sample(&Exp1, rng);
            }
            times.push(sum);
        }
        if j < k {
            sum += Distribution::<f64>::sample(&Exp1, rng); // D_k's share
        }
        let scale = (total - d_j) / sum;
        for (m, t) in (0u32..).zip(times.iter_mut()) {
            let d = if m >= j { d_j } else { 0.0 };
            *t = scale * *t + d + tau * f64::from(m.min(j - 1));
        }
    }

    /// Sweeps one shot's bin of photons at `times` (sorted, in bins), entered with the
    /// detector dead until `live_at`: every photon restarting the dead time (paralyzable)
    /// or only a recorded one (non-paralyzable).
    fn sweep(&self, live_at: f64, times: &[f64]) -> Drawn {
        let mut live_at = live_at;
        let mut recorded = 0u64;
        for &t in times {
            let live = t >= live_at;
            recorded += u64::from(live);
            if live | self.paralyzable {
                live_at = t + self.tau;
            }
        }
        Drawn {
            recorded,
            left: (live_at - 1.0).max(0.0),
        }
    }

    /// A bin of one shot holding `k` photons (uniform in it), entered with the detector
    /// dead until `live_at` (in bins, < τ/Δt).
    fn draw_bin<R: Rng>(&self, rng: &mut R, k: u64, live_at: f64, times: &mut Vec<f64>) -> Drawn {
        times.clear();
        times.extend((0..k).map(|_| unit_f64(rng.next_u64())));
        times.sort_unstable_by(f64::total_cmp);
        self.sweep(live_at, times)
    }

    /// A Poisson(λᵢ) count: inversion from `e^{−λ}`, `rand_distr::Poisson` above
    /// [`INVERSION_MAX`].
    fn count<R: Rng>(&self, rng: &mut R, i: usize) -> u64 {
        let l = self.lambda[i];
        if l > INVERSION_MAX {
            return Poisson::new(l).expect("a positive finite mean").sample(rng) as u64;
        }
        let target = unit_f64(rng.next_u64());
        let (mut k, mut term) = (0u64, self.zero[i]);
        let mut sum = term;
        while sum <= target && (term > sum * 1e-17 || k == 0) {
            k += 1;
            term *= l / k as f64;
            sum += term;
        }
        k
    }
}

/// `(1 − kτ)^k`: the share of k photons uniform in a bin that are plain (see
/// [`ColumnShots::live_shots`]), 0 where kτ ≥ 1.
fn plain_share(k: u32, tau: f64) -> f64 {
    let kk = f64::from(k);
    if kk * tau >= 1.0 {
        0.0
    } else {
        (kk * (-kk * tau).ln_1p()).exp()
    }
}

/// `Bin(n, p)`, 0 for n = 0 or p = 0: up to [`BERNOULLI_MAX_N`] trials one by one, else
/// the smaller side by inversion from `P(X = 0)`
/// where its mean is under [`BINV_MAX_MEAN`] (Kachitvichyanukul & Schmeiser 1988's BINV;
/// one `exp` and a `u64` with a step per unit of the result, where `rand_distr` would
/// also take a `powf` to set it up), else by `rand_distr::Binomial` (BTPE). Exact to the
/// rounding of the recurrence and the 53 bits of the uniform, as `rand_distr`'s BINV.
fn binomial<R: Rng>(rng: &mut R, n: u64, p: f64) -> u64 {
    if n == 0 || p <= 0.0 {
        return 0;
    }
    if p >= 1.0 {
        return n;
    }
    if n <= BERNOULLI_MAX_N {
        // n Bernoulli trials, each a u64 against ⌊p·2^64⌋
        let below = (p * 2f64.powi(64)) as u64;
        return (0..n).map(|_| u64::from(rng.next_u64() < below)).sum();
    }
    let (small, flipped) = if p > 0.5 { (1.0 - p, true) } else { (p, false) };
    if n as f64 * small >= BINV_MAX_MEAN {
        return Binomial::new(n, p).expect("0 < p < 1").sample(rng);
    }
    let x = binv(rng, n, small);
    if flipped { n - x } else { x }
}

/// Below this many hits expected, [`ColumnShots::hits`] skips from one to the next.
const SKIP_MAX_HITS: f64 = 3.0;

/// Up to this many trials [`binomial`] draws each (a `u64` against `⌊p·2^64⌋`: exact to
/// 2^-64), cheaper than an `exp`.
const BERNOULLI_MAX_N: u64 = 6;

/// Below this mean of the smaller side, [`binomial`] inverts (rand_distr's threshold).
const BINV_MAX_MEAN: f64 = 10.0;

/// `Bin(n, p)` by sequential inversion from `P(X = 0) = (1 − p)^n`, `np` < 10, p ≤ ½:
/// `P(X = x) = P(X = x − 1)·((n + 1)/x − 1)·p/(1 − p)`. A uniform left beyond the mass
/// summed to n (rounding) draws again.
fn binv<R: Rng>(rng: &mut R, n: u64, p: f64) -> u64 {
    let odds = p / (1.0 - p);
    let first = (n as f64 * (-p).ln_1p()).exp();
    loop {
        let mut u = unit_f64(rng.next_u64());
        let (mut x, mut mass) = (0u64, first);
        while u >= mass && x < n {
            u -= mass;
            x += 1;
            mass *= ((n + 1) as f64 / x as f64 - 1.0) * odds;
        }
        if u < mass || x < n {
            return x;
        }
    }
}

/// A uniform in [0, 1) from the top 53 bits of `x`.
#[inline(always)]
fn unit_f64(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream_rng;

    fn path(lambda: f64, model: DeadTimeModel) -> ColumnShots {
        let dead = DeadTime {
            tau_s: 3.5e-9,
            model,
            bin_width_s: 2e-6,
            pixels: 1,
        };
        ColumnShots::new(&[lambda; 4], &dead)
    }

    /// A dead shot's count has the Poisson mean and variance (5σ: relative standard error
    /// of the variance `√((1/λ + 2)/n)`), both sides of
    /// [`INVERSION_MAX`]; the plain share is the simplex's.
    #[test]
    fn counts_and_plain_shares() {
        for &l in &[0.01, 0.3, 2.0, 29.0, 31.0, 300.0] {
            let c = path(l, DeadTimeModel::Paralyzable);
            let mut rng = stream_rng(5, 0, 0);
            let n = 200_000;
            let draws: Vec<f64> = (0..n).map(|_| c.count(&mut rng, 0) as f64).collect();
            let mean = draws.iter().sum::<f64>() / n as f64;
            let var = draws.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
            let sigma = (l / n as f64).sqrt();
            assert!((mean - l).abs() < 5.0 * sigma, "λ {l}: mean {mean}");
            assert!(
                (var / l - 1.0).abs() < 5.0 * ((1.0 / l + 2.0) / n as f64).sqrt(),
                "λ {l}: var {var}"
            );
        }
        assert!((plain_share(3, 0.1) - 0.7f64.powi(3)).abs() < 1e-15);
        assert_eq!(plain_share(10, 0.1), 0.0);
    }

    /// χ² of `draws` draws of `sample` against `Bin(n, p)`'s pmf (statrs), cells of
    /// expected count under 5 pooled: the statistic and its 1 − 1e-4 quantile.
    fn binomial_chi2(n: u64, p: f64, draws: u64, mut sample: impl FnMut() -> u64) -> (f64, f64) {
        use statrs::distribution::{Binomial as Exact, ChiSquared, ContinuousCDF, Discrete};
        let mut hist = vec![0u64; n as usize + 1];
        for _ in 0..draws {
            hist[sample() as usize] += 1;
        }
        let exact = Exact::new(p, n).expect("a binomial");
        let (mut stat, mut cells, mut o, mut e) = (0.0, 0usize, 0.0, 0.0);
        for (k, &h) in hist.iter().enumerate() {
            o += h as f64;
            e += draws as f64 * exact.pmf(k as u64);
            if e >= 5.0 || k == n as usize {
                stat += (o - e) * (o - e) / e.max(1e-300);
                cells += 1;
                (o, e) = (0.0, 0.0);
            }
        }
        let limit = ChiSquared::new((cells - 1) as f64)
            .expect("cells > 1")
            .inverse_cdf(1.0 - 1e-4);
        (stat, limit)
    }

    /// [`binomial`] and [`ColumnShots::hits`] follow the binomial law (χ², false alarm 1e-4
    /// each, fixed seed) in each of their regimes: trials one by one (n ≤ 6), inversion
    /// (mean < 10, either side of ½), BTPE, skipping between hits; and the same test
    /// rejects a sampler whose p is 1 % too large.
    #[test]
    fn binomials_follow_the_binomial_law() {
        let mut rng = stream_rng(11, 0, 0);
        for &(n, p) in &[
            (5u64, 0.3),
            (6, 0.97),
            (50, 0.1),
            (60, 0.93),
            (2000, 0.004),
            (1000, 0.3),
        ] {
            let (stat, limit) = binomial_chi2(n, p, 400_000, || binomial(&mut rng, n, p));
            assert!(stat < limit, "Bin({n}, {p}): χ² {stat:.1} ≥ {limit:.1}");
            let (wrong, _) = binomial_chi2(n, p, 400_000, || binomial(&mut rng, n, p * 1.01));
            assert!(
                wrong >= limit,
                "Bin({n}, {p}) with p 1 % high: χ² {wrong:.1} < {limit:.1}"
            );
        }
        for &l in &[0.001, 0.01, 0.05] {
            let c = path(l, DeadTimeModel::Nonparalyzable);
            let live = 40u64;
            let p = -(-l).exp_m1();
            let (stat, limit) = binomial_chi2(live, p, 400_000, || c.hits(&mut rng, 0, live));
            assert!(stat < limit, "hits at λ {l}: χ² {stat:.1} ≥ {limit:.1}");
        }
    }
}
