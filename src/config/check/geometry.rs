//! The checks of `[platform]` and `[acquisition]`: the beam angle, the window against the
//! platform, the shots per profile, the number of profiles and the start time.

use crate::config::scenario::ScenarioConfig;
use crate::config::scene::PlatformKind;
use crate::error::{Result, compact};
use crate::limits::MAX_PROFILES;

use super::Checker;

impl ScenarioConfig {
    pub(super) fn validate_geometry(&self, c: &Checker) -> Result<()> {
        let p = &self.platform;
        let a = &self.acquisition;
        c.range("platform.off_nadir_deg", p.off_nadir_deg, 0.0, 85.0)?;
        if let Some(lat) = p.latitude_deg {
            c.range("platform.latitude_deg", lat, -90.0, 90.0)?;
        }
        if let Some(lon) = p.longitude_deg {
            c.range("platform.longitude_deg", lon, -180.0, 180.0)?;
        }
        c.range(
            "acquisition.accumulation_time_s",
            a.accumulation_time_s,
            0.0,
            1e7,
        )?;
        let shots = a.accumulation_time_s * self.instrument.rep_rate_hz;
        if shots.round() < 1.0 {
            return Err(c.fail(
                "acquisition.accumulation_time_s",
                format!("accumulates {shots} shots at instrument.rep_rate_hz; a profile needs at least one"),
            ));
        }
        c.range("acquisition.top_altitude_km", a.top_altitude_km, -10.0, 1e5)?;
        c.range(
            "acquisition.bottom_altitude_km",
            a.bottom_altitude_km,
            -10.0,
            1e5,
        )?;
        if a.bottom_altitude_km >= a.top_altitude_km {
            return Err(c.fail(
                "acquisition.bottom_altitude_km",
                format!(
                    "must be below acquisition.top_altitude_km ({} km)",
                    a.top_altitude_km
                ),
            ));
        }
        if a.profiles == 0 || a.profiles as u64 > MAX_PROFILES {
            return Err(c.fail(
                "acquisition.profiles",
                format!("must be from 1 to {}", compact(MAX_PROFILES as f64)),
            ));
        }
        if let Err(e) = humantime::parse_rfc3339(&a.start_time) {
            return Err(c.fail(
                "acquisition.start_time",
                format!(
                    "must be a UTC time like \"2004-03-21T00:00:00Z\" (RFC 3339), got {:?}: {e}",
                    a.start_time
                ),
            ));
        }
        match p.kind {
            PlatformKind::Spaceborne => {
                c.positive("platform.altitude_km", p.altitude_km, 1e5)?;
                if a.top_altitude_km >= p.altitude_km {
                    return Err(c.fail(
                        "acquisition.top_altitude_km",
                        format!(
                            "the window must lie below the platform ({} km)",
                            p.altitude_km
                        ),
                    ));
                }
            }
            PlatformKind::Ground => {
                c.range("platform.altitude_km", p.altitude_km, -0.5, 9.0)?;
                if a.bottom_altitude_km < p.altitude_km {
                    return Err(c.fail(
                        "acquisition.bottom_altitude_km",
                        format!(
                            "a ground lidar sees nothing below its station ({} km)",
                            p.altitude_km
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}
