//! `lidarsim onboard`: the run's shots drawn one by one (the shot path, dead time and a
//! changing scene included), summed onboard by every scheme given, the first scheme's
//! product written, and the report of every scheme side by side.

use std::io::Write;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::{Averager, RegionLayout, Scheme};
use crate::config::Method;
use crate::error::{Error, Result};
use crate::output::product::{ProductWriter, RegionSpec};
use crate::output::safe_file::Stream;
use crate::scenario::{ExpectedProfile, Lidar};
use crate::simulate;

/// Options of `lidarsim onboard`.
#[derive(Debug, Clone)]
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
}

/// Per scheme: its regions and averager, and per region and bin the running sums of the
/// downlinked counts (first channel) for the empirical S/N.
struct SchemeRun {
    scheme: Scheme,
    regions: Vec<RegionLayout>,
    averager: Averager,
    stats: Vec<Vec<(f64, f64, f64)>>,
    /// Per region: the running `(Σ s, Σ ln s, shots)` of the expected signal per merged
    /// bin over the pending profile's shots, and per bin the sum and number of the
    /// averaging biases of the profiles done.
    truth: Vec<(Vec<(f64, f64)>, u32)>,
    biases: Vec<Vec<(f64, u32)>>,
}

/// The averaging bias of one downlinked bin (model.md §7): how far the log of the
/// averaged true signal lies above the average of the shots' logs,
/// `ln(Σs/N) − Σ ln s/N ≥ 0` (Jensen), what a retrieval working on the log of averaged
/// counts (extinction, optical depth) misses against the full-resolution truth; 0 over a
/// uniform scene, growing with the horizontal averaging over broken cloud. NaN where a
/// shot has no signal.
fn averaging_bias(sum: f64, sum_ln: f64, n: u32) -> f64 {
    let n = f64::from(n);
    (sum / n).ln() - sum_ln / n
}

impl SchemeRun {
    /// Adds one shot's expected signal (first channel, per native bin) to the truth sums,
    /// closing each region's profile after its shots.
    fn add_truth(&mut self, signal: &[f64]) {
        for (k, r) in self.regions.iter().enumerate() {
            let (sums, shots) = &mut self.truth[k];
            for (j, s) in sums.iter_mut().enumerate() {
                let bins = r.first_bin + j * r.merge..r.first_bin + (j + 1) * r.merge;
                let x: f64 = signal[bins].iter().sum();
                *s = (s.0 + x, s.1 + if x > 0.0 { x.ln() } else { f64::NAN });
            }
            *shots += 1;
            if *shots == r.shots {
                for (acc, &(a, b)) in self.biases[k].iter_mut().zip(sums.iter()) {
                    let bias = averaging_bias(a, b, *shots);
                    if bias.is_finite() {
                        *acc = (acc.0 + bias, acc.1 + 1);
                    }
                }
                sums.iter_mut().for_each(|s| *s = (0.0, 0.0));
                *shots = 0;
            }
        }
    }
}

