//! The sampler of one stream of counts, the detector's stages stacked on the photon
//! sampler, and the seeds of a run's streams.

use super::energy::RunEnergy;
use super::method::ResolvedMethod;
use crate::detector::afterpulse::{AFTERPULSE_STREAM, Afterpulsing};
use crate::detector::{Analog, DeadTime, DetectedShots, analog, dead_time};
use crate::sampling::approx;
use crate::sampling::jitter::ModulatedShots;
use crate::sampling::{self, ShotSampler};
use crate::scenario::ExpectedProfile;

/// Seeds of the signal, background and dark streams in a component-resolved run.
fn component_seed(seed: u64, component: u64) -> u64 {
    seed ^ (component + 1).wrapping_mul(0xD1B5_4A32_D192_ED03)
}

/// Seed of channel `k`'s photons: the run's seed for the first channel (a one-channel
/// run draws what it always drew), a distinct stream for each other.
pub fn channel_seed(seed: u64, k: usize) -> u64 {
    if k == 0 {
        seed
    } else {
        seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
    }
}

/// Seed of pixel `p` of a detector of several pixels: a stream of its own for each (the
/// photons of k pixels are k independent draws at a k-th of the rate).
pub fn pixel_seed(seed: u64, p: u32) -> u64 {
    seed ^ (u64::from(p) + 1).wrapping_mul(0xA24B_AED4_963E_E407)
}

/// The sampler of one stream of counts (the total, or one component), built once per run.
#[derive(Debug, Clone)]
pub enum StreamSampler {
    /// One Poisson(M·λ) draw per bin, every bin's sampler built once.
    Aggregate(sampling::AggregateSampler),
    /// One Poisson draw per bin of mean `(Σ_s f_s)·λ_sig + M·λ_rest`: exact given the
    /// profile's emitted energies, which are drawn first (M factors, no photons).
    AggregateEnergy {
        /// Signal per shot at nominal energy.
        signal: Vec<f64>,
        /// Background and dark per shot.
        rest: Vec<f64>,
        /// The energies.
        energy: RunEnergy,
    },
    /// Every shot drawn with fixed means.
    Shot(Box<ShotSampler>),
    /// Every shot drawn, the signal scaled by the shot's pulse energy (and recorded
    /// through dead time where the detector has it).
    Modulated(Box<DetectedShots>),
    /// Aggregate with the normal approximation at and above a mean threshold.
    AggregateNormal(Vec<f64>, f64),
    /// Every shot drawn and recorded through the detector's dead time.
    DeadTimed(Box<dead_time::DeadTimedShots>),
    /// A detector of `pixels` pixels, each drawn by `pixel` (the photons' share 1/k,
    /// one pixel's dead time) from its own seed ([`pixel_seed`]), the counts summed.
    Pixels {
        /// One pixel's sampler.
        pixel: Box<dead_time::DeadTimedShots>,
        /// k.
        pixels: u32,
    },
    /// Every shot drawn and recorded by an analog chain (ADC codes).
    AnalogShots(Box<ShotSampler>, Box<Analog>),
    /// A profile's photoelectrons drawn by the inner (aggregate) sampler, recorded by an
    /// analog chain as a whole (`Analog::record_profile`).
    AnalogAggregate(Box<StreamSampler>, Box<Analog>),
    /// The inner sampler's recorded counts with their afterpulses
    /// (`Afterpulsing::add_profile`, from `stream_rng(seed ^ AFTERPULSE_STREAM, profile,
    /// AGGREGATE_STREAM)`).
    Afterpulsed(Box<StreamSampler>, Box<Afterpulsing>),
}

impl StreamSampler {
    /// Builds the sampler for per-shot means `signal` + `rest` (rest: background and
    /// dark) with relative pulse-energy jitter `jitter` drawn from the stream's own seed.
    pub fn new(method: ResolvedMethod, signal: &[f64], rest: &[f64], jitter: f64) -> Self {
        Self::with_energy(method, signal, rest, RunEnergy::jitter(jitter))
    }

