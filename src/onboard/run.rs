//! `lidarsim onboard`: the run's shots drawn one by one (the shot path, dead time and a
//! changing scene included), summed onboard by every scheme given, the first scheme's
//! product written, and the report of every scheme side by side; or, with `--shard K/N`,
//! the shots of one shard ([`super::shard`]), its product shard and the partial of its
//! report ([`super::partial`]).

use std::ops::Range;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::report::{self, ReportInput, SchemeSums, averaging_bias};
use super::shard::{FRAME_ATTRIBUTE, frame_shots, region_profiles, shard_shots_of};
use super::truth::{ProfileRows, ShotTruth};
use super::{Averager, RegionLayout, Scheme};
use crate::config::Method;
use crate::error::{Error, Result};
use crate::output::product::{ProductHeader, ProductWriter, ProfileRow, RegionSpec};
use crate::output::raw_file::AttrValue;
use crate::output::raw_file::content::PRODUCT_ATTRIBUTE;
use crate::safe_file::{OutputId, Outputs, Stream};
use crate::scenario::{ExpectedProfile, Lidar};
use crate::shard::{SHARD_ATTRIBUTES, Shard, fingerprint_with};
use crate::simulate;

/// Options of `lidarsim onboard`.
#[derive(Debug, Clone, Default)]
pub struct OnboardOptions {
    /// `--scheme`, at least one: the first one's product is written.
    pub schemes: Vec<String>,
    /// The product file.
    pub output: PathBuf,
    /// The report CSV (`-` for stdout).
    pub report: Option<PathBuf>,
    /// The native shot-level raw file of the same draw (one shot per profile).
    pub raw: Option<PathBuf>,
    /// Seed (`simulation.seed` when None).
    pub seed: Option<u64>,
    /// Bits per downlinked count, for the data rate.
    pub word_bits: u32,
    /// Draw this shard of the run only (`--shard K/N`).
    pub shard: Option<Shard>,
    /// With `shard`: the partial of the report (`--partial`, JSON).
    pub partial: Option<PathBuf>,
    /// The command line, recorded in the product's `history` (as
    /// [`crate::output::raw_file::content::history_command_omitting`] gives it, with
    /// [`crate::output::raw_file::content::PRODUCT_HISTORY_OMITS`]).
    pub command_line: String,
}

/// The method of every onboard run: shot by shot.
pub const METHOD: &str = "shot";

/// The native run that every scheme averages: one shot per native profile.
pub struct NativeRun {
    /// The lidar of the native run (`accumulation_time_s` one shot, `profiles` the shots).
    pub lidar: Lidar,
    /// Seed of the counts.
    pub seed: u64,
    /// Shots of the run, T.
    pub shots: u64,
    /// Shots per second.
    pub rep_rate_hz: f64,
    /// Every scheme given, the first one's product written.
    pub schemes: Vec<Scheme>,
    /// Their regions on the native grid.
    pub layouts: Vec<Vec<RegionLayout>>,
    /// Every channel's per-shot expectations (the scene's first column).
    pub expected: Vec<ExpectedProfile>,
    /// Whether the scene changes along the track.
    pub scene_changes: bool,
}

impl NativeRun {
    /// The native run of `config` with `overrides`: `acquisition.profiles` profiles of
    /// the config's shots each, drawn as single shots, with `seed` (`--seed`, else
    /// `simulation.seed`). The native config (the product's `config`) holds the run's
    /// shots and seed, so that running `onboard` on it again with no `--seed` draws the
    /// same shots.
    pub fn load(
        config: &Path,
        overrides: &[String],
        seed: Option<u64>,
        schemes: &[String],
    ) -> Result<NativeRun> {
        let nominal = Lidar::load(config, overrides)?;
        let first = nominal.first();
        let fl = first.instrument.rep_rate_hz;
        let total = first.shots_per_profile() * first.loaded.config.acquisition.profiles as u64;
        let mut native = overrides.to_vec();
        native.push(format!("acquisition.accumulation_time_s={}", 1.0 / fl));
        native.push(format!("acquisition.profiles={total}"));
        let seed = seed.unwrap_or(first.loaded.config.simulation.seed);
        // as text, parsed as `--set` parses it: a seed beyond a TOML integer becomes the
        // string of its digits, as `config::seed_value` writes it
        native.push(format!("simulation.seed={seed}"));
        let lidar = Lidar::load(config, &native)?;
        let schemes = schemes
            .iter()
            .map(|s| Scheme::parse(s))
            .collect::<Result<_>>()?;
        NativeRun::new(lidar, seed, schemes)
    }

