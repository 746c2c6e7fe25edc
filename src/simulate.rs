//! The Monte Carlo run (`lidarsim simulate`, model.md §6): per-bin expectations from the
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

use crate::config::Method;
use crate::detector::{DeadTime, dead_time};
use crate::error::{Error, Result};
use crate::output::raw_file::content::{self, RunInfo};
use crate::output::raw_file::{AttrValue, CountWidth, ProfileRecord, RawFileSpec, RawFileWriter};
use crate::output::safe_file::{OutputId, Outputs};
use crate::sampling::approx;
use crate::sampling::jitter::JitteredShots;
use crate::sampling::{self, ShotSampler};
use crate::scenario::{ExpectedProfile, Scenario};

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
    if !aggregate_allowed {
        return ResolvedMethod::Shot;
    }
    let means: Vec<f64> = e
        .total_per_shot()
        .iter()
        .map(|l| l * shots as f64)
        .collect();
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
    let shot = ShotSampler::new(&e.total_per_shot())
        .strategy()
        .est_ns_per_shot
        * shots as f64;
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

/// What the scene needs drawn shot by shot; `None` when every shot has the same
/// expectations and the detector is linear, so that `aggregate` is exact.
pub fn per_shot_reason(scenario: &Scenario) -> Option<&'static str> {
    if scenario.instrument.dead_time.is_some() {
        return Some("detector dead time makes the recorded counts non-Poisson");
    }
    (scenario.instrument.pulse_energy_jitter > 0.0)
        .then_some("pulse-energy jitter varies the signal from shot to shot")
}

