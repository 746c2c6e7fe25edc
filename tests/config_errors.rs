//! Every config error path gives a clear error naming the file, the key and the reason.

mod common;
use common::config_path;
use lidarsim::error::Error;
use lidarsim::scenario::Scenario;

fn load(overrides: &[&str]) -> Result<Scenario, Error> {
    let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scenario::load(&config_path("paper/scenario1.toml"), &ov)
}

/// Asserts a config error on `key` whose reason contains `reason`.
fn expect_config_error(overrides: &[&str], key: &str, reason: &str) {
    match load(overrides) {
        Err(Error::Config {
            file,
            key: k,
            reason: r,
        }) => {
            // an error in a key an override set names that override, else the file
            let set_by = overrides.iter().find(|o| {
                let k = o.split('=').next().unwrap();
                let dotted = key.replace('[', ".").replace(']', "");
                dotted == k || dotted.starts_with(&format!("{k}."))
            });
            match set_by {
                Some(o) => assert_eq!(file, format!("--set {o}"), "{overrides:?}"),
                None => assert!(
                    file.ends_with("scenario1.toml"),
                    "{overrides:?}: file {file}"
                ),
            }
            assert_eq!(k, key, "{overrides:?}: reason {r}");
            assert!(r.contains(reason), "{overrides:?}: `{r}` lacks `{reason}`");
        }
        Err(other) => panic!("{overrides:?}: not a config error: {other}"),
        Ok(_) => panic!("{overrides:?}: accepted"),
    }
}

