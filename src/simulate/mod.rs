//! The Monte Carlo run (`lidarsim simulate`, docs/simulation.md): per-bin expectations from the
//! deterministic model, Poisson photon counts accumulated over each profile's shots by
//! the chosen method, streamed into a raw HDF5 file.
//!
//! Profiles are drawn in parallel (rayon) in batches and written in order by this
//! thread (all HDF5 calls are serialized anyway). Every profile's counts come from
//! [`sampling::stream_rng`]`(seed', profile, block)` only, so the file's bytes depend on
//! the seed alone, never on the thread count, and any profile can be regenerated alone
//! with [`StreamSampler::profile_counts`].

use std::path::PathBuf;
use std::time::{Duration, Instant};

use rayon::prelude::*;

pub mod merge;
pub mod scene;

use crate::config::Method;
use crate::detector::afterpulse::{AFTERPULSE_STREAM, Afterpulsing};
use crate::detector::{Analog, DeadTime, DetectedShots, analog, dead_time};
use crate::error::{Error, Result};
use crate::laser::PulseEnergy;
use crate::output::raw_file::content::{self, RunInfo};
use crate::output::raw_file::memory::{MemoryFile, MemoryWriter};
use crate::output::raw_file::{
    AttrValue, CountWidth, ProfileRecord, ProfileSink, RawFileSpec, RawFileWriter,
};
use crate::safe_file::{OutputId, Outputs};
use crate::sampling::approx;
use crate::sampling::jitter::ModulatedShots;
use crate::sampling::{self, ShotSampler};
use crate::scenario::{ExpectedProfile, Lidar};

/// The method actually used for a run (after `auto` is resolved).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ResolvedMethod {
    /// Every shot drawn.
    Shot,
    /// One exact Poisson(M·λ) draw per bin per profile.
    Aggregate,
    /// As `Aggregate`, but bins with `M·λ ≥ threshold` draw the normal approximation
    /// (`sampling::approx`), whose KS distance to the exact law is at most the tolerance
    /// that set the threshold. Only chosen by `auto` with a tolerance.
    AggregateNormal {
        /// Smallest mean drawn by the approximation, `approx::normal_threshold(tolerance)`.
        threshold: f64,
    },
}

impl ResolvedMethod {
    /// The name stored in the file's `method` attribute.
    pub fn name(self) -> &'static str {
        match self {
            ResolvedMethod::Shot => "shot",
            ResolvedMethod::Aggregate => "aggregate",
            ResolvedMethod::AggregateNormal { .. } => "aggregate-normal",
        }
    }

    /// The method a file's `method` attribute names (`threshold`: its
    /// `normal_approximation_threshold`, for `aggregate-normal`).
    pub fn from_name(name: &str, threshold: Option<f64>) -> Option<Self> {
        match (name, threshold) {
            ("shot", _) => Some(ResolvedMethod::Shot),
            ("aggregate", _) => Some(ResolvedMethod::Aggregate),
            ("aggregate-normal", Some(threshold)) => {
                Some(ResolvedMethod::AggregateNormal { threshold })
            }
            _ => None,
        }
    }
}

/// Approximate cost of one profile by each method, ns (constants measured in
/// `validation/reports/speed_vs_error.md`; the shot path's from its own cost model).
mod cost {
    /// An exact aggregate draw with `M·λ < 12` (inversion).
    pub const AGGREGATE_SMALL_NS: f64 = 28.0;
    /// An exact aggregate draw with `M·λ ≥ 12` (Ahrens–Dieter).
    pub const AGGREGATE_LARGE_NS: f64 = 45.0;
    /// One normal-approximation draw.
    pub const NORMAL_NS: f64 = 14.0;
}

/// `auto` with a tolerance (KS distance per bin): the fastest of `shot`, `aggregate` and
/// `aggregate-normal` whose error is within it, by the cost constants above. `shot`
/// only where the scene needs it or where it is cheaper (sparse profiles of few shots).
pub fn fastest_within(
    tolerance: f64,
    e: &ExpectedProfile,
    shots: u64,
    aggregate_allowed: bool,
) -> ResolvedMethod {
    fastest_within_totals(tolerance, &e.total_per_shot(), shots, aggregate_allowed)
}

/// [`fastest_within`] for the per-shot totals of every bin of every channel.
pub fn fastest_within_totals(
    tolerance: f64,
    totals: &[f64],
    shots: u64,
    aggregate_allowed: bool,
) -> ResolvedMethod {
    if !aggregate_allowed {
        return ResolvedMethod::Shot;
    }
    let means: Vec<f64> = totals.iter().map(|l| l * shots as f64).collect();
    let exact = |m: f64| {
        if m < 12.0 {
            cost::AGGREGATE_SMALL_NS
        } else {
            cost::AGGREGATE_LARGE_NS
        }
    };
    let threshold = approx::normal_threshold(tolerance);
    let aggregate: f64 = means.iter().map(|&m| exact(m)).sum();
    let normal: f64 = means
        .iter()
        .map(|&m| {
            if m >= threshold {
                cost::NORMAL_NS
            } else {
                exact(m)
            }
        })
        .sum();
    let shot = ShotSampler::new(totals).strategy().est_ns_per_shot * shots as f64;
    let candidates = [
        (shot, ResolvedMethod::Shot),
        (aggregate, ResolvedMethod::Aggregate),
        (normal, ResolvedMethod::AggregateNormal { threshold }),
    ];
    // ties go to the exact method listed first
    candidates
        .into_iter()
        .fold((f64::INFINITY, ResolvedMethod::Aggregate), |best, c| {
            if c.0 < 0.8 * best.0 { c } else { best }
        })
        .1
}

/// What the scene needs drawn shot by shot; `None` when the profile's counts are
/// Poisson given the emitted energies (the detector is linear), so that `aggregate` is
/// exact: pulse-energy jitter and drift are drawn as the profile's summed energy.
pub fn per_shot_reason(lidar: &Lidar) -> Option<&'static str> {
    lidar
        .channels
        .iter()
        .any(|c| c.instrument.dead_time.is_some())
        .then_some("detector dead time makes the recorded counts non-Poisson")
}

