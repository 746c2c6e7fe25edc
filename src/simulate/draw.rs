//! The drawing loop of a planned run: profiles drawn in parallel batches and handed to a
//! sink (the raw file, or memory) in order; its progress bar.

use std::sync::Arc;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::changing::{SceneDraw, draw_scene_counts, file_rows};
use super::drawn::{DrawnProfile, STATIC_COLUMN, draw_profile};
use super::orbit::orbit_of;
use super::plan::{RunOptions, RunPlan};
use super::sampler::{StreamSampler, channel_seed, stream_samplers};
use super::scene::BuiltColumn;
use crate::error::{Error, Result};
use crate::output::raw_file::{ProfileRecord, ProfileSink, content};
use crate::scenario::Lidar;

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
pub(super) fn draw_into<S: ProfileSink>(
    lidar: &Lidar,
    planned: &RunPlan,
    rows: std::ops::Range<usize>,
    opts: &RunOptions,
    sink: &mut S,
    mut photons: Option<&mut crate::photons::PhotonWriter>,
) -> Result<(u64, Duration)> {
    let first = lidar.first();
    let RunPlan {
        seed,
        components,
        method,
        ref expected,
        energy,
        ref scene,
        truth,
        ..
    } = *planned;
    let layout = crate::output::raw_file::content::TruthLayout::of(lidar, scene.is_some(), truth);
    let dark: Vec<f64> = expected.iter().map(|e| e.dark).collect();
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
    // the events' truth of each channel (`--photons`)
    let models: Option<Vec<crate::photons::ChannelModel>> = match photons {
        Some(_) => Some(photon_models(lidar, planned, &channels)?),
        None => None,
    };
    // each channel's laser line has its own nominal energy; the shots' factors are shared
    let nominal_energy_j: Vec<f64> = lidar
        .channels
        .iter()
        .map(|c| c.loaded.config.instrument.pulse_energy_j)
        .collect();
    let progress = progress_bar(opts.progress, rows.len());
    let batch = batch_of(n_bins, &channels);
    let mut total_counts = 0u64;
    let mut drawing = Duration::ZERO;
    // Batch k is drawn while batch k − 1 is handed to the writer (whose chunk compression
    // runs on the same pool): the writer gets the profiles in order whatever the thread
    // count, so the file's bytes do not depend on it.
    let draw_batch = |first_profile: usize| -> Option<Batch> {
        let last = (first_profile + batch).min(rows.end);
        let draw_start = Instant::now();
        let n_channels = lidar.channels.len();
        let mut events: Vec<Vec<crate::photons::EventRow>> = Vec::new();
        let mut drawn: Vec<(DrawnProfile, Option<SceneDraw>)> = match &models {
            Some(models) => {
                let both: Vec<(DrawnProfile, Vec<crate::photons::EventRow>)> = (first_profile
                    ..last)
                    .into_par_iter()
                    .map(|p| {
                        (!cancelled(opts)).then(|| {
                            let (d, e) = super::events::draw_profile_with_events(
                                &channels, models, p as u64, shots, n_bins, &energy,
                            );
                            let rows = event_rows(
                                &first.geometry,
                                first.instrument.rep_rate_hz,
                                p as u64,
                                shots,
                                &e,
                            );
                            (d, rows)
                        })
                    })
                    .collect::<Option<_>>()?;
                both.into_iter()
                    .map(|(d, e)| {
                        events.push(e);
                        (d, None)
                    })
                    .collect()
            }
            None => (first_profile..last)
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
                .collect::<Option<_>>()?,
        };
        let took = draw_start.elapsed();
        // the truth of a changing scene's profiles (the model, not the draw)
        if let Some(sc) = scene {
            drawn.par_iter_mut().for_each(|(d, draw)| {
                if let (Some(draw), Some(columns)) = (draw, &d.columns) {
                    d.values = file_rows(sc, layout, draw, columns, &dark, shots);
                }
            });
        }
        // summed here, in parallel, not on the writer's thread
        let counted: u64 = drawn
            .par_iter()
            .map(|(d, _)| d.counts.iter().sum::<u64>())
            .sum();
        let drawn: Vec<DrawnProfile> = drawn.into_iter().map(|(d, _)| d).collect();
        Some((first_profile, drawn, took, counted, events))
    };
    let species = scene.as_ref().map_or(&[][..], |sc| &sc.aerosol_species[..]);
    let column_rows = |c: &BuiltColumn| {
        content::column_rows(lidar, expected, &c.expected, species, shots, layout)
    };
    let rep_rate_hz = first.instrument.rep_rate_hz;
    let mut write_batch = |(first_profile, drawn, took, counted, events): Batch,
                           new_columns: Vec<(usize, Arc<BuiltColumn>)>,
                           sink: &mut S| {
        drawing += took;
        total_counts += counted;
        // one column's rows at a time (they are ~30 values a bin and channel)
        for (c, column) in new_columns {
            let rows = column_rows(&column);
            drop(column);
            let rows: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
            sink.write_column(c, &rows)?;
        }
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
            if let (Some(w), Some(ev)) = (photons.as_deref_mut(), events.get(k)) {
                let place = |t: f64| {
                    orbit.as_ref().map_or((f64::NAN, f64::NAN), |o| {
                        let g = o.position(t);
                        (g.latitude_deg, g.longitude_deg)
                    })
                };
                w.events(ev)?;
                let shot_rows: Vec<crate::photons::ShotRow> = (0..shots)
                    .map(|s| {
                        let t = (index as u64 * shots + s) as f64 / rep_rate_hz;
                        let (latitude, longitude) = place(t);
                        crate::photons::ShotRow {
                            delta_time: t,
                            energy_j: pulse_energy_j[0],
                            latitude,
                            longitude,
                        }
                    })
                    .collect();
                w.shots(&shot_rows)?;
            }
        }
        progress.inc(drawn.len() as u64);
        Ok::<(), Error>(())
    };
    let mut pending = None;
    for first_profile in rows.clone().step_by(batch) {
        // the columns this batch sees, built before it is drawn (their truth written
        // with it)
        let last = (first_profile + batch).min(rows.end) as u64;
        let new_columns = match scene {
            Some(sc) => sc.prepare(lidar, first_profile as u64..last)?,
            None => vec![],
        };
        let (drawn, written) = rayon::join(
            || draw_batch(first_profile),
            || {
                pending
                    .take()
                    .map_or(Ok(()), |(b, cols)| write_batch(b, cols, &mut *sink))
            },
        );
        written?;
        match drawn {
            Some(drawn) if !cancelled(opts) => pending = Some((drawn, new_columns)),
            _ => return Err(Error::Interrupted),
        }
    }
    if let Some((last, cols)) = pending {
        write_batch(last, cols, &mut *sink)?;
    }
    // the whole run's file holds the columns no profile sees too (a shard's leaves them
    // to its merge)
    if let Some(sc) = scene.as_ref().filter(|_| rows == (0..planned.profiles)) {
        sc.for_unseen(lidar, |i, c| {
            let rows = column_rows(c);
            let rows: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
            sink.write_column(i, &rows)
        })?;
    }
    progress.finish_and_clear();
    Ok((total_counts, drawing))
}

