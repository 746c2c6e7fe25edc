//! The native run that every scheme averages (one shot per native profile): its model,
//! schemes and regions, its identity, and its product's root and regions.

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::identity::{METHOD, ProductIdentity, product_attributes, source};
use super::report::{ReportInput, SchemeSums};
use super::shard::{FRAME_ATTRIBUTE, frame_shots, region_profiles, shard_shots_of};
use super::{RegionLayout, Scheme};
use crate::error::Result;
use crate::output::product::{ProductHeader, RegionSpec};
use crate::output::raw_file::AttrValue;
use crate::scenario::{ExpectedProfile, Lidar};
use crate::shard::{SHARD_ATTRIBUTES, Shard, fingerprint_with};
use crate::simulate;

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
    pub(super) fn header(
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
    pub(super) fn region_specs(
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
                    channel_numbers: r
                        .channel_indices(names.len())
                        .iter()
                        .map(|&c| c as i64)
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
