//! The orbit of a space-borne run.

use crate::error::{Error, Result};
use crate::scenario::Lidar;

/// The orbit of a space-borne run with `[orbit]`.
pub fn orbit_of(lidar: &Lidar) -> Result<Option<crate::scene::orbit::Orbit>> {
    let cfg = &lidar.first().loaded.config;
    cfg.orbit
        .as_ref()
        .map(|o| {
            crate::scene::orbit::Orbit::from_config(o, cfg.platform.altitude_km * 1e3)
                .map_err(|reason| Error::config(lidar.first().loaded.file_label(), "orbit", reason))
        })
        .transpose()
}
