//! Afterpulsing (docs/model.md §4b, "Afterpulsing"): a recorded count triggers, with
//! probability p, one spurious later count, its delay drawn from a sum of exponentials
//! `Σ_i a_i·e^{−t/τ_i}/τ_i` (weights a_i normalized to 1), as SPCM-type detectors do
//! (MPL corrects every profile for it: Campbell et al. 2002, J. Atmos. Oceanic Technol.
//! 19, 431).
//!
//! **Model.** Each recorded count (after the dead time) is an independent trial: with
//! probability `q_j = p·w_j` its afterpulse lands j bins later, `w_j` the bin-averaged
//! shares of the delay law for a count uniform within its bin
//! ([`super::delay::exponential_shares`], mixed by the weights). Afterpulses are added
//! to the record: they neither pass the dead time nor afterpulse themselves (both are of
//! order p·m·τ and p², below 1e-4 for p ≤ 1e-2 at the rates a photon counter records
//! linearly). Afterpulses beyond the window are lost.
//!
//! **Sampler** ([`Afterpulsing::add_profile`]). Because every recorded count is an
//! independent trial, a profile's afterpulses follow from its summed recorded counts R_b
//! exactly as from its shots one by one: per bin, `T ~ Binomial(R_b, p)` afterpulses,
//! each given a component by its weight and a delay `Exp(τ_i)` from a time uniform in
//! the source bin. Cost O(bins + afterpulses) per profile, on every path; the law's
//! convolutions are recursions, O(bins) per component (or pair of components).
//!
//! **Law.** Mean `m_b + Σ_j q_j·m_{b−j}` with m the recorded mean per shot; variance
//! `(1 + q_0)²·v_b + Σ_{j≥1} q_j²·v_{b−j} + Σ_j q_j(1 − q_j)·m_{b−j}` with v the
//! recorded variance (the covariances of recorded counts in different bins, which dead
//! time makes O(m·τ) small, are neglected).

use rand::Rng;
use rand_distr::{Binomial, Distribution, Exp1};

use super::delay::{exponential_law, exponential_tail};
use crate::config::AfterpulsingConfig;

/// Seed offset of the afterpulse streams.
pub const AFTERPULSE_STREAM: u64 = 0xAF7E_9B15_0000_0001;

/// Afterpulsing of a photon counter on bins of a width.
#[derive(Debug, Clone)]
pub struct Afterpulsing {
    /// Probability p of an afterpulse per recorded count.
    pub probability: f64,
    /// The delay law's components: weight (normalized), mean delay in bins, and the
    /// component's shares as `(w_0, w_1, a)` ([`exponential_law`]).
    components: Vec<(f64, f64, (f64, f64, f64))>,
}

impl Afterpulsing {
    /// The afterpulsing of `cfg` on bins of `bin_width_s`.
    pub fn from_config(cfg: &AfterpulsingConfig, bin_width_s: f64) -> Self {
        let weights = cfg.weights();
        let total: f64 = weights.iter().sum();
        let components = cfg
            .time_constants_s
            .iter()
            .zip(&weights)
            .map(|(&tau, &a)| {
                (
                    a / total,
                    tau / bin_width_s,
                    exponential_law(tau, bin_width_s),
                )
            })
            .collect();
        Afterpulsing {
            probability: cfg.probability,
            components,
        }
    }

    /// The share `w_0` of the mixed delay law: what lands in the count's own bin.
    fn first_share(&self) -> f64 {
        self.components
            .iter()
            .map(|&(c, _, (w0, _, _))| c * w0)
            .sum()
    }

    /// `Σ_j w_j·x_{b−j}` for the mixed law, by one recursion per component (O(bins)).
    fn convolve(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        for &(c, _, (w0, w1, a)) in &self.components {
            let z = exponential_tail(x, a);
            for ((o, v), t) in y.iter_mut().zip(x).zip(&z) {
                *o += c * (w0 * v + w1 * t);
            }
        }
        y
    }

    /// `Σ_j w_j²·x_{b−j}` for the mixed law: the products of the components' shares,
    /// one recursion per pair (at most 64).
    fn convolve_squares(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        for &(ci, _, (w0i, w1i, ai)) in &self.components {
            for &(ck, _, (w0k, w1k, ak)) in &self.components {
                let z = exponential_tail(x, ai * ak);
                for ((o, v), t) in y.iter_mut().zip(x).zip(&z) {
                    *o += ci * ck * (w0i * w0k * v + w1i * w1k * t);
                }
            }
        }
        y
    }

    /// Expected afterpulses per shot of each bin for recorded means `recorded`.
    pub fn expected(&self, recorded: &[f64]) -> Vec<f64> {
        let p = self.probability;
        self.convolve(recorded).iter().map(|y| p * y).collect()
    }

    /// Variance per shot of each bin's count with its afterpulses, for the recorded
    /// means `mean` and variances `var` per shot (module docs):
    /// `(1+q_0)²v_b + Σ_{j≥1} q_j² v_{b−j} + Σ_j q_j m_{b−j} − Σ_j q_j² m_{b−j}`.
    pub fn variance(&self, mean: &[f64], var: &[f64]) -> Vec<f64> {
        let p = self.probability;
        let q0 = p * self.first_share();
        let from_var = self.convolve_squares(var);
        let q_m = self.convolve(mean);
        let q2_m = self.convolve_squares(mean);
        (0..mean.len())
            .map(|b| {
                // Σ_{j≥1} q_j² v_{b−j}: the squares' sum less its j = 0 term
                let later = p * p * from_var[b] - q0 * q0 * var[b];
                (1.0 + q0).powi(2) * var[b] + later + p * q_m[b] - p * p * q2_m[b]
            })
            .collect()
    }

    /// Adds into `acc` the afterpulses of a profile whose recorded counts are `recorded`
    /// (summed over its shots), drawn from `rng`: per bin `Binomial(R_b, p)` afterpulses,
    /// each given a component by its weight and the delay `u + E·τ_i/Δt` bins from a
    /// count uniform in its bin (`u ~ U(0,1)`, E a standard exponential: rand_distr's
    /// ziggurat), landing `⌊u + E·τ_i/Δt⌋` bins later; those past the window are lost.
    pub fn add_profile<R: Rng + ?Sized>(&self, rng: &mut R, recorded: &[u64], acc: &mut [u64]) {
        let n = recorded.len();
        for (b, &r) in recorded.iter().enumerate() {
            if r == 0 {
                continue;
            }
            let t = match Binomial::new(r, self.probability) {
                Ok(d) => d.sample(rng),
                Err(_) => 0,
            };
            for _ in 0..t {
                let tau_bins = self.component(rng);
                let u = unit(rng.next_u64());
                let e: f64 = Exp1.sample(rng);
                let j = (u + e * tau_bins).floor();
                if j < (n - b) as f64 {
                    acc[b + j as usize] += 1;
                }
            }
        }
    }

    /// A component's mean delay in bins, drawn by the components' weights.
    fn component<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        if self.components.len() == 1 {
            return self.components[0].1;
        }
        let mut x = unit(rng.next_u64());
        for &(c, tau_bins, _) in &self.components {
            if x < c {
                return tau_bins;
            }
            x -= c;
        }
        self.components[self.components.len() - 1].1
    }
}

/// A uniform in [0, 1) from the top 53 bits of `x`.
fn unit(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}