/// Runs the onboard simulation of `config`.
pub fn run(config: &Path, overrides: &[String], opts: &OnboardOptions) -> Result<()> {
    let nominal = Lidar::load(config, overrides)?;
    let first = nominal.first();
    let fl = first.instrument.rep_rate_hz;
    let total = first.shots_per_profile() * first.loaded.config.acquisition.profiles as u64;
    // the native run: one shot per profile
    let mut native_overrides = overrides.to_vec();
    native_overrides.push(format!("acquisition.accumulation_time_s={}", 1.0 / fl));
    native_overrides.push(format!("acquisition.profiles={total}"));
    let lidar = Lidar::load(config, &native_overrides)?;
    let sc = lidar.first();
    let seed = opts.seed.unwrap_or(sc.loaded.config.simulation.seed);
    let mut method = simulate::resolve_method(Method::Shot, &lidar)?;
    let energy = simulate::run_energy(&lidar, seed, total as f64 / fl)?;
    let scene =
        simulate::changing_scene(&lidar, seed, total as usize, &mut method, false, &energy)?;
    let expected = lidar.expected()?;
    let g = &sc.geometry;
    let native_vertical = g.bin_range_m * g.local_cos_at(0.0);
    let channels = lidar.channels.len();
    let mut runs: Vec<SchemeRun> = opts
        .schemes
        .iter()
        .map(|s| {
            let scheme = Scheme::parse(s)?;
            let regions =
                scheme.layout(g.n_bins, &|i| g.bin_centre_altitude_m(i), native_vertical)?;
            let stats = regions
                .iter()
                .map(|r| vec![(0.0, 0.0, 0.0); r.bins])
                .collect();
            let averager = Averager::with_channels(regions.clone(), channels, g.n_bins);
            let truth = regions
                .iter()
                .map(|r| (vec![(0.0, 0.0); r.bins], 0))
                .collect();
            let biases = regions.iter().map(|r| vec![(0.0, 0); r.bins]).collect();
            Ok(SchemeRun {
                scheme,
                regions,
                averager,
                stats,
                truth,
                biases,
            })
        })
        .collect::<Result<_>>()?;
    let mut outputs = crate::commands::outputs_for(sc);
    let product = outputs.add("-o", &opts.output, Stream::Binary)?;
    let raw = opts
        .raw
        .as_deref()
        .map(|p| outputs.add("--raw", p, Stream::Binary))
        .transpose()?;
    let report = opts
        .report
        .as_deref()
        .map(|p| outputs.add("--report", p, Stream::Text))
        .transpose()?;
    let specs = region_specs(&runs[0].regions, &expected[0], total, fl, g);
    let mut writer = ProductWriter::create(
        outputs.temp_path(product)?,
        &opts.output,
        &lidar.channel_names(),
        &crate::output::raw_file::content::time_units(&sc.loaded.config.acquisition.start_time)?,
        &[
            (
                "title",
                format!("lidarsim onboard product, scheme {}", runs[0].scheme.name),
            ),
            ("source", format!("lidarsim {}", env!("CARGO_PKG_VERSION"))),
            ("config", sc.loaded.resolved_toml.clone()),
        ],
        &specs,
    )?;
    let samplers: Vec<Vec<(simulate::StreamSampler, u64)>> = lidar
        .channels
        .iter()
        .zip(&expected)
        .enumerate()
        .map(|(k, (c, e))| {
            simulate::stream_samplers(
                e,
                method,
                energy,
                false,
                simulate::channel_seed(seed, k),
                c.instrument.dead_time,
            )
        })
        .collect();
    let n_bins = g.n_bins;
    let batch = ((4 << 20) / (n_bins * channels).max(1)).clamp(1, 4096) as u64;
    for start in (0..total).step_by(batch as usize) {
        let end = (start + batch).min(total);
        let drawn: Vec<Vec<u64>> = (start..end)
            .into_par_iter()
            .map(|p| match &scene {
                Some(s) => {
                    simulate::draw_scene_counts(s, seed, channels, p, n_bins, &energy)
                        .0
                        .counts
                }
                None => simulate::draw_profile(&samplers, p, 1, n_bins, false, &energy).counts,
            })
            .collect();
        for (shot, native) in (start..end).zip(&drawn) {
            // the true signal this shot saw (its column), for the averaging bias
            let truth = scene
                .as_ref()
                .map(|s| &s.expected[s.column_of_shot(shot)][0].signal);
            for (i, r) in runs.iter_mut().enumerate() {
                if let Some(signal) = truth {
                    r.add_truth(signal);
                }
                let SchemeRun {
                    averager, stats, ..
                } = r;
                let mut written = Ok(());
                averager.add_shot(native, |k, sums| {
                    for (s, &c) in stats[k].iter_mut().zip(sums) {
                        let x = c as f64;
                        *s = (s.0 + 1.0, s.1 + x, s.2 + x * x);
                    }
                    if i == 0 && written.is_ok() {
                        written = writer.write(k, sums);
                    }
                });
                written?;
            }
        }
    }
    writer.finish()?;
    if let Some(id) = report {
        outputs.write(id, |w| {
            write_report(
                w,
                scene.is_some(),
                &runs,
                &expected[0],
                fl,
                channels,
                opts.word_bits,
            )
        })?;
    }
    match (raw, &opts.raw) {
        // the same draw again (counts depend on the seed and shot only), written as
        // `simulate` writes it; that run commits every output together
        (Some(id), Some(path)) => {
            let raw_opts = simulate::RunOptions {
                output: path.clone(),
                seed: Some(seed),
                profiles: Some(total as usize),
                method: Some(Method::Shot),
                command_line: crate::output::raw_file::content::history_command(std::env::args()),
                ..Default::default()
            };
            simulate::run(&lidar, &raw_opts, outputs, id).map(|_| ())
        }
        _ => outputs.commit(),
    }
}

