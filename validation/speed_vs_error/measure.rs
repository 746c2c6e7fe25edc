//! What is measured of each method: its time per profile (interleaved timing) and the
//! error of R profiles against the exact Poisson law (KS distance, relative errors of the
//! mean, variance and S/N, each beside its noise floor).

use std::time::Instant;

use lidarsim::sampling::approx::{poisson_cdf, poisson_pmf};
use statrs::distribution::{ContinuousCDF, Normal};

use crate::{DrawFn, Mode};

/// Rounds of the interleaved timing: every method of a case is timed in turn, this many
/// times, so that a burst of load on the shared host hits them alike.
pub(crate) const TIMING_ROUNDS: usize = 8;

/// Time per profile of each draw: the median over chunks of profiles (each chunk ≥ ~1 ms,
/// drawn into a reused, cache-hot buffer) over [`TIMING_ROUNDS`] interleaved rounds, with
/// at least one chunk per round and `mode.timing_s` of drawing timed per method in all.
pub(crate) fn time_interleaved(draws: &[&DrawFn], bins: usize, mode: &Mode) -> Vec<f64> {
    struct Timer {
        chunk: usize,
        times: Vec<f64>,
        timed: f64,
        next: u64,
        scratch: Vec<u64>,
    }
    let mut timers: Vec<Timer> = draws
        .iter()
        .map(|draw| {
            // pilot: a few profiles (indices far from the ones measured)
            let mut acc = vec![0u64; bins];
            let start = Instant::now();
            let mut n = 0u64;
            while n < 3 || (n < 1000 && start.elapsed().as_secs_f64() < 0.01) {
                acc.fill(0);
                draw(1 << 40 | n, &mut acc);
                n += 1;
            }
            let t1 = start.elapsed().as_secs_f64() / n as f64;
            let chunk = ((1e-3 / t1).ceil() as usize).clamp(1, 4096);
            Timer {
                chunk,
                times: Vec::new(),
                timed: 0.0,
                next: 1 << 41,
                scratch: vec![0u64; chunk * bins],
            }
        })
        .collect();
    for round in 1..=TIMING_ROUNDS {
        let target = mode.timing_s * round as f64 / TIMING_ROUNDS as f64;
        for (draw, t) in draws.iter().zip(timers.iter_mut()) {
            while t.timed < target || t.times.len() < round {
                let start = Instant::now();
                for acc in t.scratch.chunks_exact_mut(bins) {
                    acc.fill(0);
                    draw(t.next, acc);
                    t.next += 1;
                }
                let dt = start.elapsed().as_secs_f64();
                t.timed += dt;
                t.times.push(dt / t.chunk as f64);
            }
        }
    }
    timers
        .into_iter()
        .map(|mut t| {
            t.times.sort_by(f64::total_cmp);
            t.times[t.times.len() / 2]
        })
        .collect()
}

/// Profiles for the error statistics: the largest of a fixed ladder that fits the budget
/// (at least `r_min`), so that a rerun mostly draws the same profiles despite timing noise.
pub(crate) fn profiles_for(mode: &Mode, time_s: f64) -> usize {
    const LADDER: [usize; 11] = [
        100, 200, 300, 500, 1000, 2000, 5000, 10000, 20000, 50000, 100000,
    ];
    let fit = (mode.error_budget_s / time_s) as usize;
    LADDER
        .iter()
        .copied()
        .filter(|&r| r >= mode.r_min && r <= mode.r_max && r <= fit)
        .max()
        .unwrap_or(mode.r_min)
}

/// Draws profiles `0..r` (untimed), bin-major.
pub(crate) fn sample(draw: &DrawFn, bins: usize, r: usize) -> Vec<u64> {
    let mut acc = vec![0u64; bins];
    let mut counts = vec![0u64; r * bins];
    for p in 0..r {
        acc.fill(0);
        draw(p as u64, &mut acc);
        for (b, &c) in acc.iter().enumerate() {
            counts[b * r + p] = c;
        }
    }
    counts
}

