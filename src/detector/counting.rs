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
//! Measured by `benches/dead_time_rates.rs` (table in
//! `validation/reports/dead_time_cost.md`, one thread, 200 bins of 2 µs, τ = 3.5 ns): given
//! the photons, 3.3 ns a bin at 0.2 photons per bin (16 ns a photon, the shot path's
//! included: 6.7× the ideal detector, whose sparse path places a photon in ~2 ns); by
//! [`RateLaw`], 4.3–7 ns a bin from 0.6 to 20 photons (1.7–3.3×) and 11–22 ns from 60
//! to 600 (3.8–6.6×: the body's count, its residual ρ and the extension's photon are
//! three or four `u64` and a table load, where the ideal detector draws one). Per hit
//! bin with no carried dead time and no boundary photon one `u64` and, where M > 1, one
//! alias draw. [`Family`] tables are built on first use per M (per process, shared by
//! threads and runs: their content depends only on τ, Δt and M): ~10–100 µs and
//! 2–30 KiB each; a [`RateLaw`] per bin and run, ~0.1–0.5 ms and up to ~10 KiB. Bins of
//! more than [`MAX_PHOTONS`] photons go through the arrival-time sweep.

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
    #[inline(always)]
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
        // without boundary photons, the count is the body's; and entered live, ρ ≤ τ = e
        // leaves nothing over
        if nb == 0 && (r == 0.0 || !need_residual) {
            if n == 1 {
                return (1, 0.0); // a lone body photon on a live detector
            }
            return (self.body(n).draw(rng).0, 0.0);
        }
        let law = self.body(n - nb);
        let (k, cell) = law.draw(rng);
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
        let (k0, entries) = around(lo, 1, k_top, masses);
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

/// Bytes of a [`RateLaw`] (for the run's table budget).
pub fn rate_law_bytes(law: &RateLaw) -> usize {
    16 * law.alias.columns() + std::mem::size_of::<RateLaw>()
}

/// A [`RateLaw`]'s body drawn, with the uniforms of the rest of the bin.
#[derive(Debug, Clone, Copy, Default)]
pub struct Drawn {
    k: u32,
    /// ρ + E and ρ − τ (see [`RateLaw::finish`]).
    a: f64,
    b: f64,
}

/// The recorded count of a non-paralyzable detector in a bin of constant true rate n,
/// drawn from Müller's counting law without the bin's photons (the law of the bin given
/// its rate, not given its photon count as [`Family`]): for bins of a fixed mean, where
/// drawing the photons first would cost more than the count itself.
///
/// The same body and extension as [`Family::record_bin`]: the body `[r, r + L)` begun
/// live, whose (R, ρ) follow
///
/// ```text
/// P(R = k, ρ = 0)  = Pois(k; n(L − kτ))
/// P(R = k, ρ > 0)  = Q(k; n(L − (k−1)τ)) − Q(k; n(L − kτ)),   Q(k; μ) = P(Pois(μ) ≥ k)
/// ρ | R = k, ρ > 0  has density ∝ a^{k−1}·e^{−na} at a = L − kτ + ρ (Γ(k, n)'s)
/// ```
///
/// (Müller 1973: the k-th record is at `(k−1)τ + Γ(k, n)`), by an alias table over the
/// pairs and rejection from the uniform within the cell, squeezed by the density's least
/// value on it (log-concave: at an end); then the extension of length `e = τ − r`, where
/// the detector, live from ρ on, records its first photon, at `ρ + E`, E ~ Exp(n), if
/// `E < e − ρ`. At low rates whether E < τ is part of the table's entry (one `u64` per
/// bin decides the body and that; E itself then drawn below τ by inversion); from
/// [`DENSE_FROM`] on, E is drawn in every
/// bin by a ziggurat ([`exp1`]) and the outcome selected without branches. Exact; the
/// photons of the bin are not drawn (their count given the recorded path is
/// `R + Poisson(n·(time dead within the bin))`, exactly, where wanted).
#[derive(Debug, Clone)]
pub struct RateLaw {
    tau: f64,
    n: f64,
    /// 1/n.
    mean_gap: f64,
    /// L = Δt − τ.
    body: f64,
    alias: AliasTable,
    k0: u32,
    /// P(Exp(n) < τ).
    ext_p: f64,
    /// P(Exp(n) < τ) > [`DENSE_FROM`]: the extension's photon drawn in every bin.
    pub dense: bool,
}

