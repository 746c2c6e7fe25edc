//! A validation of a lidar (`lidarsim validate`) in three steps, so that a run can be cut
//! into shards: [`Validation::new`] sets it up from the config and options (the models
//! to compare with, the samplers to draw from), [`Validation::draw`] draws any range of
//! realizations into exact [`Sums`], and [`Validation::report`] judges the sums of all
//! of them. Sums add exactly, so the sums of the shards (`validate::partial`) give the
//! single run's report bit for bit.

use std::ops::Range;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

use serde::{Deserialize, Serialize};

use super::bins::{
    BinSums, ChannelBins, MIN_REALIZATIONS, SimulatorSource, accumulate, bin_reports,
};
use super::model::{afterpulsed_bin_models, analog_bin_models, bin_models, recorded_bin_models};
use super::report::Report;
use super::scene;
use super::statistics::verdicts;
use crate::config::Method;
use crate::error::{Error, Result};
use crate::laser::PulseEnergy;
use crate::scenario::Lidar;
use crate::simulate::{self, ResolvedMethod, RunEnergy, scene::SceneModel};

/// Options of `lidarsim validate`.
#[derive(Debug, Clone)]
pub struct ValidateOptions {
    /// Profiles to draw.
    pub realizations: usize,
    /// Method (`simulation.method` when None).
    pub method: Option<Method>,
    /// Seed (`simulation.seed` when None).
    pub seed: Option<u64>,
    /// Write the full report as JSON.
    pub json: Option<PathBuf>,
}

/// The sufficient statistics of a validation over some of its realizations: per bin,
/// sums that add exactly ([`super::exact`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "bins", rename_all = "snake_case")]
pub enum Sums {
    /// Profiles of one law (a scene that does not change along the track).
    Identical(Vec<BinSums>),
    /// Each profile of its own law ([`scene`]).
    Changing(Vec<scene::Sums>),
}

impl Sums {
    /// Adds `other`'s sums to these; refuses sums of another layout.
    pub fn add(&mut self, other: &Sums) -> std::result::Result<(), String> {
        match (self, other) {
            (Sums::Identical(a), Sums::Identical(b)) if a.len() == b.len() => {
                a.iter_mut().zip(b).for_each(|(x, y)| x.add(y));
                Ok(())
            }
            (Sums::Changing(a), Sums::Changing(b)) if a.len() == b.len() => {
                a.iter_mut().zip(b).for_each(|(x, y)| x.add(y));
                Ok(())
            }
            _ => Err("its sums are not laid out as this run's (kind or bins differ)".into()),
        }
    }
}

/// What a validation draws from and compares with.
enum Kind {
    /// Profiles of one law: the simulator's samplers and each bin's model.
    Identical {
        source: SimulatorSource,
        models: Vec<super::model::BinModel>,
        channels: Vec<ChannelBins>,
        totals: Vec<f64>,
        background_bins: usize,
        warning: Option<String>,
    },
    /// A scene that changes along the track: each profile against its own expectation.
    Changing {
        scene: Box<SceneModel>,
        energy: RunEnergy,
    },
}

/// A validation set up: seed, method, realizations and what to draw and compare.
pub struct Validation<'a> {
    lidar: &'a Lidar,
    /// The seed of the draws.
    pub seed: u64,
    /// The method used.
    pub method: ResolvedMethod,
    /// Realizations of the whole run.
    pub realizations: usize,
    altitudes: Vec<f64>,
    kind: Kind,
}

