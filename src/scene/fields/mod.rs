//! Model fields as the scene (`[scene.model_fields]`, docs/scenes.md "Model fields"):
//! a model's temperature, pressure, humidity and cloud water on a regular
//! latitude–longitude grid with model levels (hybrid a/b with surface pressure),
//! pressure levels or heights, read from CF netCDF-4 or netCDF-3 files.
//!
//! Each profile samples the fields at the time and sub-satellite point of its middle
//! (bilinear in latitude and longitude, linear in time; or the nearest point and time),
//! level by level ([`grid`]); its levels become the layers of one segment of the track,
//! as long as the profile's stretch of it, with the optics of `atmosphere::cloud_optics`.
//! With `subcolumns = n > 1` (default 10) the profile's stretch is cut into up to n
//! sub-segments, the [`subcolumns`] of its cloud fraction by maximum-random overlap,
//! each cloudy level holding the in-cloud water q/C, the profile's shots spread evenly
//! over them (identical subcolumns merged); with 1, the grid-box mean water over the
//! whole box. With `aerosol_optics` (ECMWF's table), each level's CAMS species make an
//! aerosol layer in every subcolumn ([`aerosol::FieldAerosol::layers`], docs/model.md §4l), replacing
//! the config's background aerosol. The segments are the same scene as a curtain's: the
//! truth, shards, onboard and validate see columns.

pub mod aerosol;
pub mod column;
pub mod grid;
pub mod names;
pub mod read;
pub mod reader;
pub mod slab;
pub mod subcolumns;

use std::path::PathBuf;

use crate::atmosphere::cloud_optics::{
    air_density, extinction_per_m, ice_effective_radius_um, phase_optics,
};

use crate::config::{
    CloudPhase, FieldsMolecules, LayerConfig, LayerKind, ModelFieldsConfig, MolecularModel,
    ScenarioConfig, SegmentAerosol, SegmentConfig, WaterVapourConfig,
};
use crate::error::{Error, Result};
use crate::scene::track::AlongTrack;

pub use column::FieldColumn;
pub use read::Sample;

/// Where profile `p` of `profiles` samples the fields (under the orbit at its middle
/// time, or over a ground station: `platform.latitude_deg`/`longitude_deg` at every
/// time), with the along-track span of its segment (a ground scene's: the advection
/// speed times its duration): from half a shot before its first shot to half a shot before the next
/// profile's (so no shot sits on a boundary); the first starts at 0.
pub fn profile_samples(
    cfg: &ScenarioConfig,
    track: &AlongTrack,
    shots_per_profile: u64,
    profiles: u64,
) -> Result<Vec<(Sample, f64)>> {
    let start = humantime::parse_rfc3339(&cfg.acquisition.start_time)
        .map_err(|e| Error::Unsupported(format!("acquisition.start_time: {e}")))?;
    let start_s = start
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64());
    let shot_s = 1.0 / cfg.instrument.rep_rate_hz;
    let profile_s = shots_per_profile as f64 * shot_s;
    let edge = |p: u64| {
        if p == 0 {
            0.0
        } else {
            track.at(p as f64 * profile_s - 0.5 * shot_s)
        }
    };
    let station = (cfg.platform.latitude_deg, cfg.platform.longitude_deg);
    let position = |t_s: f64| match (track, station) {
        (AlongTrack::Orbit(o), _) => {
            let g = o.position(t_s);
            Ok((g.latitude_deg, g.longitude_deg))
        }
        (AlongTrack::Speed(_), (Some(lat), Some(lon))) => Ok((lat, lon)),
        (AlongTrack::Speed(_), _) => Err(Error::Unsupported(
            "model fields over a ground lidar need platform.latitude_deg and \
             platform.longitude_deg"
                .into(),
        )),
    };
    (0..profiles)
        .map(|p| {
            let mid = (p as f64 + 0.5) * profile_s;
            let (latitude_deg, longitude_deg) = position(mid)?;
            let sample = Sample {
                time_s: start_s + mid,
                latitude_deg,
                longitude_deg,
            };
            Ok((sample, (edge(p + 1) - edge(p)) / 1e3))
        })
        .collect()
}

/// The layers of one column: a water cloud layer per level with liquid, an ice cloud
/// layer per level with ice, each over the level's layer of the column.
pub fn layers(m: &ModelFieldsConfig, c: &FieldColumn) -> Vec<LayerConfig> {
    layers_where(m, c, |_| Some(1.0))
}

