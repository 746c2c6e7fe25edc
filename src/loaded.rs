//! A config loaded for a run: read, parsed ([`crate::config::parse`]), checked section
//! by section by the module that owns it ([`validate`]) and expanded into the
//! receiver's channels ([`crate::receiver::expand`]).
//!
//! `config` holds the typed sections and checks what it alone can judge; a limit set
//! by physics (the laser's jitter law, the detector's dead time, the ozone table, the
//! orbit, the sampler's tolerance) is checked beside that physics. This module names
//! them all, so that none of them needs to name it or each other.

use std::path::{Path, PathBuf};

use crate::config::{self, Checker, OwnerChecks, ScenarioConfig, SimulationConfig};
use crate::error::{Error, Result};
use crate::receiver::{self, ChannelConfig};
use crate::sampling::approx::MAX_TOLERANCE;

/// A loaded, overridden and validated configuration with its provenance.
#[derive(Debug, Clone)]
pub struct LoadedConfig {
    /// The validated configuration.
    pub config: ScenarioConfig,
    /// The config file as named on the command line.
    pub path: PathBuf,
    /// The resolved TOML after overrides (stored in output files).
    pub resolved_toml: String,
    /// The receiver's channels, each with the whole config as that channel sees it
    /// (`[instrument]` with the channel's overrides); one when the config lists none.
    pub channels: Vec<ChannelConfig>,
}

impl LoadedConfig {
    /// The config file's name for error messages.
    pub fn file_label(&self) -> String {
        self.path.display().to_string()
    }

    /// The config as channel `k` sees it (one channel), with the same provenance.
    pub fn for_channel(&self, k: usize) -> LoadedConfig {
        let channel = self.channels[k].clone();
        LoadedConfig {
            config: channel.config.clone(),
            path: self.path.clone(),
            resolved_toml: self.resolved_toml.clone(),
            channels: vec![channel],
        }
    }

    /// A path named in the config, resolved relative to the config file's directory.
    pub fn resolve_path(&self, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.path.parent().unwrap_or(Path::new(".")).join(p)
        }
    }

    /// Every file a run of this config reads: the config file itself and each file it
    /// names ([`ScenarioConfig::named_files`]), resolved. No output may replace one of
    /// them (`commands::input_files`).
    pub fn files_read(&self) -> Vec<PathBuf> {
        std::iter::once(self.path.clone())
            .chain(
                self.config
                    .named_files()
                    .into_iter()
                    .map(|(_, p)| self.resolve_path(p)),
            )
            .collect()
    }
}

/// Reads `path`, applies `overrides` (`KEY=VALUE`, dotted keys), deserializes and validates.
pub fn load(path: &Path, overrides: &[String]) -> Result<LoadedConfig> {
    let bytes = crate::input_file::read("config", path)?;
    let text = String::from_utf8(bytes).map_err(|_| {
        Error::config(
            path.display().to_string(),
            "",
            "is not UTF-8 text: a config is a TOML text file",
        )
    })?;
    load_str(&text, path, overrides)
}

/// As [`load`], from text already read; `path` names the source in errors, and an
/// error in a key that an override set names the override.
pub fn load_str(text: &str, path: &Path, overrides: &[String]) -> Result<LoadedConfig> {
    let file = path.display().to_string();
    let parsed = config::parse(text, path, overrides)?;
    let to_override = |e| config::attribute_to_override(e, overrides);
    validate(&parsed.config, &file).map_err(to_override)?;
    let channels =
        receiver::expand(&parsed.table, &parsed.config, &file, validate).map_err(to_override)?;
    Ok(LoadedConfig {
        config: parsed.config,
        path: path.to_path_buf(),
        resolved_toml: parsed.resolved_toml,
        channels,
    })
}