/// Resolves `auto`, and refuses `aggregate` where it would not be exact.
pub fn resolve_method(requested: Method, lidar: &Lidar) -> Result<ResolvedMethod> {
    match (requested, per_shot_reason(lidar)) {
        (Method::Shot, _) | (Method::Auto, Some(_)) => Ok(ResolvedMethod::Shot),
        (Method::Aggregate | Method::Auto, None) => Ok(ResolvedMethod::Aggregate),
        (Method::Aggregate, Some(why)) => Err(Error::Unsupported(format!(
            "--method aggregate is not exact for this scene ({why}); use --method shot or auto"
        ))),
    }
}

/// Options of one run; `None` takes the config's value.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Output raw file.
    pub output: PathBuf,
    /// Seed (`simulation.seed`).
    pub seed: Option<u64>,
    /// Profiles (`acquisition.profiles`).
    pub profiles: Option<usize>,
    /// Method (`simulation.method`).
    pub method: Option<Method>,
    /// Tolerance for `auto` (`simulation.tolerance`): largest KS distance per bin.
    pub tolerance: Option<f64>,
    /// Component-resolved counts (`simulation.components`).
    pub components: Option<bool>,
    /// Show a progress bar (on a terminal only).
    pub progress: bool,
    /// The command line, recorded in the file's `history`
    /// ([`content::history_command`] says which arguments it keeps).
    pub command_line: String,
    /// Write this shard of the run only (`--shard K/N`, [`crate::shard`]).
    pub shard: Option<crate::shard::Shard>,
    /// Stops the run when set (the Python module's Ctrl-C): [`run`] then returns
    /// [`Error::Interrupted`] before its next profile, its temporary file removed.
    pub cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

/// What a run did, for the closing summary.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// The file written.
    pub output: PathBuf,
    /// Profiles written.
    pub profiles: usize,
    /// With `--shard`: the shard, the profiles it wrote and the run's profiles.
    pub shard: Option<(crate::shard::Shard, std::ops::Range<usize>, usize)>,
    /// Bins per profile.
    pub bins: usize,
    /// Shots per profile.
    pub shots_per_profile: u64,
    /// Total counts in the file.
    pub total_counts: u64,
    /// Method used.
    pub method: ResolvedMethod,
    /// Seed used.
    pub seed: u64,
    /// Wall time.
    pub elapsed: Duration,
    /// Time spent drawing counts (the rest is the model, the file and its writes).
    pub drawing: Duration,
    /// A warning about the scene (rates beyond a photon counter's range), if any.
    pub warning: Option<String>,
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let shot_bins = self.profiles as f64 * self.shots_per_profile as f64 * self.bins as f64;
        let rate = |d: Duration| shot_bins / d.as_secs_f64().max(1e-9);
        let shard = match &self.shard {
            Some((s, rows, of)) if !rows.is_empty() => format!(
                " (shard {s}: profiles {}–{} of {of})",
                rows.start,
                rows.end - 1
            ),
            _ => String::new(),
        };
        write!(
            f,
            "Wrote {}{shard}: {} profiles × {} bins, {} shots per profile, {} counts in all; method {}, seed {}. \
             {:.3} s in all ({:.3e} shot-bins/s), of which drawing {:.3} s ({:.3e} shot-bins/s).",
            self.output.display(),
            self.profiles,
            self.bins,
            self.shots_per_profile,
            human_count(self.total_counts),
            self.method.name(),
            self.seed,
            self.elapsed.as_secs_f64(),
            rate(self.elapsed),
            self.drawing.as_secs_f64(),
            rate(self.drawing)
        )
    }
}

/// A count for a person: exact below a million, else in scientific notation.
fn human_count(n: u64) -> String {
    if n < 1_000_000 {
        n.to_string()
    } else {
        format!("{:.4e}", n as f64)
    }
}

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

/// The emitted energies of a run: their law, the run's seed (every channel sees the
/// same pulses) and the envelope bounding every factor of the run.
#[derive(Debug, Clone, Copy)]
pub struct RunEnergy {
    /// Jitter and drift.
    pub law: PulseEnergy,
    /// The seed the factors are drawn from (`None`: each stream's own seed).
    pub seed: Option<u64>,
    /// Upper bound of every factor of the run.
    pub envelope: f64,
}

