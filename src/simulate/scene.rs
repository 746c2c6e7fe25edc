//! Drawing a scene that changes along the track (`crate::scene::track`): each column's
//! model and samplers are built once, when the first profile that sees it is drawn, and
//! dropped after the last (`columns.rs`); a profile is drawn run by run, each run of
//! consecutive shots that see one column with that column's sampler.
//!
//! * `aggregate`: one Poisson draw per bin of mean `Σ_runs F_run·λ_sig,col + M·λ_rest`
//!   (F_run the run's summed energy factors, its shot count at constant energy): exact,
//!   since the profile's count is a sum of independent Poisson counts.
//! * `shot`: every shot of a run drawn by the column's shot sampler (dead time included,
//!   the detector live at each run's start: a column change is at least one shot apart,
//!   far longer than τ); run `j` of profile `p` uses the streams of
//!   `(seed ^ run_seed(j), p, block)`.
//!
//! The profile's truth is what its shots saw on average: `Σ_runs n_run·x_col / M` for
//! the expected signal, recorded counts and attenuated backscatter.

use std::collections::HashMap;
use std::sync::{Arc, RwLock};

use super::energy::RunEnergy;
use super::method::ResolvedMethod;
use super::sampler::StreamSampler;
use crate::config::{BackgroundModel, ScenarioConfig};
use crate::detector::DeadTime;
use crate::detector::dead_time::{ARRIVAL_STREAM, Scratch};
use crate::error::{Error, Result};
use crate::loaded::LoadedConfig;
use crate::receiver::ChannelConfig;
use crate::sampling::{self, CountSink, SHOT_BLOCK, ShotCounts, ShotSampler};
use crate::scenario::{ExpectedProfile, Lidar, Scenario};
use crate::scene::orbit::Orbit;
use crate::scene::sun;
use crate::scene::track::{AlongTrack, Column, MAX_COLUMNS, Track};

/// Memory kept per bin of each column and channel for its expectations and truth (about
/// 30 f64, and the raw file's copy of the truth, 20 f64, while it is written); `shot`
/// adds its sampler's tables ([`sampling::table_bytes_bound`]).
const COLUMN_BYTES_PER_BIN: f64 = 400.0;

/// How fast the scene passes the lidar without an orbit, m s⁻¹: a ground lidar's
/// `scene.advection_speed_m_per_s` (the wind carrying a frozen scene over the station),
/// else the ground-track speed of a space-borne one (model.md §3).
fn scene_speed_m_per_s(cfg: &ScenarioConfig, channel: &crate::scenario::Scenario) -> f64 {
    match cfg.platform.kind {
        crate::config::PlatformKind::Ground => cfg
            .scene
            .as_ref()
            .and_then(|s| s.advection_speed_m_per_s)
            .unwrap_or(crate::config::DEFAULT_ADVECTION_SPEED_M_PER_S),
        _ => crate::geometry::ground_track_speed_m_per_s(channel.geometry.platform_altitude_m),
    }
}

/// Seed offset of a solar background's stream.
const SKY_STREAM: u64 = 0x5C7B_ACC6_0000_0001;

/// Adds background counts of mean `per_bin` in every bin of `sink` (the run's shots
/// together), exactly, by the cheaper of two ways (`sampling::cost`):
///
/// * sparse (`per_bin` below [`BACKGROUND_PER_BIN_DENSE`]): the total
///   `N ~ Poisson(per_bin·bins)` placed uniformly (a multinomial split of a Poisson total
///   is independent Poissons), each count by the multiply-shift map of a 64-bit uniform
///   (bias ≤ bins/2⁶⁴); O(N + 1);
/// * dense: one draw per bin from an alias table over the Poisson(`per_bin`) PMF
///   ([`sampling::PmfAlias`], built once per call, shared by every bin); O(bins).
fn add_background<R: rand::Rng, S: CountSink + ?Sized>(
    rng: &mut R,
    per_bin: f64,
    bins: usize,
    sink: &mut S,
) {
    let total = per_bin * bins as f64;
    if total <= 0.0 {
        return;
    }
    if (BACKGROUND_PER_BIN_DENSE..=sampling::DENSE_ALIAS_MAX).contains(&per_bin) {
        let table = sampling::PmfAlias::new(per_bin);
        for bin in 0..bins {
            sink.add_any(bin, table.count_for(rng.next_u64()));
        }
        return;
    }
    let n = sampling::poisson_u64(rng, total);
    for _ in 0..n {
        let bin = ((u128::from(rng.next_u64()) * bins as u128) >> 64) as usize;
        sink.add(bin, 1);
    }
}

