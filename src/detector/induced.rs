//! Signal-induced noise (docs/model.md §4b, "Signal-induced noise"): after a strong
//! return a photomultiplier keeps emitting spurious counts whose rate decays over tens
//! to hundreds of microseconds (the "SIN" that biases far-range backgrounds; model.md
//! §8). Modelled as a delayed response to the backscattered signal: each signal
//! photoelectron induces, on average, `fraction` spurious counts spread over the delays
//! t ≥ 0 by a normalized decay law
//!
//! ```text
//! exponential: g(t) = e^{−t/τ}/τ                     survival S(t) = e^{−t/τ}
//! power law:   g(t) = (p−1)/τ · (1 + t/τ)^{−p}, p > 1  survival S(t) = (1 + t/τ)^{1−p}
//! ```
//!
//! **Expectation.** A signal photoelectron uniform within bin b' adds to bin b = b' + j
//! the share `w_j = (J((j−1)Δt) − 2·J(jΔt) + J((j+1)Δt))·(−1/Δt)` for j ≥ 1 and
//! `w_0 = 1 − J(Δt)/Δt`, with `J(x) = ∫₀ˣ S(s) ds` (the bin-averaged CDF of the delay; the
//! shares sum to 1). So the expected induced counts per shot are
//! `λ_SIN,b = fraction · Σ_j w_j · λ_sig,b−j`: a convolution of the expected signal.
//! Background and dark counts induce none (the sky is dim; model.md §8 names the
//! near-field return). The pulse's own shot only: a previous shot's tail (one period
//! earlier) is not carried over.
//!
//! **Counts.** The induced counts of a shot are Poisson with that mean, scaled like the
//! signal by the shot's pulse energy (they are drawn with the signal, as part of it, by
//! every sampler). This neglects their correlation with the shot's own signal-photon
//! count (a relative variance term of order `fraction·w_j`, below 1e-4 for the
//! documented ranges) and is otherwise exact on both paths.

use crate::config::SignalInducedNoiseConfig;

impl SignalInducedNoiseConfig {
    /// Expected induced counts per signal photoelectron over all delays.
    pub fn fraction(&self) -> f64 {
        match *self {
            SignalInducedNoiseConfig::Exponential { fraction, .. }
            | SignalInducedNoiseConfig::PowerLaw { fraction, .. } => fraction,
        }
    }

    /// The shares `w_j` of a bin's signal in the bins j = 0, 1, … later, for `bins` bins
    /// of `bin_width_s` (module docs).
    pub fn shares(&self, bin_width_s: f64, bins: usize) -> Vec<f64> {
        let dt = bin_width_s;
        match *self {
            SignalInducedNoiseConfig::Exponential {
                time_constant_s, ..
            } => super::delay::exponential_shares(time_constant_s, dt, bins),
            SignalInducedNoiseConfig::PowerLaw {
                time_constant_s,
                exponent,
                ..
            } => {
                let j_at = |k: usize| power_law_integral(k as f64 * dt, time_constant_s, exponent);
                let mut w = Vec::with_capacity(bins);
                if bins > 0 {
                    w.push(1.0 - j_at(1) / dt);
                }
                for j in 1..bins {
                    w.push(((2.0 * j_at(j) - j_at(j - 1) - j_at(j + 1)) / dt).max(0.0));
                }
                w
            }
        }
    }

    /// Expected induced counts per shot of each bin for the expected signal `signal`
    /// (photoelectrons per shot per bin) on bins of `bin_width_s`: the exponential law by
    /// a recursion in O(bins) ([`super::delay::exponential_convolve`]), the power law by
    /// the direct sum in O(bins²) (refused beyond [`MAX_POWER_LAW_BINS`] by the scenario).
    pub fn induced_counts(&self, signal: &[f64], bin_width_s: f64) -> Vec<f64> {
        let a = self.fraction();
        if let SignalInducedNoiseConfig::Exponential {
            time_constant_s, ..
        } = *self
        {
            let law = super::delay::exponential_law(time_constant_s, bin_width_s);
            return super::delay::exponential_convolve(signal, law)
                .into_iter()
                .map(|y| a * y)
                .collect();
        }
        let w = self.shares(bin_width_s, signal.len());
        let mut out = vec![0.0; signal.len()];
        for (b, &s) in signal.iter().enumerate() {
            if s == 0.0 {
                continue;
            }
            for (o, wj) in out[b..].iter_mut().zip(&w) {
                *o += a * wj * s;
            }
        }
        out
    }
}

/// `J(x) = ∫₀ˣ S(s) ds` of the power law `S(t) = (1 + t/τ)^{1−p}`, s.
fn power_law_integral(x: f64, tau: f64, p: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let q = 2.0 - p;
    if q.abs() < 1e-12 {
        tau * (x / tau).ln_1p()
    } else {
        tau * (q * (x / tau).ln_1p()).exp_m1() / q
    }
}

/// Most bins of a window with power-law signal-induced noise, whose expectation is a
/// direct convolution (O(bins²): 2.5e9 operations here, a few seconds).
pub const MAX_POWER_LAW_BINS: usize = 50_000;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shares_sum_to_the_delay_law_within_the_window() {
        let e = SignalInducedNoiseConfig::Exponential {
            fraction: 1e-4,
            time_constant_s: 2e-6,
        };
        let w = e.shares(2e-7, 400);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let p = SignalInducedNoiseConfig::PowerLaw {
            fraction: 1e-4,
            time_constant_s: 1e-7,
            exponent: 2.5,
        };
        // within n bins the shares sum to the mean of G over the source bin's positions:
        // 1 − J'(n) terms; far out the power law's tail is (1+x/τ)^{−1.5}
        let w = p.shares(2e-7, 2000);
        let tail = 1.0 - w.iter().sum::<f64>();
        assert!(tail > 0.0 && tail < 2e-4, "{tail}");
    }
}