#[test]
fn bad_values_name_their_key() {
    let cases: &[(&[&str], &str, &str)] = &[
        (
            &["atmosphere.molecular.model=\"msis\""],
            "atmosphere.molecular.model",
            "unknown model `msis`",
        ),
        (
            &[
                "atmosphere.molecular.model={altitude_km=[0.0, 1.0], pressure_hpa=[1013.0], \
               temperature_k=[288.0, 281.0]}",
            ],
            "atmosphere.molecular.model",
            "must be as long: 2, 1 and 2",
        ),
        (
            &[
                "atmosphere.molecular.model={altitude_km=[0.0, 1.0], pressure_hpa=[1013.0, -1.0], \
               temperature_k=[288.0, 281.0]}",
            ],
            "atmosphere.molecular.model",
            "index 1: pressure_hpa must be > 0",
        ),
        (
            &[
                "atmosphere.molecular.model={altitude_km=[1.0, 0.5], pressure_hpa=[900.0, 950.0], \
               temperature_k=[288.0, 281.0]}",
            ],
            "atmosphere.molecular.model",
            "index 1: altitude 0.5 km is not above",
        ),
        (
            &[
                "atmosphere.molecular.model={altitude_km=[0.0], pressure_hpa=[1013.0], \
               temperature_k=[288.0]}",
            ],
            "atmosphere.molecular.model",
            "at least 2 rows",
        ),
        (
            &["instrument.detector={dead_time_s=3e-9, pixels=0}"],
            "instrument.detector.pixels",
            "from 1 to 1024",
        ),
        (
            &["instrument.detector={pixels=4}"],
            "instrument.detector.pixels",
            "dead_time_s is 0",
        ),
        (
            &["instrument.detector={dead_time_s=3e-9, pixels=4, mode=\"both\"}"],
            "instrument.detector.pixels",
            "records analog",
        ),
        (
            &[
                "instrument.detector={dead_time_s=3e-9, pixels=4}",
                "instrument.pulse_energy_jitter=0.01",
            ],
            "instrument.detector.pixels",
            "pulse energy that varies",
        ),
        (
            &["instrument.pulse_energy_j=-1"],
            "instrument.pulse_energy_j",
            "within",
        ),
        (
            &["instrument.pulse_energy_j=0"],
            "instrument.pulse_energy_j",
            "greater than 0",
        ),
        (
            &["instrument.pulse_energy_j=nan"],
            "instrument.pulse_energy_j",
            "finite",
        ),
        (
            &["instrument.pulse_energy_j=inf"],
            "instrument.pulse_energy_j",
            "finite",
        ),
        (
            &["instrument.pulse_energy_j=\"abc\""],
            "instrument.pulse_energy_j",
            "expected a number",
        ),
        (
            &["instrument.receiver_efficiency=1.5"],
            "instrument.receiver_efficiency",
            "within",
        ),
        (
            &["instrument.wavelength_nm=10"],
            "instrument.wavelength_nm",
            "within",
        ),
        (
            &["instrument.bin_width_s=0"],
            "instrument.bin_width_s",
            "within",
        ),
        (
            &["instrument.dark_count_rate_hz=-5"],
            "instrument.dark_count_rate_hz",
            "within",
        ),
        (
            &["instrument.channel=\"diagonal\""],
            "instrument.channel",
            "unknown variant",
        ),
        (
            &["instrument.overlap={model=\"cone\"}"],
            "instrument.overlap.model",
            "unknown variant",
        ),
        (
            &["instrument.overlap={model=\"full_range\", full_overlap_m=-3}"],
            "instrument.overlap.full_overlap_m",
            "within",
        ),
        (
            &["platform.kind=\"balloon\""],
            "platform.kind",
            "unknown variant",
        ),
        (
            &["platform.off_nadir_deg=90"],
            "platform.off_nadir_deg",
            "within",
        ),
        (
            &["platform.altitude_km=30"],
            "acquisition.top_altitude_km",
            "below the platform",
        ),
        (
            &["acquisition.bottom_altitude_km=150"],
            "acquisition.bottom_altitude_km",
            "below acquisition.top_altitude_km",
        ),
        (
            &["acquisition.accumulation_time_s=0.01"],
            "acquisition.accumulation_time_s",
            "at least one",
        ),
        (
            &["acquisition.profiles=0"],
            "acquisition.profiles",
            "must be from 1",
        ),
        (
            &["acquisition.profiles=-2"],
            "acquisition.profiles",
            "expected a whole number",
        ),
        (
            &[
                "platform.altitude_km=50000",
                "acquisition.top_altitude_km=40000",
                "instrument.bin_width_s=1e-9",
            ],
            "instrument.bin_width_s",
            "bins",
        ),
        (
            &[
                "platform.kind=ground",
                "platform.altitude_km=1",
                "acquisition.bottom_altitude_km=0.5",
            ],
            "acquisition.bottom_altitude_km",
            "below its station",
        ),
        (
            &["atmosphere.molecular.model=\"msis\""],
            "atmosphere.molecular.model",
            "unknown model",
        ),
        (
            &["atmosphere.molecular.grid_m=0"],
            "atmosphere.molecular.grid_m",
            "within",
        ),
        (
            &["atmosphere.aerosol.visibility_km=0"],
            "atmosphere.aerosol.visibility_km",
            "greater than 0",
        ),
        (
            &["atmosphere.aerosol.lidar_ratio_sr=0.1"],
            "atmosphere.aerosol.lidar_ratio_sr",
            "within",
        ),
        (
            &["atmosphere.layers.0.top_km=9"],
            "atmosphere.layers[0].top_km",
            "above base_km",
        ),
        (
            &["atmosphere.layers.0.multiple_scattering=0"],
            "atmosphere.layers[0].multiple_scattering",
            "greater than 0",
        ),
        (
            &["atmosphere.layers.0.multiple_scattering=1.2"],
            "atmosphere.layers[0].multiple_scattering",
            "within",
        ),
        (
            &["atmosphere.layers.0.depolarization=-0.1"],
            "atmosphere.layers[0].depolarization",
            "within",
        ),
        (
            &["atmosphere.layers.0.kind=\"fog\""],
            "atmosphere.layers[0].kind",
            "unknown variant",
        ),
        (&["background.radiance=-1"], "background.radiance", "within"),
        (
            &["background.efficiency=\"all\""],
            "background.efficiency",
            "unknown variant",
        ),
        (
            &["simulation.method=\"fast\""],
            "simulation.method",
            "unknown variant",
        ),
        (
            &["simulation.tolerance=-1"],
            "simulation.tolerance",
            "within",
        ),
    ];
    for (ov, key, reason) in cases {
        expect_config_error(ov, key, reason);
    }
}

#[test]
fn unknown_keys_are_errors() {
    expect_config_error(
        &["instrument.pulse_energy=1"],
        "instrument.pulse_energy",
        "unknown key 'pulse_energy'",
    );
    expect_config_error(
        &["atmosphere.layers.0.thickness_km=1"],
        "atmosphere.layers[0].thickness_km",
        "unknown key",
    );
    expect_config_error(&["colour=1"], "colour", "unknown key 'colour'");
}