pub(crate) struct Stats {
    pub(crate) max_ks: f64,
    /// (max relative error over the selected bins, its 95 % noise floor)
    pub(crate) rel_mean: (f64, f64),
    pub(crate) rel_var: (f64, f64),
    pub(crate) rel_snr: (f64, f64),
}

/// Per-bin error statistics of `r` profiles against Poisson(`mu[i]`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn bin_stats(
    counts: &[u64],
    r: usize,
    mu: &[f64],
    signal: &[f64],
    m: f64,
    rest: f64,
    snr: &[f64],
    sel: &[usize],
) -> Stats {
    let rf = r as f64;
    let mut max_ks: f64 = 0.0;
    let (mut em, mut ev, mut es) = (0.0f64, 0.0f64, 0.0f64);
    let (mut sm, mut sv, mut ss) = (0.0f64, 0.0f64, 0.0f64);
    for (i, &mu_i) in mu.iter().enumerate() {
        let mut c = counts[i * r..(i + 1) * r].to_vec();
        c.sort_unstable();
        max_ks = max_ks.max(ks_empirical(&c, mu_i));
        if !sel.contains(&i) {
            continue;
        }
        let mean = c.iter().map(|&x| x as f64).sum::<f64>() / rf;
        let var = c.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / (rf - 1.0);
        let s = m * signal[i];
        em = em.max(((mean - mu_i) / mu_i).abs());
        ev = ev.max(((var - mu_i) / mu_i).abs());
        let snr_hat = (mean - rest) / var.sqrt();
        es = es.max((snr_hat / snr[i] - 1.0).abs());
        // standard deviations of the relative errors under the exact law
        sm = sm.max((1.0 / (rf * mu_i)).sqrt());
        sv = sv.max(((2.0 + 1.0 / mu_i) / rf).sqrt());
        ss = ss.max(
            ((mu_i / (s * s) + 0.5 + 0.25 / mu_i - 1.0 / s) / rf)
                .max(0.0)
                .sqrt(),
        );
    }
    // 95 % bound on the largest of n |normal| errors (union bound)
    let z = if sel.is_empty() {
        0.0
    } else {
        Normal::standard().inverse_cdf(1.0 - 0.025 / sel.len() as f64)
    };
    Stats {
        max_ks,
        rel_mean: (em, z * sm),
        rel_var: (ev, z * sv),
        rel_snr: (es, z * ss),
    }
}

/// 95 % quantile of the largest of `n` independent one-sample KS distances from `r`
/// draws of a continuous law (Kolmogorov's asymptote, union bound); for a discrete law
/// the distance is stochastically smaller, so this is conservative.
pub(crate) fn ks_floor(n: usize, r: usize) -> f64 {
    ((2.0 * n as f64 / 0.05).ln() / 2.0).sqrt() / (r as f64).sqrt()
}

/// `sup_k |F_emp(k) − F_Poisson(mu)(k)|` of the sorted sample `c`.
fn ks_empirical(c: &[u64], mu: f64) -> f64 {
    let n = c.len() as f64;
    let (lo, hi) = (c[0], c[c.len() - 1]);
    let mut best: f64;
    if hi - lo > 5_000_000 {
        // very wide range: evaluate at the sample values only
        best = 0.0;
        let mut i = 0;
        while i < c.len() {
            let v = c[i];
            let below = i as f64 / n;
            while i < c.len() && c[i] == v {
                i += 1;
            }
            let f_before = if v == 0 { 0.0 } else { poisson_cdf(v - 1, mu) };
            best = best.max((below - f_before).abs());
            best = best.max((i as f64 / n - poisson_cdf(v, mu)).abs());
        }
        return best;
    }
    let mut f = if lo == 0 {
        0.0
    } else {
        poisson_cdf(lo - 1, mu)
    };
    best = f;
    let mut i = 0;
    let mut k = lo;
    loop {
        f += poisson_pmf(k, mu);
        while i < c.len() && c[i] <= k {
            i += 1;
        }
        best = best.max((i as f64 / n - f).abs());
        if k == hi {
            break;
        }
        k += 1;
    }
    best
}