    /// The run of a native `lidar` (as [`NativeRun::load`] makes it, or from a stored
    /// config) with `schemes`.
    pub fn new(lidar: Lidar, seed: u64, schemes: Vec<Scheme>) -> Result<NativeRun> {
        let sc = lidar.first();
        let g = &sc.geometry;
        let native_vertical = g.bin_range_m * g.local_cos_at(0.0);
        let wavelengths: Vec<f64> = lidar
            .channels
            .iter()
            .map(|c| c.instrument.wavelength_nm)
            .collect();
        let altitude = |i| g.bin_centre_altitude_m(i);
        let layouts = schemes
            .iter()
            .map(|s| s.channel_layout(&wavelengths, g.n_bins, &altitude, native_vertical))
            .collect::<Result<_>>()?;
        Ok(NativeRun {
            seed,
            shots: sc.loaded.config.acquisition.profiles as u64,
            rep_rate_hz: sc.instrument.rep_rate_hz,
            expected: lidar.expected()?,
            scene_changes: simulate::scene_changes(&lidar),
            schemes,
            layouts,
            lidar,
        })
    }

    /// Every file the run reads: its config, the files the config names and the scheme
    /// files; no output may replace one.
    pub fn files_read(&self) -> Vec<PathBuf> {
        let scheme_files = self.schemes.iter().filter_map(|s| s.file.clone());
        let mut files = self.lidar.first().loaded.files_read();
        files.extend(scheme_files);
        files
    }

    /// Shots of a frame: the least common multiple of every region's shots, over every
    /// scheme (None beyond 64 bits).
    pub fn frame_shots(&self) -> Option<u64> {
        frame_shots(self.layouts.iter().flatten())
    }

    /// The identity of the run (`run_id` of its product shards and partials): the
    /// lidarsim version, the resolved config and its path, the seed, method, schemes,
    /// word size and shots, and the first channel's per-shot model that the report uses.
    pub fn run_id(&self, word_bits: u32) -> String {
        let loaded = &self.lidar.first().loaded;
        let schemes = serde_json::to_string(&self.schemes).unwrap_or_default();
        let e = &self.expected[0];
        let model: Vec<f64> = e
            .signal
            .iter()
            .copied()
            .chain([e.background, e.dark])
            .collect();
        fingerprint_with(
            &[
                &source(),
                &loaded.resolved_toml,
                &loaded.path.display().to_string(),
                &self.seed.to_string(),
                METHOD,
                &schemes,
                &word_bits.to_string(),
                &self.shots.to_string(),
            ],
            &model,
        )
    }

    /// The shots of `shard` (all of them without one).
    pub fn shots_of(&self, shard: Option<Shard>) -> Result<Range<u64>> {
        match shard {
            Some(s) => shard_shots_of(s, self.shots, self.frame_shots()),
            None => Ok(0..self.shots),
        }
    }

