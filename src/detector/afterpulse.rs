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
//! each placed j bins later by an alias draw over the delay shares (Walker 1977; one
//! `u64` a draw). Cost O(bins + afterpulses) per profile, on every path.
//!
//! **Law.** Mean `m_b + Σ_j q_j·m_{b−j}` with m the recorded mean per shot; variance
//! `(1 + q_0)²·v_b + Σ_{j≥1} q_j²·v_{b−j} + Σ_j q_j(1 − q_j)·m_{b−j}` with v the
//! recorded variance (the covariances of recorded counts in different bins, which dead
//! time makes O(m·τ) small, are neglected).

use rand::Rng;
use rand_distr::{Binomial, Distribution};

use crate::config::AfterpulsingConfig;
use crate::sampling::alias::AliasTable;

/// Seed offset of the afterpulse streams.
pub const AFTERPULSE_STREAM: u64 = 0xAF7E_9B15_0000_0001;

/// Afterpulsing of a photon counter on a window of bins.
#[derive(Debug, Clone)]
pub struct Afterpulsing {
    /// Probability p of an afterpulse per recorded count.
    pub probability: f64,
    /// Shares `w_j` of the delay law, j = 0, 1, … (summing to 1 less what falls beyond
    /// the window).
    shares: Vec<f64>,
    /// Alias table over j.
    table: AliasTable,
}

impl Afterpulsing {
    /// The afterpulsing of `cfg` on `bins` bins of `bin_width_s`.
    pub fn from_config(cfg: &AfterpulsingConfig, bin_width_s: f64, bins: usize) -> Self {
        let total: f64 = cfg.weights().iter().sum();
        let mut shares = vec![0.0; bins.max(1)];
        for (tau, a) in cfg.time_constants_s.iter().zip(cfg.weights()) {
            let w = super::delay::exponential_shares(*tau, bin_width_s, bins.max(1));
            for (s, x) in shares.iter_mut().zip(w) {
                *s += a / total * x;
            }
        }
        while shares.len() > 1 && shares.last() == Some(&0.0) {
            shares.pop();
        }
        // the share beyond the window: an afterpulse drawn there is dropped
        let beyond = (1.0 - shares.iter().sum::<f64>()).max(0.0);
        let mut weights = shares.clone();
        weights.push(beyond);
        let ids: Vec<u32> = (0..weights.len() as u32).collect();
        Afterpulsing {
            probability: cfg.probability,
            table: AliasTable::new(&weights, &ids),
            shares,
        }
    }

    /// The shares `w_j`.
    pub fn shares(&self) -> &[f64] {
        &self.shares
    }

    /// Expected afterpulses per shot of each bin for recorded means `recorded`.
    pub fn expected(&self, recorded: &[f64]) -> Vec<f64> {
        let p = self.probability;
        let mut out = vec![0.0; recorded.len()];
        for (b, &m) in recorded.iter().enumerate() {
            for (o, w) in out[b..].iter_mut().zip(&self.shares) {
                *o += p * w * m;
            }
        }
        out
    }

    /// Variance per shot of each bin's count with its afterpulses, for the recorded
    /// means `mean` and variances `var` per shot (module docs).
    pub fn variance(&self, mean: &[f64], var: &[f64]) -> Vec<f64> {
        let p = self.probability;
        let mut out: Vec<f64> = var
            .iter()
            .map(|v| (1.0 + p * self.shares[0]).powi(2) * v)
            .collect();
        for b in 0..mean.len() {
            for (j, w) in self.shares.iter().enumerate() {
                let Some(o) = out.get_mut(b + j) else { break };
                let q = p * w;
                if j > 0 {
                    *o += q * q * var[b];
                }
                *o += q * (1.0 - q) * mean[b];
            }
        }
        out
    }

    /// Adds into `acc` the afterpulses of a profile whose recorded counts are `recorded`
    /// (summed over its shots), drawn from `rng` (module docs).
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
                let j = self.table.bin_for(rng.next_u64());
                if j < self.shares.len() && b + j < n {
                    acc[b + j] += 1;
                }
            }
        }
    }
}
