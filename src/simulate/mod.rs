//! The Monte Carlo run (`lidarsim simulate`, docs/simulation.md): per-bin expectations from the
//! deterministic model, Poisson photon counts accumulated over each profile's shots by
//! the chosen method, streamed into a raw HDF5 file.
//!
//! Profiles are drawn in parallel (rayon) in batches and written in order by this
//! thread (all HDF5 calls are serialized anyway). Every profile's counts come from
//! [`sampling::stream_rng`](crate::sampling::stream_rng)`(seed', profile, block)` only,
//! so the file's bytes depend on the seed alone, never on the thread count, and any
//! profile can be regenerated alone with [`StreamSampler::profile_counts`].
//!
//! This file runs a plan into its sink: [`run`] into the raw file, [`run_in_memory`] into
//! arrays. The parts, a file each: the method (`method.rs`), the emitted energies
//! (`energy.rs`), the samplers and seeds (`sampler.rs`), the orbit (`orbit.rs`), the plan
//! (`plan.rs`), the drawn profile (`drawn.rs`), a changing scene's draw (`changing.rs`, its
//! model `scene.rs`), the drawing loop (`draw.rs`), the sizes checked before the run
//! (`sizes.rs`), its closing line (`summary.rs`), and `lidarsim merge` of raw shards
//! (`merge.rs`).

use std::time::Instant;

mod changing;
mod columns;
mod draw;
mod drawn;
mod energy;
pub mod events;
pub mod merge;
mod method;
mod orbit;
mod plan;
mod sampler;
pub mod scene;
mod sizes;
mod summary;

pub use changing::{
    SceneDraw, changing_scene, draw_scene_counts, draw_scene_profile, scene_changes,
    scene_profile_values,
};
pub use draw::progress_bar;
pub use drawn::{DrawnProfile, RECORDED_ROW, STATIC_COLUMN, draw_profile, profile_columns};
pub use energy::{RunEnergy, run_energy};
pub use method::{
    ResolvedMethod, check_detector, fastest_within, fastest_within_totals, per_shot_reason,
    resolve_method,
};
pub use orbit::orbit_of;
pub use plan::{RunOptions, RunPlan, RunValues, plan};
pub use sampler::{StreamSampler, channel_seed, stream_samplers};
pub use sizes::estimated_file_bytes;
pub use summary::RunSummary;

use crate::error::{Error, Result};
use crate::output::raw_file::RawFileWriter;
use crate::output::raw_file::memory::{MemoryFile, MemoryWriter};
use crate::safe_file::{OutputId, Outputs};
use crate::scenario::Lidar;
use draw::draw_into;
use sizes::check_sizes;
use summary::summary;

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
    let mut outputs = outputs;
    let photon_file = match &opts.photons {
        Some(p) => {
            if opts.shard.is_some() {
                return Err(Error::Unsupported(
                    "--photons with --shard: write the photons of a whole run".into(),
                ));
            }
            Some(outputs.add("--photons", p, crate::safe_file::Stream::Binary)?)
        }
        None => None,
    };
    check_sizes(lidar, &planned, rows.len(), opts, true)?;
    let mut writer = RawFileWriter::create(outputs.temp_path(raw)?, &opts.output, spec)?;
    let mut photons = match (photon_file, &opts.photons) {
        (Some(id), Some(shown)) => Some(crate::photons::PhotonWriter::create(
            outputs.temp_path(id)?,
            shown,
            &photon_header(lidar, &planned)?,
        )?),
        _ => None,
    };
    let (total_counts, drawing) = draw_into(
        lidar,
        &planned,
        rows.clone(),
        opts,
        &mut writer,
        photons.as_mut(),
    )?;
    writer.finish()?;
    let events = photons.map(|p| p.finish()).transpose()?;
    outputs.commit()?;
    let mut done = summary(lidar, &planned, opts, rows, start, total_counts, drawing);
    if let (Some(n), Some(p)) = (events, &opts.photons) {
        done.photons = Some((p.clone(), n, sizes::expected_events(lidar, &planned)));
    }
    Ok(done)
}

/// What the photon file says of its run.
fn photon_header(lidar: &Lidar, planned: &RunPlan) -> Result<crate::photons::PhotonHeader> {
    let first = lidar.first();
    let g = &first.geometry;
    let time_units =
        crate::output::raw_file::content::time_units(&first.loaded.config.acquisition.start_time)?;
    Ok(crate::photons::PhotonHeader {
        time_units,
        channels: lidar
            .channels
            .iter()
            .map(|c| c.channel_name.clone())
            .collect(),
        pixels: lidar
            .channels
            .iter()
            .map(|c| c.instrument.dead_time.map_or(1, |d| d.pixels.max(1)))
            .collect(),
        bin_start_range_m: (0..g.n_bins).map(|i| g.bin_range_bounds(i).0).collect(),
        bin_range_m: g.bin_range_m,
        bin_width_s: first.loaded.config.instrument.bin_width_s,
        shots_per_profile: first.shots_per_profile(),
        profiles: planned.profiles as u64,
        rep_rate_hz: first.instrument.rep_rate_hz,
        seed: planned.seed,
        config_toml: planned
            .spec
            .root_attributes
            .iter()
            .find_map(|(k, v)| match v {
                crate::output::raw_file::AttrValue::Str(s) if k == "config" => Some(s.clone()),
                _ => None,
            })
            .unwrap_or_default(),
    })
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
    if opts.photons.is_some() {
        return Err(Error::Unsupported(
            "photons are written to a file: run simulate to a path".into(),
        ));
    }
    let (total_counts, drawing) = draw_into(lidar, &planned, rows.clone(), opts, &mut sink, None)?;
    let file = sink.finish()?;
    Ok((
        file,
        summary(lidar, &planned, opts, rows, start, total_counts, drawing),
    ))
}
