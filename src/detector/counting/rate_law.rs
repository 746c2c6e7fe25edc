//! The counting law of a bin given its constant true rate, its photons not drawn
//! ([`RateLaw`]): Müller's law of the body, the extension's first photon.

use rand::Rng;

use super::probabilities::{pois_pmf, pois_tails};
use super::support::{around, unit_f64};
use super::ziggurat::exp1;
use crate::sampling::AliasTable;

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
///
/// [`Family`]: super::family::Family
/// [`Family::record_bin`]: super::family::Family::record_bin
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

#[cfg(test)]
mod tests {
    use super::*;

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