/// Whether a [`RateLaw`] of rate `n` and dead time `tau` is dense.
pub fn is_dense(n: f64, tau: f64) -> bool {
    -(-n * tau).exp_m1() > DENSE_FROM
}

/// The squeeze of an entry in its id's top 16 bits: `q/SQUEEZE_ONE`.
const SQUEEZE_ONE: f64 = 65535.0;

/// Share of bins whose extension may record above which [`RateLaw`] draws without
/// branches on the outcome (n ≳ 64 MHz at τ = 3.5 ns; measured crossover,
/// `benches/dead_time_rates.rs`).
const DENSE_FROM: f64 = 0.2;

impl RateLaw {
    /// The law of a bin of `dt` (≥ 2τ) at the true rate `n` (s⁻¹, > 0).
    pub fn new(n: f64, tau: f64, dt: f64) -> RateLaw {
        assert!(
            n > 0.0 && tau > 0.0 && dt >= 2.0 * tau,
            "n {n}, τ {tau}, Δt {dt}"
        );
        let body = dt - tau;
        let k_top = (body / tau).floor() as u32 + 1;
        let mu = |k: u32| n * (body - f64::from(k) * tau).max(0.0);
        let masses = |k: u32| -> (f64, f64) {
            if k == 0 {
                return ((-n * body).exp(), 0.0);
            }
            let atom = if f64::from(k) * tau <= body {
                pois_pmf(k, mu(k))
            } else {
                0.0
            };
            let (ge_hi, lt_hi) = pois_tails(k, mu(k - 1));
            let (ge_lo, lt_lo) = pois_tails(k, mu(k));
            let cell = if ge_hi < 0.5 {
                ge_hi - ge_lo
            } else {
                lt_lo - lt_hi
            };
            (atom, cell.max(0.0))
        };
        // the median of R by bisection on P(R ≥ k) = Q(k; n(L − (k−1)τ))
        let (mut lo, mut hi) = (0u32, k_top);
        while lo < hi {
            let mid = lo + (hi - lo).div_ceil(2);
            if pois_tails(mid, mu(mid - 1)).0 >= 0.5 {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        let (k0, entries) = around(lo, 0, k_top, masses);
        let mut weights = Vec::with_capacity(2 * entries.len());
        let mut ids = Vec::with_capacity(2 * entries.len());
        let mut law = RateLaw {
            tau,
            n,
            mean_gap: 1.0 / n,
            body,
            alias: AliasTable::new(&[1.0], &[0]),
            k0,
            ext_p: 0.0,
            dense: false,
        };
        // an entry's id carries its squeeze, the least of the cell's density over its
        // largest, rounded down to 16 bits (still a lower bound: the test stays exact),
        // so that no second table is read; the atom's is 1 (always accepted). A sparse
        // law's entries also carry whether the extension may record (E < τ, independent
        // of the body): one u64 per bin decides both.
        let ext_p = -(-n * tau).exp_m1();
        law.ext_p = ext_p;
        law.dense = is_dense(n, tau);
        let shares: &[f64] = if law.dense {
            &[1.0]
        } else {
            &[1.0 - ext_p, ext_p]
        };
        assert!(entries.len() < 1 << 13, "a law of {} counts", entries.len());
        for (i, &(atom, cell)) in entries.iter().enumerate() {
            let c = law.cell(k0 + i as u32);
            let lf_min = c.log_density(c.rho_lo).min(c.log_density(tau));
            let squeeze = if lf_min.is_finite() {
                (lf_min - c.lf_max).exp()
            } else {
                0.0
            };
            let q = (squeeze * SQUEEZE_ONE).floor().clamp(0.0, SQUEEZE_ONE) as u32;
            for (e, &share) in shares.iter().enumerate() {
                let base = (i as u32) << law.shift() | (e as u32) << 1;
                weights.extend([atom * share, cell * share]);
                ids.extend([base | (SQUEEZE_ONE as u32) << 16, (base | 1) | q << 16]);
            }
        }
        law.alias = AliasTable::new(&weights, &ids);
        law
    }

    /// Bits of an entry's id below its count's index: ρ > 0, and for a sparse law
    /// whether the extension may record.
    #[inline(always)]
    fn shift(&self) -> u32 {
        if self.dense { 1 } else { 2 }
    }

    /// The count R of an entry's id.
    #[inline(always)]
    fn k_of(&self, id: usize) -> u32 {
        self.k0 + ((id & 0xffff) >> self.shift()) as u32
    }

    /// The cell of R = k: ρ ∈ (ρ_lo, τ], its log-density and its largest value.
    fn cell(&self, k: u32) -> Cell2 {
        let kf = f64::from(k);
        let a0 = self.body - kf * self.tau;
        let rho_lo = (-a0).max(0.0);
        let km1 = (kf - 1.0).max(0.0);
        let mut c = Cell2 {
            rho_lo,
            a0,
            km1,
            n: self.n,
            lf_max: 0.0,
        };
        // log-concave: the largest value at the mode, clamped to the cell
        let mode = (km1 / self.n - a0).clamp(rho_lo, self.tau);
        c.lf_max = c.log_density(mode);
        c
    }

    /// The first step of [`record`](Self::record) for a dense law: everything of the bin
    /// that does not depend on the dead time `r` carried into it, drawn apart so that a
    /// shot draws every dense bin's before the chain from bin to bin (their table loads
    /// then overlap): R and ρ of the body (ρ = 0 for the atom, a cell of no width, so
    /// that nothing branches on the pair drawn), and E ~ Exp(n), the time from ρ to the
    /// extension's first photon.
    #[inline(always)]
    pub fn draw_body<R: Rng + ?Sized>(&self, rng: &mut R) -> Drawn {
        let id = self.alias.bin_for(rng.next_u64());
        let k = self.k0 + ((id & 0xffff) >> 1) as u32;
        let cont = (id & 1) as f64;
        let rho_lo = cont * (f64::from(k) * self.tau - self.body).max(0.0);
        let mut rho = rho_lo + cont * (self.tau - rho_lo) * (1.0 - unit_f64(rng.next_u64()));
        let w = unit_f64(rng.next_u64());
        let squeeze = (id >> 16) as f64 * (1.0 / SQUEEZE_ONE);
        if w >= squeeze {
            rho = self.rho_exactly(rng, k, squeeze, rho, w);
        }
        let x = exp1(rng.next_u64(), rng) * self.mean_gap;
        Drawn {
            k,
            a: rho + x,
            b: rho - self.tau,
        }
    }

    /// The second step: the bin entered dead for `r ∈ [0, τ)` records R + 1 if the
    /// extension's first photon comes before its end, `ρ + E < τ − r`, leaving
    /// `r + ρ + E`, else R, leaving `max(0, r + ρ − τ)`. No branch (taken about half the
    /// time at high rates): this is the chain from bin to bin.
    #[inline(always)]
    pub fn finish(&self, d: &Drawn, r: f64) -> (u32, f64) {
        let hit = r + d.a < self.tau;
        let (left_hit, left_miss) = (r + d.a, (r + d.b).max(0.0));
        let mask = 0u64.wrapping_sub(u64::from(hit));
        let left = f64::from_bits((left_hit.to_bits() & mask) | (left_miss.to_bits() & !mask));
        (d.k + u32::from(hit), left)
    }

    /// Records the bin entered dead for `r ∈ [0, τ)`: the recorded count and the dead
    /// time left at its end (one `u64` and a compare in most bins of a sparse law).
    #[inline(always)]
    pub fn record<R: Rng + ?Sized>(&self, rng: &mut R, r: f64) -> (u32, f64) {
        if self.dense {
            let d = self.draw_body(rng);
            return self.finish(&d, r);
        }
        let id = self.alias.bin_for(rng.next_u64());
        let k = self.k_of(id);
        let rho = if id & 1 == 1 {
            self.rho(rng, k, (id >> 16) as f64 / SQUEEZE_ONE)
        } else {
            0.0
        };
        let ext = self.tau - r;
        if rho >= ext {
            return (k, rho - ext);
        }
        if id & 2 == 0 {
            return (k, 0.0); // E ≥ τ: the extension records nothing
        }
        let x = self.exp_below_tau(rng);
        if x < ext - rho {
            (k + 1, rho + x + r)
        } else {
            (k, 0.0)
        }
    }

    /// ρ in the cell of R = k (of squeeze `squeeze`) by rejection from the uniform.
    #[cold]
    fn rho<R: Rng + ?Sized>(&self, rng: &mut R, k: u32, squeeze: f64) -> f64 {
        let rho_lo = (f64::from(k) * self.tau - self.body).max(0.0);
        let rho = rho_lo + (self.tau - rho_lo) * (1.0 - unit_f64(rng.next_u64()));
        let w = unit_f64(rng.next_u64());
        if w < squeeze {
            return rho;
        }
        self.rho_exactly(rng, k, squeeze, rho, w)
    }

    /// The rejection step in the cell of R = k for the proposal `rho` and its uniform `w`
    /// when the squeeze did not decide, then on.
    #[cold]
    fn rho_exactly<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        k: u32,
        squeeze: f64,
        rho: f64,
        w: f64,
    ) -> f64 {
        let c = self.cell(k);
        let (mut rho, mut w) = (rho, w);
        loop {
            if w.ln() < c.log_density(rho) - c.lf_max {
                return rho;
            }
            rho = c.rho_lo + (self.tau - c.rho_lo) * (1.0 - unit_f64(rng.next_u64()));
            w = unit_f64(rng.next_u64());
            if w < squeeze {
                return rho;
            }
        }
    }

    /// Exp(n) conditioned below τ.
    #[cold]
    fn exp_below_tau<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let v = unit_f64(rng.next_u64());
        (-(-v * self.ext_p).ln_1p() / self.n).min(self.tau)
    }
}