/// The product's regions: profiles, coordinates and bounds.
fn region_specs(
    regions: &[RegionLayout],
    e: &ExpectedProfile,
    total: u64,
    fl: f64,
    g: &crate::geometry::Geometry,
) -> Vec<RegionSpec> {
    regions
        .iter()
        .map(|r| {
            let profiles = (total / u64::from(r.shots)) as usize;
            let altitude_m = (0..r.bins)
                .map(|j| {
                    let bins = r.first_bin + j * r.merge..r.first_bin + (j + 1) * r.merge;
                    bins.clone().map(|i| e.altitude_m[i]).sum::<f64>() / r.merge as f64
                })
                .collect();
            let time_s = (0..profiles)
                .map(|j| (j as f64 + 0.5) * f64::from(r.shots) / fl)
                .collect();
            let bounds = match &r.region {
                Some(reg) => (reg.bottom_km, reg.top_km, reg.vertical_resolution_m),
                None => (
                    g.bin_centre_altitude_m(g.n_bins - 1) / 1e3,
                    g.bin_centre_altitude_m(0) / 1e3,
                    g.bin_range_m * g.cos_angle,
                ),
            };
            RegionSpec {
                profiles,
                altitude_m,
                time_s,
                shots: r.shots,
                bounds,
            }
        })
        .collect()
}

/// The median of the finite values.
fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The report: one row per scheme and region (interface.md columns).
#[allow(clippy::too_many_arguments)]
fn write_report(
    w: &mut dyn Write,
    scene_changes: bool,
    runs: &[SchemeRun],
    e: &ExpectedProfile,
    fl: f64,
    channels: usize,
    word_bits: u32,
) -> std::io::Result<()> {
    writeln!(
        w,
        "scheme,region,altitude_min_km,altitude_max_km,vertical_resolution_m,shots_averaged,bins,snr_eq4_median,snr_empirical_median,data_rate_bps,averaging_bias_median"
    )?;
    for r in runs {
        let rate: f64 = r
            .regions
            .iter()
            .map(|g| (g.bins * channels) as f64 * f64::from(word_bits) * fl / f64::from(g.shots))
            .sum();
        for (k, (g, stats)) in r.regions.iter().zip(&r.stats).enumerate() {
            let shots = f64::from(g.shots);
            let rest = (e.background + e.dark) * g.merge as f64;
            let eq4: Vec<f64> = (0..g.bins)
                .map(|j| {
                    let s: f64 = e.signal
                        [g.first_bin + j * g.merge..g.first_bin + (j + 1) * g.merge]
                        .iter()
                        .sum();
                    crate::snr::eq4(s, rest, 0.0, shots)
                })
                .collect();
            let empirical: Vec<f64> = stats
                .iter()
                .map(|&(n, sum, sq)| {
                    let mean = sum / n;
                    let var = (sq - n * mean * mean) / (n - 1.0);
                    (mean - shots * rest) / var.sqrt()
                })
                .collect();
            let (lo, hi, res) = match &g.region {
                Some(reg) => (reg.bottom_km, reg.top_km, reg.vertical_resolution_m),
                None => (f64::NAN, f64::NAN, f64::NAN),
            };
            // per bin the mean over the profiles; the median over the bins the scene's
            // changes reach (0 when none do); empty for a static scene
            let bias = if scene_changes {
                let affected: Vec<f64> = r.biases[k]
                    .iter()
                    .filter(|&&(sum, n)| n > 0 && sum > 1e-12)
                    .map(|&(sum, n)| sum / f64::from(n))
                    .collect();
                format!("{:e}", median(affected).max(0.0))
            } else {
                String::new()
            };
            writeln!(
                w,
                "{},{k},{lo},{hi},{res},{},{},{:e},{:e},{rate},{bias}",
                r.scheme.name,
                g.shots,
                g.bins,
                median(eq4),
                median(empirical)
            )?;
        }
    }
    Ok(())
}

/// A refusal of the onboard command.
pub fn no_scheme() -> Error {
    Error::Unsupported(
        "onboard needs at least one --scheme (none, uniform:N, caliop or a file)".into(),
    )
}
