//! `[acquisition]`: the range window, the accumulation and the time of the first shot.

use serde::{Deserialize, Serialize};

/// Range window and accumulation.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AcquisitionConfig {
    /// Accumulation time TC per profile, s.
    pub accumulation_time_s: f64,
    /// Top of the altitude window, km.
    pub top_altitude_km: f64,
    /// Bottom of the altitude window, km.
    pub bottom_altitude_km: f64,
    /// Number of profiles a simulation writes.
    #[serde(default = "one_usize")]
    pub profiles: usize,
    /// Signal-free bins a retrieval uses to estimate the background (model.md §2);
    /// absent = the bins of the window above the top of the atmosphere.
    #[serde(default)]
    pub background_bins: Option<usize>,
    /// Bins a ground recorder records before the pulse leaves (background and dark only),
    /// first in the bin grid, at negative range; 0 = none.
    #[serde(default)]
    pub pretrigger_bins: usize,
    /// UTC time of the first shot, RFC 3339 (`2004-03-21T00:00:00Z`): the origin of the
    /// raw file's CF `time`.
    #[serde(default = "default_start_time")]
    pub start_time: String,
}

fn one_usize() -> usize {
    1
}

fn default_start_time() -> String {
    DEFAULT_START_TIME.to_string()
}

/// Default `acquisition.start_time`.
pub const DEFAULT_START_TIME: &str = "2000-01-01T00:00:00Z";