    /// The product's root: its attributes (and a shard's, for `shots` of `shard`), with
    /// `command` in `history`.
    fn header(
        &self,
        shard: Option<(Shard, &Range<u64>)>,
        word_bits: u32,
        command: &str,
    ) -> Result<ProductHeader> {
        let sc = self.lidar.first();
        let created = crate::output::raw_file::content::creation_time()?;
        let mut attributes = product_attributes(
            &ProductIdentity {
                scheme: self.schemes[0].name.clone(),
                source: source(),
                config: sc.loaded.resolved_toml.clone(),
                seed: self.seed,
            },
            &format!("{created} {command}"),
            &created,
        );
        if let Some((s, shots)) = shard {
            let values = [
                AttrValue::U64(s.index as u64),
                AttrValue::U64(s.count as u64),
                AttrValue::U64(shots.start),
                AttrValue::U64(self.shots),
                AttrValue::Str(self.run_id(word_bits)),
                AttrValue::U64(self.frame_shots().unwrap_or(0)),
            ];
            let names = SHARD_ATTRIBUTES.iter().chain([&FRAME_ATTRIBUTE]);
            attributes.extend(names.map(|n| n.to_string()).zip(values));
        }
        Ok(ProductHeader {
            channels: self.lidar.channel_names(),
            time_units: crate::output::raw_file::content::time_units(
                &sc.loaded.config.acquisition.start_time,
            )?,
            attributes,
        })
    }

    /// The first scheme's regions within `shots`: profiles, channels, coordinates,
    /// bounds and the truth of the scene's `columns` (per column, per channel).
    fn region_specs(
        &self,
        shots: &Range<u64>,
        columns: &[&[ExpectedProfile]],
    ) -> Result<Vec<RegionSpec>> {
        let g = &self.lidar.first().geometry;
        let e = &self.expected[0];
        let names = self.lidar.channel_names();
        let geolocation = simulate::orbit_of(&self.lidar)?.is_some();
        self.layouts[0]
            .iter()
            .map(|r| {
                let profiles = region_profiles(r, shots);
                let altitude_m = (0..r.bins)
                    .map(|j| {
                        let bins = r.first_bin + j * r.merge..r.first_bin + (j + 1) * r.merge;
                        bins.clone().map(|i| e.altitude_m[i]).sum::<f64>() / r.merge as f64
                    })
                    .collect();
                let bounds = match &r.region {
                    Some(reg) => (reg.bottom_km, reg.top_km, reg.vertical_resolution_m),
                    None => (
                        g.bin_centre_altitude_m(g.n_bins - 1) / 1e3,
                        g.bin_centre_altitude_m(0) / 1e3,
                        g.bin_range_m * g.cos_angle,
                    ),
                };
                Ok(RegionSpec {
                    truth: super::truth::region_truth(&self.lidar, columns, r, geolocation)?,
                    first_profile: profiles.start,
                    profiles: profiles.len(),
                    channels: r
                        .channel_indices(names.len())
                        .iter()
                        .map(|&c| names[c].clone())
                        .collect(),
                    altitude_m,
                    shots: r.shots,
                    merge: u32::try_from(r.merge).unwrap_or(u32::MAX),
                    bounds,
                })
            })
            .collect()
    }

    /// What the report is made of, with every scheme's `sums`.
    pub fn report_input<'a>(&'a self, sums: &'a [SchemeSums], word_bits: u32) -> ReportInput<'a> {
        ReportInput {
            scene_changes: self.scene_changes,
            schemes: self
                .schemes
                .iter()
                .zip(&self.layouts)
                .zip(sums)
                .map(|((s, l), x)| (s, l.as_slice(), x))
                .collect(),
            expected: &self.expected,
            rep_rate_hz: self.rep_rate_hz,
            channels: self.lidar.channels.len(),
            word_bits,
        }
    }
}

/// `lidarsim <version>`.
pub fn source() -> String {
    format!("lidarsim {}", env!("CARGO_PKG_VERSION"))
}

/// What identifies a product's run in its root attributes.
#[derive(Debug, Clone, PartialEq)]
pub struct ProductIdentity {
    /// The scheme written.
    pub scheme: String,
    /// `lidarsim <version>`.
    pub source: String,
    /// The resolved config of the native run.
    pub config: String,
    /// The seed of the counts.
    pub seed: u64,
}