impl RunEnergy {
    /// Energies that vary with relative jitter `jitter` only, drawn from each stream's
    /// own seed (a single stream, as in tests and benches).
    pub fn jitter(jitter: f64) -> Self {
        let law = PulseEnergy {
            jitter,
            drift: None,
            rep_rate_hz: 1.0,
        };
        RunEnergy {
            law,
            seed: None,
            envelope: law.jitter_envelope(),
        }
    }
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
    /// sampler becomes `DeadTimed`, a `Modulated` one records through it; [`check_detector`]
    /// ensures the method is `shot`).
    pub fn through_detector(self, dead: Option<DeadTime>) -> Self {
        match (self, dead) {
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

/// What this version does not combine with dead time: component counts (a recorded
/// count is not a sum of parts).
pub fn check_detector(lidar: &Lidar, components: bool) -> Result<()> {
    let dead = lidar
        .channels
        .iter()
        .any(|c| c.instrument.dead_time.is_some());
    if dead && components {
        return Err(Error::Unsupported(
            "--components is not available with dead time: a recorded count is not a sum of \
             signal, background and dark counts"
                .into(),
        ));
    }
    if components
        && lidar
            .channels
            .iter()
            .any(|c| c.instrument.afterpulsing.is_some())
    {
        return Err(Error::Unsupported(
            "--components is not available with afterpulsing: an afterpulse is neither \
             signal, background nor dark"
                .into(),
        ));
    }
    if components && lidar.channels.iter().any(|c| c.instrument.analog.is_some()) {
        return Err(Error::Unsupported(
            "--components is not available with an analog detector: an ADC code is not a sum \
             of signal, background and dark counts"
                .into(),
        ));
    }
    Ok(())
}

/// The run's energies: the laser of the first channel (shared by all), its envelope over
/// the run's `duration_s`; refuses a drift that would leave the laser dark.
pub fn run_energy(lidar: &Lidar, seed: u64, duration_s: f64) -> Result<RunEnergy> {
    let sc = lidar.first();
    let law = PulseEnergy::from_config(&sc.loaded.config.instrument);
    let lowest = law.lowest_drift(duration_s);
    if lowest < 0.05 {
        return Err(Error::config(
            sc.loaded.file_label(),
            "instrument.energy_drift",
            format!(
                "drifts to {:.1} % of the pulse energy within the run ({}); a laser \
                 below 5 % is off: shorten the run or the drift",
                100.0 * lowest,
                crate::resources::human_duration(duration_s)
            ),
        ));
    }
    Ok(RunEnergy {
        law,
        seed: Some(seed),
        envelope: law.envelope(duration_s),
    })
}

/// What a run is before any count is drawn: the resolved seed, method, model and scene,
/// and the raw file of the whole run. `simulate` draws from it; `merge`
/// ([`merge`]) builds it again from a shard's stored config, so that both
/// write the same file.
pub struct RunPlan {
    /// Seed of the counts.
    pub seed: u64,
    /// Profiles of the whole run.
    pub profiles: usize,
    /// Component-resolved counts.
    pub components: bool,
    /// The method used.
    pub method: ResolvedMethod,
    /// Every channel's per-shot expectations (the scene's first column).
    pub expected: Vec<ExpectedProfile>,
    /// The emitted energies.
    pub energy: RunEnergy,
    /// The scene model where the scene changes along the track.
    pub scene: Option<scene::SceneModel>,
    /// Per-shot means of every bin of every channel.
    pub totals: Vec<f64>,
    /// The raw file of the whole run.
    pub spec: RawFileSpec,
}

/// The values of a run that a command-line option may set in place of its config key
/// ([`RunOptions`] over the loaded config): what [`plan`] runs with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunValues {
    /// `acquisition.profiles` (`--profiles`).
    pub profiles: usize,
    /// `simulation.seed` (`--seed`).
    pub seed: u64,
    /// `simulation.method` as asked (`--method`), before `auto` is resolved.
    pub method: Method,
    /// `simulation.components` (`--components`).
    pub components: bool,
    /// `simulation.tolerance` (`--tolerance`).
    pub tolerance: Option<f64>,
}

impl RunValues {
    /// Each option of `opts` that is given, else its key in `cfg` (or that key's default).
    pub fn resolve(opts: &RunOptions, cfg: &crate::config::ScenarioConfig) -> Self {
        RunValues {
            profiles: opts.profiles.unwrap_or(cfg.acquisition.profiles),
            seed: opts.seed.unwrap_or(cfg.simulation.seed),
            method: opts.method.unwrap_or(cfg.simulation.method),
            components: opts.components.unwrap_or(cfg.simulation.components),
            tolerance: opts.tolerance.or(cfg.simulation.tolerance),
        }
    }

    /// The config a run stores (the raw file's `config` attribute): `resolved_toml` (the
    /// loaded config after every `--set`) with these values written into their keys, so
    /// that simulating it again with no option reproduces the file. Every value is
    /// written, from an option, the file or a default alike, so that a stored config
    /// planned again (`merge`) stores the same text.
    pub fn stored_config(&self, resolved_toml: &str) -> Result<String> {
        let unwritable =
            |why: String| Error::Unsupported(format!("cannot store the run's config: {why}"));
        let mut table: toml::Table = resolved_toml
            .parse()
            .map_err(|e: toml::de::Error| unwritable(e.message().to_string()))?;
        let mut set = |section: &str, key: &str, value: toml::Value| {
            let slot = table
                .entry(section)
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            match slot {
                toml::Value::Table(t) => {
                    t.insert(key.to_string(), value);
                    Ok(())
                }
                _ => Err(unwritable(format!("`{section}` is not a table"))),
            }
        };
        let profiles = i64::try_from(self.profiles).map_err(|e| unwritable(e.to_string()))?;
        set("acquisition", "profiles", toml::Value::Integer(profiles))?;
        set("simulation", "seed", crate::config::seed_value(self.seed))?;
        // as the config spells it (`auto`, `shot`, `aggregate`: Method's serde names)
        let method = toml::Value::try_from(self.method).map_err(|e| unwritable(e.to_string()))?;
        set("simulation", "method", method)?;
        set(
            "simulation",
            "components",
            toml::Value::Boolean(self.components),
        )?;
        if let Some(t) = self.tolerance {
            set("simulation", "tolerance", toml::Value::Float(t))?;
        }
        toml::to_string(&table).map_err(|e| unwritable(e.to_string()))
    }
}

/// Resolves a run's options against its config and builds everything but the counts.
/// `resolved` is the method of a run already drawn (`merge`, from the shards' `method`);
/// `None` resolves `opts.method` (and `auto`'s tolerance) as `simulate` does.
pub fn plan(lidar: &Lidar, opts: &RunOptions, resolved: Option<ResolvedMethod>) -> Result<RunPlan> {
    let first = lidar.first();
    let values = RunValues::resolve(opts, &first.loaded.config);
    let RunValues {
        profiles,
        seed,
        method: requested,
        components,
        tolerance,
    } = values;
    if profiles == 0 {
        return Err(Error::Unsupported("--profiles must be at least 1".into()));
    }
    check_detector(lidar, components)?;
    let mut method = match resolved {
        Some(m) => m,
        None => resolve_method(requested, lidar)?,
    };
    // what the plan holds besides the model (whose estimate was checked when it was
    // built): the file's variables per bin, before the run's own estimate (check_sizes)
    let bins = (lidar.channels.len() * first.geometry.n_bins) as f64;
    crate::resources::require_memory(
        &format!("planning a run of {bins} bins"),
        bins * PLAN_BYTES_PER_BIN,
    )?;
    let expected = lidar.expected()?;
    let shots = first.shots_per_profile();
    let profile_time_s = shots as f64 / first.instrument.rep_rate_hz;
    let energy = run_energy(lidar, seed, profiles as f64 * profile_time_s)?;
    let totals: Vec<f64> = expected.iter().flat_map(|e| e.total_per_shot()).collect();
    if let (Some(t), None) = (tolerance, resolved) {
        if requested != Method::Auto {
            return Err(Error::Unsupported(format!(
                "--tolerance chooses among methods: use it with --method auto, not {}",
                method.name()
            )));
        }
        let approximable = method == ResolvedMethod::Aggregate && energy.law.is_constant();
        method = fastest_within_totals(t, &totals, shots, approximable);
    }
    let scene = changing_scene(lidar, seed, profiles, &mut method, components, &energy)?;
    let spec = raw_file_spec(
        lidar,
        &expected,
        method,
        &values,
        energy,
        opts,
        scene.as_ref(),
    )?;
    Ok(RunPlan {
        seed,
        profiles,
        components,
        method,
        expected,
        energy,
        scene,
        totals,
        spec,
    })
}

/// Runs the Monte Carlo of every channel of `lidar` and writes the raw file as output
/// `raw` of `outputs` (the command's output set, committed here when the file is complete):
/// the whole run, or with [`RunOptions::shard`] that shard's profiles only
/// ([`crate::shard`]).
pub fn run(
    lidar: &Lidar,
    opts: &RunOptions,
    outputs: Outputs,
    raw: OutputId,
) -> Result<RunSummary> {
    let start = Instant::now();
    let planned = plan(lidar, opts, None)?;
    // --- shards: this process writes `rows` of the run (all of them without --shard)
    let (rows, shard_spec) = match opts.shard {
        Some(shard) => {
            let rows = shard.rows_of(planned.profiles, "profiles")?;
            let spec = crate::shard::shard_spec(planned.spec.clone(), shard, rows.clone());
            (rows, Some(spec))
        }
        None => (0..planned.profiles, None),
    };
    let spec = shard_spec.as_ref().unwrap_or(&planned.spec);
    check_sizes(lidar, &planned, rows.len(), opts, true)?;
    let mut writer = RawFileWriter::create(outputs.temp_path(raw)?, &opts.output, spec)?;
    let (total_counts, drawing) = draw_into(lidar, &planned, rows.clone(), opts, &mut writer)?;
    writer.finish()?;
    outputs.commit()?;
    Ok(summary(
        lidar,
        &planned,
        opts,
        rows,
        start,
        total_counts,
        drawing,
    ))
}

/// Runs the Monte Carlo as [`run`] does (the same counts and truth for the same seed) and
/// keeps the raw file in memory, its variables as arrays ([`MemoryFile`]): for the Python
/// module's in-memory `simulate`. Refuses a shard, and a run whose arrays cannot fit in
/// memory.
pub fn run_in_memory(lidar: &Lidar, opts: &RunOptions) -> Result<(MemoryFile, RunSummary)> {
    let start = Instant::now();
    if opts.shard.is_some() {
        return Err(Error::Unsupported(
            "a shard is written to a file: give a path".into(),
        ));
    }
    let planned = plan(lidar, opts, None)?;
    let rows = 0..planned.profiles;
    crate::resources::require_memory(
        &format!("holding {} profiles in memory", rows.len()),
        crate::output::raw_file::memory::memory_bytes(&planned.spec),
    )?;
    check_sizes(lidar, &planned, rows.len(), opts, false)?;
    let mut sink = MemoryWriter::new(&planned.spec)?;
    let (total_counts, drawing) = draw_into(lidar, &planned, rows.clone(), opts, &mut sink)?;
    let file = sink.finish()?;
    Ok((
        file,
        summary(lidar, &planned, opts, rows, start, total_counts, drawing),
    ))
}

/// What a run did, for its closing line.
fn summary(
    lidar: &Lidar,
    planned: &RunPlan,
    opts: &RunOptions,
    rows: std::ops::Range<usize>,
    start: Instant,
    total_counts: u64,
    drawing: Duration,
) -> RunSummary {
    let first = lidar.first();
    RunSummary {
        output: opts.output.clone(),
        profiles: rows.len(),
        shard: opts.shard.map(|s| (s, rows, planned.profiles)),
        bins: first.geometry.n_bins,
        shots_per_profile: first.shots_per_profile(),
        total_counts,
        method: planned.method,
        seed: planned.seed,
        elapsed: start.elapsed(),
        drawing,
        warning: lidar.run_notes(&planned.expected),
    }
}

/// Whether the caller asked the run to stop ([`RunOptions::cancel`]).
fn cancelled(opts: &RunOptions) -> bool {
    opts.cancel
        .as_ref()
        .is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed))
}