/// Mean background counts per bin from which [`add_background`] draws every bin from a
/// table rather than placing each count: a placement costs ~1.5 ns a count, a table
/// draw ~2.4 ns a bin (`cargo run --release --example sampler_costs`).
const BACKGROUND_PER_BIN_DENSE: f64 = 1.6;

/// Run `j` of a solar scene through a dead-time detector, shot by shot: each shot's
/// signal and dark photons (the column's sampler) and its sunlit photons
/// (`sky_per_bin` per bin, placed uniformly) recorded together.
#[allow(clippy::too_many_arguments)]
fn sunlit_dead_time_run(
    photons: &ShotSampler,
    dead: &DeadTime,
    sky_per_bin: f64,
    seed: u64,
    p: u64,
    shots: u64,
    acc: &mut [u64],
) {
    let bins = acc.len();
    let mut rng = sampling::stream_rng(seed, p, 0);
    let mut sky = sampling::stream_rng(seed ^ SKY_STREAM, p, 0);
    let mut arrivals = sampling::stream_rng(seed ^ ARRIVAL_STREAM, p, 0);
    let mut shot = ShotCounts::new(bins);
    let mut scratch = Scratch::default();
    for _ in 0..shots {
        shot.clear();
        photons.sample_shot(&mut rng, &mut shot);
        add_background(&mut sky, sky_per_bin, bins, &mut shot);
        dead.record_shot(&mut arrivals, &shot, &mut scratch, acc);
    }
}

/// One column of the scene, every channel: its expectations, its shot samplers (`shot`
/// only) and, under the sun, the albedo below it and the sunlight's path to it and back.
pub struct BuiltColumn {
    /// Per channel: the expectations.
    pub expected: Vec<ExpectedProfile>,
    /// Per channel: the shot samplers (empty but for `shot`).
    pub(super) samplers: Vec<StreamSampler>,
    /// Per channel: the reflector's albedo and the sunlight's path (empty without the
    /// sun).
    pub(super) reflectors: Vec<(f64, sun::SunlightPath)>,
}

/// The most profiles drawn in one batch (`sizes.rs`): the columns one batch builds.
pub const MAX_BATCH_PROFILES: usize = 64;

/// Seed of run `j`'s streams within a profile (run 0 keeps the channel's seed).
fn run_seed(seed: u64, j: usize) -> u64 {
    seed ^ (j as u64).wrapping_mul(0xA076_1D64_78BD_642F)
}

/// A changing scene ready to draw: the track, its columns (built as the profiles need
/// them, `columns.rs`), the sun.
pub struct SceneModel {
    /// Where each shot is and which column it sees.
    pub track: Track,
    columns: HashMap<Column, usize>,
    /// Every column of the scene, in the file's order.
    pub(super) all: Vec<Column>,
    /// Per column: the last profile of the run that sees it (`None`: none does).
    pub(super) last_use: Vec<Option<u64>>,
    /// Per channel: the config the columns are cut from (curtain and fields made segments).
    pub(super) configs: Vec<ScenarioConfig>,
    /// Per column: its model and samplers while some profile still needs them.
    pub(super) built: RwLock<Vec<Option<Arc<BuiltColumn>>>>,
    pub(super) method: ResolvedMethod,
    pub(super) energy: RunEnergy,
    pub(super) shots: u64,
    /// The sun, for a solar background.
    pub(super) sunlight: Option<Sunlight>,
    /// Per channel: the instrument's background counts per unit radiance, and the solar
    /// irradiance at its wavelength at 1 AU (photons s⁻¹ m⁻² nm⁻¹).
    pub(super) channel_sun: Vec<(f64, f64)>,
    /// Per channel: the detector's dead time, if any.
    pub dead: Vec<Option<DeadTime>>,
    /// The most distinct columns one profile can see (the raw file's `k` slots).
    pub column_slots: usize,
    /// The largest count the file's counters hold ([`SceneModel::set_count_width`]):
    /// a column whose brightest bin could outgrow it is refused when it is built.
    pub(super) max_count: f64,
    /// The CAMS species some column's aerosol carries (0-based, increasing): the file's
    /// `alpha_aer_<species>`, named before any column is built (from the layers the
    /// model fields made, the union `truth::aerosol_species_of` takes over the columns).
    pub aerosol_species: Vec<usize>,
}

