//! A run whose scene changes along the track (or with the sun): what it refuses, the draw
//! of its profiles and their truth.

use super::drawn::{DrawnProfile, profile_columns};
use super::energy::RunEnergy;
use super::method::ResolvedMethod;
use super::sampler::channel_seed;
use super::scene;
use crate::error::{Error, Result};
use crate::output::raw_file::content::TruthLayout;
use crate::output::raw_file::per_profile;
use crate::scenario::Lidar;

/// Whether the scene of `lidar` changes along the track (or with the sun): a run of it
/// draws from a [`changing_scene`].
pub fn scene_changes(lidar: &Lidar) -> bool {
    let cfg = &lidar.first().loaded.config;
    let solar = cfg.background.model == crate::config::BackgroundModel::Solar;
    crate::scene::track::Track::is_changing(cfg) || solar
}

/// The scene model of a run whose scene changes along the track (`None` for one column
/// everywhere), every column built (for a caller that draws any profile in any order);
/// refuses what this version does not draw in a changing scene.
pub fn changing_scene(
    lidar: &Lidar,
    seed: u64,
    profiles: usize,
    method: &mut ResolvedMethod,
    components: bool,
    energy: &RunEnergy,
) -> Result<Option<scene::SceneModel>> {
    let scene = unbuilt_scene(lidar, seed, profiles, method, components, energy)?;
    if let Some(sc) = &scene {
        sc.build_all(lidar)?;
    }
    Ok(scene)
}

/// [`changing_scene`] with no column built yet: a run builds them batch by batch
/// ([`scene::SceneModel::prepare`]).
pub(super) fn unbuilt_scene(
    lidar: &Lidar,
    seed: u64,
    profiles: usize,
    method: &mut ResolvedMethod,
    components: bool,
    energy: &RunEnergy,
) -> Result<Option<scene::SceneModel>> {
    if !scene_changes(lidar) {
        return Ok(None);
    }
    if components {
        return Err(Error::Unsupported(
            "--components is not available for a scene that changes along the track yet".into(),
        ));
    }
    let induced = |c: &&crate::scenario::Scenario| {
        let d = c.loaded.config.instrument.detector.as_ref();
        d.is_some_and(|d| d.signal_induced_noise.is_some() || d.afterpulsing.is_some())
    };
    if let Some(c) = lidar.channels.iter().find(induced) {
        return Err(Error::Unsupported(format!(
            "channel {} has signal-induced noise or afterpulsing, which this version does not \
             draw in a scene that changes along the track (or with the sun) yet",
            c.channel_name
        )));
    }
    if let Some(c) = lidar
        .channels
        .iter()
        .find(|c| c.instrument.analog.is_some())
    {
        return Err(Error::Unsupported(format!(
            "channel {} records analog, which this version does not draw in a scene that \
             changes along the track (or with the sun) yet; use photon counting there",
            c.channel_name
        )));
    }
    if matches!(method, ResolvedMethod::AggregateNormal { .. }) {
        *method = ResolvedMethod::Aggregate;
    }
    scene::SceneModel::new(lidar, seed, profiles as u64, *method, *energy).map(Some)
}

/// Draws profile `p` of a changing scene, every channel, with the profile's truth.
pub fn draw_scene_profile(
    sc: &scene::SceneModel,
    seed: u64,
    channels: usize,
    p: u64,
    n_bins: usize,
    energy: &RunEnergy,
) -> DrawnProfile {
    let (mut drawn, draw) = draw_scene_counts(sc, seed, channels, p, n_bins, energy);
    drawn.values = scene_profile_values(sc, n_bins, &draw);
    drawn
}

/// What the truth of a changing scene's profile needs of its draw: its runs (column,
/// shots) and each channel's mean background counts per shot.
pub struct SceneDraw {
    runs: Vec<(usize, u64)>,
    mean_backgrounds: Vec<f64>,
}

impl SceneDraw {
    /// Each channel's background counts per shot per bin, averaged over the profile's
    /// shots (the sunlight changes along the track).
    pub fn mean_backgrounds(&self) -> &[f64] {
        &self.mean_backgrounds
    }
}

/// Draws the counts of profile `p` of a changing scene, every channel (no truth yet:
/// [`scene_profile_values`]); also returns what the truth needs of the draw.
pub fn draw_scene_counts(
    sc: &scene::SceneModel,
    seed: u64,
    channels: usize,
    p: u64,
    n_bins: usize,
    energy: &RunEnergy,
) -> (DrawnProfile, SceneDraw) {
    let runs = sc.runs(p);
    let shots = runs.iter().map(|r| r.1).sum::<u64>();
    let energies = scene::ProfileEnergies::new(energy, p, shots);
    let mut counts = vec![0u64; channels * n_bins];
    let mut mean_backgrounds = Vec::with_capacity(channels);
    for (k, acc) in counts.chunks_mut(n_bins).enumerate() {
        let bkg = sc.run_backgrounds(k, p, &runs);
        sc.draw(k, channel_seed(seed, k), p, &runs, &energies, &bkg, acc);
        let total: f64 = runs.iter().zip(&bkg).map(|(r, b)| r.1 as f64 * b).sum();
        mean_backgrounds.push(total / shots as f64);
    }
    let drawn = DrawnProfile {
        counts,
        components: None,
        energy_sum: energies.run_sums(&runs).iter().sum(),
        values: Vec::new(),
        columns: Some(profile_columns(&runs, sc.column_slots)),
    };
    (
        drawn,
        SceneDraw {
            runs,
            mean_backgrounds,
        },
    )
}

