//! What one receiver channel is (docs/model.md §4c, docs/config.md
//! `[[instrument.channels]]`): the kind of scattering it sees, its polarization and
//! cross-talk, its filter and its detector, each as the channel's view of the config
//! (`[instrument]` with the channel's own keys laid over it).
//!
//! A kind is what the channel's light is: [`ChannelKind::Elastic`], the backscatter at
//! the laser's wavelength, or [`ChannelKind::Raman`], the vibrational Raman band of a
//! species ([`RamanSpecies`]) shifted from the laser line (docs/model.md §4h). A kind
//! that sees other light (a molecular line through an HSRL filter) is a variant here,
//! checked and described in this folder.

use serde::{Deserialize, Serialize};

use crate::atmosphere::cabannes_line::{SpectralFilter, doppler_sigma_hz};
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
    /// An HSRL molecular channel: the elastic line through a narrow filter that passes
    /// `f_m` of the Doppler-broadened Cabannes line and `f_p` ≪ 1 of the particle line.
    #[serde(rename = "hsrl_molecular")]
    HsrlMolecular,
    /// The vibrational Raman band of `species` (`instrument.channels[i].species`),
    /// detected at the shifted line: molecules only, up at the laser line and back at the
    /// Raman line.
    Raman,
}

/// The species a Raman channel sees (`instrument.channels[i].species`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
pub enum RamanSpecies {
    /// Nitrogen, 0.78084 of the air's molecules (default).
    #[default]
    N2,
    /// Water vapour, from the `[atmosphere.water_vapour]` mixing-ratio profile.
    H2O,
}

/// What an HSRL molecular channel's spectral filter passes (model.md §8 "High spectral
/// resolution"): `f_m` of the Cabannes line and `f_p` of the particle line
/// (`instrument.channels[i].molecular_transmission`, `.particle_transmission`). An
/// elastic channel passes 1 and 1; a Raman channel sees neither line.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LineTransmission {
    /// `f_m`: the share of the Cabannes line passed.
    pub molecular: f64,
    /// `f_p`: the share of the particle line (and of the surface echo) passed.
    pub particle: f64,
}

impl LineTransmission {
    /// An elastic channel's: both lines whole.
    pub const ELASTIC: LineTransmission = LineTransmission {
        molecular: 1.0,
        particle: 1.0,
    };
}

impl RamanSpecies {
    /// The species' name in the config and the file: `N2`, `H2O`.
    pub fn name(self) -> &'static str {
        match self {
            RamanSpecies::N2 => "N2",
            RamanSpecies::H2O => "H2O",
        }
    }

    /// The species a channel's `species` key gives; errors name `key` and list them.
    pub fn from_value(value: &toml::Value, key: &str, file: &str) -> Result<Self> {
        RamanSpecies::deserialize(value.clone())
            .map_err(|e| Error::config(file, key, config::plain_serde_message(key, e.message())))
    }

    /// Its vibrational shift, m⁻¹ (the Stokes line is `1/λ₀ − shift`).
    pub fn shift_per_m(self) -> f64 {
        match self {
            RamanSpecies::N2 => crate::atmosphere::raman::N2_SHIFT_PER_M,
            RamanSpecies::H2O => crate::atmosphere::raman::H2O_SHIFT_PER_M,
        }
    }
}

impl ChannelKind {
    /// The kind's name in the config and the file: `elastic`, `hsrl_molecular`, `raman`.
    pub fn name(self) -> &'static str {
        match self {
            ChannelKind::Elastic => "elastic",
            ChannelKind::HsrlMolecular => "hsrl_molecular",
            ChannelKind::Raman => "raman",
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
    /// The species of a Raman channel (N2 unless `species` says otherwise; unused by
    /// other kinds, which refuse the key).
    pub species: RamanSpecies,
    /// What the channel's filter passes of the elastic lines: 1 and 1 but in an HSRL
    /// molecular channel.
    pub lines: LineTransmission,
    /// The share of a Raman channel's band its filter passes (1: the whole band; 1 for
    /// other kinds).
    pub band_transmission: f64,
    /// An HSRL molecular channel's filter as a table of transmission against frequency
    /// offset (`spectral_filter`): then `f_m` follows the temperature (docs/model.md §4i)
    /// and `lines` holds `f_p = t(0)` and `f_m` at 288.15 K.
    #[serde(skip)]
    pub spectral_filter: Option<SpectralFilter>,
    /// What this channel of the file records: photon counts or analog codes (a `both`
    /// detector is two channels of the file, one of each, `split_detection_modes` (in `receiver`)).
    #[serde(skip)]
    pub record: Record,
    /// The other channel of a `both` pair (its index among the receiver's channels).
    #[serde(skip)]
    pub glue_partner: Option<usize>,
    /// The whole config with `[instrument]` as this channel sees it.
    pub config: ScenarioConfig,
}

/// What one channel of the file records.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Record {
    /// Photon counts (through the dead time where the detector has one).
    #[default]
    PhotonCounting,
    /// Summed ADC codes of the analog chain (`src/detector/analog.rs`).
    Analog,
}

