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
        "instruments/caliop_532.toml",
    ] {
        let sc = common::scenario(cfg, &["instrument.pulse_energy_jitter=0.01"]);
        // every field, defaults included: the validated config serialized back
        let text = toml::to_string(&sc.loaded.config).unwrap();
        keys(&text.parse::<toml::Table>().unwrap(), "", &mut all);
    }
    all.sort();
    all.dedup();
    assert!(all.len() > 40, "{all:?}");
    for key in &all {
        let leaf = key.rsplit('.').next().unwrap();
        assert!(
            doc.contains(&format!("`{leaf}`")),
            "docs/config.md lacks `{leaf}` ({key})"
        );
    }
}
