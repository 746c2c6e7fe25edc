//! The draw of an onboard run's native shots (the samplers, or the changing scene) and
//! every scheme's averaging of them, shot by shot.

use std::ops::Range;

use rayon::prelude::*;

use super::native::NativeRun;
use super::report::{SchemeSums, averaging_bias};
use super::truth::{ProfileRows, ShotTruth};
use super::{Averager, RegionLayout};
use crate::config::Method;
use crate::error::Result;
use crate::output::product::{ProductWriter, ProfileRow};
use crate::scenario::ExpectedProfile;
use crate::simulate;

/// The draw of the native shots: the samplers, or the changing scene.
pub(super) struct Draw {
    seed: u64,
    energy: simulate::RunEnergy,
    scene: Option<simulate::scene::SceneModel>,
    /// Every column of the changing scene, built (none in a static scene).
    built: Vec<std::sync::Arc<simulate::scene::BuiltColumn>>,
    samplers: Vec<Vec<(simulate::StreamSampler, u64)>>,
    pub(super) channels: usize,
    pub(super) n_bins: usize,
    /// Per channel: the static scene's background and dark counts per native bin.
    rest: Vec<(f64, f64)>,
}

impl Draw {
    /// The draw of `native`'s shots (the whole run's model, whatever the shard).
    pub(super) fn new(native: &NativeRun) -> Result<Draw> {
        let lidar = &native.lidar;
        let seed = native.seed;
        let mut method = simulate::resolve_method(Method::Shot, lidar)?;
        let duration = native.shots as f64 / native.rep_rate_hz;
        let energy = simulate::run_energy(lidar, seed, duration)?;
        let profiles = native.shots as usize;
        let scene = simulate::changing_scene(lidar, seed, profiles, &mut method, false, &energy)?;
        // any shot in any order: every column built (by `changing_scene`)
        let built = scene.as_ref().map_or_else(Vec::new, |sc| sc.all_columns());
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
            built,
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
    pub(super) fn columns<'a>(&'a self, native: &'a NativeRun) -> Vec<&'a [ExpectedProfile]> {
        match &self.scene {
            Some(_) => self.built.iter().map(|c| c.expected.as_slice()).collect(),
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
                    dark: self.built[column].expected.iter().map(|e| e.dark).collect(),
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
        Some(&self.built[s.column_of_shot(p)].expected)
    }
}

/// One scheme's averaging and the sums of its report.
pub(super) struct SchemeRun {
    averager: Averager,
    pub(super) sums: SchemeSums,
    /// Per region: the running `(Σ s, Σ ln s)` of the expected signal per merged bin over
    /// the pending profile's shots, and those shots.
    truth: Vec<(Vec<(f64, f64)>, u32)>,
}

impl SchemeRun {
    pub(super) fn new(regions: &[RegionLayout], channels: usize, n_bins: usize) -> Self {
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
pub(super) fn draw_shots(
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
