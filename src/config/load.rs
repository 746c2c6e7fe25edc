//! Parsing: TOML text to a table, the `--set` overrides applied, the table deserialized
//! into [`ScenarioConfig`], and serde's messages in the user's words.

use std::path::Path;

use crate::error::{Error, Result};

use super::overrides::{apply_override, attribute_to_override, key_of};
use super::scenario::ScenarioConfig;

/// A config parsed from TOML text, overrides applied: the typed sections, not yet
/// validated.
#[derive(Debug, Clone)]
pub struct Parsed {
    /// The typed sections.
    pub config: ScenarioConfig,
    /// The TOML table after overrides (the receiver expands its channels from it).
    pub table: toml::Table,
    /// The resolved TOML after overrides (stored in output files).
    pub resolved_toml: String,
}

/// Parses `text`, applies `overrides` (`KEY=VALUE`, dotted keys) and deserializes; `path`
/// names the source in errors, and an error in a key that an override set names the
/// override. Validation is the loader's (`src/loaded.rs`): [`ScenarioConfig::validate`]
/// and the checks of the modules that own a section.
pub fn parse(text: &str, path: &Path, overrides: &[String]) -> Result<Parsed> {
    let file = path.display().to_string();
    let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
        let at = e
            .span()
            .map(|s| line_column(text, s.start))
            .unwrap_or_default();
        Error::config(
            &file,
            "",
            format!("{at}malformed TOML: {}", one_line(e.message())),
        )
    })?;
    for item in overrides {
        apply_override(&mut table, item)
            .map_err(|reason| Error::config(format!("--set {item}"), key_of(item), reason))?;
    }
    let resolved_toml = toml::to_string(&table).unwrap_or_default();
    let de = toml::Value::Table(table.clone());
    let config = deserialize(de, &file).map_err(|e| attribute_to_override(e, overrides))?;
    Ok(Parsed {
        config,
        table,
        resolved_toml,
    })
}

/// `"line 10, column 17: "` for a byte offset into `text`.
fn line_column(text: &str, offset: usize) -> String {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    format!("line {line}, column {column}: ")
}

/// A message on one line.
fn one_line(msg: &str) -> String {
    msg.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A deserialization message in the user's words: no Rust type names.
pub fn plain_serde_message(key: &str, msg: &str) -> String {
    let msg = one_line(msg);
    if key.ends_with("molecular.model") {
        return "expected \"us76\", \"none\" or { file = \"profile.txt\" }".into();
    }
    if let Some(rest) = msg.strip_prefix("invalid type: ") {
        let (got, want) = rest
            .split_once(", expected ")
            .unwrap_or((rest, "another type"));
        if want == "string only" || got == "unit variant" {
            // toml's enums: a number or a table where one of the key's names belongs
            return "expected a string, one of the names this key takes (docs/config.md)".into();
        }
        let want = match want {
            w if w.starts_with("struct ") || w.starts_with("a map") => "a table".to_string(),
            "f64" | "f32" => "a number".to_string(),
            "usize" | "u64" | "u32" => "a whole number".to_string(),
            "a boolean" | "bool" => "true or false".to_string(),
            w if w.starts_with("a sequence") => "an array".to_string(),
            w => w.to_string(),
        };
        return format!("expected {want}, got {}", got.replace('`', "'"));
    }
    if let Some(rest) = msg.strip_prefix("invalid value: ") {
        let (got, want) = rest
            .split_once(", expected ")
            .unwrap_or((rest, "another value"));
        let want = match want {
            "usize" | "u64" | "u32" => "a whole number >= 0",
            w => w,
        };
        return format!("expected {want}, got {}", got.replace('`', "'"));
    }
    if let Some(rest) = msg.strip_prefix("unknown field ") {
        return format!("unknown key {}", rest.replace('`', "'"));
    }
    if let Some(rest) = msg.strip_prefix("missing field ") {
        return format!("missing key {}", rest.replace('`', "'"));
    }
    if msg.contains("untagged enum") || msg.contains("internally tagged") {
        return "does not have one of the forms this key takes (see docs/config.md)".into();
    }
    msg.replace('`', "'")
}

/// Deserializes a whole config table; errors name `file` and the dotted key.
pub fn deserialize(table: toml::Value, file: &str) -> Result<ScenarioConfig> {
    serde_path_to_error::deserialize(table).map_err(|e| {
        let key = e.path().to_string();
        let key = if key == "." { String::new() } else { key };
        let reason = plain_serde_message(&key, e.inner().message());
        Error::config(file, key, reason)
    })
}
