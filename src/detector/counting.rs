//! The recorded count of a non-paralyzable detector in one bin, drawn from its exact
//! counting distribution given the bin's true photons: O(1) per bin instead of an arrival
//! time per photon (docs/model.md §4b).
//!
//! # Method
//!
//! A bin of width Δt holds N true photons (drawn by the shot path), their arrival times
//! uniform in the bin (the rate is constant within a bin, as everywhere in the model);
//! the detector enters the bin dead for a residual `r ∈ [0, τ)` carried over from the
//! bin before (0 after an empty bin, since Δt ≥ τ) and leaves it dead for `r'`.
//!
//! * **Live-start law** (Müller 1973, NIM 112, 47: for a Poisson process of rate n on
//!   an interval L begun live, `N(L) ≥ k ⇔ (k−1)τ + Γ(k, n) ≤ L`). Given M photons
//!   uniform on L (the law no longer depends on n: the Poisson family is complete, so
//!   the conditional law given M is the unique one whose Poisson mixture is Müller's),
//!   the k-th recorded time is `(k−1)τ + L·U₍ₖ₎` in law, `U₍ₖ₎` the k-th of M sorted
//!   uniforms, jointly with the count and the dead time left at the end:
//!
//!   ```text
//!   P(R = k, ρ = 0 | M)     = P(Bin(M, 1 − kτ/L) = k)
//!   P(R = k, ρ ∈ dx | M)    = P(L·U₍ₖ₎ − (L − kτ) ∈ dx),   0 < x ≤ τ
//!   P(R ≥ k | M)            = P(Bin(M, 1 − (k−1)τ/L) ≥ k)
//!   ```
//!
//!   (each event's Poisson mixture over M ~ Poisson(nL) is Müller's; `tests/dead_time.rs`
//!   checks the law against the arrival-time sweep).
//! * **The bin as body and boundary.** The detector is live from `r` on (a non-paralyzable
//!   detector's dead photons do not extend it). The bin splits into the *body*
//!   `[r, r + Δt − τ)`, of fixed length L = Δt − τ begun live, and the *boundary* of
//!   total length τ: the head `[0, r)` (dead: its photons are lost) and the *extension*
//!   `[r + L, Δt)` of length `e = τ − r`. Given N, the boundary holds
//!   `B ~ Bin(N, τ/Δt)` photons uniform on it and the body `M = N − B` uniform on it.
//!   The body's (R, ρ) come from the live-start law of M on L, which depends on M only:
//!   one table per M, shared by every bin and rate of the run. The extension, shorter
//!   than τ, records at most one photon: the first of its photons at least ρ after its
//!   start; then `r' = y + r` (y that photon's offset in the extension), else
//!   `r' = max(0, ρ − e)`. Exact, dead time carried across bin edges included.
//!
//! # Sampling
//!
//! * B by inversion of 64-bit tail thresholds `⌊P(B ≥ j)·2^64⌋` per N (Devroye 1986,
//!   *Non-Uniform Random Variate Generation*, §X.3.3, as `sampling::table`): one `u64`.
//! * (R, ρ = 0 or ρ > 0) by an integer alias table per M over the pairs (Walker 1977;
//!   Vose 1991, `sampling::alias`): one `u64`.
//! * ρ, when positive and needed (r > 0 or boundary photons), from the density
//!   `∝ u^{k−1}(1−u)^{M−k}` on `(1 − kτ/L, 1 − (k−1)τ/L]` by rejection from the uniform
//!   (Devroye 1986, §II.3), squeezed by the density's least value on the cell (it is
//!   log-concave: the least is at an end): two `u64`, and logarithms only when the
//!   squeeze does not decide (a few % of draws; the density varies by a few % across
//!   the cell).
//! * The B boundary photons: a `u64` each (the mean of B is Nτ/Δt, 1 at 300 MHz).
//!
//! # Precision
//!
//! The binomial probabilities by Loader's saddle-point form (Loader 2000, "Fast and
//! accurate computation of binomial probabilities"; `stirlerr` and `bd0` as in R's
//! `dbinom`), relative error ~1e-14, tails summed from the smaller side; masses below
//! `2^-72` of the largest are dropped (as `sampling::pmf_alias`); the tables realise each
//! probability to a few `2^-64` absolute. The rejection step is exact to the 53 bits of
//! its uniforms.
//!
//! # Cost
//!
//! Measured by `benches/dead_time_rates.sh` (table in `validation/reports/dead_time_cost.md`):
//! per hit bin with no carried dead time and no boundary photon (most bins below
//! ~10 MHz) one `u64` and, where M > 1, one alias draw; at 300 MHz in 2 µs bins a few
//! `u64` per bin. Tables are built on first use per M (per process, shared by threads
//! and runs: their content depends only on τ, Δt and M): ~10–100 µs and 2–30 KiB each.
//! Bins of more than [`MAX_PHOTONS`] photons go through the arrival-time sweep.

