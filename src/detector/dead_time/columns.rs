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
//! rate constant within a bin). Binomials by `rand_distr::Binomial` (Kachitvichyanukul &
//! Schmeiser 1988: inversion below a mean of 10, BTPE above); the level probabilities by
//! `counting::pois_pmf` and `counting::pois_tails` (Loader's saddle-point form, tails
//! summed from the smaller side); a dead shot's count by inversion from `e^{−λ}`
//! (`rand_distr::Poisson` above λ = 30).
//!
//! # Precision
//!
//! Exact in law to the `f64` rounding of its probabilities (relative ~1e-15) and the 53
//! bits of its uniforms. `tests/dead_time_clusters.rs` checks it against the exact
//! window laws (χ²) and the renewal mean and variance.
//!
//! # Cost
//!
//! Per bin and block, whatever its shots: one binomial per level of the count reached
//! (about `λ + 3√λ + 2` levels) ([`COLUMN_NS_PER_LEVEL`]); per shot and bin, nothing for a
//! plain shot and a drawn bin ([`COLUMN_NS_PER_DRAWN_BIN`]) for the others, a share of
//! about `τ(λ + λ²)` of the shot-bins (and `λτ` entering dead). Nothing per photon: on
//! blocks of 10⁴ shots or more it costs less than the ideal detector up to ~2 photons a
//! bin at τ/Δt = 1/571 (the ideal detector places or draws every photon), and more from
//! there on, the drawn share growing as λ². Measured by `benches/dead_time_rates.rs`
//! (`validation/reports/dead_time_cost.md`). It draws profiles only: per-shot consumers
//! (`DeadTimedShots::for_each_shot`) take the photon paths.

use rand::Rng;
use rand_distr::{Binomial, Distribution, Exp1, Poisson};

use super::model::{DeadTime, DeadTimeModel};
use crate::detector::counting::{pois_pmf, pois_tails};
use crate::sampling::{SHOT_BLOCK, add_block_sums, stream_rng};

/// Cost of one level of a bin's count per block of shots (two binomials and a Poisson
/// tail), ns: fitted to `PATH_DT=columns cargo bench --bench dead_time_rates` (2026-12-04,
/// one thread, blocks of 65,536 shots: ~650 ns a bin at 0.01 photons a bin, three levels).
pub const COLUMN_NS_PER_LEVEL: f64 = 200.0;
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
    /// τ/Δt.
    tau: f64,
    paralyzable: bool,
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
        ColumnShots {
            lambda: lambda.to_vec(),
            zero: lambda.iter().map(|&l| (-l).exp()).collect(),
            occupied,
            tau: dead.tau_s / dead.bin_width_s,
            paralyzable: dead.model == DeadTimeModel::Paralyzable,
        }
    }

    /// Estimated cost of a profile of `shots` shots on this path, ns: per bin and block
    /// its levels ([`COLUMN_NS_PER_LEVEL`]), per shot-bin its drawn share
    /// ([`COLUMN_NS_PER_DRAWN_BIN`]).
    pub(super) fn ns_per_profile(&self, shots: u64) -> f64 {
        let blocks = shots.div_ceil(SHOT_BLOCK) as f64;
        let (mut per_block, mut per_shot) = (0.0, 0.0);
        for (&l, &p) in self.lambda.iter().zip(&self.occupied) {
            if p <= 0.0 {
                continue;
            }
            per_block += (l + 3.0 * l.sqrt() + 2.0) * COLUMN_NS_PER_LEVEL;
            let drawn = (self.tau * (2.0 * l + l * l)).min(1.0);
            per_shot += drawn * (COLUMN_NS_PER_DRAWN_BIN + l * COLUMN_NS_PER_DRAWN_PHOTON);
        }
        blocks * per_block + shots as f64 * per_shot
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
            let hit = binomial(rng, live, self.occupied[i]);
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
        let (mut left, mut k) = (hit, 1u32);
        let mut tail = self.occupied[i]; // P(K ≥ k)
        while left > 0 {
            let pmf = pois_pmf(k, l);
            let at_k = if tail > 0.0 {
                binomial(rng, left, (pmf / tail).min(1.0))
            } else {
                left
            };
            left -= at_k;
            if at_k > 0 {
                let plain = binomial(rng, at_k, plain_share(k, self.tau));
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
            tail = pois_tails(k, l).0;
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

/// `Bin(n, p)`, 0 for n = 0 or p = 0.
fn binomial<R: Rng>(rng: &mut R, n: u64, p: f64) -> u64 {
    if n == 0 || p <= 0.0 {
        return 0;
    }
    if p >= 1.0 {
        return n;
    }
    Binomial::new(n, p).expect("0 < p < 1").sample(rng)
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
}