/// Draws profiles `rows` of a planned run and hands them to `sink` in order, profile by
/// profile; returns the sum of their counts and the time spent drawing. Stops with
/// [`Error::Interrupted`] between batches (and skips the rest of a batch's profiles)
/// once [`RunOptions::cancel`] is set.
fn draw_into<S: ProfileSink>(
    lidar: &Lidar,
    planned: &RunPlan,
    rows: std::ops::Range<usize>,
    opts: &RunOptions,
    sink: &mut S,
) -> Result<(u64, Duration)> {
    let first = lidar.first();
    let RunPlan {
        seed,
        components,
        method,
        ref expected,
        energy,
        ref scene,
        ..
    } = *planned;
    let shots = first.shots_per_profile();
    let profile_time_s = shots as f64 / first.instrument.rep_rate_hz;
    let n_bins = first.geometry.n_bins;
    let orbit = orbit_of(lidar)?;

    let channels: Vec<Vec<(StreamSampler, u64)>> = lidar
        .channels
        .iter()
        .zip(expected)
        .enumerate()
        .map(|(k, (c, e))| {
            let seed = channel_seed(seed, lidar.photon_source(k));
            stream_samplers(e, method, energy, components, seed, &c.instrument)
        })
        .collect();
    // each channel's laser line has its own nominal energy; the shots' factors are shared
    let nominal_energy_j: Vec<f64> = lidar
        .channels
        .iter()
        .map(|c| c.loaded.config.instrument.pulse_energy_j)
        .collect();
    let progress = progress_bar(opts.progress, rows.len());
    let streams = channels.len() * channels[0].len();
    // batch size: bounded memory (at most 32 MiB of counts) and a lively progress bar
    let batch = ((4 << 20) / (n_bins * streams).max(1)).clamp(1, 64);
    let mut total_counts = 0u64;
    let mut drawing = Duration::ZERO;
    // Batch k is drawn while batch k − 1 is handed to the writer (whose chunk compression
    // runs on the same pool): the writer gets the profiles in order whatever the thread
    // count, so the file's bytes do not depend on it.
    let draw_batch = |first_profile: usize| -> Option<Batch> {
        let last = (first_profile + batch).min(rows.end);
        let draw_start = Instant::now();
        let n_channels = lidar.channels.len();
        let mut drawn: Vec<(DrawnProfile, Option<SceneDraw>)> = (first_profile..last)
            .into_par_iter()
            .map(|p| {
                if cancelled(opts) {
                    return None;
                }
                Some(match scene {
                    Some(sc) => {
                        let (d, draw) =
                            draw_scene_counts(sc, seed, n_channels, p as u64, n_bins, &energy);
                        (d, Some(draw))
                    }
                    None => (
                        draw_profile(&channels, p as u64, shots, n_bins, components, &energy),
                        None,
                    ),
                })
            })
            .collect::<Option<_>>()?;
        let took = draw_start.elapsed();
        // the truth of a changing scene's profiles (the model, not the draw)
        if let Some(sc) = scene {
            drawn.par_iter_mut().for_each(|(d, draw)| {
                if let Some(draw) = draw {
                    d.values = scene_profile_values(sc, n_bins, draw);
                }
            });
        }
        // summed here, in parallel, not on the writer's thread
        let counted: u64 = drawn
            .par_iter()
            .map(|(d, _)| d.counts.iter().sum::<u64>())
            .sum();
        let drawn: Vec<DrawnProfile> = drawn.into_iter().map(|(d, _)| d).collect();
        Some((first_profile, drawn, took, counted))
    };
    let mut write_batch = |(first_profile, drawn, took, counted): Batch| {
        drawing += took;
        total_counts += counted;
        for (k, d) in drawn.iter().enumerate() {
            let index = first_profile + k;
            let place = orbit.as_ref().map(|o| {
                let g = o.position((index as f64 + 0.5) * profile_time_s);
                [[g.latitude_deg], [g.longitude_deg], [g.along_track_m]]
            });
            let values: Vec<&[f64]> = d
                .values
                .iter()
                .map(Vec::as_slice)
                .chain(place.iter().flat_map(|p| p.iter().map(|v| &v[..])))
                .collect();
            // E0_c·(Σf_s/M): exactly E0_c when every factor is 1
            let factor = d.energy_sum / shots as f64;
            let pulse_energy_j: Vec<f64> = nominal_energy_j.iter().map(|e0| e0 * factor).collect();
            sink.write_profile(&ProfileRecord {
                index: index - rows.start,
                time_s: index as f64 * profile_time_s + 0.5 * profile_time_s,
                n_shots: shots,
                pulse_energy_j: &pulse_energy_j,
                counts: &d.counts,
                components: d
                    .components
                    .as_ref()
                    .map(|[s, b, k]| [&s[..], &b[..], &k[..]]),
                values: &values,
                columns: d.columns.as_ref().map_or(STATIC_COLUMN.0, |c| &c.0),
                column_weights: d.columns.as_ref().map_or(STATIC_COLUMN.1, |c| &c.1),
            })?;
        }
        progress.inc(drawn.len() as u64);
        Ok::<(), Error>(())
    };
    let mut pending = None;
    for first_profile in rows.clone().step_by(batch) {
        let (drawn, written) = rayon::join(
            || draw_batch(first_profile),
            || pending.take().map_or(Ok(()), &mut write_batch),
        );
        written?;
        match drawn {
            Some(drawn) if !cancelled(opts) => pending = Some(drawn),
            _ => return Err(Error::Interrupted),
        }
    }
    if let Some(last) = pending {
        write_batch(last)?;
    }
    progress.finish_and_clear();
    Ok((total_counts, drawing))
}