use std::sync::{Arc, Mutex, OnceLock};

use rand::Rng;

use crate::sampling::{AliasTable, count_above};

/// Most photons in a bin drawn from the tables; more go through the arrival-time sweep.
pub const MAX_PHOTONS: u32 = 1 << 14;

/// Masses below this, relative to the largest, are left out of a table (`2^-72`).
const CUTOFF: f64 = 1.0 / (1u128 << 72) as f64;
const TWO_POW_64: f64 = 18_446_744_073_709_551_616.0;

/// The tables of one (τ, Δt): per N the boundary split, per M the body's law.
#[derive(Debug)]
pub struct Family {
    tau: f64,
    dt: f64,
    /// Body length L = Δt − τ.
    body_len: f64,
    /// τ/L.
    t0: f64,
    /// τ/Δt.
    boundary_share: f64,
    boundary: Vec<OnceLock<Box<[u64]>>>,
    body: Vec<OnceLock<BodyLaw>>,
}

/// One cell of the body's law: R = k with ρ > 0.
#[derive(Debug, Clone, Copy)]
struct Cell {
    /// The cell is `u ∈ (u_lo, u_lo + t0]` (ρ = L·u − (L − kτ)).
    u_lo: f64,
    u_hi: f64,
    /// `k − 1` and `M − k`, the density's exponents.
    a: f64,
    b: f64,
    /// The log-density's largest value on the cell.
    lf_max: f64,
    /// `exp(lf_min − lf_max)`: below it a proposal is accepted without logarithms.
    squeeze: f64,
}

/// The law of (R, ρ) of M photons on the body, begun live.
#[derive(Debug)]
struct BodyLaw {
    /// Entry `2(k − k0) + c`: R = k with ρ = 0 (c = 0) or ρ > 0 (c = 1).
    alias: Option<AliasTable>,
    /// R when the law is a single entry (M ≤ 1 without a cell, or no alias).
    k0: u32,
    /// Per k − k0, the cell with ρ > 0.
    cells: Box<[Cell]>,
}

static FAMILIES: Mutex<Vec<Arc<Family>>> = Mutex::new(Vec::new());

/// The (shared) tables of a non-paralyzable τ on bins of `dt` (Δt ≥ 2τ).
pub fn family(tau: f64, dt: f64) -> Arc<Family> {
    let mut all = FAMILIES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(f) = all.iter().find(|f| f.tau == tau && f.dt == dt) {
        return Arc::clone(f);
    }
    let f = Arc::new(Family::new(tau, dt));
    all.push(Arc::clone(&f));
    f
}

impl Family {
    fn new(tau: f64, dt: f64) -> Family {
        assert!(tau > 0.0 && dt >= 2.0 * tau, "τ = {tau}, Δt = {dt}");
        let n = MAX_PHOTONS as usize + 1;
        Family {
            tau,
            dt,
            body_len: dt - tau,
            t0: tau / (dt - tau),
            boundary_share: tau / dt,
            boundary: (0..n).map(|_| OnceLock::new()).collect(),
            body: (0..n).map(|_| OnceLock::new()).collect(),
        }
    }

