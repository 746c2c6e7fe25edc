//! `[scene.model_fields]`: the scene read from a model's fields (ERA5, MERRA-2, CAMS,
//! ICON) along the orbit (`src/scene/fields/`, docs/scenes.md "Model fields").

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// Which shipped mapping of variable names a model's files use.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FieldsModel {
    /// ECMWF ERA5 (netCDF from the Climate Data Store, or converted from GRIB by cdo).
    #[default]
    Era5,
    /// NASA GMAO MERRA-2 (`M2I3NVASM`, `M2T3NVRAD`).
    Merra2,
    /// CAMS reanalysis / forecasts (the IFS names, as ERA5).
    Cams,
    /// ICON output regridded to a regular latitude–longitude grid.
    Icon,
}

/// How a profile samples the fields between grid points and times.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FieldsInterpolation {
    /// Bilinear in latitude and longitude, then linear in time.
    #[default]
    Linear,
    /// The nearest grid point and the nearest time.
    Nearest,
}

/// The model fields a space-borne run flies through.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFieldsConfig {
    /// The netCDF-4 or netCDF-3 files, relative to the config file; each variable is
    /// taken from the first file that holds it (all on the same grid and times).
    pub files: Vec<PathBuf>,
    /// The shipped variable-name mapping.
    #[serde(default)]
    pub model: FieldsModel,
    /// Variable names replacing the mapping's, by role (`temperature = "ta"`, ...).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub variables: BTreeMap<String, String>,
    /// Linear (bilinear in space, linear in time) or nearest.
    #[serde(default)]
    pub interpolation: FieldsInterpolation,
    /// Droplet effective radius where the files give none, µm.
    #[serde(default = "default_liquid_radius")]
    pub liquid_effective_radius_um: f64,
    /// Extinction efficiency Q of the cloud particles (geometric optics: 2).
    #[serde(default = "default_efficiency")]
    pub extinction_efficiency: f64,
    /// Subcolumns per profile drawn from the cloud fraction by maximum-random overlap
    /// (1 = the grid-box mean water spread over the whole box).
    #[serde(default = "default_subcolumns")]
    pub subcolumns: u32,
    /// Where each profile's molecules come from: the fields' pressure, temperature and
    /// humidity, or the config's `atmosphere.molecular.model` and water vapour.
    #[serde(default)]
    pub molecules: FieldsMolecules,
    /// ECMWF's aerosol optics table (`aerosol_ifs_rrtm_*.nc`), relative to the config:
    /// with it, each level's CAMS aerosol species (`aermr01` … `aermr18`) make its
    /// aerosol in place of the config's `[atmosphere.aerosol]`; absent, no aerosol
    /// comes from the fields.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aerosol_optics: Option<PathBuf>,
    /// The species variables read (`["aermr04", ...]`); absent = every CAMS species
    /// the files hold.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aerosol_species: Option<Vec<String>>,
    /// The species' particle linear depolarization ratios by class, replacing the
    /// defaults (docs/model.md §4l) at every wavelength.
    #[serde(default, skip_serializing_if = "AerosolDepolarization::is_empty")]
    pub aerosol_depolarization: AerosolDepolarization,
    /// Linear depolarization ratio of singly scattered light by the fields' liquid cloud;
    /// absent = the default (0, spheres).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub liquid_depolarization: Option<f64>,
    /// Linear depolarization ratio of the fields' ice cloud; absent = the default (0.4).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ice_depolarization: Option<f64>,
}

/// `scene.model_fields.aerosol_depolarization`: a particle linear depolarization ratio
/// `δ = β⊥/β∥` per species class, each replacing that class's default at every
/// wavelength; absent = the default.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AerosolDepolarization {
    /// Mineral dust (`aermr04` … `aermr06`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dust: Option<f64>,
    /// Sea salt (`aermr01` … `aermr03`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub marine: Option<f64>,
    /// Organic matter and black carbon (`aermr07` … `aermr10`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smoke: Option<f64>,
    /// Sulphate, nitrate and ammonium (`aermr11`, `aermr16` … `aermr18`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sulphate: Option<f64>,
}

impl AerosolDepolarization {
    /// No override given.
    pub fn is_empty(&self) -> bool {
        *self == AerosolDepolarization::default()
    }

    /// The overrides with their keys (under `scene.model_fields.aerosol_depolarization`).
    pub fn keyed(&self) -> [(&'static str, Option<f64>); 4] {
        [
            ("dust", self.dust),
            ("marine", self.marine),
            ("smoke", self.smoke),
            ("sulphate", self.sulphate),
        ]
    }
}

/// The molecules of a model-field scene (`scene.model_fields.molecules`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FieldsMolecules {
    /// Each profile's levels: N = p/(k_B·T) and the water vapour from q.
    #[default]
    Fields,
    /// The config's molecular model and water vapour, the same everywhere.
    Config,
}

fn default_subcolumns() -> u32 {
    10
}

fn default_liquid_radius() -> f64 {
    10.0
}

fn default_efficiency() -> f64 {
    2.0
}

/// The roles a variable can play, the keys of `[scene.model_fields.variables]`
/// (docs/config.md; `src/scene/fields/names.rs` has each model's names).
pub const ROLES: [&str; 18] = [
    "temperature",
    "specific_humidity",
    "liquid",
    "ice",
    "cloud_fraction",
    "surface_pressure",
    "pressure",
    "geopotential",
    "height",
    "surface_geopotential",
    "liquid_effective_radius",
    "ice_effective_radius",
    "hybrid_a",
    "hybrid_b",
    "latitude",
    "longitude",
    "time",
    "level",
];
