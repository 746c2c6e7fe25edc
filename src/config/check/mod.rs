//! The config's own checks: [`Checker`], which words every range error alike, the
//! owners' checks the loader hands in ([`OwnerChecks`]), and [`ScenarioConfig::validate`],
//! which runs every section's checks (one file each here) in a fixed order.

mod atmosphere;
mod background;
mod geometry;
mod instrument;
mod scene;

use crate::error::{Error, Result, compact};

use super::scenario::ScenarioConfig;
use super::scene::PlatformKind;

/// Collects the checks of one file; the first failure becomes the error. Every module
/// that checks a section of the config words its errors through it, so that a range
/// reads the same whoever checks it.
#[derive(Debug, Clone, Copy)]
pub struct Checker<'a> {
    /// The file (or `--set` override) errors name.
    pub file: &'a str,
}

impl Checker<'_> {
    /// The error for `key`, naming the file.
    pub fn fail(&self, key: &str, reason: impl Into<String>) -> Error {
        Error::config(self.file, key, reason)
    }

    /// `value` must be finite and within `[lo, hi]` (bounds inclusive).
    pub fn range(&self, key: &str, value: f64, lo: f64, hi: f64) -> Result<()> {
        if !value.is_finite() {
            return Err(self.fail(key, format!("must be a finite number, got {value}")));
        }
        if value < lo || value > hi {
            return Err(self.fail(
                key,
                format!(
                    "must be within [{}, {}], got {}",
                    compact(lo),
                    compact(hi),
                    compact(value)
                ),
            ));
        }
        Ok(())
    }

    /// `value` must be finite and strictly positive, at most `hi`.
    pub fn positive(&self, key: &str, value: f64, hi: f64) -> Result<()> {
        self.range(key, value, 0.0, hi)?;
        if value == 0.0 {
            return Err(self.fail(key, "must be greater than 0"));
        }
        Ok(())
    }

    /// A fraction in (0, 1].
    pub fn efficiency(&self, key: &str, value: f64) -> Result<()> {
        self.positive(key, value, 1.0)
    }
}

/// A check of the keys whose limits another module's physics sets.
pub type OwnerCheck = fn(&ScenarioConfig, &Checker) -> Result<()>;

/// The checks the modules that own a section's limits make, handed to
/// [`ScenarioConfig::validate`] by the loader: the config names none of those modules,
/// and runs each check where its keys always were checked.
#[derive(Debug, Clone, Copy)]
pub struct OwnerChecks {
    /// `instrument.pulse_energy_jitter` (the laser's law).
    pub laser: OwnerCheck,
    /// `[instrument.detector]` (the detector).
    pub detector: OwnerCheck,
    /// `atmosphere.ozone` (the ozone cross-section table).
    pub ozone: OwnerCheck,
    /// `[atmosphere.water_vapour]` and the segments' (the mixing-ratio profile).
    pub water_vapour: OwnerCheck,
    /// The molecular profiles given as tables: `atmosphere.molecular.model` and the
    /// segments' `molecular` (a profile file's rows).
    pub molecular: OwnerCheck,
    /// `scene.model_fields.aerosol_species` (the CAMS species with optics).
    pub aerosol_species: OwnerCheck,
    /// `[orbit]` (an orbit that exists).
    pub orbit: OwnerCheck,
    /// `[simulation]` (the sampler's tolerance).
    pub simulation: OwnerCheck,
    /// `[multiple_scattering]` and the particles' sizes (the multiple-scattering model).
    pub multiple_scattering: OwnerCheck,
}

impl ScenarioConfig {
    /// Checks every field: finite, in range, consistent. A check that needs a module's
    /// physics or limits is that module's, one of `owners` (the loader's,
    /// `src/loaded.rs`), run in its place among the others. `file` names the source in
    /// errors.
    pub fn validate(&self, file: &str, owners: &OwnerChecks) -> Result<()> {
        let c = Checker { file };
        self.validate_instrument(&c, owners)?;
        self.validate_geometry(&c)?;
        self.validate_atmosphere(&c, owners)?;
        self.validate_background(&c)?;
        if let Some(surface) = &self.surface {
            self.validate_surface(&c, surface)?;
        }
        if let Some(scene) = &self.scene {
            self.validate_scene(&c, scene)?;
        }
        if let Some(o) = &self.orbit {
            if self.platform.kind == PlatformKind::Ground {
                return Err(c.fail("orbit", "an orbit needs a space-borne platform"));
            }
            c.range(
                "orbit.start_longitude_deg",
                o.start_longitude_deg,
                -360.0,
                360.0,
            )?;
            (owners.orbit)(self, &c)?;
        }
        if self
            .atmosphere
            .layers
            .iter()
            .filter(|l| l.cloud_fraction.is_some())
            .count()
            > 3
        {
            return Err(c.fail("atmosphere.layers", "at most 3 broken layers"));
        }
        (owners.multiple_scattering)(self, &c)?;
        (owners.simulation)(self, &c)
    }
}