    /// Whether these are the tables of (τ, Δt).
    pub fn is_for(&self, tau: f64, dt: f64) -> bool {
        self.tau == tau && self.dt == dt
    }

    fn boundary(&self, n: u32) -> &[u64] {
        self.boundary[n as usize].get_or_init(|| {
            let p = self.boundary_share;
            let mut out = Vec::new();
            let mut prev = u64::MAX;
            for j in 1..=n {
                let (ge, _) = binom_tails(n, j, p, 1.0 - p);
                let t = ((ge * TWO_POW_64) as u64).min(prev);
                if t == 0 {
                    break;
                }
                out.push(t);
                prev = t;
            }
            out.into_boxed_slice()
        })
    }

    fn body(&self, m: u32) -> &BodyLaw {
        self.body[m as usize].get_or_init(|| BodyLaw::new(m, self.t0))
    }

    /// Records one bin of `n` photons (1 ≤ n ≤ [`MAX_PHOTONS`]) entered dead for
    /// `r ∈ [0, τ)`: the recorded count and the dead time left at its end (0 when
    /// `need_residual` is false and it is not needed to count).
    #[inline]
    pub fn record_bin<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        n: u32,
        r: f64,
        need_residual: bool,
    ) -> (u32, f64) {
        let thr = self.boundary(n);
        let nb = match thr.first() {
            Some(&t1) => {
                let x = rng.next_u64();
                if x < t1 {
                    1 + count_above(&thr[1..], x)
                } else {
                    0
                }
            }
            None => 0,
        };
        let law = self.body(n - nb);
        let (k, cell) = law.draw(rng);
        // without boundary photons and entered live, ρ ≤ τ = e: nothing is left over
        if nb == 0 && (r == 0.0 || !need_residual) {
            return (k, 0.0);
        }
        let rho = match cell {
            Some(c) => self.rho(rng, c, k),
            None => 0.0,
        };
        let e = self.tau - r;
        // the first extension photon at least ρ into it is recorded
        let mut first: Option<f64> = None;
        for _ in 0..nb {
            let x = self.tau * unit_f64(rng.next_u64());
            if x >= r {
                let y = x - r;
                if y >= rho && first.is_none_or(|f| y < f) {
                    first = Some(y);
                }
            }
        }
        match first {
            Some(y) => (k + 1, y + r),
            None => (k, (rho - e).max(0.0)),
        }
    }

    /// ρ in the cell of R = k by rejection from the uniform.
    #[inline]
    fn rho<R: Rng + ?Sized>(&self, rng: &mut R, c: &Cell, k: u32) -> f64 {
        let u = loop {
            let u = c.u_lo + (c.u_hi - c.u_lo) * unit_f64(rng.next_u64());
            let w = unit_f64(rng.next_u64());
            if w < c.squeeze || w.ln() < log_density(c, u) - c.lf_max {
                break u;
            }
        };
        (self.body_len * u - (self.body_len - f64::from(k) * self.tau)).clamp(0.0, self.tau)
    }
}