/// The product's root attributes (docs/file-format.md), in order: `Conventions`,
/// `title`, `source`, `history`, `date_created`, `config`, [`PRODUCT_ATTRIBUTE`],
/// `scheme`, `seed`.
pub fn product_attributes(
    id: &ProductIdentity,
    history: &str,
    created: &str,
) -> Vec<(String, AttrValue)> {
    let text = |k: &str, v: &str| (k.to_string(), AttrValue::Str(v.to_string()));
    vec![
        text("Conventions", crate::output::raw_file::CONVENTIONS),
        text(
            "title",
            &format!("lidarsim onboard product, scheme {}", id.scheme),
        ),
        text("source", &id.source),
        text("history", history),
        text("date_created", created),
        text("config", &id.config),
        text(PRODUCT_ATTRIBUTE, "onboard"),
        text("scheme", &id.scheme),
        ("seed".into(), AttrValue::U64(id.seed)),
    ]
}

/// Profile-centre time of profile `j` of a region of `shots` shots, s since the start.
pub fn profile_time(j: usize, shots: u32, rep_rate_hz: f64) -> f64 {
    (j as f64 + 0.5) * f64::from(shots) / rep_rate_hz
}

/// The draw of the native shots: the samplers, or the changing scene.
struct Draw {
    seed: u64,
    energy: simulate::RunEnergy,
    scene: Option<simulate::scene::SceneModel>,
    samplers: Vec<Vec<(simulate::StreamSampler, u64)>>,
    channels: usize,
    n_bins: usize,
    /// Per channel: the static scene's background and dark counts per native bin.
    rest: Vec<(f64, f64)>,
}

impl Draw {
    /// The draw of `native`'s shots (the whole run's model, whatever the shard).
    fn new(native: &NativeRun) -> Result<Draw> {
        let lidar = &native.lidar;
        let seed = native.seed;
        let mut method = simulate::resolve_method(Method::Shot, lidar)?;
        let duration = native.shots as f64 / native.rep_rate_hz;
        let energy = simulate::run_energy(lidar, seed, duration)?;
        let profiles = native.shots as usize;
        let scene = simulate::changing_scene(lidar, seed, profiles, &mut method, false, &energy)?;
        let samplers = lidar
            .channels
            .iter()
            .zip(&native.expected)
            .enumerate()
            .map(|(k, (c, e))| {
                let seed = simulate::channel_seed(seed, lidar.photon_source(k));
                simulate::stream_samplers(e, method, energy, false, seed, &c.instrument)
            })
            .collect();
        Ok(Draw {
            seed,
            energy,
            scene,
            samplers,
            channels: lidar.channels.len(),
            n_bins: lidar.first().geometry.n_bins,
            rest: native
                .expected
                .iter()
                .map(|e| (e.background, e.dark))
                .collect(),
        })
    }

    /// The scene's columns, each with every channel's model (one in a static scene).
    fn columns<'a>(&'a self, native: &'a NativeRun) -> Vec<&'a [ExpectedProfile]> {
        match &self.scene {
            Some(s) => s.expected.iter().map(Vec::as_slice).collect(),
            None => vec![&native.expected],
        }
    }

    /// The native counts of shot `p`, every channel (channel-major), and what it saw.
    fn shot(&self, p: u64) -> (Vec<u64>, ShotTruth) {
        let (seed, channels, n_bins, energy) =
            (self.seed, self.channels, self.n_bins, &self.energy);
        match &self.scene {
            Some(s) => {
                let (drawn, draw) =
                    simulate::draw_scene_counts(s, seed, channels, p, n_bins, energy);
                let column = s.column_of_shot(p);
                let truth = ShotTruth {
                    column,
                    background: draw.mean_backgrounds().to_vec(),
                    dark: s.expected[column].iter().map(|e| e.dark).collect(),
                    energy: drawn.energy_sum(),
                };
                (drawn.counts, truth)
            }
            None => {
                let drawn = simulate::draw_profile(&self.samplers, p, 1, n_bins, false, energy);
                let truth = ShotTruth {
                    column: 0,
                    background: self.rest.iter().map(|r| r.0).collect(),
                    dark: self.rest.iter().map(|r| r.1).collect(),
                    energy: drawn.energy_sum(),
                };
                (drawn.counts, truth)
            }
        }
    }

