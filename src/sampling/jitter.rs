//! Shots whose signal varies with the emitted energy (jitter, drift: the laser's law),
//! drawn exactly by thinning. The counts of an ideal linear detector; a dead-time
//! detector records the same shots' photons through its own wrapper
//! (`DetectedShots` in `src/detector/modulated.rs`).
//!
//! **Model.** Shot `s` emits `f_s·E0`; its signal counts are Poisson(`f_s·λ_sig,i`),
//! background and dark unchanged; the factors `f_s` come from the laser's own stream
//! ([`EnergyFactors::block_factors`], the laser's `PulseEnergy`), shared by every channel.
//!
//! **Algorithm (exact thinning).** The signal sampler is built once at the envelope
//! `f_max·λ_sig` (`f_max` bounds every factor of the run); each shot's draw is thinned,
//! every count kept with probability `f_s/f_max` (a binomial thinning of a Poisson(μ)
//! count is Poisson(p·μ); Lewis & Shedler 1979, Naval Res. Logist. Q. 26, 403). The cost
//! per shot is that of the envelope draw plus one Bernoulli per signal count, with no
//! per-shot rebuild. With dead time the detector takes each shot's photons (thinned
//! signal and the rest, [`ModulatedShots::draw_shot`]) and records them. Blocks of [`SHOT_BLOCK`] shots
//! use [`stream_rng`]`(seed, profile, block)`, as in [`super::profile::shot_profile`], so results
//! depend on the seed only.

use rand::Rng;
use rand_distr::{Binomial, Distribution};

use super::shot::ShotSampler;
use super::sink::{CountSink, ShotCounts};
use super::streams::{SHOT_BLOCK, add_block_sums, stream_rng};

/// The energy factors of a run's shots, relative to the nominal energy: what the laser's
/// law (`PulseEnergy`) draws from its own stream; shared by the threads that draw blocks.
pub trait EnergyFactors: Sync {
    /// The energy factors of block `block` of profile `profile` (`shots` shots per
    /// profile), written to `out` (cleared first): a function of the arguments only.
    fn block_factors(&self, seed: u64, profile: u64, shots: u64, block: u64, out: &mut Vec<f64>);
}

/// Samplers for shots of varying energy: the signal at its envelope, the rest unchanged.
#[derive(Debug, Clone)]
pub struct ModulatedShots<E> {
    signal_envelope: ShotSampler,
    rest: ShotSampler,
    energy: E,
    /// The run's seed, from which the energy factors are drawn (`None`: the stream's own).
    energy_seed: Option<u64>,
    /// `f_max`: no factor of the run exceeds it.
    envelope: f64,
}

impl<E: EnergyFactors> ModulatedShots<E> {
    /// `signal` and `rest` (background + dark) are per-shot means per bin at the nominal
    /// energy; `envelope` bounds every energy factor of the run
    /// (the laser's `PulseEnergy::envelope`); `energy_seed` is the run's seed.
    pub fn new(
        signal: &[f64],
        rest: &[f64],
        energy: E,
        energy_seed: Option<u64>,
        envelope: f64,
    ) -> Self {
        let env: Vec<f64> = signal.iter().map(|s| s * envelope).collect();
        ModulatedShots {
            signal_envelope: ShotSampler::new(&env),
            rest: ShotSampler::new(rest),
            energy,
            energy_seed,
            envelope,
        }
    }

    /// Draws one shot per factor of `factors` (these shots' emitted energies relative to
    /// the nominal, none above the envelope) into `acc`, from `stream_rng(seed, profile,
    /// 0)`: a run of consecutive shots of a scene that changes along the track.
    pub fn add_run(&self, seed: u64, profile: u64, factors: &[f64], acc: &mut [u64]) {
        let mut envelope = ShotCounts::new(acc.len());
        self.add_block(
            &mut stream_rng(seed, profile, 0),
            factors,
            acc,
            &mut envelope,
        );
    }

    /// Draws one shot per factor of `factors` into `acc`, every count kept.
    fn add_block<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        factors: &[f64],
        acc: &mut [u64],
        envelope: &mut ShotCounts,
    ) {
        for &f in factors {
            let keep = f / self.envelope;
            envelope.clear();
            self.signal_envelope.sample_shot(rng, envelope);
            for (bin, n) in envelope.nonzero() {
                acc[bin] += thin(rng, n, keep);
            }
            self.rest.sample_shot(rng, acc);
        }
    }

    /// Draws the photons of one shot of energy factor `f` into `shot` (cleared first):
    /// the thinned signal and the rest, `envelope` a buffer. The same draws, in the same
    /// order, as a shot of [`add_run`](Self::add_run) or [`profile`](Self::profile): a
    /// detector that needs the whole shot (dead time) records it.
    pub fn draw_shot<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        f: f64,
        envelope: &mut ShotCounts,
        shot: &mut ShotCounts,
    ) {
        let keep = f / self.envelope;
        envelope.clear();
        self.signal_envelope.sample_shot(rng, envelope);
        shot.clear();
        for (bin, n) in envelope.nonzero() {
            let kept = thin(rng, n, keep);
            if kept > 0 {
                shot.add(bin, kept as u32);
            }
        }
        self.rest.sample_shot(rng, shot);
    }

    /// The energy factors of block `block` of profile `profile` of `shots` shots into
    /// `out`, from the run's seed (`seed` when the sampler has none of its own).
    pub fn block_factors(
        &self,
        seed: u64,
        profile: u64,
        shots: u64,
        block: u64,
        out: &mut Vec<f64>,
    ) {
        let energy_seed = self.energy_seed.unwrap_or(seed);
        self.energy
            .block_factors(energy_seed, profile, shots, block, out);
    }

    /// Accumulates one profile of `shots` shots into `acc`.
    pub fn profile(&self, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
        let bins = acc.len();
        let nblocks = shots.div_ceil(SHOT_BLOCK);
        add_block_sums(acc, nblocks, |b| {
            let mut part = vec![0u64; bins];
            let mut factors = Vec::new();
            self.block_factors(seed, profile, shots, b, &mut factors);
            let mut envelope = ShotCounts::new(bins);
            let mut rng = stream_rng(seed, profile, b);
            self.add_block(&mut rng, &factors, &mut part, &mut envelope);
            part
        });
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
