//! Where an analog record is linear in the photons (the file's `linear_range`, the
//! clipping warning; docs/model.md §4b "Gluing"; issue 36): its codes stay inside the
//! ADC's range, its mean above the offset exceeds one shot's noise, and the low-passed
//! record is proportional to the photons of the bin itself.
//!
//! **Clipping, from the law of the code** (not a Gaussian rule: a few photoelectrons of
//! many codes each make the sd large while the codes stay far from either end). One
//! shot's code before rounding is `X = V₀/LSB + c·Σ_j h_j q_{b−j} + σ·Z` with the
//! photoelectrons' charges `q ≥ 0`:
//!
//! * **below 0** only through the noise: `P(X < −½) ≤ Φ((−½ − V₀/LSB)/σ)`, exact when
//!   no photoelectron arrives and an upper bound otherwise;
//! * **above full scale** by the Chernoff bound `P(X > x) ≤ exp(K(θ) − θx)` at the
//!   best θ > 0 (Chernoff 1952), with the cumulant generating function of the compound
//!   Poisson–Gamma charge and the noise,
//!   `K(θ) = θV₀/LSB + θ²σ²/2 + Σ_j λ_{b−j}·(M(θ c h_j) − 1)`,
//!   `M(t) = (1 − t(F−1))^{−1/(F−1)}` (the Gamma gain of mean 1; `e^t` at F = 1), the
//!   kernel's first [`KERNEL_TERMS`] shares exactly and the rest at their mean (they
//!   spread a bin's charge over more bins than that: their spread is below 1e-3 of it).
//!
//! A bin clips where either probability exceeds [`CLIP_PROBABILITY`] a shot: the bound
//! is conservative (the true tail is below it), so a bin not flagged clips less often.
//!
//! **Proportionality** (the gluing range): the analog expectation above its offset is
//! `c·Σ_j h_j λ_{b−j}`, the photon counts' `λ_b`; their ratio is the gluing constant c
//! only where the low-pass does not move charge in or out of the bin, so a bin is linear
//! where `|Σ_j h_j λ_{b−j} / λ_b − 1| ≤` [`PROPORTIONAL_TOLERANCE`] (at layer edges the
//! 10 MHz low-pass of the PollyXT-like preset moves the ratio to 0.70–1.41).

use super::analog::Analog;

/// Largest probability a shot's code may leave the ADC's range in a bin that is called
/// linear (and no clipping warning printed).
pub const CLIP_PROBABILITY: f64 = 1e-6;

/// Largest departure of the low-passed photons from the bin's own, `Σ h_j λ_{b−j}/λ_b`
/// from 1, in a bin whose analog record is called linear (gluing range).
pub const PROPORTIONAL_TOLERANCE: f64 = 0.01;

/// Kernel shares taken exactly in the Chernoff bound; the rest at their mean.
pub const KERNEL_TERMS: usize = 64;

impl Analog {
    /// Per bin, upper bounds of the probabilities that a shot's code falls below 0 and
    /// above full scale (module docs), for photoelectron means `lambda` per shot.
    pub fn clipping_probabilities(&self, lambda: &[f64]) -> Vec<(f64, f64)> {
        let sigma = self.noise_codes();
        let v0 = self.offset_codes();
        let below = if sigma > 0.0 {
            normal_cdf((-0.5 - v0) / sigma)
        } else if v0 < -0.5 {
            1.0
        } else {
            0.0
        };
        let h = self.kernel(KERNEL_TERMS);
        let smeared = self.smear(lambda, 1);
        let top = self.full_scale_code() as f64 + 0.5;
        (0..lambda.len())
            .map(|b| {
                let near: Vec<(f64, f64)> = (0..KERNEL_TERMS.min(b + 1))
                    .map(|j| (lambda[b - j], h[j]))
                    .collect();
                let exact: f64 = near.iter().map(|(l, hj)| l * hj).sum();
                let far = (smeared[b] - exact).max(0.0);
                (below, self.chernoff_above(&near, far, top))
            })
            .collect()
    }

    /// The Chernoff bound of `P(X > top)` for the photoelectron means and shares `near`
    /// and the mean smeared photoelectrons `far` of the rest of the kernel.
    fn chernoff_above(&self, near: &[(f64, f64)], far: f64, top: f64) -> f64 {
        let (c, v0, sigma) = (
            self.codes_per_photoelectron(),
            self.offset_codes(),
            self.noise_codes(),
        );
        let f = self.excess_noise_factor - 1.0;
        let mean = v0 + c * (far + near.iter().map(|(l, h)| l * h).sum::<f64>());
        if mean >= top {
            return 1.0;
        }
        // ln M(t) of the unit-mean Gamma gain, and K(θ) − θ·top
        let ln_mgf = |t: f64| {
            if f <= 0.0 { t } else { -(-t * f).ln_1p() / f }
        };
        let exponent = |theta: f64| {
            let charge: f64 = near
                .iter()
                .map(|&(l, h)| l * (ln_mgf(theta * c * h).exp() - 1.0))
                .sum();
            theta * (v0 + c * far) + 0.5 * theta * theta * sigma * sigma + charge - theta * top
        };
        // θ within the gain's MGF domain, t·f < 1 for the largest share
        let h_max = near.iter().map(|p| p.1).fold(0.0, f64::max);
        let limit = if f > 0.0 && h_max > 0.0 {
            (1.0 - 1e-12) / (f * c * h_max)
        } else {
            f64::INFINITY
        };
        // the exponent is convex in θ: golden-section search on (0, hi]
        let mut hi = limit.min(1.0);
        while hi < limit && exponent(2.0 * hi) < exponent(hi) && hi < 1e6 {
            hi = (2.0 * hi).min(limit);
        }
        let (mut a, mut b) = (0.0, hi);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..100 {
            let (x1, x2) = (b - g * (b - a), a + g * (b - a));
            if exponent(x1) < exponent(x2) {
                b = x2;
            } else {
                a = x1;
            }
        }
        exponent(0.5 * (a + b)).min(0.0).exp()
    }

