//! `[multiple_scattering]`: which model of the multiply scattered return the signal uses.

use serde::{Deserialize, Serialize};

/// `[multiple_scattering]`: the model of the multiply scattered return (docs/model.md §4j).
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MultipleScatteringConfig {
    /// Which model; absent = `constant` (each layer's η on its optical depth).
    #[serde(default)]
    pub model: MultipleScatteringModel,
    /// Particles whose forward lobe is wider than this, rad, only attenuate in the
    /// small-angle model; absent = 0.1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wide_angle_cutoff_rad: Option<f64>,
}

/// The models of `multiple_scattering.model`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MultipleScatteringModel {
    /// A constant factor η per layer on its optical depth (Platt); the paper's model.
    #[default]
    Constant,
    /// Quasi-small-angle forward scattering: Hogan's (2008) photon variance–covariance
    /// method, which depends on the field of view, the beam and the particles' size.
    SmallAngle,
    /// The small-angle part plus the wide-angle diffuse part (Hogan & Battaglia 2008).
    SmallAndWideAngle,
}
