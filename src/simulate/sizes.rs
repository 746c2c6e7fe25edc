//! A run's sizes checked before it starts: its memory and file refused where they cannot
//! fit, its duration announced.

use super::method::{ResolvedMethod, cost};
use super::plan::{RunOptions, RunPlan};
use crate::error::Result;
use crate::output::raw_file::CountWidth;
use crate::sampling::{self, ShotSampler};
use crate::scenario::Lidar;

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

/// Profiles drawn in one batch of `n_bins` bins and `streams` count streams: at most
/// 4 Mi counts (32 MiB), at least one profile, at most 64 (what the drawing loop,
/// `simulate::draw`, draws and the estimate counts); two batches are held at once.
pub(super) fn batch_profiles(n_bins: usize, streams: usize) -> usize {
    ((4 << 20) / (n_bins * streams).max(1)).clamp(1, super::scene::MAX_BATCH_PROFILES)
}

/// Events a `--photons` run of `planned` is expected to write: the expected recorded
/// counts summed over its channels, bins, shots and profiles.
pub(super) fn expected_events(lidar: &Lidar, planned: &RunPlan) -> f64 {
    let shots = lidar.first().shots_per_profile() as f64;
    let per_shot: f64 = planned
        .expected
        .iter()
        .map(|e| e.recorded.iter().sum::<f64>())
        .sum();
    per_shot * shots * planned.profiles as f64
}

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
pub(super) fn check_sizes(
    lidar: &Lidar,
    planned: &RunPlan,
    profiles: usize,
    opts: &RunOptions,
    to_disk: bool,
) -> Result<()> {
    let (totals, method, components) = (&planned.totals, planned.method, planned.components);
    let shots = lidar.first().shots_per_profile();
    // the detectors' cost per shot (ns): the dead-time counter's from its channel's
    // means, the analog chain's from its bins (it records every bin of every shot)
    let detector_ns: f64 = lidar
        .channels
        .iter()
        .zip(&planned.expected)
        .filter(|_| method == ResolvedMethod::Shot)
        .map(|(c, e)| {
            let lambda = e.total_per_shot();
            let dead = c
                .instrument
                .dead_time
                .map_or(0.0, |d| d.ns_per_shot(&lambda));
            let analog = c
                .instrument
                .analog
                .as_ref()
                .map_or(0.0, |a| a.ns_per_shot(lambda.len()));
            dead + analog
        })
        .sum();
    let streams = if components { 4 } else { 1 };
    let bins = totals.len() as f64;
    // one bit per profile (written yet?), the batch of drawn rows, the samplers' tables,
    // the file writer's chunks (the count variables and, in a changing scene, five f64)
    let threads = rayon::current_num_threads().max(1);
    let writer =
        crate::output::raw_file::writer::buffer_bytes(bins as usize * 8, streams + 5, threads);
    let tables = streams as f64 * sampling::table_bytes_bound(bins as usize);
    let batch = batch_profiles(bins as usize, streams).min(profiles);
    let rows = batch as f64 * bins * streams as f64;
    let memory = profiles as f64 / 8.0 + rows * 8.0 * 2.0 + tables + writer;
    crate::resources::require_memory(&format!("simulating {profiles} profiles"), memory)?;
    if to_disk {
        let file = estimated_file_bytes(totals, shots, profiles, streams);
        crate::resources::require_disk("-o", &opts.output, file)?;
    }
    if let Some(p) = &opts.photons {
        // the events of a batch of profiles (as the file's rows), held twice (the batch
        // drawn and the batch written), and the file's buffers
        let events = expected_events(lidar, planned) * profiles as f64 / planned.profiles as f64;
        let per_profile = events / profiles.max(1) as f64;
        let held = 2.0
            * batch as f64
            * per_profile
            * 2.0
            * std::mem::size_of::<crate::photons::EventRow>() as f64
            + crate::photons::writer::FLUSH_EVENTS as f64
                * (crate::photons::FILE_BYTES_PER_EVENT + 32.0);
        crate::resources::require_memory(
            &format!(
                "--photons: holding the events of {batch} profiles (~{per_profile:.3e} a profile)"
            ),
            memory + held,
        )?;
        let bytes = events * crate::photons::FILE_BYTES_PER_EVENT
            + (profiles as u64 * shots) as f64 * crate::photons::FILE_BYTES_PER_SHOT;
        crate::resources::require_disk(
            &format!("--photons ({events:.4e} events expected)"),
            p,
            bytes,
        )?;
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
    } + (detector_ns + afterpulse_ns) * shots as f64;
    let ns = profiles as f64
        * (draw_ns_per_profile * streams.min(3) as f64 / threads as f64
            + bins * streams as f64 * FILE_NS_PER_COUNT);
    crate::resources::announce_duration(
        &format!("{profiles} profiles × {} bins", totals.len()),
        ns * 1e-9,
    );
    Ok(())
}