/// A drawn batch: its first profile, its profiles, the time their counts took to draw,
/// and the sum of their counts.
type Batch = (usize, Vec<DrawnProfile>, Duration, u64);

/// The orbit of a space-borne run with `[orbit]`.
pub fn orbit_of(lidar: &Lidar) -> Result<Option<crate::scene::orbit::Orbit>> {
    let cfg = &lidar.first().loaded.config;
    cfg.orbit
        .as_ref()
        .map(|o| {
            crate::scene::orbit::Orbit::from_config(o, cfg.platform.altitude_km * 1e3)
                .map_err(|reason| Error::config(lidar.first().loaded.file_label(), "orbit", reason))
        })
        .transpose()
}

/// One profile of every channel, channel-major, as the file stores it.
pub struct DrawnProfile {
    /// Recorded counts, channel-major.
    pub counts: Vec<u64>,
    components: Option<[Vec<u64>; 3]>,
    /// Sum of the shots' energy factors (the energy monitor's reading × M / E0).
    energy_sum: f64,
    /// The rows of the per-profile variables (a changing scene's truth: expected signal,
    /// background, recorded counts per shot, S/N, attenuated backscatter).
    pub values: Vec<Vec<f64>>,
    /// The columns the profile's shots saw and their shares (`profile_column`,
    /// `profile_column_weight`), padded to the file's slots; `None` in a static scene
    /// (its one column, [`STATIC_COLUMN`]).
    pub columns: Option<(Vec<i32>, Vec<f64>)>,
}

/// Index in [`DrawnProfile::values`] of a changing scene's expected recorded counts per shot.
pub const RECORDED_ROW: usize = 2;

/// Whether the scene of `lidar` changes along the track (or with the sun): a run of it
/// draws from a [`changing_scene`].
pub fn scene_changes(lidar: &Lidar) -> bool {
    let cfg = &lidar.first().loaded.config;
    let solar = cfg.background.model == crate::config::BackgroundModel::Solar;
    crate::scene::track::Track::is_changing(cfg) || solar
}

