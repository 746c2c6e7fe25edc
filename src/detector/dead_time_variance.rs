//! The variance of a non-paralyzable detector's recorded count in one bin, exact for a
//! rate constant within each bin (the model's assumption; docs/model.md §4b), whatever
//! the rate, the bin's width against τ and the history before the bin (issue 36).
//!
//! **Law given the dead time carried in.** A bin of width Δt and true rate n, entered
//! dead for `r ∈ [0, τ)`, records its k-th count at `r + (k−1)τ + Γ(k, n)` (Müller 1973,
//! NIM 112, 47: after each record the detector is blind for τ, then waits Exp(n)), so
//!
//! ```text
//! P(K ≥ k | r) = P(Γ(k, n) ≤ Δt − r − (k−1)τ) = Q(k; n·(Δt − r − (k−1)τ)),
//! ```
//!
//! `Q(k; μ) = P(Pois(μ) ≥ k)` (0 for μ ≤ 0). With an integer c near the mean and
//! `X = K − c`: `E X = Σ_{k>c} Q_k − Σ_{k≤c} L_k` and
//! `E X² = Σ_{k>c} (2(k−c)−1)·Q_k + Σ_{k≤c} (2(c−k)+1)·L_k`, `L_k = 1 − Q_k` (each
//! tail summed from its small side, `counting::pois_tails`): no cancellation of the
//! large `E K²` against `(E K)²` when the count is near its ceiling `Δt/τ`.
//!
//! **The dead time carried in.** The detector enters the bin dead for `r = τ − a` when
//! it recorded a count at the age a < τ before the bin's start (no other count can
//! follow it within τ), which has the density `m(t_b − a)` of the mean recorded rate;
//! live with the rest of the probability. The mean-rate solver of
//! [`DeadTime::recorded_means`] holds exactly that: its last τ of recorded counts per
//! grid step ([`DeadTime::solve`]), the midpoint rule in a (step min(τ, Δt)/64). Then
//! `Var K = E_r E[X² | r] − (E_r E[X | r])²`.
//!
//! Where the grid is too long ([`MAX_GRID_STEPS`](super::dead_time::MAX_GRID_STEPS)) the state entering a
//! bin is taken stationary (live with probability `1/(1+nτ)`, else r uniform on (0, τ)),
//! as the mean is.
//!
//! The renewal asymptote `nΔt/(1+nτ)³` this replaces holds for Δt much longer than the
//! count's correlation time; at nτ ≫ 1 the counts are nearly periodic, their phase
//! decorrelates only over ~(nτ)² dead times, and in a bin of a few tens of τ the
//! variance is mostly the phase's (up to 1/4 + the intrinsic part): 11× the asymptote at
//! 8 GHz, τ = 5 ns, Δt = 200 ns. The paralyzable detector keeps the renewal form
//! `mΔt·(1 − 2nτ·e^{−nτ})` (it records ever fewer counts at high rates, where it is not
//! used).

use super::counting::pois_tails;
use super::dead_time::{DeadTime, DeadTimeModel};

/// Residual dead times at most this many points per bin in the quadrature over the
/// dead time carried in (the solver's steps grouped beyond).
const MAX_RESIDUAL_POINTS: usize = 256;

/// Grid points of the stationary entering state.
const STATIONARY_POINTS: usize = 64;

/// Tail probabilities below this are taken as 0 when summing the count's law.
const TAIL_CUTOFF: f64 = 1e-18;

impl DeadTime {
    /// Mean and variance per shot of each bin's recorded count for true means `lambda`
    /// per shot: the mean of [`recorded_means`](Self::recorded_means) (the same bits), the
    /// variance exact for a non-paralyzable detector (module docs), the renewal form
    /// [`recorded_variance`](Self::recorded_variance) for a paralyzable one.
    pub fn recorded_mean_and_variance(&self, lambda: &[f64]) -> (Vec<f64>, Vec<f64>) {
        if self.pixels > 1 {
            // k independent pixels at λ/k: means and variances add
            let k = self.pixels as f64;
            let share: Vec<f64> = lambda.iter().map(|l| l / k).collect();
            let (m, v) = self.pixel().recorded_mean_and_variance(&share);
            let times_k = |x: Vec<f64>| x.into_iter().map(|x| k * x).collect();
            return (times_k(m), times_k(v));
        }
        if self.model == DeadTimeModel::Paralyzable {
            let var = lambda.iter().map(|&l| self.recorded_variance(l)).collect();
            return (self.recorded_means(lambda), var);
        }
        let mut var = vec![0.0; lambda.len()];
        let mut points: Vec<(f64, f64)> = Vec::new();
        let mean = self.solve(lambda, |b, state| {
            let n = lambda[b] / self.bin_width_s;
            match state {
                Some((recent, h)) => self.residuals_from_grid(recent, h, &mut points),
                None => self.stationary_residuals(n, &mut points),
            }
            var[b] = self.variance_given_residuals(n, &points);
        });
        (mean, var)
    }