#[test]
fn inconsistent_aerosol_source_is_an_error() {
    let path = config_path("paper/scenario1.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("surface_extinction_per_km = 0.08", "");
    let err = lidarsim::loaded::load_str(
        &text,
        &path,
        &["atmosphere.aerosol.extinction_from=surface_extinction".into()],
    )
    .unwrap_err();
    assert!(
        err.to_string()
            .contains("atmosphere.aerosol.extinction_from"),
        "{err}"
    );
}

#[test]
fn malformed_overrides_name_the_key() {
    expect_config_error(
        &["instrument.pulse_energy_j"],
        "instrument.pulse_energy_j",
        "KEY=VALUE",
    );
    expect_config_error(
        &["atmosphere.layers.3.top_km=1"],
        "atmosphere.layers.3.top_km",
        "out of range",
    );
    expect_config_error(
        &["atmosphere.layers.x.top_km=1"],
        "atmosphere.layers.x.top_km",
        "by index",
    );
    expect_config_error(&["name.first=1"], "name.first", "not a table");
    expect_config_error(&["instrument..x=1"], "instrument..x", "empty key");
}

#[test]
fn malformed_toml_names_the_line() {
    let err = lidarsim::loaded::load_str(
        "name = \"x\"\n[instrument\nfoo = 1\n",
        std::path::Path::new("bad.toml"),
        &[],
    )
    .unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.starts_with("bad.toml") && msg.contains("line 2") && msg.contains("malformed TOML"),
        "{msg}"
    );
}

#[test]
fn missing_files_are_reported_with_their_path() {
    let err = Scenario::load(std::path::Path::new("/nonexistent/x.toml"), &[]).unwrap_err();
    assert!(err.to_string().contains("/nonexistent/x.toml"), "{err}");
    let err = load(&["atmosphere.molecular.model={file=\"no_such_profile.txt\"}"]).unwrap_err();
    assert!(err.to_string().contains("no_such_profile.txt"), "{err}");
}

/// A molecular profile given as a table in the config is the same atmosphere as the file
/// holding its rows: the same expected signal, bit for bit.
#[test]
fn a_molecular_table_is_its_file() {
    let file = config_path("atmospheres/nrlmsis21_buenos_aires_january.txt");
    let rows: Vec<Vec<f64>> = std::fs::read_to_string(&file)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() > 80);
    let column = |k: usize| {
        let v: Vec<String> = rows.iter().map(|r| format!("{:?}", r[k])).collect();
        v.join(", ")
    };
    let table = format!(
        "atmosphere.molecular.model={{altitude_km=[{}], pressure_hpa=[{}], temperature_k=[{}]}}",
        column(0),
        column(1),
        column(2)
    );
    let by_file = format!(
        "atmosphere.molecular.model={{file={:?}}}",
        file.to_str().unwrap()
    );
    let a = load(&[&by_file]).unwrap().expected().unwrap();
    let b = load(&[&table]).unwrap().expected().unwrap();
    let us76 = load(&[]).unwrap().expected().unwrap();
    assert_eq!(a.signal, b.signal);
    assert_ne!(a.signal, us76.signal);
}

#[test]
fn overrides_change_the_model() {
    let base = load(&[]).unwrap().expected().unwrap();
    let half = load(&["instrument.pulse_energy_j=0.5"])
        .unwrap()
        .expected()
        .unwrap();
    for (a, b) in base.signal.iter().zip(&half.signal) {
        assert!((b - 0.5 * a).abs() <= 1e-12 * a, "signal ∝ E0");
    }
    let day = load(&["background.radiance=1.1e15"])
        .unwrap()
        .expected()
        .unwrap();
    assert!((day.background / base.background - 1e5).abs() < 1e-6 * 1e5);
    // an inline-table override and an array element override
    let sc = load(&[
        "atmosphere.layers.0.top_km=13",
        "instrument.overlap={model=\"full_range\", full_overlap_m=1}",
    ])
    .unwrap();
    assert_eq!(sc.atmosphere.layers[0].top_m, 13_000.0);
    // a bare string needs no quotes
    assert!(load(&["background.efficiency=paper"]).is_ok());
    // the resolved config records the override
    assert!(
        load(&["acquisition.profiles=7"])
            .unwrap()
            .loaded
            .resolved_toml
            .contains("profiles = 7")
    );
}