/// The CAMS species the segments' layers carry, over every channel (0-based, increasing).
fn scene_aerosol_species(configs: &[ScenarioConfig]) -> Vec<usize> {
    let mut present: Vec<usize> = (configs.iter())
        .filter_map(|c| c.scene.as_ref())
        .flat_map(|s| s.segments.iter())
        .filter_map(|s| s.layers.as_ref())
        .flatten()
        .filter_map(|l| l.species.as_ref())
        .flat_map(|s| s.iter().map(|e| e.species))
        .collect();
    present.sort_unstable();
    present.dedup();
    present
}

/// What the solar background needs: where the sun is for each profile.
pub struct Sunlight {
    orbit: Option<Orbit>,
    fixed_zenith_deg: Option<f64>,
    /// Unix time of the first shot, s.
    start_unix_s: f64,
    profile_time_s: f64,
    /// The fixed radiance added under the sun (night sky).
    floor: f64,
}

impl Sunlight {
    /// The sun of a run whose background model is solar (`None` otherwise).
    fn of(lidar: &Lidar) -> Result<Option<Sunlight>> {
        let first = lidar.first();
        let b = &first.loaded.config.background;
        if b.model != BackgroundModel::Solar {
            return Ok(None);
        }
        let start = humantime::parse_rfc3339(&first.loaded.config.acquisition.start_time)
            .map_err(|e| Error::Unsupported(format!("acquisition.start_time: {e}")))?;
        let start_unix_s = start
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64());
        Ok(Some(Sunlight {
            orbit: super::orbit::orbit_of(lidar)?,
            fixed_zenith_deg: b.solar_zenith_deg,
            start_unix_s,
            profile_time_s: first.shots_per_profile() as f64 / first.instrument.rep_rate_hz,
            floor: b.radiance.unwrap_or(0.0),
        }))
    }

    /// Solar zenith angle (degrees) and sun distance (AU) at profile `p`'s centre.
    pub fn sun_at(&self, p: u64) -> (f64, f64) {
        let t = (p as f64 + 0.5) * self.profile_time_s;
        let unix = self.start_unix_s + t;
        let zenith = match (self.fixed_zenith_deg, &self.orbit) {
            (Some(z), _) => z,
            (None, Some(o)) => {
                let g = o.position(t);
                sun::solar_zenith_deg(unix, g.latitude_deg, g.longitude_deg)
            }
            (None, None) => 90.0,
        };
        (zenith, sun::earth_sun_distance_au(unix))
    }
}

/// A profile's per-shot averages of the model over its runs, per channel.
pub struct ProfileTruth {
    /// Expected signal per shot, channel-major.
    pub signal: Vec<f64>,
    /// Expected recorded counts per shot, channel-major.
    pub recorded: Vec<f64>,
    /// Attenuated backscatter seen on average, channel-major.
    pub attenuated_backscatter: Vec<f64>,
}