/// A cell of a [`RateLaw`] for its rejection step.
struct Cell2 {
    rho_lo: f64,
    /// `L − kτ`.
    a0: f64,
    /// `k − 1`.
    km1: f64,
    n: f64,
    lf_max: f64,
}

impl Cell2 {
    /// `(k−1)·ln a − n·a` at `a = L − kτ + ρ`, with `0·ln 0 = 0`.
    fn log_density(&self, rho: f64) -> f64 {
        let a = self.a0 + rho;
        if self.km1 == 0.0 {
            -self.n * a
        } else {
            self.km1 * a.ln() - self.n * a
        }
    }
}

/// Layers of the exponential ziggurat.
const ZIG_LAYERS: usize = 256;
/// Its base layer's right end r and each layer's area v (Marsaglia & Tsang 2000, for
/// 256 layers: `v = e^{−r}(r + 1)`).
const ZIG_R: f64 = 7.697_117_470_131_05;

/// The exponential ziggurat's tables: the layers' right ends `x_0 = v/e^{−r}`, `x_1 = r`,
/// `x_{i+1} = −ln(v/x_i + e^{−x_i})`, `x_256 = 0`, and `f_i = e^{−x_i}`.
fn ziggurat() -> &'static ([f64; ZIG_LAYERS + 1], [f64; ZIG_LAYERS + 1]) {
    static TABLES: OnceLock<([f64; ZIG_LAYERS + 1], [f64; ZIG_LAYERS + 1])> = OnceLock::new();
    TABLES.get_or_init(|| {
        let v = (-ZIG_R).exp() * (ZIG_R + 1.0);
        let mut x = [0.0; ZIG_LAYERS + 1];
        x[0] = v / (-ZIG_R).exp();
        x[1] = ZIG_R;
        for i in 1..ZIG_LAYERS - 1 {
            x[i + 1] = -(v / x[i] + (-x[i]).exp()).ln();
        }
        x[ZIG_LAYERS] = 0.0;
        let f = x.map(|xi| (-xi).exp());
        (x, f)
    })
}