impl BodyLaw {
    fn new(m: u32, t0: f64) -> BodyLaw {
        if m == 0 {
            return BodyLaw {
                alias: None,
                k0: 0,
                cells: Box::new([]),
            };
        }
        // R ≥ 1 (begun live) and (R − 1)τ ≤ L
        let k_top = m.min((1.0 / t0).floor() as u32 + 1);
        // the masses of R = k: (atom, cell)
        let masses = |k: u32| -> (f64, f64) {
            let kf = f64::from(k);
            let atom = if kf * t0 <= 1.0 {
                binom_pmf(m, k, 1.0 - kf * t0, kf * t0)
            } else {
                0.0
            };
            // P(Bin(M, u_hi) ≥ k) − P(Bin(M, u_lo) ≥ k), from the smaller side
            let (q_hi, q_lo) = ((kf - 1.0) * t0, (kf * t0).min(1.0));
            let (ge_hi, lt_hi) = binom_tails(m, k, 1.0 - q_hi, q_hi);
            let (ge_lo, lt_lo) = binom_tails(m, k, 1.0 - q_lo, q_lo);
            let cell = if ge_hi < 0.5 {
                ge_hi - ge_lo
            } else {
                lt_lo - lt_hi
            };
            (atom, cell.max(0.0))
        };
        // the median of R by bisection on P(R ≥ k), then outwards to the cut-off
        let ge = |k: u32| {
            let q = (f64::from(k) - 1.0) * t0;
            if q >= 1.0 {
                0.0
            } else {
                binom_tails(m, k, 1.0 - q, q).0
            }
        };
        let (mut lo, mut hi) = (1u32, k_top);
        while lo < hi {
            let mid = lo + (hi - lo).div_ceil(2);
            if ge(mid) >= 0.5 {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        let median = lo;
        let total = |(a, c): (f64, f64)| a + c;
        let peak = total(masses(median));
        let mut below = Vec::new();
        let mut k = median;
        while k > 1 {
            k -= 1;
            let x = masses(k);
            if total(x) < CUTOFF * peak {
                break;
            }
            below.push(x);
        }
        let k0 = median - below.len() as u32;
        let mut entries: Vec<(f64, f64)> = below.into_iter().rev().collect();
        entries.push(masses(median));
        let mut k = median;
        while k < k_top {
            k += 1;
            let x = masses(k);
            if total(x) < CUTOFF * peak {
                break;
            }
            entries.push(x);
        }
        let mut weights = Vec::with_capacity(2 * entries.len());
        let mut ids = Vec::with_capacity(2 * entries.len());
        let mut cells = Vec::with_capacity(entries.len());
        for (i, &(atom, cell)) in entries.iter().enumerate() {
            let k = k0 + i as u32;
            weights.extend([atom, cell]);
            ids.extend([2 * i as u32, 2 * i as u32 + 1]);
            cells.push(Cell::new(m, k, t0));
        }
        let single = weights.iter().filter(|&&w| w > 0.0).count() == 1 && weights[0] > 0.0;
        BodyLaw {
            alias: (!single).then(|| AliasTable::new(&weights, &ids)),
            k0,
            cells: cells.into_boxed_slice(),
        }
    }

    /// R, and its cell when ρ > 0.
    #[inline(always)]
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> (u32, Option<&Cell>) {
        match &self.alias {
            None => (self.k0, None),
            Some(a) => {
                let e = a.bin_for(rng.next_u64());
                let i = e >> 1;
                (self.k0 + i as u32, (e & 1 == 1).then(|| &self.cells[i]))
            }
        }
    }
}

impl Cell {
    fn new(m: u32, k: u32, t0: f64) -> Cell {
        let kf = f64::from(k);
        let u_lo = (1.0 - kf * t0).max(0.0);
        let u_hi = (1.0 - (kf - 1.0) * t0).clamp(0.0, 1.0);
        let mut c = Cell {
            u_lo,
            u_hi,
            a: kf - 1.0,
            b: f64::from(m) - kf,
            lf_max: 0.0,
            squeeze: 0.0,
        };
        // log-concave: the largest value at the mode (clamped), the least at an end
        let mode = if m > 1 {
            (c.a / (f64::from(m) - 1.0)).clamp(u_lo, u_hi)
        } else {
            u_lo
        };
        c.lf_max = log_density(&c, mode);
        let lf_min = log_density(&c, u_lo).min(log_density(&c, u_hi));
        c.squeeze = if lf_min.is_finite() {
            (lf_min - c.lf_max).exp()
        } else {
            0.0
        };
        c
    }
}

/// `(k−1)·ln u + (M−k)·ln(1−u)`, with `0·ln 0 = 0`.
#[inline]
fn log_density(c: &Cell, u: f64) -> f64 {
    let term = |a: f64, x: f64| if a == 0.0 { 0.0 } else { a * x.ln() };
    term(c.a, u) + term(c.b, 1.0 - u)
}

/// A uniform in [0, 1) from the top 53 bits of `x`.
#[inline(always)]
fn unit_f64(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

const LN_SQRT_2PI: f64 = 0.918_938_533_204_672_8;

/// `ln n! − ln(√(2πn)·(n/e)^n)` for an integer n ≥ 1: directly below 16, else its
/// asymptotic series (as R's `stirlerr`).
fn stirlerr(n: f64) -> f64 {
    const S0: f64 = 1.0 / 12.0;
    const S1: f64 = 1.0 / 360.0;
    const S2: f64 = 1.0 / 1260.0;
    const S3: f64 = 1.0 / 1680.0;
    const S4: f64 = 1.0 / 1188.0;
    if n <= 15.0 {
        let fact: f64 = (1..=n as u64).map(|i| i as f64).product();
        return fact.ln() - (n + 0.5) * n.ln() + n - LN_SQRT_2PI;
    }
    let nn = n * n;
    if n > 500.0 {
        (S0 - S1 / nn) / n
    } else if n > 80.0 {
        (S0 - (S1 - S2 / nn) / nn) / n
    } else if n > 35.0 {
        (S0 - (S1 - (S2 - S3 / nn) / nn) / nn) / n
    } else {
        (S0 - (S1 - (S2 - (S3 - S4 / nn) / nn) / nn) / nn) / n
    }
}

/// `x·ln(x/np) + np − x`, accurately where x ≈ np (Loader 2000).
fn bd0(x: f64, np: f64) -> f64 {
    if (x - np).abs() < 0.1 * (x + np) {
        let mut v = (x - np) / (x + np);
        let mut s = (x - np) * v;
        let mut ej = 2.0 * x * v;
        v *= v;
        for j in 1..1000 {
            ej *= v;
            let s1 = s + ej / f64::from(2 * j + 1);
            if s1 == s {
                return s1;
            }
            s = s1;
        }
        return s;
    }
    x * (x / np).ln() + np - x
}

/// `P(Bin(n, p) = x)` with `q = 1 − p` given apart (for p near 1), by Loader's
/// saddle-point form.
pub(crate) fn binom_pmf(n: u32, x: u32, p: f64, q: f64) -> f64 {
    if x > n {
        return 0.0;
    }
    if p <= 0.0 {
        return if x == 0 { 1.0 } else { 0.0 };
    }
    if q <= 0.0 {
        return if x == n { 1.0 } else { 0.0 };
    }
    let (n, x) = (f64::from(n), f64::from(x));
    if x == 0.0 {
        let lc = if p < 0.1 {
            -bd0(n, n * q) - n * p
        } else {
            n * q.ln()
        };
        return lc.exp();
    }
    if x == n {
        let lc = if q < 0.1 {
            -bd0(n, n * p) - n * q
        } else {
            n * p.ln()
        };
        return lc.exp();
    }
    let lc = stirlerr(n) - stirlerr(x) - stirlerr(n - x) - bd0(x, n * p) - bd0(n - x, n * q);
    let lf = 2.0 * LN_SQRT_2PI + x.ln() + (-x / n).ln_1p();
    (lc - 0.5 * lf).exp()
}

/// `(P(Bin(n, p) ≥ k), P(Bin(n, p) < k))`, the smaller summed term by term from `k`
/// outwards (relative precision ~1e-14), the other its complement.
pub(crate) fn binom_tails(n: u32, k: u32, p: f64, q: f64) -> (f64, f64) {
    if k == 0 {
        return (1.0, 0.0);
    }
    if k > n {
        return (0.0, 1.0);
    }
    if p <= 0.0 {
        return (0.0, 1.0);
    }
    if q <= 0.0 {
        return (1.0, 0.0);
    }
    let ratio = p / q;
    if f64::from(k) > f64::from(n) * p {
        // upper tail, terms decreasing from k
        let mut term = binom_pmf(n, k, p, q);
        let mut sum = 0.0;
        let mut j = k;
        loop {
            sum += term;
            if j == n || term < sum * 1e-18 {
                break;
            }
            term *= f64::from(n - j) / f64::from(j + 1) * ratio;
            j += 1;
        }
        (sum, 1.0 - sum)
    } else {
        // lower tail, terms decreasing from k − 1 down
        let mut j = k - 1;
        let mut term = binom_pmf(n, j, p, q);
        let mut sum = 0.0;
        loop {
            sum += term;
            if j == 0 || term < sum * 1e-18 {
                break;
            }
            term *= f64::from(j) / f64::from(n - j + 1) / ratio;
            j -= 1;
        }
        (1.0 - sum, sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Loader's binomial PMF against the direct product for small n (exact factorials)
    /// and against the recurrence from P(0) for n = 600: relative 1e-12.
    #[test]
    fn binomial_probabilities_are_accurate() {
        for (n, p) in [(10u32, 0.3f64), (17, 0.9), (40, 0.01)] {
            let mut c = 1.0f64;
            for x in 0..=n {
                if x > 0 {
                    c = c * f64::from(n - x + 1) / f64::from(x);
                }
                let want = c * p.powi(x as i32) * (1.0 - p).powi((n - x) as i32);
                let got = binom_pmf(n, x, p, 1.0 - p);
                assert!(
                    (got / want - 1.0).abs() < 1e-12,
                    "n {n} x {x}: {got} vs {want}"
                );
            }
        }
        let (n, p) = (600u32, 0.49f64);
        let mut want = (1.0 - p).powi(600);
        let mut total = 0.0f64;
        for x in 0..=n {
            if x > 0 {
                want *= f64::from(n - x + 1) / f64::from(x) * p / (1.0 - p);
            }
            total += want;
            if want > 1e-250 {
                let got = binom_pmf(n, x, p, 1.0 - p);
                assert!((got / want - 1.0).abs() < 1e-11, "x {x}: {got} vs {want}");
            }
        }
        assert!((total - 1.0).abs() < 1e-12);
        let (ge, lt) = binom_tails(n, 300, p, 1.0 - p);
        assert!((ge + lt - 1.0).abs() < 1e-15);
    }

    /// The body's law sums to one and has the mean of the live-start counter: for M
    /// photons on L, `E R = Σ_k P(Bin(M, 1 − (k−1)τ/L) ≥ k)` (written here by its own
    /// sum of binomial tails, from summed logarithms).
    #[test]
    fn the_body_law_has_the_live_start_mean() {
        let t0 = 3.5e-9 / (2e-6 - 3.5e-9);
        for m in [1u32, 2, 5, 60, 600] {
            let law = BodyLaw::new(m, t0);
            let mut mean = 0.0;
            if let Some(a) = &law.alias {
                let p = a.probabilities(2 * law.cells.len());
                assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                for (e, pe) in p.iter().enumerate() {
                    mean += pe * f64::from(law.k0 + (e / 2) as u32);
                }
            } else {
                mean = f64::from(law.k0);
            }
            // ln C(m, x) from summed logarithms
            let lnfact: Vec<f64> = (0..=m)
                .scan(0.0, |s, i| {
                    if i > 0 {
                        *s += f64::from(i).ln();
                    }
                    Some(*s)
                })
                .collect();
            let mut want = 0.0;
            for k in 1..=m {
                let q = (f64::from(k) - 1.0) * t0;
                if q >= 1.0 {
                    break;
                }
                let u = 1.0 - q;
                let tail: f64 = (k..=m)
                    .map(|x| {
                        let (x, n) = (x as usize, m as usize);
                        let ln = lnfact[n] - lnfact[x] - lnfact[n - x]
                            + x as f64 * u.ln()
                            + if n > x { (n - x) as f64 * q.ln() } else { 0.0 };
                        ln.exp()
                    })
                    .sum();
                want += tail;
            }
            assert!((mean / want - 1.0).abs() < 1e-10, "M {m}: {mean} vs {want}");
        }
    }
}