/// The scene model of a run whose scene changes along the track (`None` for one column
/// everywhere); refuses what this version does not draw in a changing scene.
pub fn changing_scene(
    lidar: &Lidar,
    seed: u64,
    profiles: usize,
    method: &mut ResolvedMethod,
    components: bool,
    energy: &RunEnergy,
) -> Result<Option<scene::SceneModel>> {
    if !scene_changes(lidar) {
        return Ok(None);
    }
    if components {
        return Err(Error::Unsupported(
            "--components is not available for a scene that changes along the track yet".into(),
        ));
    }
    let induced = |c: &&crate::scenario::Scenario| {
        let d = c.loaded.config.instrument.detector.as_ref();
        d.is_some_and(|d| d.signal_induced_noise.is_some() || d.afterpulsing.is_some())
    };
    if let Some(c) = lidar.channels.iter().find(induced) {
        return Err(Error::Unsupported(format!(
            "channel {} has signal-induced noise or afterpulsing, which this version does not \
             draw in a scene that changes along the track (or with the sun) yet",
            c.channel_name
        )));
    }
    if let Some(c) = lidar
        .channels
        .iter()
        .find(|c| c.instrument.analog.is_some())
    {
        return Err(Error::Unsupported(format!(
            "channel {} records analog, which this version does not draw in a scene that \
             changes along the track (or with the sun) yet; use photon counting there",
            c.channel_name
        )));
    }
    if matches!(method, ResolvedMethod::AggregateNormal { .. }) {
        *method = ResolvedMethod::Aggregate;
    }
    scene::SceneModel::new(lidar, seed, profiles as u64, *method, *energy).map(Some)
}

/// Draws profile `p` of a changing scene, every channel, with the profile's truth.
pub fn draw_scene_profile(
    sc: &scene::SceneModel,
    seed: u64,
    channels: usize,
    p: u64,
    n_bins: usize,
    energy: &RunEnergy,
) -> DrawnProfile {
    let (mut drawn, draw) = draw_scene_counts(sc, seed, channels, p, n_bins, energy);
    drawn.values = scene_profile_values(sc, n_bins, &draw);
    drawn
}

/// What the truth of a changing scene's profile needs of its draw: its runs (column,
/// shots) and each channel's mean background counts per shot.
pub struct SceneDraw {
    runs: Vec<(usize, u64)>,
    mean_backgrounds: Vec<f64>,
}

impl SceneDraw {
    /// Each channel's background counts per shot per bin, averaged over the profile's
    /// shots (the sunlight changes along the track).
    pub fn mean_backgrounds(&self) -> &[f64] {
        &self.mean_backgrounds
    }
}

/// Draws the counts of profile `p` of a changing scene, every channel (no truth yet:
/// [`scene_profile_values`]); also returns what the truth needs of the draw.
pub fn draw_scene_counts(
    sc: &scene::SceneModel,
    seed: u64,
    channels: usize,
    p: u64,
    n_bins: usize,
    energy: &RunEnergy,
) -> (DrawnProfile, SceneDraw) {
    let runs = sc.runs(p);
    let shots = runs.iter().map(|r| r.1).sum::<u64>();
    let energies = scene::ProfileEnergies::new(energy, p, shots);
    let mut counts = vec![0u64; channels * n_bins];
    let mut mean_backgrounds = Vec::with_capacity(channels);
    for (k, acc) in counts.chunks_mut(n_bins).enumerate() {
        let bkg = sc.run_backgrounds(k, p, &runs);
        sc.draw(k, channel_seed(seed, k), p, &runs, &energies, &bkg, acc);
        let total: f64 = runs.iter().zip(&bkg).map(|(r, b)| r.1 as f64 * b).sum();
        mean_backgrounds.push(total / shots as f64);
    }
    let drawn = DrawnProfile {
        counts,
        components: None,
        energy_sum: energies.run_sums(&runs).iter().sum(),
        values: Vec::new(),
        columns: Some(profile_columns(&runs, sc.column_slots)),
    };
    (
        drawn,
        SceneDraw {
            runs,
            mean_backgrounds,
        },
    )
}

/// The rows of profile `p`'s per-profile variables in a changing scene, channel-major:
/// expected signal, background, recorded counts, Eq. 4 S/N and attenuated backscatter
/// (what the profile's shots saw on average), from its [`SceneDraw`].
pub fn scene_profile_values(
    sc: &scene::SceneModel,
    n_bins: usize,
    draw: &SceneDraw,
) -> Vec<Vec<f64>> {
    let SceneDraw {
        runs,
        mean_backgrounds,
    } = draw;
    let shots = runs.iter().map(|r| r.1).sum::<u64>() as f64;
    let mut truth = sc.truth(runs);
    let dark = |k: usize| sc.expected[runs[0].0][k].dark;
    if sc.is_solar() {
        // an ideal detector records what arrives; a dead-time one its stationary rate per
        // bin (the transient at a sharp edge, O(τ/Δt), is not in this truth)
        for (k, recorded) in truth.recorded.chunks_mut(n_bins).enumerate() {
            let signal = &truth.signal[k * n_bins..(k + 1) * n_bins];
            for (r, s) in recorded.iter_mut().zip(signal) {
                let arriving = s + mean_backgrounds[k] + dark(k);
                *r = match &sc.dead[k] {
                    Some(d) => d.stationary_rate(arriving / d.bin_width_s) * d.bin_width_s,
                    None => arriving,
                };
            }
        }
    }
    let mut background = Vec::with_capacity(truth.signal.len());
    let mut snr = Vec::with_capacity(truth.signal.len());
    for (k, signal) in truth.signal.chunks(n_bins).enumerate() {
        let b = mean_backgrounds[k];
        background.extend(std::iter::repeat_n(b, n_bins));
        snr.extend(
            signal
                .iter()
                .map(|&s| crate::snr::eq4(s, b, dark(k), shots)),
        );
    }
    vec![
        truth.signal,
        background,
        truth.recorded,
        snr,
        truth.attenuated_backscatter,
    ]
}