    /// Builds the sampler for per-shot means `signal` + `rest` with the run's energies.
    pub fn with_energy(
        method: ResolvedMethod,
        signal: &[f64],
        rest: &[f64],
        energy: RunEnergy,
    ) -> Self {
        let total = || {
            signal
                .iter()
                .zip(rest)
                .map(|(s, r)| s + r)
                .collect::<Vec<f64>>()
        };
        let constant = energy.law.is_constant();
        match method {
            ResolvedMethod::Aggregate if constant => {
                StreamSampler::Aggregate(sampling::AggregateSampler::new(&total()))
            }
            ResolvedMethod::Aggregate | ResolvedMethod::AggregateNormal { .. } if !constant => {
                StreamSampler::AggregateEnergy {
                    signal: signal.to_vec(),
                    rest: rest.to_vec(),
                    energy,
                }
            }
            ResolvedMethod::AggregateNormal { threshold } => {
                StreamSampler::AggregateNormal(total(), threshold)
            }
            ResolvedMethod::Shot if !constant => {
                StreamSampler::Modulated(Box::new(DetectedShots::new(ModulatedShots::new(
                    signal,
                    rest,
                    energy.law,
                    energy.seed,
                    energy.envelope,
                ))))
            }
            _ => StreamSampler::Shot(Box::new(ShotSampler::new(&total()))),
        }
    }

    /// The same sampler with the detector's dead time applied to every shot (a `Shot`
    /// sampler becomes `DeadTimed`, a `Modulated` one records through it;
    /// [`check_detector`](super::method::check_detector)
    /// ensures the method is `shot`).
    pub fn through_detector(self, dead: Option<DeadTime>) -> Self {
        match (self, dead) {
            (StreamSampler::Shot(s), Some(d)) if d.pixels > 1 => {
                let k = f64::from(d.pixels);
                let share: Vec<f64> = s.means().iter().map(|m| m / k).collect();
                StreamSampler::Pixels {
                    pixel: Box::new(dead_time::DeadTimedShots::new(
                        ShotSampler::new(&share),
                        d.pixel(),
                    )),
                    pixels: d.pixels,
                }
            }
            (StreamSampler::Shot(s), Some(d)) => {
                StreamSampler::DeadTimed(Box::new(dead_time::DeadTimedShots::new(*s, d)))
            }
            (StreamSampler::Modulated(m), Some(d)) => {
                StreamSampler::Modulated(Box::new(m.through_detector(Some(d))))
            }
            (other, _) => other,
        }
    }

    /// The same sampler drawing every photon of a dead-time detector's shots (none from a
    /// bin's counting law) when `yes`: a `both` pair's photon-counting half, whose photons
    /// must be the analog half's, shot for shot.
    pub fn every_photon(self, yes: bool) -> Self {
        match self {
            StreamSampler::DeadTimed(d) if yes => {
                StreamSampler::DeadTimed(Box::new(d.drawing_every_photon()))
            }
            other => other,
        }
    }

    /// The same sampler with the photon counter's afterpulses added to its record.
    pub fn through_afterpulsing(self, afterpulsing: Option<&Afterpulsing>) -> Self {
        match afterpulsing {
            Some(a) => StreamSampler::Afterpulsed(Box::new(self), Box::new(a.clone())),
            None => self,
        }
    }

    /// The same sampler recorded by an analog chain: the same photons (the same draws
    /// from the same seed), each shot's (`Shot`, `Modulated`) or the profile's sums (the
    /// aggregate samplers) recorded as ADC codes.
    pub fn through_analog(self, analog: Option<&Analog>) -> Self {
        let Some(a) = analog else {
            return self;
        };
        match self {
            StreamSampler::Shot(s) => StreamSampler::AnalogShots(s, Box::new(a.clone())),
            StreamSampler::Modulated(m) => {
                StreamSampler::Modulated(Box::new(m.through_analog(Some(a.clone()))))
            }
            other => StreamSampler::AnalogAggregate(Box::new(other), Box::new(a.clone())),
        }
    }