    /// What shot `p` saw (every channel's expectations in its column), in a changing
    /// scene.
    fn truth(&self, p: u64) -> Option<&[ExpectedProfile]> {
        let s = self.scene.as_ref()?;
        Some(&s.expected[s.column_of_shot(p)])
    }
}

/// One scheme's averaging and the sums of its report.
struct SchemeRun {
    averager: Averager,
    sums: SchemeSums,
    /// Per region: the running `(Σ s, Σ ln s)` of the expected signal per merged bin over
    /// the pending profile's shots, and those shots.
    truth: Vec<(Vec<(f64, f64)>, u32)>,
}

impl SchemeRun {
    fn new(regions: &[RegionLayout], channels: usize, n_bins: usize) -> Self {
        SchemeRun {
            averager: Averager::with_channels(regions.to_vec(), channels, n_bins),
            sums: SchemeSums::new(regions),
            truth: regions
                .iter()
                .map(|r| (vec![(0.0, 0.0); r.bins], 0))
                .collect(),
        }
    }

    /// Adds one shot's expected signal (each region's first channel, per native bin) to
    /// the truth sums, closing each region's profile after its shots with its averaging
    /// biases.
    fn add_truth(&mut self, truth: &[ExpectedProfile]) {
        for (k, r) in self.averager.regions().iter().enumerate() {
            let signal = &truth[r.first_channel()].signal;
            let (sums, shots) = &mut self.truth[k];
            for (j, s) in sums.iter_mut().enumerate() {
                let bins = r.first_bin + j * r.merge..r.first_bin + (j + 1) * r.merge;
                let x: f64 = signal[bins].iter().sum();
                *s = (s.0 + x, s.1 + if x > 0.0 { x.ln() } else { f64::NAN });
            }
            *shots += 1;
            if *shots == r.shots {
                for (acc, &(a, b)) in self.sums.regions[k].iter_mut().zip(sums.iter()) {
                    let bias = averaging_bias(a, b, *shots);
                    if bias.is_finite() {
                        acc.bias.add(bias);
                        acc.biased += 1;
                    }
                }
                sums.iter_mut().for_each(|s| *s = (0.0, 0.0));
                *shots = 0;
            }
        }
    }

    /// Adds one shot (its native counts, and its true signal in a changing scene);
    /// `emit(region, sums)` receives every downlinked profile it completes.
    fn add_shot(
        &mut self,
        native: &[u64],
        truth: Option<&[ExpectedProfile]>,
        mut emit: impl FnMut(usize, &[u64]) -> Result<()>,
    ) -> Result<()> {
        if let Some(truth) = truth {
            self.add_truth(truth);
        }
        let SchemeRun { averager, sums, .. } = self;
        let mut emitted = Ok(());
        averager.add_shot(native, |k, downlinked| {
            for (s, &c) in sums.regions[k].iter_mut().zip(downlinked) {
                s.add_count(c);
            }
            if emitted.is_ok() {
                emitted = emit(k, downlinked);
            }
        });
        emitted
    }
}