/// [`layers`] of a subcolumn: level k (bottom up) holds `in_cloud(k)` times its water,
/// or none where `None`.
fn layers_where(
    m: &ModelFieldsConfig,
    c: &FieldColumn,
    in_cloud: impl Fn(usize) -> Option<f64>,
) -> Vec<LayerConfig> {
    let mut out = Vec::new();
    for (k, l) in c.levels.iter().enumerate() {
        let Some(factor) = in_cloud(k) else { continue };
        let rho = air_density(l.p_pa, l.t_k, l.q);
        let (base_km, top_km) = (c.interfaces_m[k] / 1e3, c.interfaces_m[k + 1] / 1e3);
        let water = l.liquid_radius_um.unwrap_or(m.liquid_effective_radius_um);
        let ice = l
            .ice_radius_um
            .unwrap_or_else(|| ice_effective_radius_um(l.t_k));
        for (phase, q, r_e) in [
            (CloudPhase::Water, l.liquid * factor, water),
            (CloudPhase::Ice, l.ice * factor, ice),
        ] {
            if q <= 0.0 {
                continue;
            }
            let alpha = extinction_per_m(phase, q, rho, r_e, m.extinction_efficiency) * 1e3;
            let (lidar_ratio_sr, default_depolarization) = phase_optics(phase);
            let depolarization = match phase {
                CloudPhase::Water => m.liquid_depolarization,
                CloudPhase::Ice => m.ice_depolarization,
            }
            .unwrap_or(default_depolarization);
            out.push(LayerConfig {
                kind: LayerKind::Cloud,
                base_km,
                top_km,
                extinction_per_km: alpha.min(1e4),
                lidar_ratio_sr,
                depolarization,
                multiple_scattering: 1.0,
                phase: Some(phase),
                effective_radius_um: Some(r_e),
                asymmetry_factor: None,
                angstrom_exponent: None,
                reference_wavelength_nm: None,
                lidar_ratio_sr_by_wavelength: Default::default(),
                cloud_fraction: None,
                cell_length_km: None,
                species: None,
            });
        }
    }
    out
}

/// The segments of `cfg`'s model fields `m` (its `files`, resolved) along `track`,
/// a profile's [`profile_subcolumns`] for each of `profiles` profiles of
/// `shots_per_profile` shots, drawn from `seed` (the run's); a Raman channel's aerosol
/// also at its detected line `raman_line_nm`.
pub fn segments(
    cfg: &ScenarioConfig,
    m: &ModelFieldsConfig,
    files: &[PathBuf],
    track: &AlongTrack,
    (shots_per_profile, profiles): (u64, u64),
    seed: u64,
    raman_line_nm: Option<f64>,
) -> Result<Vec<SegmentConfig>> {
    let samples = profile_samples(cfg, track, shots_per_profile, profiles)?;
    let points: Vec<Sample> = samples.iter().map(|s| s.0).collect();
    let aerosol = match &m.aerosol_optics {
        Some(path) => Some(aerosol::FieldAerosol::read(
            path,
            aerosol_wavelength_m(cfg)?,
            raman_line_nm.map(|nm| nm * 1e-9),
            m.aerosol_depolarization,
        )?),
        None => None,
    };
    let mut out = Vec::new();
    // each column made into its segments as it is read, not kept
    let mut failed = None;
    read::for_each_column(
        m,
        files,
        &points,
        slab::MAX_SLAB_CELLS,
        |p, c| match column_segments(
            cfg,
            m,
            aerosol.as_ref(),
            &c,
            (p, samples[p].1),
            (seed, shots_per_profile),
        ) {
            Ok(s) => {
                out.extend(s);
                Ok(())
            }
            Err(e) => {
                failed = Some(e);
                Err((PathBuf::new(), String::new()))
            }
        },
    )
    .map_err(|(path, why)| failed.take().unwrap_or_else(|| Error::output(path, why)))?;
    Ok(out)
}

/// The segments of profile `p` (its column `c`, its stretch `length_km`): its
/// subcolumns, each with the profile's aerosol layers, surface and molecules.
fn column_segments(
    cfg: &ScenarioConfig,
    m: &ModelFieldsConfig,
    aerosol: Option<&aerosol::FieldAerosol>,
    c: &FieldColumn,
    (p, length_km): (usize, f64),
    (seed, shots_per_profile): (u64, u64),
) -> Result<Vec<SegmentConfig>> {
    let aerosol_layers = match aerosol {
        Some(a) => Some(
            a.layers(c)
                .map_err(|e| Error::Unsupported(format!("profile {p}: {e}")))?,
        ),
        None => None,
    };
    // the config's surface at the model's height
    let surface =
        cfg.surface
            .as_ref()
            .zip(c.surface_height_m)
            .map(|(s, z)| crate::config::SurfaceConfig {
                altitude_km: (z / 1e3).clamp(-0.5, 9.0),
                ..s.clone()
            });
    let (molecular, water_vapour) = match m.molecules {
        FieldsMolecules::Fields => (Some(molecules(c)), Some(water_vapour(c))),
        FieldsMolecules::Config => (None, None),
    };
    let segment = |length_km: f64, mut layers: Vec<LayerConfig>| SegmentConfig {
        length_km,
        aerosol: aerosol_layers.as_ref().map(|a| {
            layers.extend(a.iter().cloned());
            SegmentAerosol::Named("none".into())
        }),
        layers: Some(layers),
        surface: surface.clone(),
        water_vapour: water_vapour.clone(),
        molecular: molecular.clone(),
    };
    Ok(profile_subcolumns(m, c, seed, p as u64, shots_per_profile)
        .into_iter()
        .map(|(share, layers)| segment(length_km * share, layers))
        .collect())
}

