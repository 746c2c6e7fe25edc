//! A scenario ready to compute: the config turned into instrument, geometry,
//! atmosphere and beam path, and its expected per-bin counts (the `expect` model).

use std::path::Path;

use rayon::prelude::*;

use crate::atmosphere::multiple_scattering::{self, Footprint};
use crate::atmosphere::{Atmosphere, MolecularState, Optics};
use crate::config::{self, MultipleScatteringModel};
use crate::error::{Error, Result};
use crate::geometry::{Geometry, Overlap};
use crate::instrument::Instrument;
use crate::loaded::{self, LoadedConfig};
use crate::signal::{BeamPath, BinMultipleScattering};
use crate::snr;

/// Memory the deterministic model holds per range bin beyond its slabs
/// ([`MODEL_BYTES_PER_SLAB`]), bytes: the expected profile and truth by species (~31 f64),
/// the detector's means and the CSV's columns. Measured (heaptrack of `expect --csv` on
/// scenario 1 at `bin_width_s` 2e-9, 1.33e5 bins: 150.9 MB at the peak, of which the
/// 1.15e6 slabs' 101 MB): 375 bytes a bin, rounded up.
pub const MODEL_BYTES_PER_BIN: f64 = 450.0;
/// Memory per slab of the beam path (`signal::Segment`, 11 f64, and its altitude edge
/// while the path is laid), bytes: 96, rounded up. A window's slabs are at least four per
/// bin over the whole path, the atmosphere above a space-borne window included (8.6 per
/// bin for scenario 1's 40 km window under its 86 km atmosphere). Peak RSS of
/// `/usr/bin/time -v lidarsim expect configs/paper/scenario1.toml --set
/// instrument.bin_width_s=1e-10 --set acquisition.top_altitude_km=40 --csv big.csv`
/// (2.67e6 bins, 2.29e7 slabs): 2.91 GB, 3.5 GB estimated; 5.27 GB before the model's
/// bins were taken a piece at a time into vectors of their final size.
pub const MODEL_BYTES_PER_SLAB: f64 = 100.0;

/// The model's memory for `bins` range bins along a path of `slabs` slabs, bytes.
pub fn model_bytes(bins: f64, slabs: f64) -> f64 {
    bins * MODEL_BYTES_PER_BIN + slabs * MODEL_BYTES_PER_SLAB
}

/// Everything the deterministic model needs, built from one validated config.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The configuration it came from.
    pub loaded: LoadedConfig,
    /// Eq. 2–3 instrument figures.
    pub instrument: Instrument,
    /// Bins and beam geometry.
    pub geometry: Geometry,
    /// The atmosphere.
    pub atmosphere: Atmosphere,
    /// The atmosphere laid along the beam.
    pub path: BeamPath,
    /// The receiver channel this scenario computes (its name in the file).
    pub channel_name: String,
}

/// The whole lidar: one [`Scenario`] per receiver channel (`[[instrument.channels]]`),
/// all on the same geometry, atmosphere and seed.
#[derive(Debug, Clone)]
pub struct Lidar {
    /// The channels, in the config's order.
    pub channels: Vec<Scenario>,
}