/// Draws `shots` in batches (in parallel, then in order) and adds each to every scheme;
/// the first scheme's downlinked profiles go to `writer` with their `rows`.
fn draw_shots(
    draw: &Draw,
    shots: Range<u64>,
    runs: &mut [SchemeRun],
    rows: &mut ProfileRows,
    writer: &mut ProductWriter,
) -> Result<()> {
    let batch = ((4 << 20) / (draw.n_bins * draw.channels).max(1)).clamp(1, 4096) as u64;
    for start in shots.clone().step_by(batch as usize) {
        let end = (start + batch).min(shots.end);
        let drawn: Vec<(Vec<u64>, ShotTruth)> =
            (start..end).into_par_iter().map(|p| draw.shot(p)).collect();
        for (shot, (native, seen)) in (start..end).zip(&drawn) {
            let truth = draw.truth(shot);
            rows.add_shot(seen);
            for (i, r) in runs.iter_mut().enumerate() {
                r.add_shot(native, truth, |k, sums| match i {
                    0 => {
                        let (values, columns) = rows.take(k);
                        let row = ProfileRow {
                            counts: sums,
                            values: &values,
                            columns: &columns,
                        };
                        writer.write(k, row)
                    }
                    _ => Ok(()),
                })?;
            }
        }
    }
    Ok(())
}

/// Refuses a draw whose memory cannot fit (issue 18: checked before the work): the
/// samplers' tables per channel, per scheme the pending sums (`u64` per native bin and
/// channel) and truth sums (two `f64` per bin) and its report sums, and the batch of
/// drawn shots (4 Mi counts, twice: the batch and its collection).
fn check_memory(native: &NativeRun, schemes: usize) -> Result<()> {
    let first = native.lidar.first();
    let (bins, channels) = (
        first.geometry.n_bins as f64,
        native.lidar.channels.len() as f64,
    );
    let bytes = channels * crate::sampling::table_bytes_bound(first.geometry.n_bins)
        + schemes as f64 * bins * (8.0 * channels + 16.0 + 64.0)
        + 2.0 * 8.0 * (4u64 << 20).max((bins * channels) as u64) as f64;
    let channels = match native.lidar.channels.len() {
        1 => "1 channel".to_string(),
        n => format!("{n} channels"),
    };
    crate::resources::require_memory(
        &format!(
            "the onboard draw of {} bins in {channels}",
            crate::error::compact(bins)
        ),
        bytes,
    )
}

/// Refuses a product whose truth cannot fit: per region, 20 f64 per column, channel and
/// region bin (the truth of every column, built once).
fn check_truth_memory(native: &NativeRun, columns: usize) -> Result<()> {
    let channels = native.lidar.channels.len();
    let bins: usize = native.layouts[0]
        .iter()
        .map(|r| r.bins * r.channel_indices(channels).len())
        .sum();
    crate::resources::require_memory(
        &format!("the product's truth of {columns} columns of {bins} bins"),
        columns as f64 * bins as f64 * 20.0 * 8.0 * 2.0,
    )
}

/// Refuses options that do not go together (one line each).
fn check_options(opts: &OnboardOptions) -> Result<()> {
    let refuse = |why: &str| Err(Error::Unsupported(why.into()));
    if opts.schemes.is_empty() {
        return Err(no_scheme());
    }
    match opts.shard {
        Some(_) if opts.report.is_some() => refuse(
            "--report needs the whole run: with --shard write --partial PART.json, then \
             `lidarsim onboard --combine PART.json ... --report PATH`",
        ),
        Some(_) if opts.raw.is_some() => refuse(
            "--raw is not written with --shard (a product shard cuts at whole frames, not \
             as `simulate --shard`); run `simulate --shard` for the raw shards",
        ),
        None if opts.partial.is_some() => refuse("--partial goes with --shard K/N"),
        _ => Ok(()),
    }
}

