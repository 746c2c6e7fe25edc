//! The columns of a changing scene, built as its profiles need them and dropped after
//! their last profile: what keeps a run's memory flat in the track's length (a model-field
//! scene has new columns every profile, each about 0.5 kB a bin and channel with its
//! sampler). A run builds the columns of each batch of profiles before drawing it
//! ([`SceneModel::prepare`]) and writes their truth then; validate and onboard, which draw
//! any profile in any order, build them all ([`SceneModel::build_all`]).

use std::sync::Arc;

use rayon::prelude::*;

use super::energy::RunEnergy;
use super::method::ResolvedMethod;
use super::sampler::StreamSampler;
use super::scene::{BuiltColumn, SceneModel, column_scenario};
use crate::error::{Error, Result};
use crate::scenario::{ExpectedProfile, Lidar, Scenario};
use crate::scene::sun;

/// Columns built at once when a run builds what no profile sees (at its end).
const UNSEEN_BLOCK: usize = 64;

impl SceneModel {
    /// Builds column `i`, every channel.
    fn build_column(&self, lidar: &Lidar, i: usize) -> Result<BuiltColumn> {
        let col = self.all[i];
        let channels = lidar
            .channels
            .iter()
            .zip(&self.configs)
            .map(|(c, cfg)| column_scenario(&self.track, c, cfg, col))
            .collect::<Result<Vec<Scenario>>>()?;
        let solar = self.sunlight.is_some();
        let reflectors = match solar {
            false => vec![],
            true => {
                // the sky above the column's reflector
                let below = crate::surface::reflector_below(
                    &self.track.column_config(&self.configs[0], col),
                );
                channels
                    .iter()
                    .map(|c| {
                        let cfg = &c.loaded.config;
                        let path = sun::SunlightPath::of(cfg, &c.atmosphere, below.altitude_m);
                        (below.albedo, path)
                    })
                    .collect()
            }
        };
        let expected: Vec<ExpectedProfile> = channels
            .iter()
            .map(Scenario::expected)
            .collect::<Result<_>>()?;
        let samplers = match self.method {
            ResolvedMethod::Shot => channels
                .iter()
                .zip(&expected)
                .map(|(c, e)| shot_sampler(c, e, solar, self.energy))
                .collect(),
            _ => vec![],
        };
        let column = BuiltColumn {
            expected,
            samplers,
            reflectors,
        };
        self.check_counts_fit(i, &column)?;
        Ok(column)
    }

    /// Refuses column `i` if its brightest bin could outgrow the file's counters
    /// ([`SceneModel::max_count`]: the width is chosen before the columns are built).
    fn check_counts_fit(&self, i: usize, column: &BuiltColumn) -> Result<()> {
        let sky = self.brightest_background_of(column);
        let shots = self.shots as f64;
        let envelope = self.energy.envelope;
        let brightest = column
            .expected
            .iter()
            .flat_map(|e| {
                e.signal
                    .iter()
                    .map(move |s| envelope * s + e.background + e.dark)
            })
            .fold(0.0f64, f64::max);
        let mean = (brightest + sky) * shots;
        if mean + 20.0 * mean.sqrt() + 64.0 < self.max_count {
            return Ok(());
        }
        Err(Error::Unsupported(format!(
            "column {i} of the scene expects {mean:.3e} counts in its brightest bin per \
             profile, beyond what the file's counters hold ({:.3e}); accumulate fewer shots \
             per profile",
            self.max_count
        )))
    }

    /// Column `i`, built ([`prepare`](Self::prepare) or [`build_all`](Self::build_all)
    /// made it).
    pub fn column(&self, i: usize) -> Arc<BuiltColumn> {
        let built = self.built.read().unwrap_or_else(|e| e.into_inner());
        match &built[i] {
            Some(c) => Arc::clone(c),
            None => panic!("internal: column {i} drawn before it was built"),
        }
    }

