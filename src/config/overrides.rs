//! `--set KEY=VALUE`: applying a dotted override to the TOML table, and naming the
//! override in an error in a key it set.

use crate::error::Error;

/// An error in a key that a `--set` override set (the key or a table above it) names
/// that override rather than the file.
pub fn attribute_to_override(e: Error, overrides: &[String]) -> Error {
    let Error::Config { file, key, reason } = e else {
        return e;
    };
    // "atmosphere.layers[0].top_km" -> "atmosphere.layers.0.top_km"
    let dotted = key.replace('[', ".").replace(']', "");
    let hit = overrides.iter().rev().find(|item| {
        let k = key_of(item);
        !k.is_empty() && (dotted == k || dotted.starts_with(&format!("{k}.")))
    });
    match hit {
        Some(item) => Error::config(format!("--set {item}"), key, reason),
        None => Error::Config { file, key, reason },
    }
}

pub(super) fn key_of(item: &str) -> String {
    item.split_once('=')
        .map(|(k, _)| k.trim())
        .unwrap_or(item)
        .to_string()
}

/// Applies one `KEY=VALUE` override to `table`. The value is read as a TOML value
/// (number, boolean, string in quotes, inline table, array); anything that is not
/// valid TOML is taken as a bare string, so `--set platform.kind=ground` works.
/// Array elements are addressed by index: `atmosphere.layers.0.top_km=12`.
pub fn apply_override(table: &mut toml::Table, item: &str) -> std::result::Result<(), String> {
    let (key, raw) = item
        .split_once('=')
        .ok_or_else(|| format!("--set expects KEY=VALUE, got `{item}`"))?;
    let key = key.trim();
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(format!("--set has an empty key part in `{item}`"));
    }
    let parts: Vec<&str> = key.split('.').collect();
    let mut root = toml::Value::Table(std::mem::take(table));
    let result = set_path(&mut root, &parts, parse_value(raw.trim()));
    if let toml::Value::Table(t) = root {
        *table = t;
    }
    result
}

fn set_path(
    node: &mut toml::Value,
    parts: &[&str],
    value: toml::Value,
) -> std::result::Result<(), String> {
    let mut node = node;
    for (i, part) in parts.iter().enumerate() {
        let last = i + 1 == parts.len();
        let here = parts[..i].join(".");
        node = match node {
            toml::Value::Table(t) => {
                if last {
                    t.insert((*part).to_string(), value);
                    return Ok(());
                }
                t.entry((*part).to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            toml::Value::Array(a) => {
                let idx: usize = part
                    .parse()
                    .map_err(|_| format!("`{here}` is an array: address its elements by index"))?;
                let len = a.len();
                let slot = a.get_mut(idx).ok_or_else(|| {
                    format!("index {idx} is out of range (`{here}` has {len} elements)")
                })?;
                if last {
                    *slot = value;
                    return Ok(());
                }
                slot
            }
            _ => return Err(format!("`{here}` is a value, not a table")),
        };
    }
    Err("empty key".into())
}

fn parse_value(raw: &str) -> toml::Value {
    let doc = format!("v = {raw}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or_else(|| toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.trim_matches('"').to_string()),
    }
}
