//! The receiver's channels (docs/model.md §4c, docs/config.md `[[instrument.channels]]`).
//!
//! A channel ([`channel`]) is the whole instrument as one detector sees it: `[instrument]`
//! with the channel's own keys laid over it (`wavelength_nm`, `pulse_energy_j`,
//! efficiencies, filter, dark rate, `detector`, ...), its `kind`, `polarization` and
//! `crosstalk`. Expanding the config once per channel keeps every formula in one place:
//! each channel is a single-channel scenario of its own, with the same geometry,
//! atmosphere and seed.
//!
//! What one laser, one digitizer and one telescope share cannot differ per channel:
//! [`SHARED_KEYS`]. Layers keep their values at the `[instrument]` wavelength and reach
//! a channel at another wavelength through their Ångström exponent.

pub mod channel;
pub mod polarization;

pub use channel::{
    ChannelConfig, ChannelKind, Filter, LineTransmission, RamanSpecies, Record, channel_name,
};
pub use polarization::{PolarizationOptics, analyser_transmission, delta90_calibration_constant};

use crate::config::{self, ScenarioConfig};
use crate::error::{Error, Result};
use channel::number;

/// Keys shared by every channel: the laser's timing and energy statistics, the
/// digitizer's bins, the telescope's overlap.
pub const SHARED_KEYS: [&str; 6] = [
    "rep_rate_hz",
    "bin_width_s",
    "pulse_energy_jitter",
    "energy_drift",
    "overlap",
    "channels",
];
/// Most channels one receiver may have.
pub const MAX_CHANNELS: usize = 32;

/// Checks a whole config (`file` names it in errors): what the loader calls valid.
pub type Validate = fn(&ScenarioConfig, &str) -> Result<()>;

/// The channels of a validated config (`base`, deserialized from `table`): one per
/// `[[instrument.channels]]` entry, or the instrument itself when there is none. Each
/// channel's config is checked by `validate`, the loader's checks of a whole config.
/// Errors name the entry's key, e.g. `instrument.channels[1].wavelength_nm`.
pub fn expand(
    table: &toml::Table,
    base: &ScenarioConfig,
    file: &str,
    validate: Validate,
) -> Result<Vec<ChannelConfig>> {
    let entries = &base.instrument.channels;
    let listed_empty = table
        .get("instrument")
        .and_then(|i| i.get("channels"))
        .is_some_and(|c| c.as_array().is_some_and(|a| a.is_empty()));
    if listed_empty {
        return Err(Error::config(
            file,
            "instrument.channels",
            format!(
                "lists no channel; give 1 to {MAX_CHANNELS} [[instrument.channels]] tables, or \
                 leave the key out for one channel (the [instrument] itself)"
            ),
        ));
    }
    if entries.is_empty() {
        let i = &base.instrument;
        let channels = vec![ChannelConfig {
            name: channel_name(i.wavelength_nm, i.channel),
            kind: ChannelKind::default(),
            species: RamanSpecies::default(),
            lines: LineTransmission::ELASTIC,
            band_transmission: 1.0,
            spectral_filter: None,
            record: Record::default(),
            glue_partner: None,
            config: base.clone(),
        }];
        return split_detection_modes(channels, file);
    }
    if entries.len() > MAX_CHANNELS {
        return Err(Error::config(
            file,
            "instrument.channels",
            format!(
                "lists {} channels; a receiver has at most {MAX_CHANNELS}",
                entries.len()
            ),
        ));
    }
    let mut channels: Vec<ChannelConfig> = Vec::with_capacity(entries.len());
    for (k, entry) in entries.iter().enumerate() {
        let channel = expand_one(table, base, (k, entry), file, validate)?;
        if let Some(j) = channels.iter().position(|c| c.name == channel.name) {
            return Err(Error::config(
                file,
                format!("instrument.channels[{k}].name"),
                format!(
                    "`{}` is also the name of channel {j}; give each channel its own name",
                    channel.name
                ),
            ));
        }
        channels.push(channel);
    }
    split_detection_modes(channels, file)
}