    /// Builds the columns profiles `profiles` see that are not built yet, in parallel,
    /// and drops those no profile from `profiles.start` on sees; returns the new ones in
    /// column order, for their truth to be written.
    pub fn prepare(
        &self,
        lidar: &Lidar,
        profiles: std::ops::Range<u64>,
    ) -> Result<Vec<(usize, Arc<BuiltColumn>)>> {
        let start = profiles.start;
        let mut needed: Vec<usize> = profiles
            .flat_map(|p| self.runs(p).into_iter().map(|(c, _)| c))
            .collect();
        needed.sort_unstable();
        needed.dedup();
        {
            let mut built = self.built.write().unwrap_or_else(|e| e.into_inner());
            for (i, slot) in built.iter_mut().enumerate() {
                if slot.is_some() && self.last_use[i].is_none_or(|last| last < start) {
                    *slot = None;
                }
            }
        }
        let missing: Vec<usize> = {
            let built = self.built.read().unwrap_or_else(|e| e.into_inner());
            needed.into_iter().filter(|&i| built[i].is_none()).collect()
        };
        self.build_these(lidar, &missing)
    }

    /// Builds columns `which` in parallel and keeps them; returns them in that order.
    fn build_these(
        &self,
        lidar: &Lidar,
        which: &[usize],
    ) -> Result<Vec<(usize, Arc<BuiltColumn>)>> {
        let new: Vec<(usize, Arc<BuiltColumn>)> = which
            .par_iter()
            .map(|&i| self.build_column(lidar, i).map(|c| (i, Arc::new(c))))
            .collect::<Result<_>>()?;
        let mut built = self.built.write().unwrap_or_else(|e| e.into_inner());
        for (i, c) in &new {
            built[*i] = Some(Arc::clone(c));
        }
        Ok(new)
    }

    /// Builds every column and keeps them (for a caller that draws any profile in any
    /// order).
    pub fn build_all(&self, lidar: &Lidar) -> Result<()> {
        let all: Vec<usize> = (0..self.all.len()).collect();
        self.build_these(lidar, &all).map(drop)
    }

    /// Every column, built ([`build_all`](Self::build_all) first).
    pub fn all_columns(&self) -> Vec<Arc<BuiltColumn>> {
        (0..self.all.len()).map(|i| self.column(i)).collect()
    }

    /// Builds the columns no profile of the run sees (the subsets of broken cells the
    /// track never meets), [`UNSEEN_BLOCK`] at a time, and hands each to `write`: the
    /// file holds every column's truth. The whole run only (a shard leaves them NaN, its
    /// merge builds them).
    pub fn for_unseen(
        &self,
        lidar: &Lidar,
        mut write: impl FnMut(usize, &BuiltColumn) -> Result<()>,
    ) -> Result<()> {
        let unseen: Vec<usize> = (0..self.all.len())
            .filter(|&i| self.last_use[i].is_none())
            .collect();
        for block in unseen.chunks(UNSEEN_BLOCK) {
            let new: Vec<(usize, BuiltColumn)> = block
                .par_iter()
                .map(|&i| self.build_column(lidar, i).map(|c| (i, c)))
                .collect::<Result<_>>()?;
            for (i, c) in &new {
                write(*i, c)?;
            }
        }
        Ok(())
    }

    /// An upper bound of the solar background counts per shot per bin of any channel
    /// under `column`: its albedo under an overhead sun at perihelion (0 without the sun).
    fn brightest_background_of(&self, column: &BuiltColumn) -> f64 {
        if self.sunlight.is_none() {
            return 0.0;
        }
        self.channel_sun
            .iter()
            .zip(&column.reflectors)
            .map(|(&(factor, irradiance), (albedo, path))| {
                factor * irradiance * path.brightest(*albedo, 1.04)
            })
            .fold(0.0, f64::max)
    }
}

/// Channel `c`'s shot sampler of the column whose expectations are `e`: signal, and the
/// fixed background and dark (a solar background is placed per run instead).
fn shot_sampler(
    c: &Scenario,
    e: &ExpectedProfile,
    solar: bool,
    energy: RunEnergy,
) -> StreamSampler {
    let sky = if solar { 0.0 } else { e.background };
    let rest = vec![sky + e.dark; e.n_bins()];
    StreamSampler::with_energy(ResolvedMethod::Shot, &e.signal, &rest, energy)
        .through_detector(c.instrument.dead_time)
}
