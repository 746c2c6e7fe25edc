//! What a run did: its closing line.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use super::method::ResolvedMethod;
use super::plan::{RunOptions, RunPlan};
use crate::scenario::Lidar;

/// What a run did, for the closing summary.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// The file written.
    pub output: PathBuf,
    /// Profiles written.
    pub profiles: usize,
    /// With `--shard`: the shard, the profiles it wrote and the run's profiles.
    pub shard: Option<(crate::shard::Shard, std::ops::Range<usize>, usize)>,
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
    /// With `--photons`: the photon file, the events it holds and the estimate made
    /// before the run.
    pub photons: Option<(PathBuf, u64, f64)>,
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let shot_bins = self.profiles as f64 * self.shots_per_profile as f64 * self.bins as f64;
        let rate = |d: Duration| shot_bins / d.as_secs_f64().max(1e-9);
        let shard = match &self.shard {
            Some((s, rows, of)) if !rows.is_empty() => format!(
                " (shard {s}: profiles {}–{} of {of})",
                rows.start,
                rows.end - 1
            ),
            _ => String::new(),
        };
        write!(
            f,
            "Wrote {}{shard}: {} profiles × {} bins, {} shots per profile, {} counts in all; method {}, seed {}. \
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
        )?;
        if let Some((p, n, est)) = &self.photons {
            write!(
                f,
                " Wrote {}: {} events (estimated {:.4e} before the run).",
                p.display(),
                human_count(*n),
                est
            )?;
        }
        Ok(())
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

/// What a run did, for its closing line.
pub(super) fn summary(
    lidar: &Lidar,
    planned: &RunPlan,
    opts: &RunOptions,
    rows: std::ops::Range<usize>,
    start: Instant,
    total_counts: u64,
    drawing: Duration,
) -> RunSummary {
    let first = lidar.first();
    RunSummary {
        output: opts.output.clone(),
        profiles: rows.len(),
        shard: opts.shard.map(|s| (s, rows, planned.profiles)),
        bins: first.geometry.n_bins,
        shots_per_profile: first.shots_per_profile(),
        total_counts,
        method: planned.method,
        seed: planned.seed,
        elapsed: start.elapsed(),
        drawing,
        warning: lidar.run_notes(&planned.expected),
        photons: None,
    }
}