/// Each channel as the file records it: an `analog` detector's channel records analog
/// codes; a `both` detector's channel becomes two, `<name>_an` (analog) then `<name>_pc`
/// (photon counting), partners of each other, recording the same photons.
pub fn split_detection_modes(
    channels: Vec<ChannelConfig>,
    file: &str,
) -> Result<Vec<ChannelConfig>> {
    let mut out: Vec<ChannelConfig> = Vec::with_capacity(channels.len());
    for (k, channel) in channels.into_iter().enumerate() {
        let mode = channel.detector().map(|d| d.mode).unwrap_or_default();
        if mode == config::DetectionMode::Both {
            let key = format!("instrument.channels[{k}].name");
            channel::check_split_name(&channel.name, &key, file)?;
        }
        match mode {
            config::DetectionMode::PhotonCounting => out.push(channel),
            config::DetectionMode::Analog => out.push(ChannelConfig {
                record: Record::Analog,
                ..channel
            }),
            config::DetectionMode::Both => {
                let k = out.len();
                let analog = ChannelConfig {
                    name: format!("{}_an", channel.name),
                    record: Record::Analog,
                    glue_partner: Some(k + 1),
                    ..channel.clone()
                };
                out.push(analog);
                out.push(ChannelConfig {
                    name: format!("{}_pc", channel.name),
                    record: Record::PhotonCounting,
                    glue_partner: Some(k),
                    ..channel
                });
            }
        }
    }
    for (k, c) in out.iter().enumerate() {
        if let Some(j) = out[..k].iter().position(|o| o.name == c.name) {
            return Err(Error::config(
                file,
                "instrument.channels",
                format!(
                    "two channels are named `{}` (channels {j} and {k} of the file, after a \
                     `both` detector's channel became `<name>_an` and `<name>_pc`); rename one",
                    c.name
                ),
            ));
        }
    }
    Ok(out)
}