/// Draws `shots` of `native` into the first scheme's product, written as output
/// `product` of `outputs`, and returns every scheme's report sums.
fn write_product(
    native: &NativeRun,
    shots: &Range<u64>,
    opts: &OnboardOptions,
    outputs: &Outputs,
    product: OutputId,
) -> Result<Vec<SchemeSums>> {
    check_memory(native, native.layouts.len())?;
    let draw = Draw::new(native)?;
    let header = native.header(
        opts.shard.map(|s| (s, shots)),
        opts.word_bits,
        &opts.command_line,
    )?;
    let columns = draw.columns(native);
    check_truth_memory(native, columns.len())?;
    let specs = native.region_specs(shots, &columns)?;
    let mut rows = ProfileRows::new(
        native.layouts[0]
            .iter()
            .zip(&specs)
            .map(|(r, s)| (r.clone(), s.truth.slots))
            .collect(),
        native.lidar.channels.len(),
        specs.iter().map(|s| s.first_profile).collect(),
        simulate::orbit_of(&native.lidar)?,
        native.rep_rate_hz,
        native
            .lidar
            .channels
            .iter()
            .map(|c| c.loaded.config.instrument.pulse_energy_j)
            .collect(),
    );
    let fl = native.rep_rate_hz;
    let mut times = |k: usize, rows: Range<usize>| {
        let r = &specs[k];
        Ok(rows
            .map(|i| profile_time(r.first_profile + i, r.shots, fl))
            .collect())
    };
    let path = outputs.temp_path(product)?;
    let mut writer = ProductWriter::create(path, &opts.output, &header, &specs, &mut times)?;
    let mut runs: Vec<SchemeRun> = native
        .layouts
        .iter()
        .map(|l| SchemeRun::new(l, draw.channels, draw.n_bins))
        .collect();
    draw_shots(&draw, shots.clone(), &mut runs, &mut rows, &mut writer)?;
    writer.finish()?;
    Ok(runs.into_iter().map(|r| r.sums).collect())
}

/// Commits `outputs`, with `--raw` (output `raw`) the native raw file of the same draw
/// first (counts depend on the seed and shot only), written as `simulate` writes it:
/// that run commits every output together.
fn commit_with_raw(
    native: &NativeRun,
    outputs: Outputs,
    raw: Option<(OutputId, &Path)>,
) -> Result<()> {
    let Some((id, path)) = raw else {
        return outputs.commit();
    };
    let raw_opts = simulate::RunOptions {
        output: path.to_path_buf(),
        seed: Some(native.seed),
        profiles: Some(native.shots as usize),
        method: Some(Method::Shot),
        command_line: crate::output::raw_file::content::history_command(std::env::args()),
        ..Default::default()
    };
    simulate::run(&native.lidar, &raw_opts, outputs, id).map(|_| ())
}

/// Runs the onboard simulation of `config` (with `opts.shard`, one shard of it).
pub fn run(config: &Path, overrides: &[String], opts: &OnboardOptions) -> Result<()> {
    check_options(opts)?;
    let native = NativeRun::load(config, overrides, opts.seed, &opts.schemes)?;
    let shots = native.shots_of(opts.shard)?;
    let inputs = native.files_read();
    let mut outputs = Outputs::new(inputs.iter().map(PathBuf::as_path));
    let product = outputs.add("-o", &opts.output, Stream::Binary)?;
    let mut add = |option, path: &Option<PathBuf>, stream| {
        let id = path.as_deref().map(|p| outputs.add(option, p, stream));
        id.transpose()
    };
    let raw = add("--raw", &opts.raw, Stream::Binary)?;
    let report = add("--report", &opts.report, Stream::Text)?;
    let partial = add("--partial", &opts.partial, Stream::Text)?;
    let sums = write_product(&native, &shots, opts, &outputs, product)?;
    if let Some(id) = report {
        let input = native.report_input(&sums, opts.word_bits);
        outputs.write(id, |w| report::write_report(w, &input))?;
    }
    if let (Some(id), Some(shard)) = (partial, opts.shard) {
        let p = super::partial::OnboardPartial::new(&native, opts.word_bits, shard, shots, sums);
        outputs.write(id, |w| p.write(w))?;
    }
    commit_with_raw(&native, outputs, raw.zip(opts.raw.as_deref()))?;
    // the native config differs from the user's only in accumulation and profiles
    for w in native.lidar.first().loaded.config.plausibility_warnings() {
        eprintln!("{w}");
    }
    Ok(())
}

/// A refusal of the onboard command.
pub fn no_scheme() -> Error {
    Error::Unsupported(
        "onboard needs at least one --scheme (none, uniform:N, caliop or a file)".into(),
    )
}
