//! The counting tables given a bin's photons ([`Family`]): per N the boundary split, per M
//! the body's law of (R, ρ) begun live, and the draw of one bin from them (the method,
//! its sampling and precision: the docs of `detector::counting`).

use std::sync::{Arc, Mutex, OnceLock};

use rand::Rng;

use super::probabilities::{binom_pmf, binom_tails};
use super::support::{around, unit_f64};
use crate::sampling::{AliasTable, count_above};

/// Most photons in a bin drawn from the tables; more go through the arrival-time sweep.
pub const MAX_PHOTONS: u32 = 1 << 14;

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

/// `(k−1)·ln u + (M−k)·ln(1−u)`, with `0·ln 0 = 0`.
#[inline]
fn log_density(c: &Cell, u: f64) -> f64 {
    let term = |a: f64, x: f64| if a == 0.0 { 0.0 } else { a * x.ln() };
    term(c.a, u) + term(c.b, 1.0 - u)
}

#[cfg(test)]
mod tests {
    use super::*;

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
