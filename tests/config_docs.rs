//! docs/config.md names every config key the code reads.

mod common;

fn keys(table: &toml::Table, prefix: &str, out: &mut Vec<String>) {
    for (k, v) in table {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(t) => keys(t, &path, out),
            toml::Value::Array(a) => {
                for t in a.iter().filter_map(toml::Value::as_table) {
                    keys(t, &path, out);
                }
            }
            _ => out.push(path),
        }
    }
}

#[test]
fn every_config_key_is_documented() {
    let doc =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/config.md")).unwrap();
    let mut all = Vec::new();
    for cfg in [
        "paper/scenario1.toml",
        "ground/ground_532_overlap.toml",
        "ground/ground_532_depol.toml",
        "ground/mpl_like.toml",
        "ground/pollyxt_like_glued.toml",
        "instruments/caliop_532.toml",
        "instruments/caliop_3ch.toml",
        "instruments/caliop_orbit.toml",
        "instruments/caliop_curtain.toml",
        "instruments/caliop_fields.toml",
        "instruments/caliop_fields_aerosol.toml",
    ] {
        let mut overrides = vec![
            "instrument.pulse_energy_jitter=0.01",
            "instrument.energy_drift={ model = \"periodic\", amplitude = 0.01, period_s = 100 }",
        ];
        // the optional keys no shipped config sets
        if cfg.ends_with("caliop_fields_aerosol.toml") {
            overrides.extend([
                "scene.model_fields.aerosol_depolarization={ dust = 0.3, marine = 0.1, smoke = 0.1, sulphate = 0.0 }",
                "scene.model_fields.liquid_depolarization=0.0",
                "scene.model_fields.ice_depolarization=0.4",
            ]);
        }
        let lidar = common::lidar(cfg, &overrides);
        // every field, defaults included: the validated config serialized back
        let text = toml::to_string(&lidar.first().loaded.config).unwrap();
        keys(&text.parse::<toml::Table>().unwrap(), "", &mut all);
    }
    all.sort();
    all.dedup();
    assert!(all.len() > 40, "{all:?}");
    // the keys of a wavelength map are wavelengths, not names
    all.retain(|k| !k.contains("lidar_ratio_sr_by_wavelength."));
    let documented = documented_keys(&doc);
    let mut missing = vec![];
    for key in &all {
        if !documented.contains(&canonical(key)) {
            missing.push(format!("{key} (as {})", canonical(key)));
        }
    }
    assert!(
        missing.is_empty(),
        "docs/config.md lacks, under its section's header, the keys:\n{}",
        missing.join("\n")
    );
}

/// A key of a table that docs/config.md documents by reference ("as `[[atmosphere.layers]]`",
/// "any other `[instrument]` key"), under the key it refers to.
fn canonical(key: &str) -> String {
    for (from, to) in [
        ("scene.segments.layers.", "atmosphere.layers."),
        ("scene.segments.aerosol.", "atmosphere.aerosol."),
        ("scene.segments.surface.", "surface."),
    ] {
        if let Some(rest) = key.strip_prefix(from) {
            return format!("{to}{rest}");
        }
    }
    if let Some(rest) = key.strip_prefix("instrument.channels.")
        && !["name", "polarization", "crosstalk"].contains(&rest)
    {
        return format!("instrument.{rest}");
    }
    key.to_string()
}

/// Words in backticks, and `word =` inside them (inline tables), of a text.
fn names(text: &str) -> Vec<String> {
    let ident = |w: &str| {
        !w.is_empty()
            && w.chars().next().unwrap().is_ascii_lowercase()
            && w.chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
    };
    let mut out = vec![];
    for (k, quoted) in text.split('`').enumerate() {
        if k % 2 == 0 {
            continue;
        }
        if ident(quoted) {
            out.push(quoted.to_string());
        }
        let words = quoted.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '='));
        for w in words {
            if let Some(name) = w.strip_suffix('=').filter(|n| ident(n)) {
                out.push(name.to_string());
            } else if ident(w) && quoted.contains(&format!("{w} =")) {
                out.push(w.to_string());
            }
        }
    }
    out
}

/// Full dotted keys documented in docs/config.md: each table row's backticked names in
/// its first column, under the section whose header (`## `[instrument]``, `[[…]]`, or a
/// line opening with `` `[instrument.detector]` ``) it stands in; a row's inline-table keys
/// (`{ model = …, per_hour = … }`) under the row's key; for a table keyed by `model`,
/// its `keys` column under the same section.
fn documented_keys(doc: &str) -> std::collections::HashSet<String> {
    let mut keys = std::collections::HashSet::new();
    let mut section: Option<String> = None;
    let mut by_model = false;
    for line in doc.lines() {
        let header = line.starts_with("## ") || line.starts_with("### ");
        let opener = line.starts_with("`[");
        if header || opener {
            section = if line.contains("Top level") {
                Some(String::new())
            } else if let Some(start) = line.find("`[") {
                let rest = &line[start + 1..];
                let end = rest.find('`').unwrap();
                Some(
                    rest[..end]
                        .trim_matches(|c| c == '[' || c == ']')
                        .to_string(),
                )
            } else {
                None
            };
            continue;
        }
        let Some(sec) = &section else { continue };
        if !line.starts_with('|') || line.starts_with("|---") {
            continue;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 3 {
            continue;
        }
        let full = |name: &str| {
            if sec.is_empty() {
                name.to_string()
            } else {
                format!("{sec}.{name}")
            }
        };
        if cells[1] == "key" || cells[1] == "model" {
            by_model = cells[1] == "model";
            if by_model {
                keys.insert(full("model"));
            }
            continue;
        }
        if by_model {
            for n in names(cells[2]) {
                keys.insert(full(&n));
            }
            continue;
        }
        let first = names(cells[1]);
        for n in &first {
            keys.insert(full(n));
            for inner in names(&cells[2..].join("|")) {
                keys.insert(full(&format!("{n}.{inner}")));
            }
        }
    }
    keys
}

#[test]
fn a_key_counts_only_under_its_own_section() {
    let doc = "## `[instrument]`\n\n| key | meaning |\n|---|---|\n| `model` | x |\n\n## `[atmosphere.molecular]`\n\n| key | meaning |\n|---|---|\n| `grid_m` | y |\n";
    let k = documented_keys(doc);
    assert!(k.contains("instrument.model") && k.contains("atmosphere.molecular.grid_m"));
    assert!(!k.contains("atmosphere.molecular.model"), "{k:?}");
    assert!(!k.contains("instrument.grid_m"));
}
