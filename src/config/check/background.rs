//! The checks of `[background]`: the fixed model's radiance, the solar model's sun and scene.

use crate::config::background::BackgroundModel;
use crate::config::scenario::ScenarioConfig;
use crate::config::scene::PlatformKind;
use crate::error::Result;

use super::Checker;

impl ScenarioConfig {
    /// The background: a radiance for the fixed model; the solar model's sun and scene.
    pub(super) fn validate_background(&self, c: &Checker) -> Result<()> {
        let b = &self.background;
        match b.model {
            BackgroundModel::Fixed => match b.radiance {
                Some(r) => c.range("background.radiance", r, 0.0, 1e25),
                None => Err(c.fail(
                    "background.radiance",
                    "is required (photons m-2 s-1 sr-1 nm-1; the paper: 1.1e10 night, 1.1e15 day), \
                     or set background.model = \"solar\"",
                )),
            },
            BackgroundModel::Solar => {
                if let Some(r) = b.radiance {
                    c.range("background.radiance", r, 0.0, 1e25)?;
                }
                if self.platform.kind == PlatformKind::Ground {
                    return Err(c.fail(
                        "background.model",
                        "\"solar\" is sunlight reflected below a space-borne lidar; a ground lidar \
                         takes a fixed sky radiance",
                    ));
                }
                if self.orbit.is_none() && b.solar_zenith_deg.is_none() {
                    return Err(c.fail(
                        "background.model",
                        "\"solar\" needs the sun's angle: give [orbit] (and acquisition.start_time) \
                         or background.solar_zenith_deg",
                    ));
                }
                if let Some(t) = b.transmission {
                    c.range("background.transmission", t, 0.0, 1.0)?;
                }
                if let Some(a) = b.cloud_albedo {
                    c.range("background.cloud_albedo", a, 0.0, 1.0)?;
                }
                if let Some(z) = b.solar_zenith_deg {
                    c.range("background.solar_zenith_deg", z, 0.0, 180.0)?;
                }
                Ok(())
            }
        }
    }
}