impl SceneModel {
    /// The scene of `lidar` for a run of `profiles` profiles drawn by `method` from
    /// `seed`: its track and columns, none built yet ([`SceneModel::prepare`],
    /// [`SceneModel::build_all`]).
    pub fn new(
        lidar: &Lidar,
        seed: u64,
        profiles: u64,
        method: ResolvedMethod,
        energy: RunEnergy,
    ) -> Result<Self> {
        let first = lidar.first();
        let shots = first.shots_per_profile();
        // a curtain file is the same scene as its segments
        let configs: Vec<ScenarioConfig> = lidar
            .channels
            .iter()
            .map(|c| with_curtain(&c.loaded))
            .collect::<Result<_>>()?;
        let orbit = super::orbit::orbit_of(lidar)?;
        // with an orbit, the length of the track the file's latitudes and longitudes describe
        let along = match orbit {
            Some(o) => AlongTrack::Orbit(o),
            None => AlongTrack::Speed(scene_speed_m_per_s(&first.loaded.config, first)),
        };
        // model fields: one segment per profile, sampled along the orbit or over the station
        let configs = configs
            .into_iter()
            .zip(&lidar.channels)
            .map(|(c, ch)| {
                crate::scene::fields::with_model_fields(
                    c,
                    &ch.loaded,
                    &along,
                    (shots, profiles),
                    seed,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        let track = Track::new(&configs[0], seed, along, shots, profiles)?;
        let all = track.columns();
        if all.len() > MAX_COLUMNS {
            return Err(Error::Unsupported(format!(
                "the scene has {} columns (segments × broken-layer subsets), at most {MAX_COLUMNS}",
                all.len()
            )));
        }
        let columns: HashMap<Column, usize> =
            all.iter().enumerate().map(|(i, c)| (*c, i)).collect();
        let column_slots = track.columns_per_profile_bound(profiles, all.len());
        // the raw file's writer holds a block of profiles' columns and weights
        crate::resources::require_memory(
            &format!("the raw file's profile columns ({column_slots} slots a profile)"),
            (crate::output::raw_file::writer::COLUMN_BLOCK * column_slots * 12) as f64,
        )?;
        let mut last_use = vec![None; all.len()];
        for p in 0..profiles {
            for (c, _) in track.runs(p) {
                last_use[columns[&c]] = Some(p);
            }
        }
        // the columns kept at once: a batch's (`prepare`), and those seen again later
        let kept = all
            .len()
            .min(MAX_BATCH_PROFILES * column_slots + column_slots);
        let streams = kept * lidar.channels.len();
        let kept_bytes = (streams * first.geometry.n_bins) as f64 * COLUMN_BYTES_PER_BIN
            + if method == ResolvedMethod::Shot {
                streams as f64 * sampling::table_bytes_bound(first.geometry.n_bins)
            } else {
                0.0
            };
        crate::resources::require_memory(
            &format!(
                "the scene's columns of {} bins ({kept} at a time)",
                first.geometry.n_bins
            ),
            kept_bytes,
        )?;
        let channel_sun = lidar
            .channels
            .iter()
            .map(|c| {
                let f = sun::solar_spectral_irradiance_photons(c.instrument.wavelength_nm);
                (
                    c.instrument.background_per_radiance,
                    if f.is_finite() { f } else { 0.0 },
                )
            })
            .collect();
        let aerosol_species = scene_aerosol_species(&configs);
        Ok(SceneModel {
            built: RwLock::new(vec![None; all.len()]),
            track,
            columns,
            all,
            last_use,
            configs,
            method,
            energy,
            shots,
            sunlight: Sunlight::of(lidar)?,
            channel_sun,
            dead: lidar
                .channels
                .iter()
                .map(|c| c.instrument.dead_time)
                .collect(),
            column_slots,
            max_count: f64::INFINITY,
            aerosol_species,
        })
    }

    /// Columns of the scene.
    pub fn n_columns(&self) -> usize {
        self.all.len()
    }

    /// Sets the largest count the file's counters hold: a column is refused when built
    /// if its brightest bin could outgrow it ([`CountWidth::for_max_count`]'s margin).
    pub fn set_count_width(&mut self, width: crate::output::raw_file::CountWidth) {
        self.max_count = width.max_value() as f64;
    }

    /// Whether the background comes from the sun.
    pub fn is_solar(&self) -> bool {
        self.sunlight.is_some()
    }

    /// The sun of a solar run.
    pub fn sunlight(&self) -> Option<&Sunlight> {
        self.sunlight.as_ref()
    }

    /// Background counts per shot per bin of each run of profile `p`, channel `channel`:
    /// the channel's fixed background, or the sunlight reflected below each run's
    /// column and the air's scattered sunlight above it (docs/model.md §4f, through the
    /// column's atmosphere at the channel's wavelength, [`sun::SunlightPath::radiance`])
    /// times the instrument's factor, plus the fixed radiance's background as a floor.
    pub fn run_backgrounds(&self, channel: usize, p: u64, runs: &[(usize, u64)]) -> Vec<f64> {
        match &self.sunlight {
            None => runs
                .iter()
                .map(|&(col, _)| self.column(col).expected[channel].background)
                .collect(),
            Some(sunlight) => {
                let (zenith, au) = sunlight.sun_at(p);
                let (factor, irradiance) = self.channel_sun[channel];
                let floor = sunlight.floor;
                runs.iter()
                    .map(|&(col, _)| {
                        let column = self.column(col);
                        let (albedo, path) = &column.reflectors[channel];
                        let l = path
                            .radiance(*albedo, irradiance / (au * au), zenith)
                            .total();
                        // the fixed radiance, if any, is a floor (night sky)
                        (l + floor) * factor
                    })
                    .collect()
            }
        }
    }

    /// The runs of profile `p`: (column index, shots).
    pub fn runs(&self, p: u64) -> Vec<(usize, u64)> {
        self.track
            .runs(p)
            .into_iter()
            .map(|(c, n)| (self.columns[&c], n))
            .collect()
    }

    /// The column seen by the first shot of profile `p` (the only one in one-shot
    /// profiles), without building the profile's runs.
    pub fn column_of_shot(&self, p: u64) -> usize {
        self.columns[&self.track.column_at(self.track.position_m(p, 0))]
    }

    /// Draws channel `channel` of profile `p` into `acc`; `backgrounds` are the runs'
    /// background counts per shot per bin ([`run_backgrounds`](Self::run_backgrounds)),
    /// `energies` the profile's pulse energies ([`ProfileEnergies`]).
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &self,
        channel: usize,
        seed: u64,
        p: u64,
        runs: &[(usize, u64)],
        energies: &ProfileEnergies,
        backgrounds: &[f64],
        acc: &mut [u64],
    ) {
        if self.method != ResolvedMethod::Shot {
            let m = self.shots as f64;
            let dark = self.column(runs[0].0).expected[channel].dark;
            let rest = dark
                + runs
                    .iter()
                    .zip(backgrounds)
                    .map(|(r, b)| r.1 as f64 / m * b)
                    .sum::<f64>();
            let mut lambda = vec![rest; acc.len()];
            for (&(col, _), f) in runs.iter().zip(energies.run_sums(runs)) {
                let column = self.column(col);
                let signal = &column.expected[channel].signal;
                lambda
                    .iter_mut()
                    .zip(signal)
                    .for_each(|(l, s)| *l += f / m * s);
            }
            sampling::aggregate_profile(&lambda, seed, p, self.shots, acc);
        } else {
            let mut first = 0usize;
            for (j, &(col, n)) in runs.iter().enumerate() {
                let sky = self.sunlight.as_ref().map(|_| backgrounds[j]);
                let factors = energies.run(first, n);
                first += n as usize;
                let column = self.column(col);
                let sampler = &column.samplers[channel];
                draw_run(sampler, run_seed(seed, j), p, n, factors, sky, acc);
            }
        }
    }

    /// What profile `p`'s shots saw on average, every channel.
    pub fn truth(&self, runs: &[(usize, u64)]) -> ProfileTruth {
        let m = self.shots as f64;
        let channels = self.dead.len();
        let n = self.column(runs[0].0).expected[0].n_bins();
        let mut t = ProfileTruth {
            signal: vec![0.0; channels * n],
            recorded: vec![0.0; channels * n],
            attenuated_backscatter: vec![0.0; channels * n],
        };
        for c in 0..channels {
            let bins = c * n..(c + 1) * n;
            for &(col, shots) in runs {
                let column = self.column(col);
                let (w, e) = (shots as f64 / m, &column.expected[c]);
                add_scaled(&mut t.signal[bins.clone()], &e.signal, w);
                add_scaled(&mut t.recorded[bins.clone()], &e.recorded, w);
                add_scaled(
                    &mut t.attenuated_backscatter[bins.clone()],
                    &e.attenuated_backscatter,
                    w,
                );
            }
        }
        t
    }
}

/// `dst += w·src`, element by element.
fn add_scaled(dst: &mut [f64], src: &[f64], w: f64) {
    dst.iter_mut().zip(src).for_each(|(d, s)| *d += w * s);
}

/// The pulse energies of one profile's shots, relative to the nominal energy: none drawn
/// at constant energy (every factor 1), else the profile's factors in shot order, cut
/// at the runs' boundaries by [`run`](Self::run) and [`run_sums`](Self::run_sums).
pub struct ProfileEnergies(Option<Vec<f64>>);

impl ProfileEnergies {
    /// The energies of profile `p` of `shots` shots: the factors of its blocks.
    pub fn new(energy: &RunEnergy, p: u64, shots: u64) -> Self {
        if energy.law.is_constant() {
            return ProfileEnergies(None);
        }
        let seed = energy.seed.unwrap_or_default();
        let mut factors = Vec::with_capacity(shots as usize);
        let mut block = Vec::new();
        for b in 0..shots.div_ceil(SHOT_BLOCK) {
            energy.law.block_factors(seed, p, shots, b, &mut block);
            factors.extend_from_slice(&block);
        }
        ProfileEnergies(Some(factors))
    }

    /// The factors of the `n` shots from shot `first` on (`None` at constant energy).
    pub fn run(&self, first: usize, n: u64) -> Option<&[f64]> {
        self.0.as_ref().map(|f| &f[first..first + n as usize])
    }

    /// The summed factors of each run (the shot counts at constant energy).
    pub fn run_sums(&self, runs: &[(usize, u64)]) -> Vec<f64> {
        let mut first = 0usize;
        runs.iter()
            .map(|&(_, n)| {
                let sum = self.run(first, n).map_or(n as f64, |f| f.iter().sum());
                first += n as usize;
                sum
            })
            .collect()
    }
}

/// Draws one run of `n` shots of one column and channel into `acc`, from `seed` (the
/// run's) and its streams: the column's shot sampler (its pulse energies `factors` where
/// they vary), and, under the sun, `sky` background counts per shot per bin: placed into
/// each shot before a dead-time detector records it, else added for the whole run.
fn draw_run(
    sampler: &StreamSampler,
    seed: u64,
    p: u64,
    n: u64,
    factors: Option<&[f64]>,
    sky: Option<f64>,
    acc: &mut [u64],
) {
    let bins = acc.len();
    let mut sky_rng = sampling::stream_rng(seed ^ SKY_STREAM, p, 0);
    let energies = || factors.expect("a modulated sampler draws with the run's energies");
    match (sampler, sky) {
        // through a dead-time detector the sunlight joins each shot
        (StreamSampler::DeadTimed(s), Some(b)) => {
            return sunlit_dead_time_run(s.photons(), s.dead(), b, seed, p, n, acc);
        }
        // each pixel its share of the sunlight, through its own dead time
        (StreamSampler::Pixels { pixel, pixels }, Some(b)) => {
            let share = b / f64::from(*pixels);
            for k in 0..*pixels {
                let s = super::sampler::pixel_seed(seed, k);
                sunlit_dead_time_run(pixel.photons(), pixel.dead(), share, s, p, n, acc);
            }
            return;
        }
        (StreamSampler::Modulated(m), Some(b)) if m.has_detector() => {
            let mut add_sky = |shot: &mut ShotCounts| add_background(&mut sky_rng, b, bins, shot);
            return m.add_run(seed, p, energies(), acc, &mut add_sky);
        }
        (StreamSampler::Modulated(m), _) => m.add_run(seed, p, energies(), acc, &mut |_| {}),
        _ => sampler.profile_counts(seed, p, n, acc),
    }
    // an ideal detector: the run's sunlight all at once (the same law)
    if let Some(b) = sky {
        add_background(&mut sky_rng, n as f64 * b, bins, acc);
    }
}

/// The config with its curtain file, if any, turned into segments.
fn with_curtain(loaded: &LoadedConfig) -> Result<ScenarioConfig> {
    let mut cfg = loaded.config.clone();
    if let Some(scene) = cfg.scene.as_mut()
        && let Some(file) = scene.curtain.take()
    {
        scene.segments = crate::scene::curtain::segments(&loaded.resolve_path(&file))?;
    }
    Ok(cfg)
}

/// Channel scenario `c` in column `col`: its config with the column's layers, aerosol
/// and surface.
pub(super) fn column_scenario(
    track: &Track,
    c: &Scenario,
    cfg: &ScenarioConfig,
    col: Column,
) -> Result<Scenario> {
    let config = track.column_config(cfg, col);
    let loaded = LoadedConfig {
        channels: vec![ChannelConfig {
            name: c.channel_name.clone(),
            kind: c.loaded.channels[0].kind,
            species: c.loaded.channels[0].species,
            lines: c.loaded.channels[0].lines,
            band_transmission: c.loaded.channels[0].band_transmission,
            spectral_filter: c.loaded.channels[0].spectral_filter.clone(),
            record: c.loaded.channels[0].record,
            glue_partner: c.loaded.channels[0].glue_partner,
            config: config.clone(),
        }],
        config,
        path: c.loaded.path.clone(),
        resolved_toml: c.loaded.resolved_toml.clone(),
    };
    Scenario::from_loaded(loaded)
}
