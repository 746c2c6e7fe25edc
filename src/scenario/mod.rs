//! A scenario ready to compute: the config turned into instrument, geometry,
//! atmosphere and beam path, and its expected per-bin counts (the `expect` model).
//! Here: one channel's [`Scenario`] built and checked, and the whole [`Lidar`].

mod expected;
mod model;

pub use expected::{ExpectedProfile, MODEL_BYTES_PER_BIN, model_bytes};

use std::path::Path;

use crate::atmosphere::Atmosphere;
use crate::config::{self, MultipleScatteringModel};
use crate::error::{Error, Result};
use crate::geometry::{Geometry, Overlap};
use crate::instrument::Instrument;
use crate::loaded::{self, LoadedConfig};
use crate::signal::{BeamPath, PathExtent};

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
        let extent = PathExtent::for_model(cfg.multiple_scattering.model);
        // a first look before the atmosphere is built (at least four slabs per bin)
        crate::resources::require_memory(
            &format!("the model of {bins} range bins"),
            model_bytes(
                bins,
                crate::signal::PathBytes {
                    kept: 4.0 * bins * PathExtent::Bins.bytes_per_segment(),
                    ..Default::default()
                },
            ),
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
        let path_bytes =
            crate::signal::laying_bytes(&atmosphere, &geometry, surface.as_ref(), extent);
        crate::resources::require_memory(
            &format!(
                "the model of {bins} range bins ({} slabs of the beam path)",
                crate::error::compact(path_bytes.slabs.round())
            ),
            model_bytes(bins, path_bytes),
        )?;
        let path = BeamPath::new(&atmosphere, &geometry, overlap, surface, extent);
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
}
