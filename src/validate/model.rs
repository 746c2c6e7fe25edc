//! The model of each bin's accumulated count ([`BinModel`]): its (mixed) Poisson
//! cumulants, or those of what a detector stage records, from a scenario's expectations.

use serde::Serialize;

use crate::detector::DeadTime;
use crate::laser::PulseEnergy;
use crate::scenario::ExpectedProfile;

/// The model moments of one bin's accumulated count.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct BinModel {
    /// Expected signal per profile `M·λ_sig`.
    pub signal: f64,
    /// Expected background + dark per profile `M·(λ_bkg+λ_dc)`.
    pub rest: f64,
    /// Cumulants κ1..κ4 of the accumulated count.
    pub cumulants: [f64; 4],
    /// Whether the counts pass a detector stage (dead time, analog chain): mean and
    /// variance are tested against the recorded law, the S/N (Eq. 4 is for an ideal
    /// photon counter) is not.
    pub recorded: bool,
}

impl BinModel {
    /// Mixed-Poisson cumulants for `shots` shots with signal `s`, rest `r` per shot and
    /// relative energy jitter `jitter`.
    pub fn new(s: f64, r: f64, shots: f64, jitter: f64) -> Self {
        let k1 = s + r;
        let v = jitter * jitter * s * s;
        BinModel {
            signal: shots * s,
            rest: shots * r,
            cumulants: [
                shots * k1,
                shots * (k1 + v),
                shots * (k1 + 3.0 * v),
                shots * (k1 + 7.0 * v),
            ],
            recorded: false,
        }
    }

    /// The recorded count of a dead-time detector over `shots` shots: per shot mean
    /// `recorded` and variance `variance` (`detector::DeadTime`); the higher cumulants
    /// take the variance's value (the Poisson shape at that variance).
    pub fn recorded(s: f64, r: f64, recorded: f64, variance: f64, shots: f64) -> Self {
        BinModel {
            signal: shots * s,
            rest: shots * r,
            cumulants: [
                shots * recorded,
                shots * variance,
                shots * variance,
                shots * variance,
            ],
            recorded: true,
        }
    }
}

/// Central moments (μ2, μ3, μ4) from cumulants (κ2, κ3, κ4).
pub(super) fn central_moments(k2: f64, k3: f64, k4: f64) -> (f64, f64, f64) {
    (k2, k3, k4 + 3.0 * k2 * k2)
}

/// Delta-method standard error of `x̄/s_x` over `n` draws of a variable with mean `m`
/// and central moments μ2, μ3, μ4.
pub fn snr_standard_error(m: f64, mu2: f64, mu3: f64, mu4: f64, n: f64) -> f64 {
    let v = (1.0 + m * m * (mu4 - mu2 * mu2) / (4.0 * mu2.powi(3)) - m * mu3 / (mu2 * mu2)) / n;
    v.max(0.0).sqrt()
}

/// The per-bin models of a scenario's expectations.
pub fn bin_models(e: &ExpectedProfile, shots: u64, jitter: f64) -> Vec<BinModel> {
    e.photon_signal()
        .iter()
        .map(|&s| BinModel::new(s, e.background + e.dark, shots as f64, jitter))
        .collect()
}

/// The per-bin models of the counts a dead-time detector records (with the laser's
/// jitter where it has one, [`DeadTime::recorded_moments`]).
pub fn recorded_bin_models(
    e: &ExpectedProfile,
    shots: u64,
    dead: &DeadTime,
    energy: &PulseEnergy,
) -> Vec<BinModel> {
    let rest = e.background + e.dark;
    let signal = e.photon_signal();
    let (mean, var) = dead.recorded_moments(&signal, rest, energy);
    signal
        .iter()
        .zip(mean.iter().zip(&var))
        .map(|(&s, (&m, &v))| BinModel::recorded(s, rest, m, v, shots as f64))
        .collect()
}

/// The per-bin models of the ADC codes an analog chain records (`detector::analog`):
/// the cumulants of one shot's code times the shots, the jitter's share of the variance
/// (`c²·σ_f²·(h∗λ_sig)²`, the law of total variance over the shot's energy factor f)
/// added to κ2.
pub fn analog_bin_models(
    e: &ExpectedProfile,
    shots: u64,
    analog: &crate::detector::Analog,
    jitter: f64,
) -> Vec<BinModel> {
    let m = shots as f64;
    let rest = e.background + e.dark;
    let c = analog.codes_per_photoelectron();
    let signal = e.photon_signal();
    let smeared_signal = analog.smear(&signal, 1);
    analog
        .shot_cumulants(&e.total_per_shot())
        .iter()
        .zip(signal.iter())
        .zip(&smeared_signal)
        .map(|((k, &s), &hs)| {
            let jitter_var = (c * jitter * hs).powi(2);
            BinModel {
                signal: m * s,
                rest: m * rest,
                cumulants: [m * k[0], m * (k[1] + jitter_var), m * k[2], m * k[3]],
                recorded: true,
            }
        })
        .collect()
}

/// `models` of a photon counter's record with its afterpulses added
/// (`Afterpulsing::expected` and `variance` on the models' per-shot mean and variance).
pub fn afterpulsed_bin_models(
    models: &[BinModel],
    afterpulsing: &crate::detector::afterpulse::Afterpulsing,
    shots: u64,
) -> Vec<BinModel> {
    let m = shots as f64;
    let mean: Vec<f64> = models.iter().map(|b| b.cumulants[0] / m).collect();
    let var: Vec<f64> = models.iter().map(|b| b.cumulants[1] / m).collect();
    let extra = afterpulsing.expected(&mean);
    let total_var = afterpulsing.variance(&mean, &var);
    models
        .iter()
        .enumerate()
        .map(|(b, x)| {
            BinModel::recorded(
                x.signal / m,
                x.rest / m,
                mean[b] + extra[b],
                total_var[b],
                m,
            )
        })
        .collect()
}