impl<'a> Validation<'a> {
    /// Sets up the validation of every channel of `lidar`; refuses what `validate`
    /// cannot check.
    pub fn new(lidar: &'a Lidar, opts: &ValidateOptions) -> Result<Self> {
        if opts.realizations < MIN_REALIZATIONS {
            return Err(Error::Unsupported(format!(
                "--realizations must be at least {MIN_REALIZATIONS}: fewer leave the verdicts' \
                 stated false-alarm rate (validation/README.md)"
            )));
        }
        let first = lidar.first();
        let cfg = &first.loaded.config;
        if cfg.instrument.energy_drift.is_some() {
            return Err(Error::config(
                first.loaded.file_label(),
                "instrument.energy_drift",
                "makes every profile's law its own, and validate checks profiles of one law: \
                 validate the scene without the drift",
            ));
        }
        let seed = opts.seed.unwrap_or(cfg.simulation.seed);
        let requested = opts.method.unwrap_or(cfg.simulation.method);
        let mut method = simulate::resolve_method(requested, lidar)?;
        simulate::check_detector(lidar, false)?;
        let energy = simulate::run_energy(lidar, seed, 0.0)?;
        let n = opts.realizations;
        let scene = simulate::changing_scene(lidar, seed, n, &mut method, false, &energy)?;
        let (altitudes, kind) = match scene {
            Some(sc) => changing(lidar, sc, energy)?,
            None => identical(lidar, method, energy, seed)?,
        };
        Ok(Validation {
            lidar,
            seed,
            method,
            realizations: n,
            altitudes,
            kind,
        })
    }

    /// Refuses a validation of `n` realizations whose memory or sums cannot fit, and
    /// announces a long one.
    pub fn check_sizes(&self, n: usize) -> Result<()> {
        match &self.kind {
            Kind::Identical {
                totals,
                models,
                channels,
                ..
            } => {
                let shots = self.lidar.first().shots_per_profile();
                // the dead-time detector's cost per shot (ns)
                let dead_time_ns: f64 = self
                    .lidar
                    .channels
                    .iter()
                    .zip(channels.iter())
                    .filter(|_| self.method == ResolvedMethod::Shot)
                    .filter_map(|(c, b)| {
                        Some(c.instrument.dead_time?.ns_per_shot(&totals[b.bins.clone()]))
                    })
                    .sum();
                check_sizes(totals, self.method, shots, n, dead_time_ns)?;
                check_exact_sums(models, channels, self.realizations)
            }
            Kind::Changing { .. } => Ok(()),
        }
    }

    /// Draws realizations `rows` into their sums.
    pub fn draw(&self, rows: Range<usize>) -> Sums {
        self.draw_until(rows, &AtomicBool::new(false))
    }

    /// [`Self::draw`], each realization not yet begun skipped (drawn as nothing) once
    /// `cancel` is set: then the sums are incomplete and are to be thrown away.
    fn draw_until(&self, rows: Range<usize>, cancel: &AtomicBool) -> Sums {
        let first = self.lidar.first();
        let go = || !cancel.load(Ordering::Relaxed);
        match &self.kind {
            Kind::Identical {
                source,
                models,
                channels,
                ..
            } => {
                let source = UntilCancelled { source, go: &go };
                Sums::Identical(accumulate(&source, rows, models.len(), channels))
            }
            Kind::Changing { scene: sc, energy } => {
                let n_bins = first.geometry.n_bins;
                let channels = self.lidar.channels.len();
                let shots = first.shots_per_profile() as f64;
                let draw = |p: u64| {
                    if !go() {
                        return (Vec::new(), Vec::new());
                    }
                    let d =
                        simulate::draw_scene_profile(sc, self.seed, channels, p, n_bins, energy);
                    let mu = d.values[simulate::RECORDED_ROW]
                        .iter()
                        .map(|x| x * shots)
                        .collect();
                    (d.counts, mu)
                };
                Sums::Changing(scene::accumulate(&draw, rows, self.altitudes.len()))
            }
        }
    }

    /// The report of the sums of every realization; refuses sums of another layout.
    pub fn report(&self, sums: &Sums) -> Result<Report> {
        let first = self.lidar.first();
        let n = self.realizations;
        let names = self.lidar.channel_names();
        let (bins, checks, background_bins, warning) = match (&self.kind, sums) {
            (
                Kind::Identical {
                    models,
                    channels,
                    background_bins,
                    warning,
                    ..
                },
                Sums::Identical(s),
            ) if s.len() == models.len() => {
                let bins = bin_reports(s, models, &self.altitudes, n, channels);
                let checks = verdicts(&bins);
                (bins, checks, *background_bins, warning.clone())
            }
            (Kind::Changing { .. }, Sums::Changing(s)) if s.len() == self.altitudes.len() => {
                let (bins, checks) = scene::reports(s, n, &names, &self.altitudes);
                (bins, checks, 0, None)
            }
            _ => {
                return Err(Error::Unsupported(
                    "the sums are not laid out as this validation's (kind or bins differ)".into(),
                ));
            }
        };
        Ok(Report {
            scenario: first.loaded.config.name.clone(),
            method: self.method.name().into(),
            seed: self.seed,
            realizations: n,
            shots_per_profile: first.shots_per_profile(),
            background_bins,
            channels: names,
            consistent: checks.iter().all(|c| c.pass),
            bins,
            checks,
            warning,
        })
    }
}