    /// The dead times `(r, probability)` carried into a bin from the solver's recorded
    /// counts `recent` (m·h per step of `h`, newest first): the step at age a (its
    /// middle, within τ) leaves `r = τ − a`; grouped into at most
    /// [`MAX_RESIDUAL_POINTS`] points (probability-weighted mean r).
    fn residuals_from_grid(&self, recent: &[f64], h: f64, points: &mut Vec<(f64, f64)>) {
        points.clear();
        let tau = self.tau_s;
        let group = recent.len().div_ceil(MAX_RESIDUAL_POINTS).max(1);
        for (g, chunk) in recent.chunks(group).enumerate() {
            let (mut w, mut wr) = (0.0, 0.0);
            for (i, &p) in chunk.iter().enumerate() {
                let age = ((g * group + i) as f64 + 0.5) * h;
                if age < tau && p > 0.0 {
                    w += p;
                    wr += p * (tau - age);
                }
            }
            if w > 0.0 {
                points.push((wr / w, w));
            }
        }
    }

    /// The stationary dead time carried in at rate `n`: r uniform on (0, τ) with
    /// probability `nτ/(1+nτ)` (the age of the last count has density `n/(1+nτ)` below
    /// τ), by the midpoint rule on [`STATIONARY_POINTS`] points.
    fn stationary_residuals(&self, n: f64, points: &mut Vec<(f64, f64)>) {
        points.clear();
        let x = n * self.tau_s;
        let w = x / (1.0 + x) / STATIONARY_POINTS as f64;
        points.extend((0..STATIONARY_POINTS).map(|i| {
            let r = self.tau_s * (i as f64 + 0.5) / STATIONARY_POINTS as f64;
            (r, w)
        }));
    }

    /// `Var K` of a bin at rate `n` entered dead for r with the probabilities `points`
    /// (live with the rest): `E_r E[X²|r] − (E_r E[X|r])²`, X = K − c (module docs).
    fn variance_given_residuals(&self, n: f64, points: &[(f64, f64)]) -> f64 {
        if n <= 0.0 {
            return 0.0;
        }
        let dt = self.bin_width_s;
        let c = (n * dt / (1.0 + n * self.tau_s)).round() as u32;
        let dead: f64 = points.iter().map(|p| p.1).sum();
        let live = (1.0 - dead).max(0.0);
        let (m0, s0) = self.centred_moments(n, 0.0, c);
        let (mut ex, mut ex2) = (live * m0, live * s0);
        for &(r, w) in points {
            let (m, s) = self.centred_moments(n, r, c);
            ex += w * m;
            ex2 += w * s;
        }
        let total = live + dead;
        let (ex, ex2) = (ex / total, ex2 / total);
        (ex2 - ex * ex).max(0.0)
    }

    /// `(E[X | r], E[X² | r])` of `X = K − c` for a bin at rate `n` entered dead for `r`
    /// (module docs).
    fn centred_moments(&self, n: f64, r: f64, c: u32) -> (f64, f64) {
        let (tau, dt) = (self.tau_s, self.bin_width_s);
        let (mut ex, mut ex2) = (0.0, 0.0);
        let mut k = 1u32;
        loop {
            let mu = n * (dt - r - f64::from(k - 1) * tau);
            if mu <= 0.0 {
                // K < k surely: L_k = 1 for every k ≤ c left
                for j in k..=c {
                    ex -= 1.0;
                    ex2 += f64::from(2 * (c - j) + 1);
                }
                break;
            }
            let (ge, lt) = pois_tails(k, mu);
            if k <= c {
                ex -= lt;
                ex2 += f64::from(2 * (c - k) + 1) * lt;
            } else {
                ex += ge;
                ex2 += f64::from(2 * (k - c) - 1) * ge;
                if ge < TAIL_CUTOFF {
                    break;
                }
            }
            k += 1;
        }
        (ex, ex2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nonparalyzable(tau_s: f64, bin_width_s: f64) -> DeadTime {
        DeadTime {
            tau_s,
            model: DeadTimeModel::Nonparalyzable,
            bin_width_s,
            pixels: 1,
        }
    }

    #[test]
    fn a_live_bin_of_low_rate_is_poisson_and_the_mean_is_the_solvers() {
        let d = nonparalyzable(5e-9, 2e-7);
        let lambda = vec![1e-3; 5];
        let (m, v) = d.recorded_mean_and_variance(&lambda);
        assert_eq!(m, d.recorded_means(&lambda));
        // nτ = 2.5e-5: the variance is λ to O(λ·nτ)
        assert!((v[3] / 1e-3 - 1.0).abs() < 1e-4, "{v:?}");
    }

    #[test]
    fn the_laws_mean_given_the_carried_dead_time_is_the_solvers() {
        // E_r E[K|r] against the solver's mean, at rates from 1 MHz to 8 GHz
        let d = nonparalyzable(5e-9, 2e-7);
        for rate in [1e6, 1e8, 1e9, 8e9] {
            let lambda = vec![rate * 2e-7; 30];
            let mean = d.recorded_means(&lambda);
            let mut points = Vec::new();
            let mut law = vec![0.0; 30];
            d.solve(&lambda, |b, state| {
                let (recent, h) = state.unwrap();
                d.residuals_from_grid(recent, h, &mut points);
                let dead: f64 = points.iter().map(|p| p.1).sum();
                let c = 3;
                let mut e = (1.0 - dead) * d.centred_moments(rate, 0.0, c).0;
                for &(r, w) in &points {
                    e += w * d.centred_moments(rate, r, c).0;
                }
                law[b] = e + f64::from(c);
            });
            for b in [0, 1, 5, 29] {
                assert!(
                    (law[b] / mean[b] - 1.0).abs() < 1e-4,
                    "{rate} Hz bin {b}: {} vs {}",
                    law[b],
                    mean[b]
                );
            }
        }
    }
}
