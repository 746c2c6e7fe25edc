//! The whole scenario, [`ScenarioConfig`]: one field per section, and the files it names.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::acquisition::AcquisitionConfig;
use super::atmosphere::{AtmosphereConfig, MolecularModel};
use super::background::BackgroundConfig;
use super::instrument::InstrumentConfig;
use super::multiple_scattering::MultipleScatteringConfig;
use super::scene::{OrbitConfig, PlatformConfig, SceneConfig, SurfaceConfig};
use super::simulation::SimulationConfig;

/// A whole scenario: instrument, platform, acquisition, atmosphere, background, simulation.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioConfig {
    /// Short name, used in titles.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The lidar instrument.
    pub instrument: InstrumentConfig,
    /// Where the lidar is and where it points.
    pub platform: PlatformConfig,
    /// Range window and accumulation.
    pub acquisition: AcquisitionConfig,
    /// Molecules, aerosols, layers.
    pub atmosphere: AtmosphereConfig,
    /// Sky background.
    pub background: BackgroundConfig,
    /// The surface below a space-borne lidar; absent = no surface echo.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<SurfaceConfig>,
    /// The scene along the track (space-borne); absent = one column everywhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<SceneConfig>,
    /// A circular orbit for a space-borne platform: geolocation of every profile.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orbit: Option<OrbitConfig>,
    /// Monte Carlo settings.
    #[serde(default)]
    pub simulation: SimulationConfig,
    /// How multiple scattering enters the signal (`src/atmosphere/multiple_scattering.rs`).
    #[serde(default)]
    pub multiple_scattering: MultipleScatteringConfig,
}

impl ScenarioConfig {
    /// A copy of the config without its scene: what one column of the scene is built
    /// from (`Track::column_config`). Cloning the scene too would copy every segment of
    /// the track for every column, quadratic in the track length (a day of model fields
    /// has ~1e5 segments). The destructuring names every field, so that a new one is
    /// not forgotten here.
    pub fn clone_without_scene(&self) -> ScenarioConfig {
        let ScenarioConfig {
            name,
            description,
            instrument,
            platform,
            acquisition,
            atmosphere,
            background,
            surface,
            scene: _,
            orbit,
            simulation,
            multiple_scattering,
        } = self;
        ScenarioConfig {
            name: name.clone(),
            description: description.clone(),
            instrument: instrument.clone(),
            platform: platform.clone(),
            acquisition: acquisition.clone(),
            atmosphere: atmosphere.clone(),
            background: background.clone(),
            surface: surface.clone(),
            scene: None,
            orbit: orbit.clone(),
            simulation: simulation.clone(),
            multiple_scattering: multiple_scattering.clone(),
        }
    }

    /// Every file the config names, with its key, as written (relative to the config
    /// file): the molecular profile file, the scene's curtain, model fields and aerosol
    /// optics table. A key that names a
    /// file belongs here, so that the file is an input no output may replace
    /// (`LoadedConfig::files_read`); its reader opens it through `src/input_file.rs`.
    pub fn named_files(&self) -> Vec<(&'static str, &Path)> {
        let mut files = Vec::new();
        if let MolecularModel::File { file } = &self.atmosphere.molecular.model {
            files.push(("atmosphere.molecular.model.file", file.as_path()));
        }
        for seg in self.scene.iter().flat_map(|s| &s.segments) {
            if let Some(MolecularModel::File { file }) = &seg.molecular {
                files.push(("scene.segments.molecular.file", file.as_path()));
            }
        }
        if let Some(curtain) = self.scene.as_ref().and_then(|s| s.curtain.as_ref()) {
            files.push(("scene.curtain", curtain.as_path()));
        }
        if let Some(m) = self.scene.as_ref().and_then(|s| s.model_fields.as_ref()) {
            for f in &m.files {
                files.push(("scene.model_fields.files", f.as_path()));
            }
            if let Some(t) = &m.aerosol_optics {
                files.push(("scene.model_fields.aerosol_optics", t.as_path()));
            }
        }
        files
    }
}
