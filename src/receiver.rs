//! The receiver's channels (docs/model.md §4c, docs/config.md `[[instrument.channels]]`).
//!
//! A channel is the whole instrument as one detector sees it: `[instrument]` with the
//! channel's own keys laid over it (`wavelength_nm`, `pulse_energy_j`, efficiencies,
//! filter, dark rate, `detector`, ...), its `polarization` and `crosstalk`. Expanding the
//! config once per channel keeps every formula in one place: each channel is a
//! single-channel scenario of its own, with the same geometry, atmosphere and seed.
//!
//! What one laser, one digitizer and one telescope share cannot differ per channel:
//! [`SHARED_KEYS`]. Layers keep their values at the `[instrument]` wavelength and reach
//! a channel at another wavelength through their Ångström exponent.

use serde::Serialize;

use crate::config::{self, Channel, ScenarioConfig};
use crate::error::{Error, Result};

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
/// Longest channel name, characters.
const MAX_NAME_CHARS: usize = 64;

/// One channel: its name and the config as it sees it.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelConfig {
    /// The channel's name (the file's `channel` coordinate), e.g. `532_parallel`.
    pub name: String,
    /// The whole config with `[instrument]` as this channel sees it.
    pub config: ScenarioConfig,
}

/// A channel's default name: wavelength and polarization, e.g. `532_total`.
pub fn channel_name(wavelength_nm: f64, polarization: Channel) -> String {
    format!("{wavelength_nm}_{}", polarization.name())
}

/// The channels of a validated config (`base`, deserialized from `table`): one per
/// `[[instrument.channels]]` entry, or the instrument itself when there is none.
/// Errors name the entry's key, e.g. `instrument.channels[1].wavelength_nm`.
pub fn expand(
    table: &toml::Table,
    base: &ScenarioConfig,
    file: &str,
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
        return Ok(vec![ChannelConfig {
            name: channel_name(i.wavelength_nm, i.channel),
            config: base.clone(),
        }]);
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
        let channel = expand_one(table, base, entry, k, file)?;
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
    Ok(channels)
}

/// The config as channel `k` (`entry`) sees it.
fn expand_one(
    table: &toml::Table,
    base: &ScenarioConfig,
    entry: &toml::Table,
    k: usize,
    file: &str,
) -> Result<ChannelConfig> {
    let key = |s: &str| format!("instrument.channels[{k}].{s}");
    let mut root = table.clone();
    let mut name = None;
    {
        let Some(toml::Value::Table(inst)) = root.get_mut("instrument") else {
            return Err(Error::config(file, "instrument", "must be a table"));
        };
        inst.remove("channels");
        for (field, value) in entry {
            match field.as_str() {
                "name" => name = Some(channel_label(value, &key("name"), file)?),
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
    config.validate(file).map_err(in_channel)?;
    let i = &config.instrument;
    Ok(ChannelConfig {
        name: name.unwrap_or_else(|| channel_name(i.wavelength_nm, i.channel)),
        config,
    })
}

/// A channel name: a string of 1–64 printable characters.
fn channel_label(value: &toml::Value, key: &str, file: &str) -> Result<String> {
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
}