#[test]
fn paper_background_form_drops_the_receiver_efficiencies() {
    let rx = load(&[]).unwrap().instrument.background_per_bin;
    let paper = load(&["background.efficiency=paper"])
        .unwrap()
        .instrument
        .background_per_bin;
    assert!((paper * 0.8 * 1.0 - rx).abs() < 1e-15, "ε_bkg = TR·Q = 0.8");
}

/// A config with several errors is told the first in the order the keys are checked,
/// whichever module checks them (the limits the laser, the detector, the ozone table,
/// the orbit and the sampler set are checked in their place among the config's own).
#[test]
fn several_errors_are_told_in_the_order_of_the_keys() {
    let cases: [(&[&str], &str); 6] = [
        (
            &[
                "instrument.rep_rate_hz=-1",
                "instrument.pulse_energy_jitter=0.5",
            ],
            "instrument.pulse_energy_jitter",
        ),
        (
            &[
                "instrument.wavelength_nm=100",
                "instrument.pulse_energy_jitter=0.5",
            ],
            "instrument.wavelength_nm",
        ),
        (
            &[
                "instrument.overlap={ model = \"full_range\", full_overlap_m = -1 }",
                "instrument.detector={ dead_time_s = 1 }",
            ],
            "instrument.detector.dead_time_s",
        ),
        (
            &[
                "atmosphere.aerosol.visibility_km=-1",
                "atmosphere.ozone=true",
                "instrument.wavelength_nm=300",
            ],
            "atmosphere.ozone",
        ),
        (
            &["background.radiance=-1", "simulation.tolerance=1"],
            "background.radiance",
        ),
        (
            &[
                "platform.off_nadir_deg=99",
                "instrument.detector={ dead_time_s = 1 }",
            ],
            "instrument.detector.dead_time_s",
        ),
    ];
    for (overrides, key) in cases {
        expect_config_error(overrides, key, "");
    }
}

/// `text` (a preset with `from` replaced by `to`) loaded: its config error as
/// (file, key, reason), the message one line.
fn preset_error(preset: &str, from: &str, to: &str) -> (String, String, String) {
    let base = std::fs::read_to_string(config_path(preset)).unwrap();
    assert!(base.contains(from), "{preset} lacks {from:?}");
    let text = base.replacen(from, to, 1);
    match lidarsim::loaded::load_str(&text, std::path::Path::new("test.toml"), &[]) {
        Err(e @ Error::Config { .. }) => {
            assert!(!e.to_string().contains('\n'), "{e}");
            let Error::Config { file, key, reason } = e else {
                unreachable!()
            };
            (file, key, reason)
        }
        Err(other) => panic!("{preset} with {to:?}: not a config error: {other}"),
        Ok(_) => panic!("{preset} with {to:?}: accepted"),
    }
}