/// A standard exponential by the ziggurat (Marsaglia & Tsang 2000, "The ziggurat method
/// for generating random variables", J. Stat. Softw. 5(8)), its first try from the
/// uniform `u64` `bits` (low 8 bits the layer, top 53 the abscissa): accepted at once
/// ~99 % of the time; otherwise the wedge test, or the tail `r + Exp(1)`, from `rng`.
#[inline(always)]
fn exp1<R: Rng + ?Sized>(bits: u64, rng: &mut R) -> f64 {
    let (x, _) = ziggurat();
    let i = (bits & 0xff) as usize;
    let u = x[i] * unit_f64(bits);
    if u < x[i + 1] {
        return u;
    }
    exp1_slow(i, u, rng)
}

/// The ziggurat's wedge and tail for layer `i` and abscissa `u`, then on.
#[cold]
fn exp1_slow<R: Rng + ?Sized>(i: usize, u: f64, rng: &mut R) -> f64 {
    let (x, f) = ziggurat();
    let (mut i, mut u) = (i, u);
    loop {
        if i == 0 {
            // the tail beyond r: memoryless
            return ZIG_R - (1.0 - unit_f64(rng.next_u64())).ln();
        }
        if f[i] + (f[i + 1] - f[i]) * unit_f64(rng.next_u64()) < (-u).exp() {
            return u;
        }
        let bits = rng.next_u64();
        i = (bits & 0xff) as usize;
        u = x[i] * unit_f64(bits);
        if u < x[i + 1] {
            return u;
        }
    }
}