/// Runs the validation of every channel of a lidar.
pub fn run(lidar: &Lidar, opts: &ValidateOptions) -> Result<Report> {
    let v = Validation::new(lidar, opts)?;
    v.check_sizes(opts.realizations)?;
    v.report(&v.draw(0..opts.realizations))
}

/// A source whose realizations are drawn only while `go` says so (an empty profile
/// after: [`run_cancellable`] throws those sums away).
struct UntilCancelled<'a> {
    source: &'a dyn super::bins::RealizationSource,
    go: &'a (dyn Fn() -> bool + Sync),
}

impl super::bins::RealizationSource for UntilCancelled<'_> {
    fn draw(&self, p: u64, counts: &mut [u64]) {
        if (self.go)() {
            self.source.draw(p, counts);
        }
    }
}

/// Realizations drawn between two looks at the cancel flag of [`run_cancellable`] (the
/// blocks' sums added; within a block every realization looks at it before it starts).
const CANCEL_BLOCK: usize = 256;

/// [`run`], stopping with [`Error::Interrupted`] once `cancel` is set (the Python
/// module's Ctrl-C): the realizations under way finish, no other starts. The same
/// report as [`run`]: the blocks' sums add exactly ([`Sums::add`]).
pub fn run_cancellable(
    lidar: &Lidar,
    opts: &ValidateOptions,
    cancel: &AtomicBool,
) -> Result<Report> {
    let v = Validation::new(lidar, opts)?;
    v.check_sizes(opts.realizations)?;
    let n = opts.realizations;
    let mut sums: Option<Sums> = None;
    for start in (0..n).step_by(CANCEL_BLOCK) {
        let block = v.draw_until(start..(start + CANCEL_BLOCK).min(n), cancel);
        if cancel.load(Ordering::Relaxed) {
            return Err(Error::Interrupted);
        }
        match &mut sums {
            None => sums = Some(block),
            Some(all) => all.add(&block).map_err(Error::Unsupported)?,
        }
    }
    v.report(&sums.ok_or_else(|| Error::Unsupported("no realization to validate".into()))?)
}

/// Profiles of one law: the simulator's samplers, each channel's bins and models.
fn identical(
    lidar: &Lidar,
    method: ResolvedMethod,
    energy: RunEnergy,
    seed: u64,
) -> Result<(Vec<f64>, Kind)> {
    let first = lidar.first();
    let expected = lidar.expected()?;
    let shots = first.shots_per_profile();
    let laser = PulseEnergy::from_config(&first.loaded.config.instrument);
    let source = SimulatorSource::for_lidar(lidar, &expected, method, energy, seed);
    let mut models = Vec::new();
    let mut altitudes = Vec::new();
    let mut channels = Vec::new();
    for (c, e) in lidar.channels.iter().zip(&expected) {
        let offset = models.len();
        let recorded = match (&c.instrument.dead_time, &c.instrument.analog) {
            (Some(d), _) => recorded_bin_models(e, shots, d, &laser),
            (None, Some(a)) => analog_bin_models(e, shots, a, laser.jitter),
            (None, None) => bin_models(e, shots, laser.jitter),
        };
        models.extend(match &c.instrument.afterpulsing {
            Some(ap) => afterpulsed_bin_models(&recorded, ap, shots),
            None => recorded,
        });
        altitudes.extend_from_slice(&e.altitude_m);
        channels.push(ChannelBins {
            name: c.channel_name.clone(),
            bins: offset..models.len(),
            background: e
                .background_bin_indices
                .iter()
                .map(|i| i + offset)
                .collect(),
        });
    }
    let kind = Kind::Identical {
        source,
        models,
        channels,
        totals: expected.iter().flat_map(|e| e.total_per_shot()).collect(),
        background_bins: expected[0].background_bins,
        warning: lidar.run_notes(&expected),
    };
    Ok((altitudes, kind))
}

