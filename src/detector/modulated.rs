//! Shots of varying energy (jitter, drift) as the detector records them: the jitter
//! sampler ([`ModulatedShots`]) draws each shot's photons, and a dead-time detector
//! records them shot by shot ([`DeadTime::record_shot`]). The detector wraps the
//! sampler, so the sampler knows counts and means only.
//!
//! Blocks of [`SHOT_BLOCK`] shots use `stream_rng(seed, profile, block)` for the photons
//! and `stream_rng(seed ^ ARRIVAL_STREAM, profile, block)` for their arrival times, so
//! results depend on the seed only.

use super::analog::Analog;
use super::dead_time::{ARRIVAL_STREAM, DeadTime, Scratch};
use super::recorder::ShotRecorder;
use crate::laser::PulseEnergy;
use crate::sampling::jitter::ModulatedShots;
use crate::sampling::{SHOT_BLOCK, ShotCounts, add_block_sums, stream_rng};

/// Shots of varying energy recorded by the detector: every photon (an ideal linear
/// detector) or through its dead time.
#[derive(Debug, Clone)]
pub struct DetectedShots {
    photons: ModulatedShots<PulseEnergy>,
    dead: Option<DeadTime>,
    analog: Option<Analog>,
}

/// Reusable buffers of one block.
struct Buffers {
    envelope: ShotCounts,
    shot: ShotCounts,
    factors: Vec<f64>,
    scratch: Scratch,
}

impl Buffers {
    fn new(bins: usize, factors: Vec<f64>) -> Self {
        Buffers {
            envelope: ShotCounts::new(bins),
            shot: ShotCounts::new(bins),
            factors,
            scratch: Scratch::default(),
        }
    }
}

impl DetectedShots {
    /// The shots of `photons` recorded by an ideal linear detector.
    pub fn new(photons: ModulatedShots<PulseEnergy>) -> Self {
        DetectedShots {
            photons,
            dead: None,
            analog: None,
        }
    }

    /// The same shots recorded by an analog chain (ADC codes; its gains and noise from
    /// `stream_rng(seed ^ ANALOG_STREAM, profile, block)`).
    pub fn through_analog(mut self, analog: Option<Analog>) -> Self {
        self.analog = analog;
        self
    }

    /// The same shots recorded through `dead`.
    pub fn through_detector(mut self, dead: Option<DeadTime>) -> Self {
        self.dead = dead;
        self
    }

    /// Whether every shot is recorded through a detector stage (dead time or analog).
    pub fn has_detector(&self) -> bool {
        self.dead.is_some() || self.analog.is_some()
    }

    /// Draws one shot per factor of `factors` (these shots' emitted energies relative to
    /// the nominal, none above the envelope) into `acc`, from `stream_rng(seed, profile,
    /// 0)` and its arrival stream: a run of consecutive shots of a scene that changes
    /// along the track. `extra` adds photons to each shot before the dead-time detector
    /// records it (sunlight in a changing scene); without a detector it is not called
    /// (the caller adds such photons for the whole run: the same law).
    pub fn add_run(
        &self,
        seed: u64,
        profile: u64,
        factors: &[f64],
        acc: &mut [u64],
        extra: &mut dyn FnMut(&mut ShotCounts),
    ) {
        let Some(dead) = &self.dead else {
            return self.photons.add_run(seed, profile, factors, acc);
        };
        let mut buf = Buffers::new(acc.len(), factors.to_vec());
        let mut arrivals = stream_rng(seed ^ ARRIVAL_STREAM, profile, 0);
        let mut rng = stream_rng(seed, profile, 0);
        for &f in &buf.factors {
            self.photons
                .draw_shot(&mut rng, f, &mut buf.envelope, &mut buf.shot);
            extra(&mut buf.shot);
            dead.record_shot(&mut arrivals, &buf.shot, &mut buf.scratch, acc);
        }
    }

    /// Accumulates one profile of `shots` shots into `acc`.
    pub fn profile(&self, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
        match (&self.analog, &self.dead) {
            (Some(analog), _) => self.recorded(analog, seed, profile, shots, acc),
            (None, Some(dead)) => self.recorded(dead, seed, profile, shots, acc),
            (None, None) => self.photons.profile(seed, profile, shots, acc),
        }
    }

    /// [`profile`](Self::profile) through a detector stage: the photons as without it,
    /// shot for shot, the stage's draws from its own stream.
    fn recorded<D: ShotRecorder>(
        &self,
        detector: &D,
        seed: u64,
        profile: u64,
        shots: u64,
        acc: &mut [u64],
    ) {
        let bins = acc.len();
        add_block_sums(acc, shots.div_ceil(SHOT_BLOCK), |b| {
            let mut part = vec![0u64; bins];
            let mut buf = Buffers::new(bins, Vec::new());
            let mut scratch = D::Scratch::default();
            self.photons
                .block_factors(seed, profile, shots, b, &mut buf.factors);
            let mut own = stream_rng(seed ^ D::STREAM, profile, b);
            let mut rng = stream_rng(seed, profile, b);
            for &f in &buf.factors {
                self.photons
                    .draw_shot(&mut rng, f, &mut buf.envelope, &mut buf.shot);
                detector.record_shot(&mut own, &buf.shot, &mut scratch, &mut part);
            }
            part
        });
    }
}
