//! What one receiver channel is (docs/model.md §4c, docs/config.md
//! `[[instrument.channels]]`): the kind of scattering it sees, its polarization and
//! cross-talk, its filter and its detector, each as the channel's view of the config
//! (`[instrument]` with the channel's own keys laid over it).
//!
//! A kind is what the channel's light is: today only [`ChannelKind::Elastic`], the
//! backscatter at the laser's wavelength. A kind that sees other light (a Raman line, a
//! molecular line through an HSRL filter) is a variant here, checked and described in
//! this folder.

use serde::{Deserialize, Serialize};

use crate::config::{self, Channel, DetectorConfig, ScenarioConfig};
use crate::error::{Error, Result};

/// Longest channel name, characters.
const MAX_NAME_CHARS: usize = 64;

/// The kind of scattering a channel sees (`instrument.channels[i].kind`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ChannelKind {
    /// Elastic backscatter at the laser's wavelength, molecules and particles (default).
    #[default]
    Elastic,
}

impl ChannelKind {
    /// The kind's name in the config: `elastic`.
    pub fn name(self) -> &'static str {
        match self {
            ChannelKind::Elastic => "elastic",
        }
    }

    /// The kind a channel's `kind` key gives; errors name `key` and list the kinds.
    pub fn from_value(value: &toml::Value, key: &str, file: &str) -> Result<Self> {
        ChannelKind::deserialize(value.clone())
            .map_err(|e| Error::config(file, key, config::plain_serde_message(key, e.message())))
    }
}

/// One channel: its name, its kind and the config as it sees it.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelConfig {
    /// The channel's name (the file's `channel` coordinate), e.g. `532_parallel`.
    pub name: String,
    /// The kind of scattering it sees.
    pub kind: ChannelKind,
    /// The whole config with `[instrument]` as this channel sees it.
    pub config: ScenarioConfig,
}

/// A channel's filter: the band it passes and the share of it it transmits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Filter {
    /// Width Δλ, nm.
    pub width_nm: f64,
    /// Transmission TF.
    pub transmission: f64,
}

impl ChannelConfig {
    /// The polarization it sees with respect to the laser's.
    pub fn polarization(&self) -> Channel {
        self.config.instrument.channel
    }

    /// The share of the other polarization's light it sees.
    pub fn crosstalk(&self) -> f64 {
        self.config.instrument.crosstalk
    }

    /// Its spectral filter.
    pub fn filter(&self) -> Filter {
        let i = &self.config.instrument;
        Filter {
            width_nm: i.filter_width_nm,
            transmission: i.filter_transmission,
        }
    }

    /// Its detector; `None` = an ideal linear photon counter.
    pub fn detector(&self) -> Option<&DetectorConfig> {
        self.config.instrument.detector.as_ref()
    }
}

/// A channel's default name: wavelength and polarization, e.g. `532_total`.
pub fn channel_name(wavelength_nm: f64, polarization: Channel) -> String {
    format!("{wavelength_nm}_{}", polarization.name())
}

/// A channel name: a string of 1–64 printable characters.
pub fn channel_label(value: &toml::Value, key: &str, file: &str) -> Result<String> {
    let fail = |why: &str| Error::config(file, key, why.to_string());
    let name = value.as_str().ok_or_else(|| fail("must be a string"))?;
    if name.is_empty() || name.chars().count() > MAX_NAME_CHARS {
        return Err(fail("must have 1 to 64 characters"));
    }
    if name.chars().any(char::is_control) {
        return Err(fail("must not contain control characters"));
    }
    Ok(name.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_like_the_field() {
        assert_eq!(channel_name(532.0, Channel::Total), "532_total");
        assert_eq!(
            channel_name(1064.0, Channel::Perpendicular),
            "1064_perpendicular"
        );
        assert_eq!(channel_name(354.7, Channel::Parallel), "354.7_parallel");
    }

    #[test]
    fn crosstalk_mixes_the_polarizations() {
        let d = 0.4;
        let (par, per) = (1.0 / 1.4, 0.4 / 1.4);
        assert_eq!(Channel::Total.share(d, 0.1), 1.0);
        assert!((Channel::Parallel.share(d, 0.0) - par).abs() < 1e-15);
        assert!((Channel::Parallel.share(d, 0.1) - (0.9 * par + 0.1 * per)).abs() < 1e-15);
        assert!((Channel::Perpendicular.share(d, 0.1) - (0.9 * per + 0.1 * par)).abs() < 1e-15);
        // the two polarization channels together see all of it, whatever the cross-talk
        let sum = Channel::Parallel.share(d, 0.03) + Channel::Perpendicular.share(d, 0.03);
        assert!((sum - 1.0).abs() < 1e-15);
    }

    #[test]
    fn kinds_are_named_and_refused_by_key() {
        let v = |s: &str| toml::Value::String(s.into());
        let key = "instrument.channels[1].kind";
        assert_eq!(
            ChannelKind::from_value(&v("elastic"), key, "f.toml").unwrap(),
            ChannelKind::Elastic
        );
        assert_eq!(ChannelKind::default().name(), "elastic");
        let e = ChannelKind::from_value(&v("raman"), key, "f.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(key) && e.contains("'elastic'") && e.contains("'raman'"),
            "{e}"
        );
        assert!(!e.contains('\n'), "{e}");
    }
}