impl Record {
    /// The name in files (`acquisition_mode`).
    pub fn name(self) -> &'static str {
        match self {
            Record::PhotonCounting => "photon_counting",
            Record::Analog => "analog",
        }
    }
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

    /// The wavelength of the line it detects, nm: the laser's for an elastic channel,
    /// the species' Stokes line for a Raman channel.
    pub fn detection_wavelength_nm(&self) -> f64 {
        let laser = self.config.instrument.wavelength_nm;
        match self.kind {
            ChannelKind::Elastic | ChannelKind::HsrlMolecular => laser,
            ChannelKind::Raman => {
                crate::atmosphere::raman::shifted_wavelength_nm(laser, self.species.shift_per_m())
            }
        }
    }

    /// Its name when the config gives none: `532_total`, `386.7_raman_N2`.
    pub fn default_name(&self) -> String {
        let i = &self.config.instrument;
        match self.kind {
            ChannelKind::Elastic => channel_name(i.wavelength_nm, i.channel),
            ChannelKind::HsrlMolecular => {
                format!("{}_molecular_{}", i.wavelength_nm, i.channel.name())
            }
            ChannelKind::Raman => raman_channel_name(self.detection_wavelength_nm(), self.species),
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

/// A Raman channel's default name: its detected line to 0.1 nm and the species, e.g.
/// `386.7_raman_N2`.
pub fn raman_channel_name(detection_nm: f64, species: RamanSpecies) -> String {
    format!("{:.1}_raman_{}", detection_nm, species.name())
}

/// An HSRL molecular channel's filter from its keys (`given`: `molecular_transmission`,
/// `particle_transmission`, each None when absent): both required, `0 < f_p < f_m ≤ 1`
/// (the filter blocks the particle line more than the molecular one); other kinds refuse
/// the keys.
pub fn line_transmission(
    kind: ChannelKind,
    given: (Option<f64>, Option<f64>),
    key: &dyn Fn(&str) -> String,
    file: &str,
) -> Result<LineTransmission> {
    let names = ["molecular_transmission", "particle_transmission"];
    if kind != ChannelKind::HsrlMolecular {
        return match given {
            (None, None) => Ok(LineTransmission::ELASTIC),
            (m, _) => Err(Error::config(
                file,
                key(names[usize::from(m.is_none())]),
                "is for HSRL molecular channels (kind = \"hsrl_molecular\")",
            )),
        };
    }
    let (Some(molecular), Some(particle)) = given else {
        let missing = names[usize::from(given.0.is_some())];
        return Err(Error::config(
            file,
            key(missing),
            "is required for an hsrl_molecular channel (the share of the Cabannes line, \
             or of the particle line, its filter passes)",
        ));
    };
    if !(molecular > 0.0 && molecular <= 1.0) {
        return Err(Error::config(file, key(names[0]), "must be in (0, 1]"));
    }
    if !(0.0..molecular).contains(&particle) {
        return Err(Error::config(
            file,
            key(names[1]),
            format!(
                "must be in [0, molecular_transmission = {}): the filter blocks the particle \
                 line more than the molecular one",
                crate::error::compact(molecular)
            ),
        ));
    }
    Ok(LineTransmission {
        molecular,
        particle,
    })
}

/// Temperature at which a filter table's `f_m` is reported as the channel's constant
/// (`LineTransmission::molecular`), K: US76's sea level.
pub const FILTER_REFERENCE_TEMPERATURE_K: f64 = 288.15;

/// An HSRL channel's `spectral_filter = { offset_ghz = [...], transmission = [...] }`:
/// the table ([`SpectralFilter`], offsets in GHz from the laser line, strictly
/// increasing, transmissions in [0, 1], 1 to 10,000 points); only on an
/// `hsrl_molecular` channel, and instead of `molecular_transmission` and
/// `particle_transmission`. Returns the filter and the line shares it gives (`f_m` at
/// 288.15 K, `f_p = t(0)`).
pub fn spectral_filter(
    value: &toml::Value,
    kind: ChannelKind,
    wavelength_nm: f64,
    key: &dyn Fn(&str) -> String,
    file: &str,
) -> Result<(SpectralFilter, LineTransmission)> {
    let name = key("spectral_filter");
    let fail = |why: String| Error::config(file, &name, why);
    if kind != ChannelKind::HsrlMolecular {
        return Err(fail(
            "is for HSRL molecular channels (kind = \"hsrl_molecular\")".into(),
        ));
    }
    let table = value.as_table().ok_or_else(|| {
        fail("must be a table { offset_ghz = [...], transmission = [...] }".into())
    })?;
    if let Some(other) = table
        .keys()
        .find(|k| *k != "offset_ghz" && *k != "transmission")
    {
        return Err(fail(format!(
            "unknown key '{other}', expected 'offset_ghz' or 'transmission'"
        )));
    }
    let column = |k: &str| -> Result<Vec<f64>> {
        let values = table
            .get(k)
            .and_then(toml::Value::as_array)
            .ok_or_else(|| fail(format!("needs `{k}`, an array of numbers")))?;
        if values.is_empty() || values.len() > MAX_FILTER_POINTS {
            return Err(fail(format!(
                "`{k}` needs 1 to {MAX_FILTER_POINTS} values, has {}",
                values.len()
            )));
        }
        // each value as the channel's other numeric keys: a finite number
        values
            .iter()
            .enumerate()
            .map(|(i, v)| number(v, &format!("{name}.{k}[{i}]"), file))
            .collect()
    };
    let (offsets, transmissions) = (column("offset_ghz")?, column("transmission")?);
    if offsets.len() != transmissions.len() {
        return Err(fail(format!(
            "has {} offsets and {} transmissions: give one transmission per offset",
            offsets.len(),
            transmissions.len()
        )));
    }
    let points = offsets.iter().map(|f| f * 1e9).zip(transmissions).collect();
    let filter = SpectralFilter::new(points).map_err(fail)?;
    let sigma = doppler_sigma_hz(wavelength_nm, FILTER_REFERENCE_TEMPERATURE_K);
    let lines = LineTransmission {
        molecular: filter.molecular_transmission(sigma),
        particle: filter.particle_transmission(),
    };
    if lines.molecular.is_nan() || lines.molecular <= 0.0 || lines.particle >= lines.molecular {
        return Err(fail(format!(
            "passes {} of the Cabannes line at 288.15 K and {} of the particle line: an \
             HSRL filter must pass more of the molecules than of the particles",
            crate::error::compact(lines.molecular),
            crate::error::compact(lines.particle)
        )));
    }
    Ok((filter, lines))
}

/// Most points a filter table may have.
pub const MAX_FILTER_POINTS: usize = 10_000;

/// A channel's `band_transmission` (None when absent): on a Raman channel the share of
/// the band its filter passes, in (0, 1], 1 when absent; other kinds refuse the key.
pub fn band_transmission(
    kind: ChannelKind,
    given: Option<f64>,
    key: &dyn Fn(&str) -> String,
    file: &str,
) -> Result<f64> {
    match (kind, given) {
        (_, None) => Ok(1.0),
        (ChannelKind::Raman, Some(t)) if t > 0.0 && t <= 1.0 => Ok(t),
        (ChannelKind::Raman, Some(_)) => Err(Error::config(
            file,
            key("band_transmission"),
            "must be in (0, 1] (the share of the Raman band the filter passes)",
        )),
        (_, Some(_)) => Err(Error::config(
            file,
            key("band_transmission"),
            "is for Raman channels (kind = \"raman\")",
        )),
    }
}

/// The checks of a channel's kind against its other keys (`key` gives an entry's key):
/// `species` only on a Raman channel, H2O only with a water-vapour profile
/// (`has_water_vapour`), and a Raman channel sees the total band (its depolarization is
/// not modelled).
pub fn check_kind(
    kind: ChannelKind,
    species: Option<RamanSpecies>,
    polarization: Channel,
    has_water_vapour: bool,
    key: &dyn Fn(&str) -> String,
    file: &str,
) -> Result<()> {
    match (kind, species) {
        (ChannelKind::Elastic | ChannelKind::HsrlMolecular, Some(_)) => Err(Error::config(
            file,
            key("species"),
            format!(
                "is for Raman channels (kind = \"raman\"); an {} channel sees the laser line",
                kind.name()
            ),
        )),
        (ChannelKind::Raman, Some(RamanSpecies::H2O)) if !has_water_vapour => Err(Error::config(
            file,
            key("species"),
            "H2O needs a water-vapour profile: give [atmosphere.water_vapour] \
                 (altitude_km, mixing_ratio_g_per_kg) or model fields with their molecules \
                 (scene.model_fields.molecules = \"fields\")",
        )),
        (ChannelKind::Raman, _) if polarization != Channel::Total => Err(Error::config(
            file,
            key("polarization"),
            "a Raman channel sees the whole band, whose depolarization lidarsim does not \
             model: use polarization = \"total\"",
        )),
        _ => Ok(()),
    }
}

/// A Raman channel's line against the wavelengths the model covers: the Stokes line
/// `1/λ = 1/λ₀ − shift` ([`crate::atmosphere::raman::shifted_wavelength_nm`]) must
/// exist (the shift below the laser's wavenumber) and lie within
/// [`config::WAVELENGTH_RANGE_NM`], like every other wavelength of the model. `laser_key`
/// names the key that set the laser's wavelength.
pub fn check_raman_line(
    kind: ChannelKind,
    species: RamanSpecies,
    laser_nm: f64,
    laser_key: &str,
    file: &str,
) -> Result<()> {
    if kind != ChannelKind::Raman {
        return Ok(());
    }
    let (_, top_nm) = config::WAVELENGTH_RANGE_NM;
    let shift_per_m = species.shift_per_m();
    // the longest laser wavelength whose line is at most top_nm
    let longest_laser_nm = 1.0 / (1.0 / top_nm + shift_per_m * 1e-9);
    let line_nm = crate::atmosphere::raman::shifted_wavelength_nm(laser_nm, shift_per_m);
    if line_nm > 0.0 && line_nm <= top_nm {
        return Ok(());
    }
    let line = if line_nm > 0.0 {
        format!("would be at {line_nm:.0} nm, beyond the {top_nm:.0} nm the model covers")
    } else {
        format!(
            "does not exist: the shift, {:.0} cm⁻¹, exceeds the laser's wavenumber, {:.0} cm⁻¹",
            shift_per_m / 100.0,
            1e7 / laser_nm
        )
    };
    Err(Error::config(
        file,
        laser_key,
        format!(
            "{} nm: the {} Raman line of a channel of kind \"raman\" {line}; its laser must be \
             at most {longest_laser_nm:.1} nm",
            crate::error::compact(laser_nm),
            species.name()
        ),
    ))
}

/// An HSRL channel's filter table needs the air's temperature: refused where
/// `atmosphere.molecular.model` is `"none"` (no air), as docs/config.md says.
pub fn check_filter_needs_air(cfg: &ScenarioConfig, key: &str, file: &str) -> Result<()> {
    match &cfg.atmosphere.molecular.model {
        config::MolecularModel::Named(n) if n == "none" => Err(Error::config(
            file,
            key,
            "needs the air's temperature (the Cabannes line's width), and \
             atmosphere.molecular.model = \"none\" has no air: use \"us76\" or a profile of \
             altitude_km, pressure_hpa, temperature_k",
        )),
        _ => Ok(()),
    }
}

/// A `both` detector's channel `name` becomes `<name>_an` and `<name>_pc`: those must be
/// channel names too, at most [`MAX_NAME_CHARS`] characters.
pub fn check_split_name(name: &str, key: &str, file: &str) -> Result<()> {
    let most = MAX_NAME_CHARS - "_an".len();
    let n = name.chars().count();
    if n <= most {
        return Ok(());
    }
    Err(Error::config(
        file,
        key,
        format!(
            "has {n} characters: a detector of mode \"both\" makes it `<name>_an` and \
             `<name>_pc`, which must have at most {MAX_NAME_CHARS}: give it at most {most}"
        ),
    ))
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

/// A finite number (an integer is taken as a float), for a channel's own keys.
pub(super) fn number(value: &toml::Value, key: &str, file: &str) -> Result<f64> {
    let x = match value {
        toml::Value::Float(x) => *x,
        toml::Value::Integer(i) => *i as f64,
        _ => return Err(Error::config(file, key, "must be a number")),
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::config(file, key, "must be a finite number"))
    }
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
    fn kinds_are_named_and_refused_by_key() {
        let v = |s: &str| toml::Value::String(s.into());
        let key = "instrument.channels[1].kind";
        assert_eq!(
            ChannelKind::from_value(&v("elastic"), key, "f.toml").unwrap(),
            ChannelKind::Elastic
        );
        assert_eq!(ChannelKind::default().name(), "elastic");
        assert_eq!(
            ChannelKind::from_value(&v("raman"), key, "f.toml").unwrap(),
            ChannelKind::Raman
        );
        let e = ChannelKind::from_value(&v("hsrl"), key, "f.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(key) && e.contains("'elastic'") && e.contains("'raman'"),
            "{e}"
        );
        assert!(!e.contains('\n'), "{e}");
    }
}