impl Lidar {
    /// Loads `path` with `overrides` and builds every channel.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Self> {
        Self::from_loaded(loaded::load(path, overrides)?)
            .map_err(|e| config::attribute_to_override(e, overrides))
    }

    /// Builds every channel of a loaded config.
    pub fn from_loaded(loaded: LoadedConfig) -> Result<Self> {
        let channels = (0..loaded.channels.len())
            .map(|k| Scenario::from_loaded(loaded.for_channel(k)))
            .collect::<Result<Vec<_>>>()?;
        Ok(Lidar { channels })
    }

    /// The channel whose photons channel `k` records, for its seed: itself, or for the
    /// photon-counting half of a `both` pair the analog half before it (the same draws
    /// from the same seed, so that both record the same photons).
    pub fn photon_source(&self, k: usize) -> usize {
        let c = &self.channels[k].loaded.channels[0];
        match c.glue_partner {
            Some(j) if j < k => j,
            _ => k,
        }
    }

    /// The first channel: the config, geometry and timing every channel shares.
    pub fn first(&self) -> &Scenario {
        &self.channels[0]
    }

    /// The deterministic model of every channel.
    pub fn expected(&self) -> Result<Vec<ExpectedProfile>> {
        self.channels.iter().map(Scenario::expected).collect()
    }

    /// The channels' names.
    pub fn channel_names(&self) -> Vec<String> {
        self.channels
            .iter()
            .map(|c| c.channel_name.clone())
            .collect()
    }

    /// What a run tells after it succeeds: the config's plausibility warnings (once,
    /// from the config every channel shares), the model's notes (a profile file
    /// continued with US76) and every channel's warning (rates beyond a photon
    /// counter's range).
    pub fn run_notes(&self, expected: &[ExpectedProfile]) -> Option<String> {
        let plausibility = self.first().loaded.config.plausibility_warnings();
        let note = self.first().atmosphere.molecules.continuation_note();
        let warnings = self.channels.iter().zip(expected).filter_map(|(c, e)| {
            let w = c.linear_range_warning(e)?;
            Some(if self.channels.len() > 1 {
                w.replacen(
                    "warning: ",
                    &format!("warning: channel {}: ", c.channel_name),
                    1,
                )
            } else {
                w
            })
        });
        let lines: Vec<String> = plausibility
            .into_iter()
            .chain(note)
            .chain(warnings)
            .collect();
        (!lines.is_empty()).then(|| lines.join("\n"))
    }
}

/// One bin of [`Scenario::expected`]'s model, before multiple scattering and the
/// detector.
struct ModelBin {
    altitude_m: f64,
    range_m: f64,
    point: Optics,
    state: MolecularState,
    overlap: f64,
    t2: f64,
    signal: f64,
    range_weight: f64,
    attenuated_backscatter: f64,
}

/// Expected counts per shot per bin and the atmosphere's truth at bin centres.
#[derive(Debug, Clone, Default)]
pub struct ExpectedProfile {
    /// Bin-centre altitude, m.
    pub altitude_m: Vec<f64>,
    /// Bin-centre range, m.
    pub range_m: Vec<f64>,
    /// The atmosphere's optics at the bin centre, by species (the point truth).
    pub point: Vec<Optics>,
    /// The molecular state at the bin centre.
    pub state: Vec<MolecularState>,
    /// Overlap η(r) at the bin centre.
    pub overlap: Vec<f64>,
    /// Two-way transmission to the bin centre (multiple-scattering factors applied).
    pub t2: Vec<f64>,
    /// Expected signal counts per shot (exact bin integral of Eq. 2).
    pub signal: Vec<f64>,
    /// Range weight `∫_bin η(r)/r² dr`, m⁻¹.
    pub range_weight: Vec<f64>,
    /// Bin-averaged attenuated backscatter `∫η β T² r⁻² dr / ∫η r⁻² dr`, m⁻¹ sr⁻¹, so
    /// that `signal = C · attenuated_backscatter · range_weight`; 0 where the range
    /// weight is 0 (no overlap).
    pub attenuated_backscatter: Vec<f64>,
    /// Expected background counts per shot per bin (Eq. 3).
    pub background: f64,
    /// Expected dark counts per shot per bin.
    pub dark: f64,
    /// Expected recorded counts per shot per bin after the detector (dead time); the
    /// total `λ_i` for an ideal detector.
    pub recorded: Vec<f64>,
    /// Expected signal-induced counts per shot per bin (`src/detector/induced.rs`); empty
    /// when the detector has none.
    pub induced: Vec<f64>,
    /// Expected afterpulses per shot per bin (`src/detector/afterpulse.rs`), included in
    /// `recorded`; empty when the detector has none.
    pub afterpulse: Vec<f64>,
    /// The small-angle multiple scattering of each bin (`multiple_scattering.model =
    /// "small_angle"`), already in `signal` and `attenuated_backscatter`; empty in the
    /// `constant` model.
    pub multiple_scattering: Vec<BinMultipleScattering>,
    /// Signal-free bins used to estimate the background (0 = none available).
    pub background_bins: usize,
    /// Their indices: bins of the window lying wholly above the atmosphere, nearest the
    /// atmosphere first, at most `acquisition.background_bins` of them.
    pub background_bin_indices: Vec<usize>,
}