/// What docs/config.md refuses for a channel, refused when the channels are read
/// (issue 36, item 18), in one line naming the file, the channel's key and the reason:
/// `species` on an `hsrl_molecular` channel; a filter table without air
/// (`atmosphere.molecular.model = "none"`: the Cabannes line's width needs the
/// temperature); a `both` channel whose `<name>_an` would pass the 64-character limit; a
/// Raman line beyond the 200–4000 nm the model covers, or none at all (the shift larger
/// than the laser's wavenumber: H₂O at 3,000 nm, refused late before as "the signal is
/// not finite").
#[test]
fn documented_channel_limits_are_refused_at_the_channel_key() {
    let atlid = "instruments/atlid_like.toml";
    let molecular = "kind = \"hsrl_molecular\"\n";
    let (file, key, reason) =
        preset_error(atlid, molecular, &format!("{molecular}species = \"N2\"\n"));
    assert_eq!(file, "test.toml");
    assert_eq!(key, "instrument.channels[1].species");
    assert!(
        reason.contains("Raman channels") && reason.contains("hsrl_molecular"),
        "{reason}"
    );

    let constants = "molecular_transmission = 0.6     # f_m: the Cabannes line's wings (ASSUMED)\nparticle_transmission = 0.02     # f_p: particle line leaking through the filter (ASSUMED)\n";
    let notch = "spectral_filter = { offset_ghz = [-1.5, -0.5, 0.5, 1.5], transmission = [0.9, 0.02, 0.02, 0.9] }\n";
    let base = std::fs::read_to_string(config_path(atlid)).unwrap();
    let us76 = base[base.find("[atmosphere.molecular]").unwrap()..]
        .lines()
        .find(|l| l.starts_with("model"))
        .unwrap()
        .to_string();
    let text = base
        .replacen(constants, notch, 1)
        .replacen(&us76, "model = \"none\"", 1);
    let Err(e) = lidarsim::loaded::load_str(&text, std::path::Path::new("test.toml"), &[]) else {
        panic!("a filter table without air accepted");
    };
    let shown = e.to_string();
    assert!(
        shown.starts_with("test.toml: key `instrument.channels[1].spectral_filter`:")
            && shown.contains("\"none\"")
            && !shown.contains('\n'),
        "{shown}"
    );

    let glued = "ground/pollyxt_like_glued.toml";
    let text = std::fs::read_to_string(config_path(glued)).unwrap();
    let old_name = "name = \"355_total\"";
    let long = format!("name = \"{}\"", "x".repeat(62));
    let (_, key, reason) = preset_error(glued, old_name, &long);
    assert_eq!(key, "instrument.channels[0].name");
    assert!(
        reason.contains("62 characters") && reason.contains("at most 61"),
        "{reason}"
    );
    // 61 characters make `<name>_an` of 64: accepted
    let ok = text.replacen(old_name, &format!("name = \"{}\"", "x".repeat(61)), 1);
    lidarsim::loaded::load_str(&ok, std::path::Path::new("test.toml"), &[]).unwrap();

    let polly = "ground/pollyxt_like.toml";
    let n2 = "wavelength_nm = 354.7            # the laser line; the channel detects 386.7 nm";
    let h2o =
        "species = \"H2O\"                  # the channel detects 407.5 nm\nwavelength_nm = 354.7";
    let cases = [
        // N2 (2330.7 cm⁻¹) of a 4,000 nm laser: the line at 59 µm; at most 2,070 nm
        (
            n2,
            "wavelength_nm = 4000".to_string(),
            2,
            "at most 2070.1 nm",
            "59067 nm",
        ),
        // H2O (3652 cm⁻¹) of 2,738 nm: 3,652.3 cm⁻¹, the line at ~3e7 nm
        (
            h2o,
            "species = \"H2O\"\nwavelength_nm = 2738".to_string(),
            3,
            "at most 1625.5 nm",
            "beyond",
        ),
        // H2O of 3,000 nm: 3,333 cm⁻¹, less than the shift: no line
        (
            h2o,
            "species = \"H2O\"\nwavelength_nm = 3000".to_string(),
            3,
            "at most 1625.5 nm",
            "does not exist",
        ),
    ];
    for (from, to, k, limit, why) in cases {
        let (_, key, reason) = preset_error(polly, from, &to);
        assert_eq!(
            key,
            format!("instrument.channels[{k}].wavelength_nm"),
            "{to}"
        );
        assert!(
            reason.contains(limit) && reason.contains(why),
            "{to}: {reason}"
        );
    }
    // the longest N2 laser accepted: its line at 4,000 nm
    let base = std::fs::read_to_string(config_path(polly)).unwrap();
    let ok = base.replacen(n2, "wavelength_nm = 2070.0", 1);
    lidarsim::loaded::load_str(&ok, std::path::Path::new("test.toml"), &[]).unwrap();
}

/// A number where a key takes one of its names (`mode = 5`) says so, not serde's
/// "expected string only, got unit variant" (issue 36, item 18).
#[test]
fn a_number_for_a_name_says_a_name_is_expected() {
    for set in ["instrument.detector={mode=5}", "instrument.channel=5"] {
        let Err(e) = load(&[set]) else {
            panic!("{set}: accepted");
        };
        let e = e.to_string();
        assert!(
            e.contains("expected a string, one of the names this key takes")
                && !e.contains("unit variant")
                && !e.contains('\n'),
            "{e}"
        );
    }
}
