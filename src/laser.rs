//! The laser's emitted energy shot by shot, as an energy monitor measures it (model.md
//! §7): shot `s` at time `t_s` emits `E0·f_s` with
//!
//! ```text
//! f_s = d(t_s) · clamp(1 + σ·g_s, 0, 1 + 6σ),   g_s ~ N(0, 1) i.i.d.
//! ```
//!
//! σ the relative rms jitter (`instrument.pulse_energy_jitter`), `d` the slow drift
//! (`instrument.energy_drift`: `1 + a·t/3600 s` or `1 + a·sin(2πt/P + φ)`). The clamp
//! changes the law with probability below 2·10⁻⁹ for σ ≤ 0.2.
//!
//! The factors come from a stream of their own, `stream_rng(seed ^ ENERGY_STREAM,
//! profile, block)` with the run's seed, so every channel of a run sees the same pulses
//! and the monitor's `pulse_energy (profile)` is the mean of exactly the energies the
//! counts were drawn with. Shot `s` of profile `p` fires at `t = (p·M + s)/fL`.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::config::{Checker, EnergyDriftConfig, InstrumentConfig, ScenarioConfig};
use crate::error::Result;
use crate::sampling::jitter::EnergyFactors;
use crate::sampling::{SHOT_BLOCK, stream_rng};

/// Largest relative rms pulse-energy jitter σ supported: up to it the clamp at
/// `1 + 6σ` changes the law with probability below 2·10⁻⁹.
pub const MAX_JITTER: f64 = 0.2;

/// Checks what the laser's law limits: `instrument.pulse_energy_jitter` within
/// `[0, MAX_JITTER]`.
pub fn validate(config: &ScenarioConfig, c: &Checker) -> Result<()> {
    c.range(
        "instrument.pulse_energy_jitter",
        config.instrument.pulse_energy_jitter,
        0.0,
        MAX_JITTER,
    )
}

/// Seed offset of the pulse-energy streams.
const ENERGY_STREAM: u64 = 0xE4E2_6000_51A7_0001;

/// The emitted energy's law: jitter and drift.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PulseEnergy {
    /// Relative rms shot-to-shot jitter σ.
    pub jitter: f64,
    /// Slow drift, if any.
    pub drift: Option<EnergyDriftConfig>,
    /// Pulse repetition frequency fL, Hz.
    pub rep_rate_hz: f64,
}

impl PulseEnergy {
    /// The energy law of an instrument.
    pub fn from_config(i: &InstrumentConfig) -> Self {
        PulseEnergy {
            jitter: i.pulse_energy_jitter,
            drift: i.energy_drift,
            rep_rate_hz: i.rep_rate_hz,
        }
    }

    /// Whether every shot emits exactly `E0` (no jitter, no drift).
    pub fn is_constant(&self) -> bool {
        self.jitter == 0.0 && self.drift.is_none()
    }

    /// The drift factor `d(t)` at `t_s` seconds after the first shot.
    pub fn drift_factor(&self, t_s: f64) -> f64 {
        match self.drift {
            None => 1.0,
            Some(EnergyDriftConfig::Linear { per_hour }) => 1.0 + per_hour * t_s / 3600.0,
            Some(EnergyDriftConfig::Periodic {
                amplitude,
                period_s,
                phase_deg,
            }) => {
                1.0 + amplitude
                    * (std::f64::consts::TAU * t_s / period_s + phase_deg.to_radians()).sin()
            }
        }
    }

    /// Largest jitter factor, `1 + 6σ`.
    pub fn jitter_envelope(&self) -> f64 {
        1.0 + 6.0 * self.jitter
    }

    /// An upper bound of `f_s` over a run of `duration_s` seconds (the envelope that
    /// thinning draws at).
    pub fn envelope(&self, duration_s: f64) -> f64 {
        let drift = match self.drift {
            None => 1.0,
            Some(EnergyDriftConfig::Linear { .. }) => {
                self.drift_factor(0.0).max(self.drift_factor(duration_s))
            }
            Some(EnergyDriftConfig::Periodic { amplitude, .. }) => 1.0 + amplitude,
        };
        drift * self.jitter_envelope()
    }