/// Resolves `auto`, and refuses `aggregate` where it would not be exact.
pub fn resolve_method(requested: Method, scenario: &Scenario) -> Result<ResolvedMethod> {
    match (requested, per_shot_reason(scenario)) {
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
    /// The command line, recorded in the file's `history`.
    pub command_line: String,
}

/// What a run did, for the closing summary.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// The file written.
    pub output: PathBuf,
    /// Profiles written.
    pub profiles: usize,
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
        write!(
            f,
            "Wrote {}: {} profiles × {} bins, {} shots per profile, {} counts in all; method {}, seed {}. \
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

/// The sampler of one stream of counts (the total, or one component), built once per run.
#[derive(Debug, Clone)]
pub enum StreamSampler {
    /// One Poisson(M·λ) draw per bin.
    Aggregate(Vec<f64>),
    /// Every shot drawn with fixed means.
    Shot(Box<ShotSampler>),
    /// Every shot drawn, the signal scaled by the shot's pulse energy.
    Jittered(Box<JitteredShots>),
    /// Aggregate with the normal approximation at and above a mean threshold.
    AggregateNormal(Vec<f64>, f64),
    /// Every shot drawn and recorded through the detector's dead time.
    DeadTimed(Box<ShotSampler>, DeadTime),
}

impl StreamSampler {
    /// Builds the sampler for per-shot means `signal` + `rest` (rest: background and dark).
    pub fn new(method: ResolvedMethod, signal: &[f64], rest: &[f64], jitter: f64) -> Self {
        let total = || {
            signal
                .iter()
                .zip(rest)
                .map(|(s, r)| s + r)
                .collect::<Vec<f64>>()
        };
        match method {
            ResolvedMethod::Aggregate => StreamSampler::Aggregate(total()),
            ResolvedMethod::AggregateNormal { threshold } => {
                StreamSampler::AggregateNormal(total(), threshold)
            }
            ResolvedMethod::Shot if jitter > 0.0 => {
                StreamSampler::Jittered(Box::new(JitteredShots::new(signal, rest, jitter)))
            }
            ResolvedMethod::Shot => StreamSampler::Shot(Box::new(ShotSampler::new(&total()))),
        }
    }

    /// The same sampler with the detector's dead time applied to every shot (a `Shot`
    /// sampler becomes `DeadTimed`; [`check_detector`] ensures the method is `shot`).
    pub fn through_detector(self, dead: Option<DeadTime>) -> Self {
        match (self, dead) {
            (StreamSampler::Shot(s), Some(d)) => StreamSampler::DeadTimed(s, d),
            (other, _) => other,
        }
    }

    /// Draws profile `profile` of `shots` shots into `acc`: a function of the arguments only,
    /// so any profile can be regenerated alone.
    pub fn profile_counts(&self, seed: u64, profile: u64, shots: u64, acc: &mut [u64]) {
        match self {
            StreamSampler::Aggregate(l) => {
                sampling::aggregate_profile(l, seed, profile, shots, acc)
            }
            StreamSampler::Shot(s) => sampling::shot_profile(s, seed, profile, shots, acc),
            StreamSampler::Jittered(j) => j.profile(seed, profile, shots, acc),
            StreamSampler::AggregateNormal(l, threshold) => {
                approx::aggregate_approx_profile(l, seed, profile, shots, *threshold, acc)
            }
            StreamSampler::DeadTimed(s, d) => {
                dead_time::recorded_profile(s, d, seed, profile, shots, acc)
            }
        }
    }
}

/// The streams of a run with their seeds: the total, or signal, background and dark apart.
fn stream_samplers(
    e: &ExpectedProfile,
    method: ResolvedMethod,
    jitter: f64,
    components: bool,
    seed: u64,
    dead: Option<DeadTime>,
) -> Vec<(StreamSampler, u64)> {
    let n = e.n_bins();
    let zeros = vec![0.0; n];
    if components {
        vec![
            (
                StreamSampler::new(method, &e.signal, &zeros, jitter),
                component_seed(seed, 0),
            ),
            (
                StreamSampler::new(method, &zeros, &vec![e.background; n], 0.0),
                component_seed(seed, 1),
            ),
            (
                StreamSampler::new(method, &zeros, &vec![e.dark; n], 0.0),
                component_seed(seed, 2),
            ),
        ]
    } else {
        let rest = vec![e.background + e.dark; n];
        let sampler = StreamSampler::new(method, &e.signal, &rest, jitter).through_detector(dead);
        vec![(sampler, seed)]
    }
}

/// What this version does not combine with dead time: jitter (a shot's energy and its
/// arrival times would both have to be drawn) and component counts (a recorded count is
/// not a sum of parts).
pub fn check_detector(scenario: &Scenario, components: bool) -> Result<()> {
    if scenario.instrument.dead_time.is_none() {
        return Ok(());
    }
    if scenario.instrument.pulse_energy_jitter > 0.0 {
        return Err(Error::Unsupported(
            "instrument.detector.dead_time_s with instrument.pulse_energy_jitter is not simulated yet; \
             set one of them to 0"
                .into(),
        ));
    }
    if components {
        return Err(Error::Unsupported(
            "--components is not available with dead time: a recorded count is not a sum of \
             signal, background and dark counts"
                .into(),
        ));
    }
    Ok(())
}

/// Runs the Monte Carlo of `scenario` and writes the raw file as output `raw` of
/// `outputs` (the command's output set, committed here when the file is complete).
pub fn run(
    scenario: &Scenario,
    opts: &RunOptions,
    outputs: Outputs,
    raw: OutputId,
) -> Result<RunSummary> {
    let start = Instant::now();
    let cfg = &scenario.loaded.config;
    let seed = opts.seed.unwrap_or(cfg.simulation.seed);
    let profiles = opts.profiles.unwrap_or(cfg.acquisition.profiles);
    if profiles == 0 {
        return Err(Error::Unsupported("--profiles must be at least 1".into()));
    }
    let components = opts.components.unwrap_or(cfg.simulation.components);
    let requested = opts.method.unwrap_or(cfg.simulation.method);
    let tolerance = opts.tolerance.or(cfg.simulation.tolerance);
    check_detector(scenario, components)?;
    let mut method = resolve_method(requested, scenario)?;
    let e = scenario.expected()?;
    let shots = scenario.shots_per_profile();
    if let Some(t) = tolerance {
        if requested != Method::Auto {
            return Err(Error::Unsupported(format!(
                "--tolerance chooses among methods: use it with --method auto, not {}",
                method.name()
            )));
        }
        method = fastest_within(t, &e, shots, method == ResolvedMethod::Aggregate);
    }
    let n_bins = e.n_bins();
    let max_mean = e.total_per_shot().iter().fold(0.0f64, |m, &l| m.max(l)) * shots as f64;
    check_sizes(&e, method, shots, profiles, components, opts)?;
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
    };
    let spec = RawFileSpec {
        n_bins,
        n_profiles: profiles,
        channels: vec![content::channel_name(
            scenario.instrument.wavelength_nm,
            scenario.instrument.channel,
        )],
        count_width: CountWidth::for_max_count(max_mean)?,
        components,
        time_units: content::time_units(&cfg.acquisition.start_time)?,
        variables: content::variables(scenario, &e, shots),
        root_attributes: content::root_attributes(scenario, &run_info)?,
    };
    let mut writer = RawFileWriter::create(outputs.temp_path(raw)?, &opts.output, &spec)?;

    let samplers = stream_samplers(
        &e,
        method,
        scenario.instrument.pulse_energy_jitter,
        components,
        seed,
        scenario.instrument.dead_time,
    );
    let profile_time_s = shots as f64 / scenario.instrument.rep_rate_hz;
    let progress = progress_bar(opts.progress, profiles);
    // batch size: bounded memory (at most 32 MiB of counts) and a lively progress bar
    let batch = (4 << 20) / (n_bins * samplers.len()).max(1);
    let batch = batch.clamp(1, 64);
    let mut total_counts = 0u64;
    let mut drawing = Duration::ZERO;
    for first in (0..profiles).step_by(batch) {
        let last = (first + batch).min(profiles);
        let draw_start = Instant::now();
        let drawn: Vec<Vec<Vec<u64>>> = (first..last)
            .into_par_iter()
            .map(|p| {
                samplers
                    .iter()
                    .map(|(sampler, stream_seed)| {
                        let mut acc = vec![0u64; n_bins];
                        sampler.profile_counts(*stream_seed, p as u64, shots, &mut acc);
                        acc
                    })
                    .collect()
            })
            .collect();
        drawing += draw_start.elapsed();
        for (k, streams) in drawn.iter().enumerate() {
            let summed: Vec<u64>;
            let total: &[u64] = if components {
                summed = (0..n_bins)
                    .map(|i| streams.iter().map(|s| s[i]).sum())
                    .collect();
                &summed
            } else {
                &streams[0]
            };
            total_counts += total.iter().sum::<u64>();
            writer.write_profile(&ProfileRecord {
                index: first + k,
                time_s: (first + k) as f64 * profile_time_s + 0.5 * profile_time_s,
                n_shots: shots,
                counts: total,
                components: components.then(|| [&streams[0][..], &streams[1][..], &streams[2][..]]),
            })?;
        }
        progress.inc((last - first) as u64);
    }
    writer.finish()?;
    outputs.commit()?;
    progress.finish_and_clear();
    Ok(RunSummary {
        output: opts.output.clone(),
        profiles,
        bins: n_bins,
        shots_per_profile: shots,
        total_counts,
        method,
        seed,
        elapsed: start.elapsed(),
        drawing,
        warning: scenario.linear_range_warning(&e),
    })
}

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
/// (measured: 0.06–0.14 µs on scenario 1 and the CALIOP-like config).
const FILE_NS_PER_COUNT: f64 = 150.0;

/// Estimated size of the raw file, bytes: per stored count the smaller of its width and
/// the compressed Poisson entropy of its mean.
pub fn estimated_file_bytes(
    e: &ExpectedProfile,
    shots: u64,
    profiles: usize,
    streams: usize,
) -> f64 {
    let max_mean = e.total_per_shot().iter().fold(0.0f64, |m, &l| m.max(l)) * shots as f64;
    let width = CountWidth::for_max_count(max_mean).map_or(8.0, |w| w.bytes() as f64);
    let per_profile: f64 = e
        .total_per_shot()
        .iter()
        .map(|l| {
            let h = crate::resources::poisson_entropy_bits(l * shots as f64) / 8.0;
            width.min(FILE_BYTES_PER_ENTROPY_BYTE * h + 0.05)
        })
        .sum();
    FILE_FIXED_BYTES
        + FILE_BYTES_PER_BIN * e.n_bins() as f64
        + profiles as f64 * (per_profile * streams as f64 + FILE_BYTES_PER_PROFILE)
}

/// Refuses a run whose memory or file cannot fit, and announces a long one
/// (interface.md: sizes checked before work starts).
fn check_sizes(
    e: &ExpectedProfile,
    method: ResolvedMethod,
    shots: u64,
    profiles: usize,
    components: bool,
    opts: &RunOptions,
) -> Result<()> {
    let streams = if components { 4 } else { 1 };
    let bins = e.n_bins() as f64;
    // one bit per profile (written yet?), the batch of drawn rows, the samplers' tables
    let memory = profiles as f64 / 8.0 + 64.0 * bins * 8.0 * 2.0 * streams as f64 + 64.0 * bins;
    crate::resources::require_memory(&format!("simulating {profiles} profiles"), memory)?;
    let file = estimated_file_bytes(e, shots, profiles, streams);
    crate::resources::require_disk("-o", &opts.output, file)?;
    let draw_ns_per_profile = match method {
        ResolvedMethod::Shot => {
            ShotSampler::new(&e.total_per_shot())
                .strategy()
                .est_ns_per_shot
                * shots as f64
        }
        _ => bins * cost::AGGREGATE_LARGE_NS,
    };
    let threads = rayon::current_num_threads().max(1) as f64;
    let ns = profiles as f64
        * (draw_ns_per_profile * streams.min(3) as f64 / threads
            + bins * streams as f64 * FILE_NS_PER_COUNT);
    crate::resources::announce_duration(
        &format!("{profiles} profiles × {} bins", e.n_bins()),
        ns * 1e-9,
    );
    Ok(())
}

fn progress_bar(show: bool, profiles: usize) -> indicatif::ProgressBar {
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