/// The checks of the modules whose physics sets a key's limits.
const OWNERS: OwnerChecks = OwnerChecks {
    laser: crate::laser::validate,
    detector: crate::detector::validate,
    ozone: crate::atmosphere::ozone::validate,
    water_vapour: crate::atmosphere::water_vapour::validate,
    molecular: crate::atmosphere::profile_file::validate_tables,
    aerosol_species: crate::atmosphere::aerosol_species::validate,
    orbit: crate::scene::orbit::validate,
    simulation: |config, c| validate_tolerance(&config.simulation, c),
    multiple_scattering: crate::atmosphere::multiple_scattering::validate,
};

/// Checks `simulation.tolerance`: a KS distance in (0, [`MAX_TOLERANCE`]] (the sampler's
/// limit, `sampling::approx`).
fn validate_tolerance(simulation: &SimulationConfig, c: &Checker) -> Result<()> {
    if let Some(t) = simulation.tolerance {
        c.positive("simulation.tolerance", t, MAX_TOLERANCE)?;
    }
    Ok(())
}

/// Checks a whole config, `file` naming it in errors: the config's own checks
/// ([`ScenarioConfig::validate`]) with, each in its place among them, the checks of
/// the modules whose physics sets a key's limits.
pub fn validate(config: &ScenarioConfig, file: &str) -> Result<()> {
    config.validate(file, &OWNERS)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every config key that holds a path is a file the run reads, so it must be in
    /// [`ScenarioConfig::named_files`] (else no output is kept off it): the config's
    /// path-typed fields, counted in its source and this one, are the keys it lists
    /// plus `LoadedConfig::path`.
    #[test]
    fn every_path_key_is_a_named_file() {
        let source = [
            include_str!("config/acquisition.rs"),
            include_str!("config/atmosphere.rs"),
            include_str!("config/background.rs"),
            include_str!("config/defaults.rs"),
            include_str!("config/detector.rs"),
            include_str!("config/instrument.rs"),
            include_str!("config/load.rs"),
            include_str!("config/mod.rs"),
            include_str!("config/model_fields.rs"),
            include_str!("config/multiple_scattering.rs"),
            include_str!("config/overrides.rs"),
            include_str!("config/scenario.rs"),
            include_str!("config/scene.rs"),
            include_str!("config/simulation.rs"),
            include_str!("config/warnings.rs"),
            include_str!("config/check/atmosphere.rs"),
            include_str!("config/check/background.rs"),
            include_str!("config/check/geometry.rs"),
            include_str!("config/check/instrument.rs"),
            include_str!("config/check/mod.rs"),
            include_str!("config/check/scene.rs"),
            include_str!("loaded.rs"),
        ];
        let path_fields = source
            .iter()
            .flat_map(|s| s.lines())
            .map(str::trim)
            .filter(|l| {
                let l = l.strip_prefix("pub ").unwrap_or(l);
                l.split_once(": ").is_some_and(|(name, ty)| {
                    name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                        && matches!(ty, "PathBuf," | "Option<PathBuf>,")
                })
            })
            .count();
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/instruments/caliop_curtain.toml");
        let loaded = load(
            &path,
            &["atmosphere.molecular.model={ file = \"p.txt\" }".into()],
        )
        .unwrap();
        let named: Vec<&str> = loaded.config.named_files().iter().map(|f| f.0).collect();
        assert_eq!(named, ["atmosphere.molecular.model.file", "scene.curtain"]);
        // the single-path keys of a model-field config (its `files` are a list)
        let fields = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("configs/instruments/caliop_fields_aerosol.toml");
        let fields = load(&fields, &[]).unwrap();
        let fields: Vec<&str> = fields.config.named_files().iter().map(|f| f.0).collect();
        assert!(fields.contains(&"scene.model_fields.aerosol_optics"));
        let singles = named.len() + 1;
        // and `LoadedConfig::path`, the config itself
        assert_eq!(
            path_fields,
            singles + 1,
            "a path key missing from named_files"
        );
        let read = loaded.files_read();
        assert_eq!(read[0], path);
        assert_eq!(read[1], path.parent().unwrap().join("p.txt"));
    }
}