/// Bins of [`Scenario::expected`]'s model computed at once (their [`ModelBin`]s held
/// until taken into the profile): 64 Ki bins, ~17 MB.
const MODEL_PIECE_BINS: usize = 1 << 16;

impl ExpectedProfile {
    /// Room for `n` bins in each per-bin vector the model fills, exactly (no vector
    /// grows past the window by doubling).
    fn reserve_exact(&mut self, n: usize) {
        self.altitude_m.reserve_exact(n);
        self.range_m.reserve_exact(n);
        self.point.reserve_exact(n);
        self.state.reserve_exact(n);
        self.overlap.reserve_exact(n);
        self.t2.reserve_exact(n);
        self.signal.reserve_exact(n);
        self.range_weight.reserve_exact(n);
        self.attenuated_backscatter.reserve_exact(n);
    }

    /// Takes bin `b` of the model as the next bin.
    fn push_bin(&mut self, b: ModelBin) {
        self.altitude_m.push(b.altitude_m);
        self.range_m.push(b.range_m);
        self.point.push(b.point);
        self.state.push(b.state);
        self.overlap.push(b.overlap);
        self.t2.push(b.t2);
        self.signal.push(b.signal);
        self.range_weight.push(b.range_weight);
        self.attenuated_backscatter.push(b.attenuated_backscatter);
    }

    /// Number of bins.
    pub fn n_bins(&self) -> usize {
        self.signal.len()
    }

    /// Bin `i`'s small-angle multiple scattering (ratio 1 in the `constant` model).
    pub fn multiple_scattering_at(&self, i: usize) -> BinMultipleScattering {
        self.multiple_scattering
            .get(i)
            .copied()
            .unwrap_or(BinMultipleScattering::NONE)
    }

    /// Expected total counts per shot in each bin, `λ_i = λ_sig,i + λ_bkg + λ_dc` (Eq. 1).
    pub fn total_per_shot(&self) -> Vec<f64> {
        self.photon_signal()
            .iter()
            .map(|s| s + self.background + self.dark)
            .collect()
    }

    /// What of the photons per shot scales with the pulse energy: the backscattered
    /// signal, plus the signal-induced counts where the detector has them
    /// ([`induced`](Self::induced)). The samplers draw this as the signal.
    pub fn photon_signal(&self) -> std::borrow::Cow<'_, [f64]> {
        if self.induced.is_empty() {
            return std::borrow::Cow::Borrowed(&self.signal);
        }
        std::borrow::Cow::Owned(
            self.signal
                .iter()
                .zip(&self.induced)
                .map(|(s, i)| s + i)
                .collect(),
        )
    }

    /// Eq. 4 S/N of each bin after `shots` shots.
    pub fn snr_eq4(&self, shots: f64) -> Vec<f64> {
        self.signal
            .iter()
            .map(|&s| snr::eq4(s, self.background, self.dark, shots))
            .collect()
    }

    /// S/N with the background estimated from `background_bins` bins; `None` when there are none.
    pub fn snr_estimated_background(&self, shots: f64) -> Option<Vec<f64>> {
        (self.background_bins > 0).then(|| {
            self.signal
                .iter()
                .map(|&s| {
                    snr::with_estimated_background(
                        s,
                        self.background,
                        self.dark,
                        shots,
                        self.background_bins,
                    )
                })
                .collect()
        })
    }
}