/// Profiles drawn in one batch by samplers `channels` of `n_bins` bins: bounded memory
/// (at most 32 MiB of counts) and a lively progress bar. A changing scene's columns are
/// built batch by batch, and `merge` writes them at the same points, so the batches
/// depend on the run alone (never on the shard or the thread count).
fn batch_of(n_bins: usize, channels: &[Vec<(StreamSampler, u64)>]) -> usize {
    let streams = channels.len() * channels[0].len();
    super::sizes::batch_profiles(n_bins, streams)
}

/// The batches of a planned run ([`batch_of`]) whose profiles are `profiles`.
pub(super) fn run_batch(lidar: &Lidar, planned: &RunPlan) -> usize {
    let channels: Vec<Vec<(StreamSampler, u64)>> = lidar
        .channels
        .iter()
        .zip(&planned.expected)
        .enumerate()
        .map(|(k, (c, e))| {
            let seed = channel_seed(planned.seed, lidar.photon_source(k));
            let (method, energy) = (planned.method, planned.energy);
            stream_samplers(e, method, energy, planned.components, seed, &c.instrument)
        })
        .collect();
    batch_of(lidar.first().geometry.n_bins, &channels)
}

/// A drawn batch: its first profile, its profiles, the time their counts took to draw,
/// and the sum of their counts.
type Batch = (
    usize,
    Vec<DrawnProfile>,
    Duration,
    u64,
    Vec<Vec<crate::photons::EventRow>>,
);

/// The origin models of a run's channels, refusing a run whose events cannot be drawn.
fn photon_models(
    lidar: &Lidar,
    planned: &RunPlan,
    channels: &[Vec<(StreamSampler, u64)>],
) -> Result<Vec<crate::photons::ChannelModel>> {
    if planned.scene.is_some() {
        return Err(Error::Unsupported(
            "--photons: a scene that changes along the track (scene, orbit columns, model \
             fields) is not supported yet; the events are drawn for a static scene"
                .into(),
        ));
    }
    if planned.components {
        return Err(Error::Unsupported(
            "--photons and --components: the events carry their origin (truth_origin); \
             drop --components"
                .into(),
        ));
    }
    for (c, streams) in lidar.channels.iter().zip(channels) {
        for (s, _) in streams {
            super::events::check_sampler(s, &c.channel_name)?;
        }
    }
    lidar
        .channels
        .iter()
        .zip(&planned.expected)
        .map(|(c, e)| super::events::channel_model(c, e))
        .collect()
}

/// Profile `profile`'s events (of `shots` shots) as the photon file stores them: shot
/// times, ranges, times of flight and heights on the run's bins (on the drawing threads).
fn event_rows(
    geometry: &crate::geometry::Geometry,
    rep_rate_hz: f64,
    profile: u64,
    shots: u64,
    events: &[crate::photons::Event],
) -> Vec<crate::photons::EventRow> {
    let c = crate::constants::SPEED_OF_LIGHT_M_PER_S;
    events
        .iter()
        .map(|e| {
            let (ra, rb) = geometry.bin_range_bounds(e.bin as usize);
            let range_m = ra + e.frac * (rb - ra);
            let pulse = profile * shots + u64::from(e.shot);
            crate::photons::EventRow {
                delta_time: pulse as f64 / rep_rate_hz,
                pulse,
                channel: e.channel,
                pixel: e.pixel,
                bin: e.bin,
                range_m,
                tof_s: 2.0 * range_m / c,
                h_ph: geometry.altitude_at_range(range_m),
                origin: e.origin as u8,
            }
        })
        .collect()
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