/// Draws profile `p` of every channel's streams.
pub fn draw_profile(
    channels: &[Vec<(StreamSampler, u64)>],
    p: u64,
    shots: u64,
    n_bins: usize,
    components: bool,
    energy: &RunEnergy,
) -> DrawnProfile {
    let len = channels.len() * n_bins;
    let mut counts = vec![0u64; len];
    let mut parts: Option<[Vec<u64>; 3]> =
        components.then(|| std::array::from_fn(|_| vec![0; len]));
    for (k, streams) in channels.iter().enumerate() {
        let bins = k * n_bins..(k + 1) * n_bins;
        for (c, (sampler, stream_seed)) in streams.iter().enumerate() {
            match parts.as_mut() {
                // component c of channel k, added into the channel's counts too
                Some(parts) => {
                    let part = &mut parts[c][bins.clone()];
                    sampler.profile_counts(*stream_seed, p, shots, part);
                    let acc = &mut counts[bins.clone()];
                    acc.iter_mut().zip(part.iter()).for_each(|(a, x)| *a += x);
                }
                None => sampler.profile_counts(*stream_seed, p, shots, &mut counts[bins.clone()]),
            }
        }
    }
    let energy_seed = energy.seed.unwrap_or_default();
    DrawnProfile {
        counts,
        components: parts,
        energy_sum: energy.law.profile_sum(energy_seed, p, shots),
        values: Vec::new(),
        columns: None,
    }
}

impl DrawnProfile {
    /// Sum of the shots' energy factors (relative to the nominal energy).
    pub fn energy_sum(&self) -> f64 {
        self.energy_sum
    }
}

/// The columns of every profile of a static scene: its one column, all the shots.
pub const STATIC_COLUMN: (&[i32], &[f64]) = (&[0], &[1.0]);

/// The distinct columns of a profile's `runs` (column, shots) in the order first seen,
/// with the share of the shots that saw each, padded with (−1, 0) to `slots`.
pub fn profile_columns(runs: &[(usize, u64)], slots: usize) -> (Vec<i32>, Vec<f64>) {
    let shots: u64 = runs.iter().map(|r| r.1).sum();
    let mut columns: Vec<i32> = Vec::with_capacity(slots);
    let mut counts: Vec<u64> = Vec::with_capacity(slots);
    for &(col, n) in runs {
        let col = col as i32;
        match columns.iter().position(|&c| c == col) {
            Some(j) => counts[j] += n,
            None => {
                columns.push(col);
                counts.push(n);
            }
        }
    }
    let mut weights: Vec<f64> = counts.iter().map(|&n| n as f64 / shots as f64).collect();
    columns.resize(slots.max(columns.len()), -1);
    weights.resize(columns.len(), 0.0);
    (columns, weights)
}

/// Everything the raw file holds besides the profiles.
fn raw_file_spec(
    lidar: &Lidar,
    expected: &[ExpectedProfile],
    method: ResolvedMethod,
    values: &RunValues,
    energy: RunEnergy,
    opts: &RunOptions,
    scene: Option<&scene::SceneModel>,
) -> Result<RawFileSpec> {
    let RunValues {
        seed,
        profiles,
        components,
        tolerance,
        ..
    } = *values;
    let changing = scene.is_some();
    let first = lidar.first();
    let shots = first.shots_per_profile();
    let mut method_attributes = vec![];
    if let ResolvedMethod::AggregateNormal { threshold } = method {
        method_attributes.push((
            "normal_approximation_threshold".into(),
            AttrValue::F64(threshold),
        ));
        method_attributes.push((
            "tolerance_ks".into(),
            AttrValue::F64(tolerance.unwrap_or(f64::NAN)),
        ));
    }
    let run_info = RunInfo {
        seed,
        method: method.name(),
        method_attributes,
        command_line: &opts.command_line,
        config: values.stored_config(&first.loaded.resolved_toml)?,
    };
    // the brightest bin at the brightest pulse of the run sizes the counters (every
    // column of a changing scene, in full sunlight)
    let columns: Vec<&ExpectedProfile> = match scene {
        Some(sc) => sc.expected.iter().flatten().collect(),
        None => expected.iter().collect(),
    };
    let brightest_sky = scene.map_or(0.0, |sc| sc.brightest_background());
    let max_mean = columns
        .into_iter()
        .flat_map(|e| {
            e.signal
                .iter()
                .map(move |s| energy.envelope * s + e.background + brightest_sky + e.dark)
        })
        .fold(0.0f64, f64::max)
        * shots as f64;
    // an analog record's codes reach at most the ADC's full scale every shot
    let analog_max = lidar
        .channels
        .iter()
        .filter_map(|c| c.instrument.analog.as_ref())
        .map(|a| a.full_scale_code() as f64 * shots as f64)
        .fold(0.0f64, f64::max);
    let max_mean = max_mean.max(analog_max);
    let column_models: Vec<&[ExpectedProfile]> = match scene {
        Some(sc) => sc.expected.iter().map(Vec::as_slice).collect(),
        None => vec![expected],
    };
    Ok(RawFileSpec {
        n_bins: first.geometry.n_bins,
        n_profiles: profiles,
        first_profile: 0,
        channel_text: crate::output::raw_file::truth::channel_text(lidar),
        n_columns: column_models.len(),
        column_slots: scene.map_or(1, |sc| sc.column_slots),
        channels: lidar.channel_names(),
        count_width: CountWidth::for_max_count(max_mean)?,
        components,
        time_units: content::time_units(&first.loaded.config.acquisition.start_time)?,
        variables: content::variables(lidar, expected, &column_models, shots, changing)
            .into_iter()
            .chain(
                orbit_of(lidar)?
                    .is_some()
                    .then(content::geolocation_variables)
                    .into_iter()
                    .flatten(),
            )
            .collect(),
        profile_coordinates: match orbit_of(lidar)? {
            Some(_) => content::GEOLOCATION.iter().map(|s| s.to_string()).collect(),
            None => vec![],
        },
        root_attributes: content::root_attributes(first, &run_info)?,
    })
}

/// Memory a run's plan holds per bin and channel beyond the model: the raw file's
/// per-bin variables (the truth, the expectations), bytes. Measured: peak RSS of
/// `simulate --profiles 2` over `expect --csv` of scenario 1's 40 km window at
/// `bin_width_s` 2e-9 and 1e-9 (1.33e5 and 2.67e5 bins): 111 and 167 MB more, 418 bytes a
/// bin (plus 55 MB of buffers the run's own estimate counts), rounded up.
const PLAN_BYTES_PER_BIN: f64 = 500.0;

