//! `[background]`: the sky background, a fixed radiance or sunlight from the scene.

use serde::{Deserialize, Serialize};

/// Which efficiencies the detected sky background carries (model.md §1).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BackgroundEfficiency {
    /// ε_bkg = TR·Qλ: the background crosses the same receiver as the signal (default).
    #[default]
    Receiver,
    /// ε_bkg = 1: the paper's literal Eq. 3.
    Paper,
}

/// Sky background.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BackgroundConfig {
    /// `"fixed"` (the paper's: `radiance`) or `"solar"` (sunlight from the scene).
    #[serde(default)]
    pub model: BackgroundModel,
    /// Spectral radiance Lλ, photons m⁻² s⁻¹ sr⁻¹ nm⁻¹ (paper: 1.1e10 night, 1.1e15
    /// day); required by the fixed model; with the solar model a floor added to the
    /// reflected sunlight (night sky, moonlight).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radiance: Option<f64>,
    /// Efficiencies applied to the background.
    #[serde(default)]
    pub efficiency: BackgroundEfficiency,
    /// Solar model: a stated two-way transmission of the sunlight (sun → scene →
    /// instrument), whatever the angle; absent = the slant path through the modelled
    /// atmosphere and its path radiance (`SunlightPath` in `src/scene/sun.rs`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transmission: Option<f64>,
    /// Solar model: albedo of an optically thick cloud top (column optical depth ≥ 1); absent = 0.7.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cloud_albedo: Option<f64>,
    /// Solar model: a fixed solar zenith angle, degrees (instead of the sun's position
    /// along the orbit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solar_zenith_deg: Option<f64>,
    /// Solar model: whether the air's once-scattered sunlight (path radiance) is added
    /// to the reflected sunlight (`src/scene/sky.rs`); absent = true.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path_radiance: Option<bool>,
}

/// Where the sky background comes from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BackgroundModel {
    /// A fixed radiance (`background.radiance`), the paper's way.
    #[default]
    Fixed,
    /// Sunlight reflected by the surface or a cloud top below a space-borne lidar, from
    /// the solar zenith angle at each profile's time and place (docs/model.md §4f).
    Solar,
}