/// The entries of a law around its median `median` (R from `k_bottom` to `k_top`), each
/// side stopped once a mass (atom + cell) falls below [`CUTOFF`] of the median's: the
/// first R and the (atom, cell) masses.
fn around(
    median: u32,
    k_bottom: u32,
    k_top: u32,
    masses: impl Fn(u32) -> (f64, f64),
) -> (u32, Vec<(f64, f64)>) {
    let total = |(a, c): (f64, f64)| a + c;
    let peak = total(masses(median));
    let mut below = Vec::new();
    let mut k = median;
    while k > k_bottom {
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
    (k0, entries)
}

/// `P(Pois(μ) = x)` by Loader's saddle-point form.
pub(crate) fn pois_pmf(x: u32, mu: f64) -> f64 {
    if mu <= 0.0 {
        return if x == 0 { 1.0 } else { 0.0 };
    }
    if x == 0 {
        return (-mu).exp();
    }
    let x = f64::from(x);
    (-stirlerr(x) - bd0(x, mu)).exp() / (2.0 * std::f64::consts::PI * x).sqrt()
}

/// `(P(Pois(μ) ≥ k), P(Pois(μ) < k))`, the smaller summed from `k` outwards.
pub(crate) fn pois_tails(k: u32, mu: f64) -> (f64, f64) {
    if k == 0 {
        return (1.0, 0.0);
    }
    if mu <= 0.0 {
        return (0.0, 1.0);
    }
    if f64::from(k) > mu {
        let mut term = pois_pmf(k, mu);
        let (mut sum, mut j) = (0.0, k);
        loop {
            sum += term;
            if term < sum * 1e-18 || term == 0.0 {
                break;
            }
            j += 1;
            term *= mu / f64::from(j);
        }
        (sum, 1.0 - sum)
    } else {
        let mut j = k - 1;
        let mut term = pois_pmf(j, mu);
        let mut sum = 0.0;
        loop {
            sum += term;
            if j == 0 || term < sum * 1e-18 {
                break;
            }
            term *= f64::from(j) / mu;
            j -= 1;
        }
        (1.0 - sum, sum)
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

    /// A rate law's body has the mean of Müller's live-start counter on L = Δt − τ,
    /// `E R = Σ_{k≥1} P(Pois(n(L − (k−1)τ)) ≥ k)` (the tails written here from summed
    /// logarithms), within 1e-10, from 10 kHz to 400 MHz; and its probabilities sum to 1.
    /// Deterministic; a 1 % error in τ moves this mean by ≥ 3e-7 of itself from 1 MHz up.
    #[test]
    fn the_rate_law_has_the_live_start_mean() {
        let (tau, dt) = (3.5e-9, 2e-6);
        let body = dt - tau;
        let tail = |k: u32, mu: f64| -> f64 {
            // P(Pois(mu) >= k) = 1 − Σ_{j<k} e^{−mu} mu^j / j!
            let mut lnfact = 0.0;
            let mut below = 0.0;
            for j in 0..k {
                if j > 0 {
                    lnfact += f64::from(j).ln();
                }
                below += (-mu + f64::from(j) * mu.ln() - lnfact).exp();
            }
            if mu == 0.0 {
                0.0
            } else {
                (1.0 - below).max(0.0)
            }
        };
        for n in [1e4, 1e6, 3e7, 3e8, 4e8] {
            let law = RateLaw::new(n, tau, dt);
            let mut total = 0.0;
            let mut mean = 0.0;
            for (id, pe) in law.alias.halves() {
                total += pe;
                mean += pe * f64::from(law.k_of(id as usize));
            }
            let mut want = 0.0;
            let mut k = 1u32;
            loop {
                let mu = n * (body - (f64::from(k) - 1.0) * tau);
                if mu <= 0.0 {
                    break;
                }
                let t = tail(k, mu);
                want += t;
                if t < 1e-18 && f64::from(k) > n * body {
                    break;
                }
                k += 1;
            }
            assert!((total - 1.0).abs() < 1e-12, "n {n}: total {total}");
            assert!((mean / want - 1.0).abs() < 1e-10, "n {n}: {mean} vs {want}");
        }
    }
}
