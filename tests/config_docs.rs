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
        "instruments/caliop_532.toml",
        "instruments/caliop_3ch.toml",
        "instruments/caliop_orbit.toml",
        "instruments/caliop_curtain.toml",
    ] {
        let lidar = common::lidar(
            cfg,
            &[
                "instrument.pulse_energy_jitter=0.01",
                "instrument.energy_drift={ model = \"periodic\", amplitude = 0.01, period_s = 100 }",
            ],
        );
        // every field, defaults included: the validated config serialized back
        let text = toml::to_string(&lidar.first().loaded.config).unwrap();
        keys(&text.parse::<toml::Table>().unwrap(), "", &mut all);
    }
    all.sort();
    all.dedup();
    assert!(all.len() > 40, "{all:?}");
    // the keys of a wavelength map are wavelengths, not names
    all.retain(|k| !k.contains("lidar_ratio_sr_by_wavelength."));
    for key in &all {
        let leaf = key.rsplit('.').next().unwrap();
        assert!(
            doc.contains(&format!("`{leaf}`")),
            "docs/config.md lacks `{leaf}` ({key})"
        );
    }
}
