//! `[platform]`, `[orbit]`, `[scene]` (segments or a curtain) and `[surface]`: where the
//! lidar is, how it moves, and what lies along and below its track.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::atmosphere::{AerosolConfig, LayerConfig, WaterVapourConfig};
use super::defaults::yes;

/// Platform kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PlatformKind {
    /// Looking down from orbit (or aircraft).
    Spaceborne,
    /// Looking up from the ground.
    Ground,
}

/// Platform geometry.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PlatformConfig {
    /// Space-borne or ground-based.
    pub kind: PlatformKind,
    /// Platform altitude above sea level, km (space-borne: orbit; ground: station height).
    #[serde(default)]
    pub altitude_km: f64,
    /// Beam angle from nadir (space-borne) or from zenith (ground), degrees.
    #[serde(default)]
    pub off_nadir_deg: f64,
    /// A spherical Earth (default) or the paper's flat Earth for slanted beams.
    #[serde(default = "yes")]
    pub earth_curvature: bool,
    /// A ground station's latitude, degrees north (the SCC's `Latitude_degrees_north`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub latitude_deg: Option<f64>,
    /// A ground station's longitude, degrees east (the SCC's `Longitude_degrees_east`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub longitude_deg: Option<f64>,
}

/// A circular orbit (`src/scene/orbit.rs`, which checks it) at `platform.altitude_km`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OrbitConfig {
    /// Inclination, degrees (above 90: retrograde, e.g. 98.2 sun-synchronous).
    pub inclination_deg: f64,
    /// Latitude of the first shot, degrees north.
    #[serde(default)]
    pub start_latitude_deg: f64,
    /// Longitude of the first shot, degrees east.
    #[serde(default)]
    pub start_longitude_deg: f64,
    /// Moving north at the first shot (else south).
    #[serde(default = "yes")]
    pub ascending: bool,
}

/// The scene along the track (`src/scene/`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneConfig {
    /// Stretches of the track, in order from the first shot; the last continues to the
    /// end of the run.
    #[serde(default)]
    pub segments: Vec<SegmentConfig>,
    /// A tabulated curtain (along-track × altitude aerosol and cloud, `src/scene/curtain.rs`),
    /// relative to the config file; instead of `segments`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curtain: Option<PathBuf>,
    /// A model's fields along the orbit or over a ground station (`src/scene/fields/`),
    /// instead of `segments`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_fields: Option<super::model_fields::ModelFieldsConfig>,
    /// A ground lidar's scene: the speed at which the segments (and broken cells) pass
    /// over the station, m s⁻¹ (a frozen scene carried by the wind), so that a segment
    /// of `length_km` lasts `length_km·1000/speed` seconds. Space-borne: the ground
    /// track's speed instead; the key is refused.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub advection_speed_m_per_s: Option<f64>,
}

/// The speed a ground lidar's scene passes over the station without
/// `scene.advection_speed_m_per_s`, m s⁻¹ (ASSUMED: a mid-tropospheric wind).
pub const DEFAULT_ADVECTION_SPEED_M_PER_S: f64 = 10.0;

/// One stretch of the track with its own layers, aerosol and surface.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentConfig {
    /// Length along the track, km.
    pub length_km: f64,
    /// The layers of this stretch (replacing `[[atmosphere.layers]]`); absent = those.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layers: Option<Vec<LayerConfig>>,
    /// The background aerosol of this stretch (replacing `[atmosphere.aerosol]`), or
    /// `"none"`; absent = that of `[atmosphere]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aerosol: Option<SegmentAerosol>,
    /// The surface of this stretch (replacing `[surface]`); absent = that one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<SurfaceConfig>,
    /// The water vapour of this stretch (replacing `[atmosphere.water_vapour]`); absent
    /// = that one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub water_vapour: Option<WaterVapourConfig>,
    /// The molecules of this stretch (replacing `atmosphere.molecular.model`): `"us76"`,
    /// a profile file or a table; absent = that one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub molecular: Option<super::atmosphere::MolecularModel>,
}

/// A segment's aerosol: `"none"` or a whole `[atmosphere.aerosol]` table.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum SegmentAerosol {
    /// `"none"`: no background aerosol in this stretch.
    Named(String),
    /// This stretch's aerosol.
    Given(AerosolConfig),
}

/// A Lambertian surface (docs/model.md §4e, `src/surface.rs`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceConfig {
    /// What the surface is (sets the default albedo).
    #[serde(default)]
    pub kind: SurfaceKind,
    /// Lambertian reflectance ρ at the laser wavelength; absent = the kind's.
    #[serde(default)]
    pub albedo: Option<f64>,
    /// Altitude of the surface above sea level, km.
    #[serde(default)]
    pub altitude_km: f64,
}

/// Surface presets.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceKind {
    /// Open ocean.
    Ocean,
    /// Vegetated land (default).
    #[default]
    Land,
    /// Fresh snow.
    Snow,
}