/// A scene that changes along the track: an ideal detector without jitter (this version).
fn changing(lidar: &Lidar, scene: SceneModel, energy: RunEnergy) -> Result<(Vec<f64>, Kind)> {
    if lidar
        .channels
        .iter()
        .any(|c| c.instrument.dead_time.is_some())
        || !energy.law.is_constant()
    {
        return Err(Error::Unsupported(
            "validate of a scene that changes along the track checks an ideal detector with a \
             constant pulse energy (this version): set instrument.detector.dead_time_s = 0 and \
             instrument.pulse_energy_jitter = 0"
                .into(),
        ));
    }
    let first = lidar.first();
    let n_bins = first.geometry.n_bins;
    let altitudes: Vec<f64> = (0..lidar.channels.len())
        .flat_map(|_| (0..n_bins).map(|i| first.geometry.bin_centre_altitude_m(i)))
        .collect();
    let kind = Kind::Changing {
        scene: Box::new(scene),
        energy,
    };
    Ok((altitudes, kind))
}

/// Memory held per bin beyond the scenario's model: the running sums and the report.
/// Measured: a 667,129-bin `validate --realizations 100` of scenario 1 peaks at 657 MB
/// resident, `expect` of the same config at 238 MB, so 630 B per bin; 800 keeps a margin
/// (issue 18: the 400 counted before let a 6.7e6-bin run pass the check and abort).
const BYTES_PER_BIN: f64 = 800.0;

/// Refuses a validation whose memory cannot fit and announces a long one; `totals` are
/// the per-shot means of every bin of every channel, `dead_time_ns` the dead-time
/// detector's cost per shot (`DeadTime::ns_per_shot`).
fn check_sizes(
    totals: &[f64],
    method: ResolvedMethod,
    shots: u64,
    n: usize,
    dead_time_ns: f64,
) -> Result<()> {
    let bins = totals.len() as f64;
    crate::resources::require_memory(
        &format!("validating {} bins", crate::error::compact(bins)),
        bins * BYTES_PER_BIN + (8 << 20) as f64 * 8.0,
    )?;
    let per_profile_ns = (match method {
        ResolvedMethod::Shot => {
            crate::sampling::ShotSampler::new(totals)
                .strategy()
                .est_ns_per_shot
                * shots as f64
        }
        _ => bins * 45.0,
    } + dead_time_ns * shots as f64)
        / rayon::current_num_threads().max(1) as f64
        + bins * 20.0;
    crate::resources::announce_duration(
        &format!("validating {n} realizations of {} bins", totals.len()),
        n as f64 * per_profile_ns * 1e-9,
    );
    Ok(())
}

/// Refuses a run whose exact sums could overflow 128 bits: `Σu²` over `n` realizations,
/// `u = n_b·c − B` bounded by `n_b` times a count far beyond any draw
/// (`κ1 + 20√κ1 + 64`, as [`crate::output::raw_file::CountWidth`] bounds counts).
fn check_exact_sums(
    models: &[super::model::BinModel],
    channels: &[ChannelBins],
    n: usize,
) -> Result<()> {
    let k1 = models.iter().map(|m| m.cumulants[0]).fold(0.0, f64::max);
    let count = k1 + 20.0 * k1.sqrt() + 64.0;
    let n_b = channels
        .iter()
        .map(|c| c.background.len())
        .max()
        .unwrap_or(0)
        .max(1) as f64;
    if n as f64 * (n_b * count).powi(2) >= 1e38 {
        return Err(Error::Unsupported(format!(
            "{n} realizations of up to {} counts per bin overflow validate's exact sums; \
             validate fewer realizations or shots per profile",
            crate::error::compact(count)
        )));
    }
    Ok(())
}