    /// The smallest drift factor over a run of `duration_s` seconds.
    pub fn lowest_drift(&self, duration_s: f64) -> f64 {
        match self.drift {
            None => 1.0,
            Some(EnergyDriftConfig::Linear { .. }) => {
                self.drift_factor(0.0).min(self.drift_factor(duration_s))
            }
            Some(EnergyDriftConfig::Periodic { amplitude, .. }) => 1.0 - amplitude,
        }
    }

    /// The energy factors of block `block` of profile `profile` (`shots` shots per
    /// profile), written to `out` (cleared first): a function of the arguments only.
    pub fn block_factors(
        &self,
        seed: u64,
        profile: u64,
        shots: u64,
        block: u64,
        out: &mut Vec<f64>,
    ) {
        out.clear();
        let first = block * SHOT_BLOCK;
        let n = SHOT_BLOCK.min(shots - first);
        let mut rng = stream_rng(seed ^ ENERGY_STREAM, profile, block);
        let t0 = (profile as f64 * shots as f64 + first as f64) / self.rep_rate_hz;
        out.extend((0..n).map(|s| {
            let jitter = self.jitter_factor(&mut rng);
            self.drift_factor(t0 + s as f64 / self.rep_rate_hz) * jitter
        }));
    }

    /// One shot's jitter factor `clamp(1 + σ·g, 0, 1 + 6σ)` (1 without jitter, drawing
    /// nothing).
    fn jitter_factor<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        if self.jitter == 0.0 {
            return 1.0;
        }
        let g: f64 = StandardNormal.sample(rng);
        (1.0 + self.jitter * g).clamp(0.0, self.jitter_envelope())
    }

    /// The sum of the energy factors of profile `profile`'s `shots` shots: what the
    /// energy monitor integrates (`pulse_energy = E0 · sum / shots`).
    pub fn profile_sum(&self, seed: u64, profile: u64, shots: u64) -> f64 {
        if self.is_constant() {
            return shots as f64;
        }
        let mut buf = Vec::new();
        (0..shots.div_ceil(SHOT_BLOCK))
            .map(|b| {
                self.block_factors(seed, profile, shots, b, &mut buf);
                buf.iter().sum::<f64>()
            })
            .sum()
    }

    /// `E[h(f)]` over the jitter at drift 1, for a smooth `h` returning a vector: the
    /// trapezoid rule in `g` on [−6, 6] with step 1/2 against the normal density (spectrally
    /// accurate for analytic integrands; the tails beyond ±6 weigh 2·10⁻⁹).
    pub fn jitter_expectation(&self, h: impl Fn(f64) -> Vec<f64>) -> Vec<f64> {
        if self.jitter == 0.0 {
            return h(1.0);
        }
        let step = 0.5;
        let mut total: Vec<f64> = Vec::new();
        let mut weights = 0.0;
        for k in -12..=12 {
            let g = k as f64 * step;
            let w = (-0.5 * g * g).exp();
            let f = (1.0 + self.jitter * g).clamp(0.0, self.jitter_envelope());
            let v = h(f);
            if total.is_empty() {
                total = vec![0.0; v.len()];
            }
            total.iter_mut().zip(&v).for_each(|(t, x)| *t += w * x);
            weights += w;
        }
        total.iter_mut().for_each(|t| *t /= weights);
        total
    }
}