/// The wavelength of the fields' aerosol, m: the config's laser's (each channel's
/// config carries its own `instrument.wavelength_nm`, so each channel's model has the
/// aerosol at its own wavelength).
fn aerosol_wavelength_m(cfg: &ScenarioConfig) -> Result<f64> {
    Ok(cfg.instrument.wavelength_nm * 1e-9)
}

/// The molecules of a column: its levels' heights, pressures and temperatures as a
/// profile table (N = p/(k_B·T) at each level, ln N and ln p linear in height between
/// levels, docs/model.md §4; above the model's top US76 continues it, scaled to match).
pub fn molecules(c: &FieldColumn) -> MolecularModel {
    MolecularModel::Table {
        altitude_km: c.levels.iter().map(|l| l.height_m / 1e3).collect(),
        pressure_hpa: c.levels.iter().map(|l| l.p_pa / 100.0).collect(),
        temperature_k: c.levels.iter().map(|l| l.t_k).collect(),
    }
}

/// The water vapour of a column for the H₂O Raman channels: the mass mixing ratio to dry
/// air `r = q/(1 − q)` of each level's specific humidity q, in g kg⁻¹.
pub fn water_vapour(c: &FieldColumn) -> WaterVapourConfig {
    WaterVapourConfig {
        altitude_km: c.levels.iter().map(|l| l.height_m / 1e3).collect(),
        mixing_ratio_g_per_kg: c.levels.iter().map(|l| 1e3 * l.q / (1.0 - l.q)).collect(),
    }
}

/// The subcolumns of profile `p` (its column `c`, `shots` shots), each with its share of
/// the profile's stretch (its share of the shots) and its layers: one with the grid-box
/// mean where `subcolumns` is 1 or no level is partly cloudy.
fn profile_subcolumns(
    m: &ModelFieldsConfig,
    c: &FieldColumn,
    seed: u64,
    p: u64,
    shots: u64,
) -> Vec<(f64, Vec<LayerConfig>)> {
    let partly = |l: &column::Level| {
        (l.liquid > 0.0 || l.ice > 0.0) && l.cloud_fraction > 0.0 && l.cloud_fraction < 1.0
    };
    let n = (m.subcolumns as u64).min(shots.max(1)) as usize;
    if n <= 1 {
        return vec![(1.0, layers(m, c))];
    }
    if !c.levels.iter().any(partly) {
        // every level overcast or clear: one subcolumn holds them all (water where the
        // cloud fraction is 0 makes no cloud, as in SCOPS)
        let overcast = |k: usize| (c.levels[k].cloud_fraction > 0.0).then_some(1.0);
        return vec![(1.0, layers_where(m, c, overcast))];
    }
    let top = c.levels.len() - 1;
    let fraction_top_down: Vec<f64> = c.levels.iter().rev().map(|l| l.cloud_fraction).collect();
    let mut masks = subcolumns::of_profile(&fraction_top_down, n, seed, p);
    // subcolumns are exchangeable: identical ones side by side make one segment
    masks.sort();
    let counts = subcolumns::shot_counts(shots, n);
    let mut groups: Vec<(Vec<bool>, u64)> = Vec::new();
    for (mask, count) in masks.into_iter().zip(counts) {
        match groups.last_mut() {
            Some((last, total)) if *last == mask => *total += count,
            _ => groups.push((mask, count)),
        }
    }
    groups
        .into_iter()
        .map(|(mask, count)| {
            let in_cloud = |k: usize| mask[top - k].then(|| 1.0 / c.levels[k].cloud_fraction);
            (count as f64 / shots as f64, layers_where(m, c, in_cloud))
        })
        .collect()
}

/// `cfg` with its model fields, if any, turned into segments: a profile's subcolumns
/// for each profile of `shots` shots, drawn from the run's `seed`.
pub fn with_model_fields(
    mut cfg: ScenarioConfig,
    loaded: &crate::loaded::LoadedConfig,
    track: &AlongTrack,
    (shots, profiles): (u64, u64),
    seed: u64,
) -> Result<ScenarioConfig> {
    let Some(m) = cfg.scene.as_mut().and_then(|s| s.model_fields.take()) else {
        return Ok(cfg);
    };
    let files: Vec<_> = m.files.iter().map(|f| loaded.resolve_path(f)).collect();
    for f in &files {
        crate::input_file::check("scene.model_fields.files", f)?;
    }
    let mut m = m;
    if let Some(t) = &m.aerosol_optics {
        let t = loaded.resolve_path(t);
        crate::input_file::check("scene.model_fields.aerosol_optics", &t)?;
        m.aerosol_optics = Some(t);
    }
    // a Raman channel's return sees the aerosol at its detected line
    let raman_line_nm = loaded
        .channels
        .first()
        .filter(|c| c.kind == crate::receiver::ChannelKind::Raman)
        .map(|c| c.detection_wavelength_nm());
    let segments = segments(
        &cfg,
        &m,
        &files,
        track,
        (shots, profiles),
        seed,
        raman_line_nm,
    )?;
    if let Some(s) = cfg.scene.as_mut() {
        s.segments = segments;
    }
    Ok(cfg)
}
