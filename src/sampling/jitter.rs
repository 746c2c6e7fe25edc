//! Shots whose signal varies: pulse-energy jitter, drawn exactly by thinning.
//!
//! **Model.** Shot `s` emits `f_s·E0` with `f_s = clamp(1 + σ·g_s, 0, f_max)`,
//! `g_s ~ N(0, 1)` i.i.d., `f_max = 1 + 6σ` (the clamps change the law with
//! probability below 2·10⁻⁹ for σ ≤ 0.2). Its signal counts are Poisson(`f_s·λ_sig,i`),
//! background and dark unchanged.
//!
//! **Algorithm (exact thinning).** The signal sampler is built once at the envelope
//! `f_max·λ_sig`; each shot's draw is thinned, every count kept with probability
//! `f_s/f_max` (a binomial thinning of a Poisson(μ) count is Poisson(p·μ); Lewis &
//! Shedler 1979, Naval Res. Logist. Q. 26, 403). The cost per shot is that of the
//! envelope draw plus one Bernoulli per signal count, with no per-shot rebuild.
//! Blocks of [`SHOT_BLOCK`] shots use [`stream_rng`]`(seed, profile, block)`, as in
//! [`super::shot_profile`], so results depend on the seed only.

use rand::Rng;
use rand_distr::{Binomial, Distribution, StandardNormal};
use rayon::prelude::*;

use super::{SHOT_BLOCK, ShotCounts, ShotSampler, stream_rng};

/// Largest relative rms pulse-energy jitter supported.
pub const MAX_JITTER: f64 = 0.2;

/// Envelope factor `f_max = 1 + 6σ`.
pub fn envelope(jitter: f64) -> f64 {
    1.0 + 6.0 * jitter
}

/// One shot's energy factor `f = clamp(1 + σ·g, 0, f_max)`.
pub fn energy_factor<R: Rng + ?Sized>(rng: &mut R, jitter: f64) -> f64 {
    let g: f64 = StandardNormal.sample(rng);
    (1.0 + jitter * g).clamp(0.0, envelope(jitter))
}

/// Samplers for a jittered scene: the signal at its envelope, the rest unchanged.
#[derive(Debug, Clone)]
pub struct JitteredShots {
    signal_envelope: ShotSampler,
    rest: ShotSampler,
    jitter: f64,
}

impl JitteredShots {
    /// `signal` and `rest` (background + dark) are per-shot means per bin at nominal energy.
    pub fn new(signal: &[f64], rest: &[f64], jitter: f64) -> Self {
        let f_max = envelope(jitter);
        let env: Vec<f64> = signal.iter().map(|s| s * f_max).collect();
        JitteredShots {
            signal_envelope: ShotSampler::new(&env),
            rest: ShotSampler::new(rest),
            jitter,
        }
    }

    fn add_shots<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        shots: u64,
        acc: &mut [u64],
        buf: &mut ShotCounts,
    ) {
        let f_max = envelope(self.jitter);
        for _ in 0..shots {
            let keep = energy_factor(rng, self.jitter) / f_max;
            buf.clear();
            self.signal_envelope.sample_shot(rng, buf);
            for (bin, n) in buf.nonzero() {
                acc[bin] += thin(rng, n, keep);
            }
            self.rest.sample_shot(rng, acc);
        }
    }

    /// Accumulates one profile of `shots` jittered shots into `acc`.
    pub fn profile(&self, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
        let bins = acc.len();
        let nblocks = shots.div_ceil(SHOT_BLOCK);
        let sum = (0..nblocks)
            .into_par_iter()
            .map(|b| {
                let mut part = vec![0u64; bins];
                let mut buf = ShotCounts::new(bins);
                let n = SHOT_BLOCK.min(shots - b * SHOT_BLOCK);
                self.add_shots(&mut stream_rng(seed, profile, b), n, &mut part, &mut buf);
                part
            })
            .reduce(
                || vec![0u64; bins],
                |mut x, y| {
                    x.iter_mut().zip(&y).for_each(|(a, b)| *a += b);
                    x
                },
            );
        acc.iter_mut().zip(&sum).for_each(|(a, s)| *a += s);
    }
}

/// A uniform in [0, 1) from the top 53 bits of `x`.
fn unit_f64(x: u64) -> f64 {
    (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Keeps each of `n` counts with probability `p`: Binomial(n, p), by Bernoulli trials
/// for small n.
fn thin<R: Rng + ?Sized>(rng: &mut R, n: u32, p: f64) -> u64 {
    if n <= 16 {
        (0..n).filter(|_| unit_f64(rng.next_u64()) < p).count() as u64
    } else {
        Binomial::new(u64::from(n), p)
            .map(|b| b.sample(rng))
            .unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mean and variance of a jittered bin: E = M·λ, Var = M·λ + M·σ²·λ² (law of total
    /// variance over the shots' energies). 4000 profiles; |z| < 5 is a false-alarm rate
    /// below 1e-6 per check.
    #[test]
    fn jitter_adds_the_expected_variance() {
        let (lambda, sigma, m, profiles) = (2.0, 0.1, 50u64, 4000u64);
        let js = JitteredShots::new(&[lambda], &[0.0], sigma);
        let draws: Vec<f64> = (0..profiles)
            .map(|p| {
                let mut acc = [0u64];
                js.profile(11, p, m, &mut acc);
                acc[0] as f64
            })
            .collect();
        let n = profiles as f64;
        let mean = draws.iter().sum::<f64>() / n;
        let var = draws.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let mu = m as f64 * lambda;
        let v = mu + m as f64 * sigma * sigma * lambda * lambda;
        assert!(
            ((mean - mu) / (v / n).sqrt()).abs() < 5.0,
            "mean {mean} vs {mu}"
        );
        // var of the sample variance ≈ 2v²/(n−1) (near-normal counts)
        assert!(
            ((var - v) / (2.0 * v * v / (n - 1.0)).sqrt()).abs() < 5.0,
            "var {var} vs {v}"
        );
        // and it is distinguishable from no jitter (v = 100 vs 104): the test has power
        assert!(var > mu);
    }

    #[test]
    fn zero_jitter_is_plain_poisson_and_deterministic() {
        let js = JitteredShots::new(&[0.3, 0.0, 1e-300], &[1e-3, 1e-3, 0.0], 0.0);
        let mut a = vec![0u64; 3];
        let mut b = vec![0u64; 3];
        js.profile(3, 1, 70_000, &mut a);
        js.profile(3, 1, 70_000, &mut b);
        assert_eq!(a, b);
        assert_eq!(a[2], 0);
        assert!((a[0] as f64 - 70_000.0 * 0.301).abs() < 5.0 * (70_000.0f64 * 0.301).sqrt());
    }
}