/// The config as channel `k` (`entry`) sees it.
fn expand_one(
    table: &toml::Table,
    base: &ScenarioConfig,
    (k, entry): (usize, &toml::Table),
    file: &str,
    validate: Validate,
) -> Result<ChannelConfig> {
    let key = |s: &str| format!("instrument.channels[{k}].{s}");
    let mut root = table.clone();
    let mut name = None;
    let mut kind = ChannelKind::default();
    let mut species = None;
    let mut lines = (None, None);
    let mut band = None;
    let mut filter_table = None;
    {
        let Some(toml::Value::Table(inst)) = root.get_mut("instrument") else {
            return Err(Error::config(file, "instrument", "must be a table"));
        };
        inst.remove("channels");
        for (field, value) in entry {
            match field.as_str() {
                "name" => name = Some(channel::channel_label(value, &key("name"), file)?),
                "kind" => kind = ChannelKind::from_value(value, &key("kind"), file)?,
                "species" => {
                    species = Some(channel::RamanSpecies::from_value(
                        value,
                        &key("species"),
                        file,
                    )?)
                }
                "molecular_transmission" => lines.0 = Some(number(value, &key(field), file)?),
                "particle_transmission" => lines.1 = Some(number(value, &key(field), file)?),
                "band_transmission" => band = Some(number(value, &key(field), file)?),
                "spectral_filter" => filter_table = Some(value.clone()),
                "polarization" | "channel" => {
                    inst.remove("polarization");
                    inst.insert("channel".into(), value.clone());
                }
                "detector" => merge_table(inst, "detector", value),
                shared if SHARED_KEYS.contains(&shared) => {
                    return Err(Error::config(
                        file,
                        key(shared),
                        "is shared by every channel (one laser, one digitizer, one telescope): \
                         set it in [instrument]",
                    ));
                }
                _ => {
                    inst.insert(field.clone(), value.clone());
                }
            }
        }
    }
    // the layers' values stay at the instrument's wavelength, the scene's too
    let reference = toml::Value::Float(base.instrument.wavelength_nm);
    let keep_reference = |layers: Option<&mut toml::Value>| {
        for layer in layers
            .and_then(toml::Value::as_array_mut)
            .into_iter()
            .flatten()
        {
            if let Some(t) = layer.as_table_mut() {
                t.entry("reference_wavelength_nm")
                    .or_insert(reference.clone());
            }
        }
    };
    if let Some(toml::Value::Table(atm)) = root.get_mut("atmosphere") {
        keep_reference(atm.get_mut("layers"));
    }
    if let Some(toml::Value::Table(scene)) = root.get_mut("scene")
        && let Some(toml::Value::Array(segments)) = scene.get_mut("segments")
    {
        for seg in segments.iter_mut().filter_map(toml::Value::as_table_mut) {
            keep_reference(seg.get_mut("layers"));
        }
    }
    let label = name.clone().unwrap_or_else(|| format!("{k}"));
    let in_channel = |e: Error| rename_key(e, k, entry, &label);
    let config = config::deserialize(toml::Value::Table(root), file).map_err(in_channel)?;
    validate(&config, file).map_err(in_channel)?;
    channel::check_kind(
        kind,
        species,
        config.instrument.channel,
        config.atmosphere.water_vapour.is_some()
            || crate::atmosphere::water_vapour::from_fields(&config),
        &key,
        file,
    )?;
    let laser_key = match entry.contains_key("wavelength_nm") {
        true => key("wavelength_nm"),
        false => "instrument.wavelength_nm".to_string(),
    };
    let laser_nm = config.instrument.wavelength_nm;
    channel::check_raman_line(
        kind,
        species.unwrap_or_default(),
        laser_nm,
        &laser_key,
        file,
    )?;
    if filter_table.is_some() {
        channel::check_filter_needs_air(&config, &key("spectral_filter"), file)?;
    }
    let (spectral_filter, lines) = match (&filter_table, lines) {
        (Some(_), (Some(_), _) | (_, Some(_))) => {
            let given = if lines.0.is_some() {
                "molecular_transmission"
            } else {
                "particle_transmission"
            };
            return Err(Error::config(
                file,
                key(given),
                "is given by the channel's spectral_filter table: give one or the other",
            ));
        }
        (Some(table), _) => {
            let wl = config.instrument.wavelength_nm;
            let (filter, lines) = channel::spectral_filter(table, kind, wl, &key, file)?;
            (Some(filter), lines)
        }
        (None, given) => (None, channel::line_transmission(kind, given, &key, file)?),
    };
    let band_transmission = channel::band_transmission(kind, band, &key, file)?;
    let mut channel = ChannelConfig {
        name: String::new(),
        kind,
        species: species.unwrap_or_default(),
        lines,
        band_transmission,
        spectral_filter,
        record: Record::default(),
        glue_partner: None,
        config,
    };
    channel.name = name.unwrap_or_else(|| channel.default_name());
    Ok(channel)
}

/// `inst[key]` = `value`, merged key by key into an existing table.
fn merge_table(inst: &mut toml::Table, key: &str, value: &toml::Value) {
    match (inst.get_mut(key), value) {
        (Some(toml::Value::Table(old)), toml::Value::Table(new)) => {
            for (k, v) in new {
                old.insert(k.clone(), v.clone());
            }
        }
        _ => {
            inst.insert(key.into(), value.clone());
        }
    }
}

/// An error in channel `k`'s config: a key the entry set is named as the entry's key;
/// any other error says which channel it concerns.
fn rename_key(e: Error, k: usize, entry: &toml::Table, label: &str) -> Error {
    match e {
        Error::Config { file, key, reason } => {
            let field = key
                .strip_prefix("instrument.")
                .map(|rest| rest.split(['.', '[']).next().unwrap_or(rest));
            let set_here = field.is_some_and(|f| {
                entry.contains_key(f) || (f == "channel" && entry.contains_key("polarization"))
            });
            if set_here {
                let rest = match &key["instrument.".len()..] {
                    "channel" => "polarization",
                    rest => rest,
                };
                Error::Config {
                    file,
                    key: format!("instrument.channels[{k}].{rest}"),
                    reason,
                }
            } else {
                Error::Config {
                    file,
                    key,
                    reason: format!("{reason} (in channel {label})"),
                }
            }
        }
        other => other,
    }
}