    /// Per bin whether a shot's code may leave the ADC's range: either probability of
    /// [`clipping_probabilities`](Self::clipping_probabilities) above
    /// [`CLIP_PROBABILITY`].
    pub fn clipping_bins(&self, lambda: &[f64]) -> Vec<bool> {
        self.clipping_probabilities(lambda)
            .iter()
            .map(|&(lo, hi)| lo > CLIP_PROBABILITY || hi > CLIP_PROBABILITY)
            .collect()
    }

    /// Per bin whether the low-passed photoelectrons stay within
    /// [`PROPORTIONAL_TOLERANCE`] of the bin's own (module docs).
    pub fn proportional_bins(&self, lambda: &[f64]) -> Vec<bool> {
        self.smear(lambda, 1)
            .iter()
            .zip(lambda)
            .map(|(&s, &l)| l > 0.0 && (s / l - 1.0).abs() <= PROPORTIONAL_TOLERANCE)
            .collect()
    }
}

/// The standard normal CDF, `erfc(−x/√2)/2` (statrs' erfc, ~1e-15 relative).
fn normal_cdf(x: f64) -> f64 {
    0.5 * statrs::function::erf::erfc(-x / std::f64::consts::SQRT_2)
}

/// The linear range and the clipping warning, from the laws above.
impl Analog {
    /// Whether each bin's record is linear in its photoelectrons (the file's
    /// `linear_range`, this file): the mean code above the offset is at least
    /// the rms of one shot's electronic noise and rounding (below, a shot's code is mostly
    /// noise), a shot's code leaves the ADC's range with probability at most
    /// `CLIP_PROBABILITY` (from the law of the code), and the low-passed photoelectrons
    /// are the bin's own to `PROPORTIONAL_TOLERANCE` (the ratio to the photon counts is
    /// the gluing constant there).
    pub fn linear_bins(&self, lambda: &[f64]) -> Vec<bool> {
        let floor = (self.noise_codes().powi(2) + 1.0 / 12.0).sqrt();
        let clipping = self.clipping_bins(lambda);
        let proportional = self.proportional_bins(lambda);
        self.expected_codes(lambda)
            .iter()
            .zip(clipping.iter().zip(&proportional))
            .map(|(&m, (&clips, &prop))| m - self.offset_codes() >= floor && !clips && prop)
            .collect()
    }

    /// The warning for a chain whose law the codes leave: electronic noise below one
    /// code (the rounding's bias is then up to `e^{−2π²σ²}/π` codes a shot), or bins whose
    /// codes leave the ADC's range with a probability above `CLIP_PROBABILITY` a shot
    /// (clipping, this file), naming the first such bin; `None` when neither.
    pub fn clipping_warning(&self, lambda: &[f64], altitude_m: &[f64]) -> Option<String> {
        let sigma = self.noise_codes();
        if sigma < 1.0 {
            let bias =
                (-2.0 * std::f64::consts::PI.powi(2) * sigma * sigma).exp() / std::f64::consts::PI;
            return Some(format!(
                "lidarsim: warning: the analog electronic noise is {sigma:.2} ADC codes, below \
                 one: rounding may bias a shot's code by up to {bias:.2e} codes, which \
                 expected_counts leaves out; raise instrument.detector.electronic_noise_v to \
                 at least {:.3e} V (one code) or narrow adc_range_v",
                self.volts_per_code()
            ));
        }
        let full = self.full_scale_code();
        let limit = CLIP_PROBABILITY;
        let (bin, (lo, hi)) = self
            .clipping_probabilities(lambda)
            .into_iter()
            .enumerate()
            .find(|(_, (lo, hi))| *lo > limit || *hi > limit)?;
        let mean = self.expected_codes(&lambda[..=bin])[bin];
        Some(format!(
            "lidarsim: warning: analog bin {bin} ({:.2} km) has a mean of {mean:.1} codes per \
             shot and its codes leave the ADC's range (0, {full}) with a probability up to \
             {:.1e} a shot (above {limit:e}): they clip, and expected_counts (which has no \
             clipping) overstates or understates them; change instrument.detector.adc_range_v, \
             offset_v or gain",
            altitude_m.get(bin).copied().unwrap_or(f64::NAN) / 1e3,
            lo.max(hi)
        ))
    }
}