impl Scenario {
    /// Loads `path` with `overrides` and builds the scenario.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Self> {
        Self::from_loaded(loaded::load(path, overrides)?)
            .map_err(|e| config::attribute_to_override(e, overrides))
    }

    /// Builds the scenario of a loaded single-channel config (see [`Lidar`] for several
    /// channels).
    pub fn from_loaded(loaded: LoadedConfig) -> Result<Self> {
        let file = loaded.file_label();
        if loaded.channels.len() != 1 {
            return Err(Error::config(
                &file,
                "instrument.channels",
                format!(
                    "lists {} channels: build it as a Lidar, one Scenario per channel",
                    loaded.channels.len()
                ),
            ));
        }
        let channel_name = loaded.channels[0].name.clone();
        let cfg = &loaded.config;
        let geometry = Geometry::from_config(cfg, &file)?;
        let bins = geometry.n_bins as f64;
        // a first look before the atmosphere is built (at least four slabs per bin)
        crate::resources::require_memory(
            &format!("the model of {bins} range bins"),
            model_bytes(bins, 4.0 * bins),
        )?;
        let mut atmosphere = Atmosphere::from_config(&loaded)?;
        let channel = &loaded.channels[0];
        let instrument = Instrument::from_config(cfg, atmosphere.detected_line())
            .recording(channel.record, channel.detector())
            .with_afterpulsing(channel.detector());
        // at least four slabs per bin, so that the piecewise representation resolves every bin
        let lowest = cfg.acquisition.bottom_altitude_km * 1e3;
        atmosphere.grid_m = atmosphere
            .grid_m
            .min(geometry.bin_range_m * geometry.local_cos_at(lowest) / 4.0);
        let overlap = Overlap::from_config(cfg);
        if overlap.sees_zero_range() && geometry.window_start_range_m <= 0.0 {
            return Err(Error::config(
                &file,
                "acquisition.bottom_altitude_km",
                "the first bin starts at the instrument (range 0) where 1/r² diverges; raise the window \
                 or set instrument.overlap (e.g. { model = \"full_range\", full_overlap_m = 300 })",
            ));
        }
        let surface = cfg
            .surface
            .as_ref()
            .map(crate::surface::Surface::from_config);
        if cfg.multiple_scattering.model != MultipleScatteringModel::Constant
            && atmosphere.raman.is_some()
        {
            return Err(Error::config(
                &file,
                "multiple_scattering.model",
                format!(
                    "models the elastic return; channel {channel_name} is a Raman channel: use \
                     \"constant\" (each layer's multiple_scattering factor)"
                ),
            ));
        }
        let (z_lo, z_hi) = BeamPath::altitude_span(&atmosphere, &geometry, surface.as_ref());
        // the grid's slabs, split further at each layer edge and profile top
        let edges = 8.0 + 2.0 * atmosphere.layers.len() as f64;
        let slabs = ((z_hi - z_lo) / atmosphere.grid_m).max(0.0) + edges;
        crate::resources::require_memory(
            &format!(
                "the model of {bins} range bins ({} slabs of the beam path)",
                crate::error::compact(slabs.round())
            ),
            model_bytes(bins, slabs),
        )?;
        let path = BeamPath::new(&atmosphere, &geometry, overlap, surface);
        let sc = Scenario {
            loaded,
            instrument,
            geometry,
            atmosphere,
            path,
            channel_name,
        };
        sc.check_pulses_in_flight(&file)?;
        if let Some(asked) = sc.loaded.config.acquisition.background_bins {
            let available = sc.signal_free_bins().len();
            if asked > available {
                return Err(Error::config(
                    &file,
                    "acquisition.background_bins",
                    format!(
                        "asks for {} signal-free bins, the window holds {available} (pre-trigger \
                         bins and bins above the atmosphere; raise acquisition.top_altitude_km or \
                         acquisition.pretrigger_bins, or omit the key to use them all)",
                        crate::error::compact(asked as f64)
                    ),
                ));
            }
        }
        Ok(sc)
    }

    /// Refuses a space-borne repetition rate at which another pulse's returns (from the
    /// top of the atmosphere down to the surface echo) reach the recording window
    /// (docs/model.md §3, [`crate::geometry::clean_windows_max_rep_rate_hz`]).
    fn check_pulses_in_flight(&self, file: &str) -> Result<()> {
        let g = &self.geometry;
        if g.kind != crate::config::PlatformKind::Spaceborne {
            return Ok(());
        }
        let ground_m = self
            .loaded
            .config
            .surface
            .as_ref()
            .map_or(0.0, |s| s.altitude_km * 1e3);
        let top_m = self.atmosphere.top_m().min(g.platform_altitude_m);
        let window = (g.first_bin_range_m(), g.max_range_m());
        // the returns that matter: from the window's top (or the atmosphere's, if lower)
        // down to the ground; the thin air above a window that starts inside the
        // atmosphere returns far less than the window's own scene and is not counted
        let first_return_m = g.range_at_altitude(top_m).max(window.0);
        let last_return_m = g.range_at_altitude(ground_m);
        let max_hz =
            crate::geometry::clean_windows_max_rep_rate_hz((first_return_m, last_return_m), window);
        let fl = self.instrument.rep_rate_hz;
        if fl <= max_hz {
            return Ok(());
        }
        Err(Error::config(
            file,
            "instrument.rep_rate_hz",
            format!(
                "at {fl} Hz the returns of another pulse (from {:.0} km range down to the \
                 ground) reach the recording window ({:.0}-{:.0} km range); at most {:.0} Hz \
                 keeps every window clean (several pulses in flight are fine below it)",
                first_return_m / 1e3,
                window.0 / 1e3,
                window.1 / 1e3,
                max_hz.floor()
            ),
        ))
    }

    /// The signal-free bins, which measure the background alone: the pre-trigger bins
    /// first (in order), then the window's bins lying wholly above the atmosphere,
    /// nearest the atmosphere first.
    pub fn signal_free_bins(&self) -> Vec<usize> {
        let g = &self.geometry;
        let top = self.atmosphere.top_m();
        let mut above: Vec<usize> = (g.pretrigger_bins..g.n_bins)
            .filter(|&i| {
                let (ra, rb) = g.bin_range_bounds(i);
                g.altitude_at_range(ra).min(g.altitude_at_range(rb)) >= top
            })
            .collect();
        let altitude = |i: usize| g.altitude_at_range(g.bin_centre_range_m(i));
        above.sort_by(|&a, &b| altitude(a).total_cmp(&altitude(b)));
        (0..g.pretrigger_bins).chain(above).collect()
    }

    /// The bins a retrieval estimates the background from: the signal-free bins, at most
    /// `acquisition.background_bins` of them (checked against those available when the
    /// scenario is built).
    pub fn background_bin_indices(&self) -> Vec<usize> {
        let mut bins = self.signal_free_bins();
        if let Some(cap) = self.loaded.config.acquisition.background_bins {
            bins.truncate(cap);
        }
        bins
    }

    /// The warning for a scene without dead time that counts beyond a photon counter's
    /// linear range, or for an analog record that leaves its law (noise below one code,
    /// clipping: `Analog::clipping_warning`); the commands print it after a successful
    /// run, so that an error stays one line.
    pub fn linear_range_warning(&self, e: &ExpectedProfile) -> Option<String> {
        if let Some(a) = &self.instrument.analog {
            return a.clipping_warning(&e.total_per_shot(), &e.altitude_m);
        }
        if self.instrument.dead_time.is_some() {
            return None;
        }
        crate::detector::linear_range_warning(
            &e.total_per_shot(),
            &e.altitude_m,
            self.instrument.bin_width_s,
        )
    }

    /// Accumulation time TC of one profile, s.
    pub fn accumulation_time_s(&self) -> f64 {
        self.loaded.config.acquisition.accumulation_time_s
    }

    /// Shots per profile `M = round(fL·TC)`.
    pub fn shots_per_profile(&self) -> u64 {
        self.instrument
            .shots_per_profile(self.accumulation_time_s())
    }

    /// The deterministic model: per-bin expectations and truth (docs/config.md `expect`).
    pub fn expected(&self) -> Result<ExpectedProfile> {
        let g = &self.geometry;
        let n = g.n_bins;
        let mut e = ExpectedProfile {
            background: self.instrument.background_per_bin,
            dark: self.instrument.dark_per_bin,
            ..Default::default()
        };
        e.reserve_exact(n);
        for i in 0..g.pretrigger_bins {
            self.push_pretrigger_bin(&mut e, g.bin_centre_range_m(i));
        }
        // the bins are independent: computed in parallel a piece at a time, taken in order
        // (the first bad bin's error, as a loop would give it); only a piece's bins are
        // held twice, not the window's
        for start in (g.pretrigger_bins..n).step_by(MODEL_PIECE_BINS) {
            let bins: Vec<Result<ModelBin>> = (start..(start + MODEL_PIECE_BINS).min(n))
                .into_par_iter()
                .with_min_len(256)
                .map(|i| self.model_bin(i))
                .collect();
            for bin in bins {
                e.push_bin(bin?);
            }
        }
        self.add_multiple_scattering(&mut e);
        let detector = self.loaded.config.instrument.detector.as_ref();
        if let Some(sin) = detector.and_then(|d| d.signal_induced_noise.as_ref()) {
            let power_law = matches!(
                sin,
                crate::config::SignalInducedNoiseConfig::PowerLaw { .. }
            );
            let most = crate::detector::induced::MAX_POWER_LAW_BINS;
            if power_law && n > most {
                return Err(Error::config(
                    self.loaded.file_label(),
                    "instrument.detector.signal_induced_noise.model",
                    format!(
                        "\"power_law\" convolves the signal directly, in time growing as the \
                         square of the bins: at most {most} bins, the window has {n}; use \
                         \"exponential\" (any number of bins) or fewer bins"
                    ),
                ));
            }
            e.induced = sin.induced_counts(&e.signal, self.instrument.bin_width_s);
        }
        e.recorded = match &self.instrument.dead_time {
            Some(d) if self.instrument.pulse_energy_jitter > 0.0 => {
                let laser = crate::laser::PulseEnergy::from_config(&self.loaded.config.instrument);
                d.recorded_moments(&e.photon_signal(), e.background + e.dark, &laser)
                    .0
            }
            Some(d) => d.recorded_means(&e.total_per_shot()),
            None => match &self.instrument.analog {
                // the mean code is linear in the photoelectrons: jitter leaves it
                Some(a) => a.expected_codes(&e.total_per_shot()),
                None => e.total_per_shot(),
            },
        };
        if let Some(ap) = &self.instrument.afterpulsing {
            e.afterpulse = ap.expected(&e.recorded);
            e.recorded
                .iter_mut()
                .zip(&e.afterpulse)
                .for_each(|(r, a)| *r += a);
        }
        e.background_bin_indices = self.background_bin_indices();
        e.background_bins = e.background_bin_indices.len();
        check_finite(&e)?;
        Ok(e)
    }

    /// The model of bin `i` (past the pre-trigger bins): Eq. 2's bin integral and the
    /// truth at the bin centre.
    fn model_bin(&self, i: usize) -> Result<ModelBin> {
        let g = &self.geometry;
        let (ra, rb) = g.bin_range_bounds(i);
        let r = g.bin_centre_range_m(i);
        let z = g.altitude_at_range(r);
        // below the surface the beam does not go: no optics there (t2 stays the
        // surface's), the molecular state that of the atmosphere continued
        let point = if r <= self.path.end_range_m() {
            self.atmosphere.optics_at(z)
        } else {
            self.atmosphere.no_optics()
        };
        let integral = self.path.bin_integral(ra, rb)?;
        let signal = self.instrument.signal_constant * integral;
        let weight = self.path.range_weight(ra, rb);
        if !signal.is_finite() {
            return Err(Error::Unsupported(format!(
                "bin {i} (altitude {z:.0} m): the signal is not finite"
            )));
        }
        Ok(ModelBin {
            altitude_m: z,
            range_m: r,
            point,
            state: self.atmosphere.state_at(z),
            overlap: self.path.overlap().eta(r),
            t2: self.path.two_way_transmission(r),
            signal,
            range_weight: weight,
            attenuated_backscatter: if weight > 0.0 { integral / weight } else { 0.0 },
        })
    }

    /// Multiplies each bin's signal and attenuated backscatter by its multiple-scattering
    /// ratio ([`BeamPath::multiple_scattering_bins`]) when the config asks for the
    /// `small_angle` or `small_and_wide_angle` model.
    fn add_multiple_scattering(&self, e: &mut ExpectedProfile) {
        let cfg = &self.loaded.config;
        if cfg.multiple_scattering.model == MultipleScatteringModel::Constant {
            return;
        }
        let footprint = Footprint {
            divergence_rad: cfg.instrument.beam_divergence_rad.unwrap_or(0.0),
            fov_half_angle_rad: cfg.instrument.fov_rad / 2.0,
        };
        let g = &self.geometry;
        let bins: Vec<(f64, f64)> = (g.pretrigger_bins..g.n_bins)
            .map(|i| g.bin_range_bounds(i))
            .collect();
        e.multiple_scattering = vec![BinMultipleScattering::NONE; g.pretrigger_bins];
        e.multiple_scattering
            .extend(self.path.multiple_scattering_bins(
                footprint,
                &bins,
                cfg.multiple_scattering.model == MultipleScatteringModel::SmallAndWideAngle,
            ));
        for (i, m) in e.multiple_scattering.iter().enumerate() {
            e.signal[i] *= m.ratio;
            e.attenuated_backscatter[i] *= m.ratio;
        }
        self.depolarize_water_clouds(e);
    }

    /// Gives each water cloud's apparent return the depolarization of Hu et al. (2006)
    /// (`multiple_scattering::water_cloud_depolarization`, docs/model.md §4j): the
    /// channel sees the cloud's apparent return in every polarization with that
    /// depolarization instead of the droplets' own (`depolarization`, kept where it is
    /// larger); the air's part keeps its own. The cloud's apparent return in every
    /// polarization, `W_i`, is the bin's own (`BinMultipleScattering::cloud_apparent`),
    /// the same for every channel, never the channel's return divided by its share of
    /// the droplets' own depolarization: that share is 0 for a perpendicular channel
    /// without cross-talk under droplets of δ = 0, whose multiply scattered light the
    /// channel does see. The channel's return becomes
    /// `old − W_i·share(δ_own) + W_i·share(δ_i)`.
    fn depolarize_water_clouds(&self, e: &mut ExpectedProfile) {
        let g = &self.geometry;
        let share = |d: f64| {
            self.atmosphere
                .polarization
                .share(self.atmosphere.channel, d)
        };
        let particle_line = self.atmosphere.lines.particle;
        let mut k = g.pretrigger_bins;
        while k < g.n_bins {
            if e.point[k].alpha_water <= 0.0 {
                k += 1;
                continue;
            }
            let start = k;
            while k < g.n_bins && e.point[k].alpha_water > 0.0 {
                k += 1;
            }
            // the cloud's multiple scattering in every polarization, alike for every
            // channel (a channel's own ratio weights a bin across the cloud's base by
            // its own mix of cloud and air)
            let before = e
                .multiple_scattering_at(start.saturating_sub(1))
                .total_ratio;
            let (mut single, mut apparent, mut tau, mut whole) = (vec![], vec![], vec![], vec![]);
            let mut depth = 0.0;
            for i in start..k {
                let (ra, rb) = g.bin_range_bounds(i);
                let half = 0.5 * e.point[i].alpha_water * (rb - ra);
                tau.push(depth + half);
                depth += 2.0 * half;
                // the clouds' own return in every polarization, bin-averaged, through
                // the channel's particle line: alike for every channel
                let m = &e.multiple_scattering[i];
                whole.push(particle_line * m.cloud_apparent);
                single.push(m.cloud_single);
                apparent.push(m.cloud_apparent / before);
            }
            let delta = multiple_scattering::water_cloud_depolarization(&single, &apparent, &tau);
            for ((i, d), w) in (start..k).zip(delta).zip(whole) {
                let own = e.point[i].depol_cld();
                let d = d.max(own);
                let old = e.attenuated_backscatter[i];
                // the channel's return less the cloud's part of it, plus the cloud's
                // apparent return with its new depolarization
                let new = (old - w * share(own)).max(0.0) + w * share(d);
                let factor = if old > 0.0 {
                    new / old
                } else if new > 0.0 {
                    f64::INFINITY // the channel saw none of the cloud's single scattering
                } else {
                    1.0
                };
                e.signal[i] = if old > 0.0 {
                    e.signal[i] * factor
                } else {
                    self.instrument.signal_constant * e.range_weight[i] * new
                };
                e.attenuated_backscatter[i] = new;
                e.multiple_scattering[i].water_depolarization = d;
                e.multiple_scattering[i].polarization_factor = factor;
            }
        }
    }

    /// A pre-trigger bin at (negative) range `r_m`: recorded before the pulse leaves, it
    /// sees nothing: no signal, no optics, η = 0, T² = 1, and the molecular state of the
    /// air at the station (docs/file-format.md "Pre-trigger bins").
    fn push_pretrigger_bin(&self, e: &mut ExpectedProfile, r_m: f64) {
        let station_m = self.geometry.platform_altitude_m;
        e.altitude_m.push(self.geometry.altitude_at_range(r_m));
        e.range_m.push(r_m);
        e.point.push(self.atmosphere.no_optics());
        e.state.push(self.atmosphere.state_at(station_m));
        e.overlap.push(0.0);
        e.t2.push(1.0);
        e.signal.push(0.0);
        e.range_weight.push(0.0);
        e.attenuated_backscatter.push(0.0);
    }
}

/// No expectation that is not finite reaches a sampler or a file: the first bin whose
/// signal, induced noise, afterpulses, recorded mean or attenuated backscatter is NaN or
/// infinite (or a background or dark rate that is) is a clear error instead.
fn check_finite(e: &ExpectedProfile) -> Result<()> {
    for (what, rate) in [("background", e.background), ("dark", e.dark)] {
        if !rate.is_finite() {
            return Err(Error::Unsupported(format!(
                "the expected {what} counts per bin are not finite ({rate})"
            )));
        }
    }
    let rows: [(&str, &[f64]); 5] = [
        ("signal", &e.signal),
        ("signal-induced noise", &e.induced),
        ("afterpulses", &e.afterpulse),
        ("recorded mean", &e.recorded),
        ("attenuated backscatter", &e.attenuated_backscatter),
    ];
    for (what, row) in rows {
        if let Some(i) = row.iter().position(|v| !v.is_finite()) {
            let z = e.altitude_m.get(i).copied().unwrap_or(f64::NAN);
            return Err(Error::Unsupported(format!(
                "bin {i} (altitude {z:.0} m): the expected {what} is not finite ({}); \
                 a model gave no number there",
                row[i]
            )));
        }
    }
    Ok(())
}