    /// Draws profile `profile` of `shots` shots into `acc`: a function of the arguments only,
    /// so any profile can be regenerated alone.
    pub fn profile_counts(&self, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
        match self {
            StreamSampler::Aggregate(a) => {
                sampling::aggregate_profile_fixed(a, seed, profile, shots, acc)
            }
            StreamSampler::AggregateEnergy {
                signal,
                rest,
                energy,
            } => {
                let sum = energy
                    .law
                    .profile_sum(energy.seed.unwrap_or(seed), profile, shots);
                let mean_factor = sum / shots as f64;
                let l: Vec<f64> = signal
                    .iter()
                    .zip(rest)
                    .map(|(s, r)| mean_factor * s + r)
                    .collect();
                sampling::aggregate_profile(&l, seed, profile, shots, acc)
            }
            StreamSampler::Shot(s) => sampling::shot_profile(s, seed, profile, shots, acc),
            StreamSampler::Modulated(j) => j.profile(seed, profile, shots, acc),
            StreamSampler::AggregateNormal(l, threshold) => {
                approx::aggregate_approx_profile(l, seed, profile, shots, *threshold, acc)
            }
            StreamSampler::DeadTimed(s) => s.profile(seed, profile, shots, acc),
            StreamSampler::Pixels { pixel, pixels } => {
                for p in 0..*pixels {
                    pixel.profile(pixel_seed(seed, p), profile, shots, acc)
                }
            }
            StreamSampler::AnalogShots(s, a) => {
                crate::detector::recorded_profile(s, a.as_ref(), seed, profile, shots, acc)
            }
            StreamSampler::AnalogAggregate(photons, a) => {
                let mut n = vec![0u64; acc.len()];
                photons.profile_counts(seed, profile, shots, &mut n);
                a.record_profile(&mut analog::aggregate_rng(seed, profile), &n, shots, acc)
            }
            StreamSampler::Afterpulsed(inner, a) => {
                let mut recorded = vec![0u64; acc.len()];
                inner.profile_counts(seed, profile, shots, &mut recorded);
                let mut rng = sampling::stream_rng(
                    seed ^ AFTERPULSE_STREAM,
                    profile,
                    sampling::AGGREGATE_STREAM,
                );
                a.add_profile(&mut rng, &recorded, acc);
                acc.iter_mut().zip(&recorded).for_each(|(x, r)| *x += r);
            }
        }
    }
}

/// The streams of one channel with their seeds: the total, or signal, background and
/// dark apart.
pub fn stream_samplers(
    e: &ExpectedProfile,
    method: ResolvedMethod,
    energy: RunEnergy,
    components: bool,
    seed: u64,
    instrument: &crate::instrument::Instrument,
) -> Vec<(StreamSampler, u64)> {
    let n = e.n_bins();
    let zeros = vec![0.0; n];
    let constant = RunEnergy::jitter(0.0);
    if components {
        vec![
            (
                StreamSampler::with_energy(method, &e.photon_signal(), &zeros, energy),
                component_seed(seed, 0),
            ),
            (
                StreamSampler::with_energy(method, &zeros, &vec![e.background; n], constant),
                component_seed(seed, 1),
            ),
            (
                StreamSampler::with_energy(method, &zeros, &vec![e.dark; n], constant),
                component_seed(seed, 2),
            ),
        ]
    } else {
        let rest = vec![e.background + e.dark; n];
        let sampler = StreamSampler::with_energy(method, &e.photon_signal(), &rest, energy)
            .through_detector(instrument.dead_time)
            .every_photon(instrument.glued)
            .through_analog(instrument.analog.as_ref())
            .through_afterpulsing(instrument.afterpulsing.as_ref());
        vec![(sampler, seed)]
    }
}