/// The shots of a jittered run are drawn at this law's factors (`sampling::jitter`).
impl EnergyFactors for PulseEnergy {
    fn block_factors(&self, seed: u64, profile: u64, shots: u64, block: u64, out: &mut Vec<f64>) {
        PulseEnergy::block_factors(self, seed, profile, shots, block, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn laser(jitter: f64, drift: Option<EnergyDriftConfig>) -> PulseEnergy {
        PulseEnergy {
            jitter,
            drift,
            rep_rate_hz: 20.0,
        }
    }

    #[test]
    fn drifts_follow_their_formulas() {
        let lin = laser(0.0, Some(EnergyDriftConfig::Linear { per_hour: -0.02 }));
        assert!((lin.drift_factor(1800.0) - 0.99).abs() < 1e-15);
        assert_eq!(lin.envelope(3600.0), 1.0);
        assert!((lin.lowest_drift(3600.0) - 0.98).abs() < 1e-15);
        let per = laser(
            0.1,
            Some(EnergyDriftConfig::Periodic {
                amplitude: 0.05,
                period_s: 100.0,
                phase_deg: 0.0,
            }),
        );
        assert!((per.drift_factor(25.0) - 1.05).abs() < 1e-12);
        assert!((per.envelope(1.0) - 1.05 * 1.6).abs() < 1e-12);
    }

    #[test]
    fn factors_are_reproducible_and_have_the_stated_moments() {
        let l = laser(0.1, None);
        let mut a = Vec::new();
        let mut b = Vec::new();
        l.block_factors(7, 3, 1000, 0, &mut a);
        l.block_factors(7, 3, 1000, 0, &mut b);
        assert_eq!(a, b);
        assert_eq!(a.len(), 1000);
        // 40,000 factors: mean 1 ± 5·0.1/200, variance 0.01 ± 5·sd
        let all: Vec<f64> = (0..40)
            .flat_map(|p| {
                let mut v = Vec::new();
                l.block_factors(7, p, 1000, 0, &mut v);
                v
            })
            .collect();
        let n = all.len() as f64;
        let mean = all.iter().sum::<f64>() / n;
        let var = all.iter().map(|f| (f - mean).powi(2)).sum::<f64>() / (n - 1.0);
        assert!((mean - 1.0).abs() < 5.0 * 0.1 / n.sqrt(), "mean {mean}");
        assert!(
            (var - 0.01).abs() < 5.0 * 0.01 * (2.0 / n).sqrt(),
            "var {var}"
        );
        // the profile sum is the sum of the same factors
        assert!((l.profile_sum(7, 3, 1000) - a.iter().sum::<f64>()).abs() < 1e-9);
    }

    #[test]
    fn the_jitter_expectation_is_exact_for_polynomials() {
        let l = laser(0.1, None);
        // E[f] = 1, E[f²] = 1 + σ², E[f³] = 1 + 3σ²
        let m = l.jitter_expectation(|f| vec![f, f * f, f * f * f]);
        assert!((m[0] - 1.0).abs() < 1e-9, "{m:?}");
        assert!((m[1] - 1.01).abs() < 1e-9, "{m:?}");
        assert!((m[2] - 1.03).abs() < 1e-9, "{m:?}");
    }
}

/// The jitter sampler (`sampling::jitter`) at this law's factors.
#[cfg(test)]
mod jittered_shots {
    use super::*;
    use crate::sampling::jitter::ModulatedShots;

    fn laser(jitter: f64) -> PulseEnergy {
        PulseEnergy {
            jitter,
            drift: None,
            rep_rate_hz: 10.0,
        }
    }

    /// Mean and variance of a jittered bin: E = M·λ, Var = M·λ + M·σ²·λ² (law of total
    /// variance over the shots' energies). 100,000 profiles; |z| < 5 is a false-alarm
    /// rate below 1e-6 per check. Power: the variance without jitter (M·λ = 100 against
    /// 108) is 16 standard deviations of the sample variance away, and is rejected at
    /// z > 4.
    #[test]
    fn jitter_adds_the_expected_variance() {
        let (lambda, sigma, m, profiles) = (2.0, 0.2, 50u64, 100_000u64);
        let js = ModulatedShots::new(&[lambda], &[0.0], laser(sigma), None, 1.0 + 6.0 * sigma);
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
        // and it is distinguishable from no jitter (v = 100 vs 108): the test has power
        let sd_var = (2.0 * v * v / (n - 1.0)).sqrt();
        assert!((var - mu) / sd_var > 4.0, "var {var} vs no jitter {mu}");
    }

    #[test]
    fn zero_jitter_is_plain_poisson_and_deterministic() {
        let js = ModulatedShots::new(
            &[0.3, 0.0, 1e-300],
            &[1e-3, 1e-3, 0.0],
            laser(0.0),
            None,
            1.0,
        );
        let mut a = vec![0u64; 3];
        let mut b = vec![0u64; 3];
        js.profile(3, 1, 70_000, &mut a);
        js.profile(3, 1, 70_000, &mut b);
        assert_eq!(a, b);
        assert_eq!(a[2], 0);
        assert!((a[0] as f64 - 70_000.0 * 0.301).abs() < 5.0 * (70_000.0f64 * 0.301).sqrt());
    }
}
