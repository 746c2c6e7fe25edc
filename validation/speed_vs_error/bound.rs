//! The dense check of the KS bound of the normal approximation (the threshold's
//! guarantee), and the approximation's exact mean and variance biases.

use std::time::Instant;

use lidarsim::sampling::approx::{KS_ASYMPTOTE, normal_approx_ks, normal_approx_ks_bound};

use crate::report::sci;

/// Exact relative biases `(E/μ − 1, Var/μ − 1)` of the approximate law
/// `max(0, round(μ + √μ·g))` (summed over its support; Sheppard's `(0, 1/(12μ))` above
/// μ = 1e5, where the clamp is below Φ(−316)).
fn approx_bias(mu: f64) -> (f64, f64) {
    if mu >= 1e5 {
        return (0.0, 1.0 / (12.0 * mu));
    }
    let s = mu.sqrt();
    let phi = |z: f64| 0.5 * statrs::function::erf::erfc(-z / std::f64::consts::SQRT_2);
    let lo = (mu - 14.0 * s - 50.0).floor().max(0.0) as u64;
    let hi = (mu + 14.0 * s + 50.0).ceil() as u64;
    let (mut m1, mut m2) = (0.0, 0.0);
    let mut below = if lo == 0 {
        0.0
    } else {
        phi((lo as f64 - 0.5 - mu) / s)
    };
    for k in lo..=hi {
        let upto = phi((k as f64 + 0.5 - mu) / s);
        let p = upto - below;
        below = upto;
        let d = k as f64 - mu;
        m1 += d * p;
        m2 += d * d * p;
    }
    (m1 / mu, (m2 - m1 * m1) / mu - 1.0)
}

/// Largest |relative bias| of the mean and the variance of the approximation over means
/// `μ* … 1000 μ*` (150 log-spaced means; from 1e-3 when μ* = 0).
pub(crate) fn bias_above(threshold: f64) -> (f64, f64) {
    let start = threshold.max(1e-3);
    (0..=150)
        .map(|j| approx_bias(start * 10f64.powf(j as f64 / 50.0)))
        .fold((0.0f64, 0.0f64), |a, (m, v)| {
            (a.0.max(m.abs()), a.1.max(v.abs()))
        })
}

pub(crate) struct BoundCheck {
    pub(crate) points: usize,
    pub(crate) seconds: f64,
    /// max over the grid of (√μ·KS/c − 1)·μ, for μ ≤ 1e7 (where f64 resolves it).
    pub(crate) lattice_max: f64,
    /// max over the grid of KS / bound (must be ≤ 1).
    pub(crate) worst_ratio: f64,
    pub(crate) worst_mu: f64,
    pub(crate) sup_ks: f64,
    pub(crate) sup_mu: f64,
    /// √μ·KS/c at the largest means.
    pub(crate) far: Vec<(f64, f64)>,
    /// (segment, points per decade or per unit)
    pub(crate) grid: Vec<String>,
}

pub(crate) fn bound_check(quick: bool) -> BoundCheck {
    let t = Instant::now();
    let q = if quick { 10 } else { 1 };
    let c = KS_ASYMPTOTE;
    let mut pts: Vec<f64> = Vec::new();
    let mut grid = Vec::new();
    let segs: [(f64, f64, usize); 6] = [
        (-6.0, -1.0, 200),
        (-1.0, 2.0, 20000),
        (2.0, 4.0, 2000),
        (4.0, 7.0, 100),
        (7.0, 12.0, 20),
        (12.0, 15.0, 10),
    ];
    for (a, b, per) in segs {
        let per = (per / q).max(5);
        let n = ((b - a) * per as f64) as usize;
        pts.extend((0..n).map(|i| 10f64.powf(a + (b - a) * i as f64 / n as f64)));
        grid.push(format!("10^{a}–10^{b}: {per} per decade"));
    }
    pts.push(1e15);
    // full periods of the lattice term at a few means
    for base in [10.0, 1e3, 1e5, 1e7] {
        let per = 400 / q;
        pts.extend((0..per).map(|i| base + i as f64 / per as f64));
        grid.push(format!(
            "[{}, {}+1): {per} per unit",
            sci(base, 0),
            sci(base, 0)
        ));
    }
    let mut bc = BoundCheck {
        points: pts.len(),
        seconds: 0.0,
        lattice_max: f64::NEG_INFINITY,
        worst_ratio: 0.0,
        worst_mu: 0.0,
        sup_ks: 0.0,
        sup_mu: 0.0,
        far: Vec::new(),
        grid,
    };
    for &mu in &pts {
        let ks = normal_approx_ks(mu);
        let s = ks * mu.sqrt() / c;
        if (1.0..=1e7).contains(&mu) {
            bc.lattice_max = bc.lattice_max.max((s - 1.0) * mu);
        }
        let ratio = ks / normal_approx_ks_bound(mu);
        if ratio > bc.worst_ratio {
            bc.worst_ratio = ratio;
            bc.worst_mu = mu;
        }
        if ks > bc.sup_ks {
            bc.sup_ks = ks;
            bc.sup_mu = mu;
        }
    }
    for mu in [1e9, 1e12, 1e15] {
        bc.far.push((mu, normal_approx_ks(mu) * mu.sqrt() / c));
    }
    bc.seconds = t.elapsed().as_secs_f64();
    bc
}