/// The rows of profile `p`'s per-profile variables in a changing scene, channel-major:
/// expected signal, background, recorded counts, Eq. 4 S/N and attenuated backscatter
/// (what the profile's shots saw on average), from its [`SceneDraw`].
pub fn scene_profile_values(
    sc: &scene::SceneModel,
    n_bins: usize,
    draw: &SceneDraw,
) -> Vec<Vec<f64>> {
    let SceneDraw {
        runs,
        mean_backgrounds,
    } = draw;
    let shots = runs.iter().map(|r| r.1).sum::<u64>() as f64;
    let mut truth = sc.truth(runs);
    let first = sc.column(runs[0].0);
    let dark = |k: usize| first.expected[k].dark;
    if sc.is_solar() {
        // an ideal detector records what arrives; a dead-time one its stationary rate per
        // bin (the transient at a sharp edge, O(τ/Δt), is not in this truth)
        for (k, recorded) in truth.recorded.chunks_mut(n_bins).enumerate() {
            let signal = &truth.signal[k * n_bins..(k + 1) * n_bins];
            for (r, s) in recorded.iter_mut().zip(signal) {
                let arriving = s + mean_backgrounds[k] + dark(k);
                *r = match &sc.dead[k] {
                    Some(d) => d.stationary_rate(arriving / d.bin_width_s) * d.bin_width_s,
                    None => arriving,
                };
            }
        }
    }
    let mut background = Vec::with_capacity(truth.signal.len());
    let mut snr = Vec::with_capacity(truth.signal.len());
    for (k, signal) in truth.signal.chunks(n_bins).enumerate() {
        let b = mean_backgrounds[k];
        background.extend(std::iter::repeat_n(b, n_bins));
        snr.extend(
            signal
                .iter()
                .map(|&s| crate::snr::eq4(s, b, dark(k), shots)),
        );
    }
    vec![
        truth.signal,
        background,
        truth.recorded,
        snr,
        truth.attenuated_backscatter,
    ]
}

/// The rows profile `p` of a changing scene writes into its file, in the order of its
/// per-profile variables ([`TruthLayout`]): with the compact truth the sky background
/// per channel, and the recorded counts of a dead-time detector under the sun; with
/// `--truth per-profile` format 3's five rows, each exactly what
/// [`crate::output::raw_file::per_profile`] rebuilds from the compact form. `columns`
/// are the profile's slots and weights, `dark` every channel's dark counts per shot
/// (the file's `expected_dark`), `shots` the profile's.
pub fn file_rows(
    sc: &scene::SceneModel,
    layout: TruthLayout,
    draw: &SceneDraw,
    columns: &(Vec<i32>, Vec<f64>),
    dark: &[f64],
    shots: u64,
) -> Vec<Vec<f64>> {
    let channels = dark.len();
    let n_bins = sc.column(draw.runs[0].0).expected[0].n_bins();
    let background = &draw.mean_backgrounds;
    let mix = |f: fn(&crate::scenario::ExpectedProfile) -> &[f64]| {
        let mut out = vec![0.0; channels * n_bins];
        for (k, row) in out.chunks_mut(n_bins).enumerate() {
            // an unused slot (−1, weight 0) adds nothing: its column need not be built
            let built: Vec<_> = (columns.0.iter().zip(&columns.1))
                .filter(|&(&c, _)| c >= 0)
                .map(|(&c, &w)| (w, sc.column(per_profile::slot_column(c))))
                .collect();
            let slots = built.iter().map(|(w, b)| (*w, f(&b.expected[k])));
            per_profile::mix_into(row, slots);
        }
        out
    };
    let signal = mix(|e| &e.signal);
    let dead = sc.dead.iter().any(Option::is_some);
    // (signal + background) + dark in every bin, or a dead-time channel's stationary
    // recorded rate of it (the transient at a sharp edge, O(τ/Δt), is not in this truth)
    let recorded_of_arriving = || -> Vec<f64> {
        let mut out = signal.clone();
        for (k, row) in out.chunks_mut(n_bins).enumerate() {
            for r in row.iter_mut() {
                let arriving = per_profile::ideal_counts(*r, background[k], dark[k]);
                *r = match &sc.dead[k] {
                    Some(d) => d.stationary_rate(arriving / d.bin_width_s) * d.bin_width_s,
                    None => arriving,
                };
            }
        }
        out
    };
    match layout {
        TruthLayout::Static => vec![],
        TruthLayout::Compact { dead_time, solar } => {
            let mut rows = vec![background.clone()];
            if dead_time && solar {
                rows.push(recorded_of_arriving());
            }
            rows
        }
        TruthLayout::PerProfile => {
            let recorded = if dead && !sc.is_solar() {
                mix(|e| &e.recorded)
            } else {
                recorded_of_arriving()
            };
            let bkg: Vec<f64> = background
                .iter()
                .flat_map(|&b| std::iter::repeat_n(b, n_bins))
                .collect();
            let snr = (0..signal.len())
                .map(|j| {
                    let k = j / n_bins;
                    crate::snr::eq4(signal[j], background[k], dark[k], shots as f64)
                })
                .collect();
            vec![
                signal,
                bkg,
                recorded,
                snr,
                mix(|e| &e.attenuated_backscatter),
            ]
        }
    }
}