/// Bytes per stored count beyond the Poisson entropy: deflate after shuffle stores
/// ~1.6–1.75 × the entropy (measured: scenario 1 1.46 B against 0.90 B of entropy, the
/// CALIOP-like config 0.51 B against 0.29 B), rounded up.
const FILE_BYTES_PER_ENTROPY_BYTE: f64 = 1.8;
/// Bytes per profile of the per-profile variables (`profile`, `time`, `n_shots`, ...).
const FILE_BYTES_PER_PROFILE: f64 = 32.0;
/// Bytes of a raw file besides its profiles: metadata, attributes (the config), and the
/// per-bin variables at this many bytes per bin (measured: 39 kB for 20 profiles of
/// scenario 1's 134 bins).
const FILE_FIXED_BYTES: f64 = 64e3;
/// Bytes per bin of the per-bin variables (about 25 f64 per bin).
const FILE_BYTES_PER_BIN: f64 = 200.0;
/// Single-threaded cost of the model, the file and its writes per stored count, ns
/// (measured, `validation/reports/writer.md`: ~7 ns with u16 counts alone, the
/// CALIOP-like config; ~20 ns on scenario 1's small file; ~110 ns with the orbit's five
/// f64 truth values per count), rounded up for counts alone.
const FILE_NS_PER_COUNT: f64 = 40.0;

/// Estimated size of the raw file, bytes: per stored count the smaller of its width and
/// the compressed Poisson entropy of its mean.
pub fn estimated_file_bytes(totals: &[f64], shots: u64, profiles: usize, streams: usize) -> f64 {
    let max_mean = totals.iter().fold(0.0f64, |m, &l| m.max(l)) * shots as f64;
    let width = CountWidth::for_max_count(max_mean).map_or(8.0, |w| w.bytes() as f64);
    let per_profile: f64 = totals
        .iter()
        .map(|l| {
            let h = crate::resources::poisson_entropy_bits(l * shots as f64) / 8.0;
            width.min(FILE_BYTES_PER_ENTROPY_BYTE * h + 0.05)
        })
        .sum();
    FILE_FIXED_BYTES
        + FILE_BYTES_PER_BIN * totals.len() as f64
        + profiles as f64 * (per_profile * streams as f64 + FILE_BYTES_PER_PROFILE)
}

/// Refuses a run of `profiles` profiles of `planned` whose memory or file (`to_disk`)
/// cannot fit, and announces a long one (docs/outputs.md: sizes checked before work
/// starts).
fn check_sizes(
    lidar: &Lidar,
    planned: &RunPlan,
    profiles: usize,
    opts: &RunOptions,
    to_disk: bool,
) -> Result<()> {
    let (totals, method, components) = (&planned.totals, planned.method, planned.components);
    let shots = lidar.first().shots_per_profile();
    // the dead-time detector's cost per shot (ns), from its channels' means
    let dead_time_ns: f64 = lidar
        .channels
        .iter()
        .zip(&planned.expected)
        .filter(|_| method == ResolvedMethod::Shot)
        .filter_map(|(c, e)| Some(c.instrument.dead_time?.ns_per_shot(&e.total_per_shot())))
        .sum();
    let streams = if components { 4 } else { 1 };
    let bins = totals.len() as f64;
    // one bit per profile (written yet?), the batch of drawn rows, the samplers' tables,
    // the file writer's chunks (the count variables and, in a changing scene, five f64)
    let threads = rayon::current_num_threads().max(1);
    let writer =
        crate::output::raw_file::writer::buffer_bytes(bins as usize * 8, streams + 5, threads);
    let tables = streams as f64 * sampling::table_bytes_bound(bins as usize);
    let memory = profiles as f64 / 8.0 + 64.0 * bins * 8.0 * 2.0 * streams as f64 + tables + writer;
    crate::resources::require_memory(&format!("simulating {profiles} profiles"), memory)?;
    if to_disk {
        let file = estimated_file_bytes(totals, shots, profiles, streams);
        crate::resources::require_disk("-o", &opts.output, file)?;
    }
    // the afterpulses, drawn one at a time from each profile's recorded counts
    let afterpulse_ns: f64 = lidar
        .channels
        .iter()
        .zip(&planned.expected)
        .filter_map(|(c, e)| {
            let p = c.instrument.afterpulsing.as_ref()?.probability;
            Some(crate::resources::afterpulse_ns_per_shot(
                p,
                e.recorded.iter().sum(),
            ))
        })
        .sum();
    let draw_ns_per_profile = match method {
        ResolvedMethod::Shot => ShotSampler::new(totals).strategy().est_ns_per_shot * shots as f64,
        _ => bins * cost::AGGREGATE_LARGE_NS,
    } + (dead_time_ns + afterpulse_ns) * shots as f64;
    let ns = profiles as f64
        * (draw_ns_per_profile * streams.min(3) as f64 / threads as f64
            + bins * streams as f64 * FILE_NS_PER_COUNT);
    crate::resources::announce_duration(
        &format!("{profiles} profiles × {} bins", totals.len()),
        ns * 1e-9,
    );
    Ok(())
}

pub fn progress_bar(show: bool, profiles: usize) -> indicatif::ProgressBar {
    if !show {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(profiles as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {pos}/{len} profiles [{bar:40}] {elapsed} (eta {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stored_config_planned_again_stores_the_same_text() {
        // what `merge` relies on: the stored config, loaded and resolved with the run's
        // values (or no option), gives those values and the same text
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("configs")
            .join("paper")
            .join("scenario1.toml");
        let loaded = crate::loaded::load(&path, &[]).unwrap();
        let values = RunValues {
            profiles: 400,
            seed: u64::MAX,
            method: Method::Auto,
            components: true,
            tolerance: Some(1e-3),
        };
        let stored = values.stored_config(&loaded.resolved_toml).unwrap();
        assert!(
            stored.contains("seed = \"18446744073709551615\""),
            "{stored}"
        );
        let again = crate::loaded::load_str(&stored, &path, &[]).unwrap();
        assert_eq!(
            RunValues::resolve(&RunOptions::default(), &again.config),
            values
        );
        assert_eq!(values.stored_config(&again.resolved_toml).unwrap(), stored);
        // the file's own values, written in when no option is given
        let own = RunValues::resolve(&RunOptions::default(), &loaded.config);
        let written = own.stored_config(&loaded.resolved_toml).unwrap();
        assert!(written.contains("profiles = 100"), "{written}");
    }
}
