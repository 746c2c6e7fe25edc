//! The CAMS species of a model-field scene (issue 39 item 4) in the raw file's truth and
//! optics, along `configs/instruments/caliop_fields_aerosol.toml` moved into the
//! fixture's dust plume, each against a reference computed here from the fixtures' raw
//! numbers (`configs/fields/*.nc` read with `hdf5` / `netcdf3`), not the code under test:
//!
//! * the extinction by species (`alpha_aer_aermrNN`) sums to `alpha_aer` within 1e-12
//!   relative in every bin, and a dust species' equals `ρ_air·mmr·k_ext` of the level
//!   holding the bin (ρ_air = p/(R_d·T·(1 + (1/ε − 1)q)), the mass mixing ratio interpolated by the stated rule, bilinear in
//!   latitude and longitude and linear in time) within 1e-9;
//! * the depolarization overrides (`scene.model_fields.aerosol_depolarization`,
//!   `liquid_depolarization`, `ice_depolarization`) give `depol_aer` the mixture's
//!   `Σβ_s δ_s/(1+δ_s) / Σβ_s/(1+δ_s)` (the dust backscatter from the species' truth and
//!   the table's lidar ratios) within 1e-9, and `depol_cld` the phases' value; bad
//!   values are refused naming the file and key;
//! * a 607 nm N₂ Raman channel of the 532 nm laser sees each dust species at 607.4 nm:
//!   its extinction at 532 nm times the table's `(k(865)/k(532))^f`,
//!   `f = ln(λ_R/532)/ln(865/532)` (log-log between the tabulated wavelengths), within
//!   1e-9 relative.

mod common;

use common::cli::scratch;
use common::config_path;
use common::h5::{floats, simulate_with};
use lidarsim::error::Error;
use lidarsim::scene::fields::{Sample, profile_samples, read};
use lidarsim::scene::orbit::Orbit;

const CONFIG: &str = "instruments/caliop_fields_aerosol.toml";
const PROFILES: usize = 3;
const UNIX_1900: f64 = -2_208_988_800.0;
/// The pass moved to start at 35.5 N, in the plume.
const START: [&str; 2] = [
    "orbit.start_latitude_deg=35.5",
    "orbit.start_longitude_deg=-2.0",
];
/// The dust species and their hydrophobic types (1-based) in ECMWF's 49R1 map.
const DUST: [(&str, usize); 3] = [("aermr04", 7), ("aermr05", 8), ("aermr06", 9)];

/// Runs the config (with `more` `--set` overrides, or another config text) and opens the
/// file.
fn run(tag: &str, config: Option<&str>, sets: &[&str]) -> hdf5::File {
    let dir = scratch(tag);
    let cfg = match config {
        Some(text) => {
            let p = dir.join("c.toml");
            std::fs::write(&p, text).unwrap();
            p
        }
        None => config_path(CONFIG),
    };
    let mut more = vec![];
    for s in START.iter().chain(sets) {
        more.extend(["--set", s]);
    }
    simulate_with(&dir, &cfg, "a.h5", &PROFILES.to_string(), &more)
}

/// The shipped config with absolute fixture paths and `extra` appended.
fn config_text(extra: &str) -> String {
    let fields = config_path("fields");
    std::fs::read_to_string(config_path(CONFIG))
        .unwrap()
        .replace("../fields/", &format!("{}/", fields.display()))
        + extra
}

/// The fixture table's float variable `name`, raw.
fn table(name: &str) -> Vec<f64> {
    let mut r =
        netcdf3::FileReader::open(config_path("fields/aerosol_optics_like_ifs.nc")).unwrap();
    match r.read_var(name).unwrap() {
        netcdf3::DataVector::F32(v) => v.into_iter().map(f64::from).collect(),
        other => panic!("{name}: {:?}", other.data_type()),
    }
}

/// Index of `w` in the table's wavelengths.
fn wavelength(w: f64) -> usize {
    table("wavelength_mono")
        .iter()
        .position(|x| (x - w).abs() < 1e-12)
        .unwrap()
}

/// A hydrophobic type's `mass_ext_mono` / `lidar_ratio_mono` at wavelength index `w`.
fn phobic(var: &str, t: usize, w: usize) -> f64 {
    let n = table("wavelength_mono").len();
    table(&format!("{var}_mono_hydrophobic"))[(t - 1) * n + w]
}

fn rel(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / a.abs().max(b.abs())
    }
}

/// `(columns, channels, bins)` of a raw file's truth.
fn sizes(f: &hdf5::File, channels: usize) -> (usize, usize, usize) {
    let nb = floats(f, "altitude").len();
    (floats(f, "alpha_aer").len() / (channels * nb), channels, nb)
}

#[test]
fn the_species_sum_to_the_aerosol_and_a_dust_species_is_its_mixing_ratio_by_hand() {
    let f = run("species_truth", None, &[]);
    let total = floats(&f, "alpha_aer");
    let names: Vec<String> = f
        .member_names()
        .unwrap()
        .into_iter()
        .filter(|n| n.starts_with("alpha_aer_aermr"))
        .collect();
    // the fixture's seven species
    assert_eq!(names.len(), 7, "{names:?}");
    let parts: Vec<Vec<f64>> = names.iter().map(|n| floats(&f, n)).collect();
    let mut with_aerosol = 0;
    for (i, t) in total.iter().enumerate() {
        let sum: f64 = parts.iter().map(|p| p[i]).sum();
        assert!(
            rel(sum, *t) < 1e-12,
            "bin {i}: Σ species {sum} vs alpha_aer {t}"
        );
        with_aerosol += usize::from(*t > 0.0);
    }
    assert!(with_aerosol > 100, "{with_aerosol}");
    // aermr06 (dust 0.9-20 um, hydrophobic type 9) of profile 0's first column by hand
    let (_, _, nb) = sizes(&f, 1);
    let col = f
        .dataset("profile_column")
        .unwrap()
        .read_raw::<i64>()
        .unwrap();
    let c = col[0] as usize;
    let alt = floats(&f, "altitude");
    let dust = floats(&f, "alpha_aer_aermr06");
    let (levels, interfaces, mmr) = hand_column("aermr06");
    let k_ext = phobic("mass_ext", 9, wavelength(532e-9));
    let mut seen = 0;
    for (i, z) in alt.iter().enumerate() {
        let Some(k) = (0..levels.len()).find(|&k| interfaces[k] <= *z && *z < interfaces[k + 1])
        else {
            continue;
        };
        let (p, t, q) = levels[k];
        // ρ_air = p/(R_d·T·(1 + (1/ε − 1)·q)), R_d = 287.0597, ε = 0.622
        let rho = p / (287.0597 * t * (1.0 + (1.0 / 0.622 - 1.0) * q));
        let want = rho * mmr[k] * k_ext;
        let got = dust[c * nb + i];
        if want > 0.0 {
            seen += 1;
        }
        assert!(
            rel(got, want) < 1e-9,
            "bin {i} ({z} m, level {k}): {got} vs {want} by hand"
        );
    }
    assert!(seen > 20, "{seen} bins with dust");
}

/// A column by hand: levels bottom up (p, T, q), their layers' interfaces, a species'
/// mass mixing ratio at each.
type HandColumn = (Vec<(f64, f64, f64)>, Vec<f64>, Vec<f64>);

/// Profile 0's levels bottom up (p, T, q), their layers' interfaces, and the species
/// `name`'s mass mixing ratio at each, interpolated by hand from the raw CAMS-like file.
fn hand_column(name: &str) -> HandColumn {
    let ov: Vec<String> = START.iter().map(|s| s.to_string()).collect();
    let cfg = lidarsim::loaded::load(&config_path(CONFIG), &ov)
        .unwrap()
        .config;
    let mut m = cfg.scene.as_ref().unwrap().model_fields.clone().unwrap();
    let orbit = Orbit::from_config(cfg.orbit.as_ref().unwrap(), 705e3).unwrap();
    let along = lidarsim::scene::track::AlongTrack::Orbit(orbit);
    let s: Sample = profile_samples(&cfg, &along, 15, 1).unwrap()[0].0;
    // the levels' p, T, q and layers, without the aerosol
    m.aerosol_optics = None;
    let files = [config_path("fields/era5_like_model_levels.nc")];
    let c = &read::columns(&m, &files, &[s]).unwrap()[0];
    let f = hdf5::File::open(config_path("fields/cams_like_model_levels.nc")).unwrap();
    let raw = |n: &str| f.dataset(n).unwrap().read_raw::<f64>().unwrap();
    let time: Vec<f64> = raw("time").iter().map(|h| UNIX_1900 + 3600.0 * h).collect();
    let (lat, lon) = (raw("latitude"), raw("longitude"));
    let nl = raw("level").len();
    let (ny, nx) = (lat.len(), lon.len());
    let field = raw(name);
    let weights = |axis: &[f64], x: f64| -> Vec<(usize, f64)> {
        let i = (0..axis.len() - 1)
            .find(|&i| (axis[i] - x) * (axis[i + 1] - x) <= 0.0)
            .unwrap();
        let w = (x - axis[i]) / (axis[i + 1] - axis[i]);
        vec![(i, 1.0 - w), (i + 1, w)]
    };
    let mmr_at = |k: usize| {
        let mut v = 0.0;
        for (ti, wt) in weights(&time, s.time_s) {
            for (y, wy) in weights(&lat, s.latitude_deg) {
                for (x, wx) in weights(&lon, s.longitude_deg) {
                    v += wt * wy * wx * field[((ti * nl + k) * ny + y) * nx + x];
                }
            }
        }
        v.max(0.0)
    };
    // the file's levels run top down; the column's bottom up
    let mmr = (0..c.levels.len()).map(|i| mmr_at(nl - 1 - i)).collect();
    let levels = c.levels.iter().map(|l| (l.p_pa, l.t_k, l.q)).collect();
    (levels, c.interfaces_m.clone(), mmr)
}

#[test]
fn depolarization_overrides_give_the_mixture_s_ratio() {
    let (dust, other) = (0.3, 0.1);
    let sets = [
        "scene.model_fields.aerosol_depolarization={ dust = 0.3, marine = 0.1, smoke = 0.1, sulphate = 0.1 }",
        "scene.model_fields.liquid_depolarization=0.25",
        "scene.model_fields.ice_depolarization=0.25",
    ];
    let f = run("species_depol", None, &sets);
    let depol = floats(&f, "depol_aer");
    let beta = floats(&f, "beta_aer");
    let w = wavelength(532e-9);
    // the dust backscatter: each dust species' extinction over its lidar ratio
    let species: Vec<(Vec<f64>, f64)> = DUST
        .iter()
        .map(|(n, t)| {
            (
                floats(&f, &format!("alpha_aer_{n}")),
                phobic("lidar_ratio", *t, w),
            )
        })
        .collect();
    let mut mixed = 0;
    for i in 0..depol.len() {
        if beta[i] <= 0.0 {
            continue;
        }
        let beta_dust: f64 = species.iter().map(|(a, s)| a[i] / s).sum();
        let beta_other = (beta[i] - beta_dust).max(0.0);
        let perp = beta_dust * dust / (1.0 + dust) + beta_other * other / (1.0 + other);
        let par = beta_dust / (1.0 + dust) + beta_other / (1.0 + other);
        let want = perp / par;
        assert!(
            (depol[i] - want).abs() < 1e-9 * want,
            "bin {i}: depol_aer {} vs {want} (dust share {})",
            depol[i],
            beta_dust / beta[i]
        );
        mixed += usize::from(beta_dust > 0.05 * beta[i] && beta_other > 0.05 * beta[i]);
    }
    assert!(mixed > 10, "{mixed} bins mix dust and other species");
    let cloud = floats(&f, "depol_cld");
    let cloudy = floats(&f, "beta_cld").iter().filter(|b| **b > 0.0).count();
    assert!(cloudy > 10, "{cloudy}");
    for (b, d) in floats(&f, "beta_cld").iter().zip(&cloud) {
        if *b > 0.0 {
            assert!((d - 0.25).abs() < 1e-12, "depol_cld {d}");
        }
    }
}

#[test]
fn bad_depolarizations_are_refused_naming_file_and_key() {
    for (set, key) in [
        (
            "scene.model_fields.aerosol_depolarization={ dust = 1.0 }",
            "scene.model_fields.aerosol_depolarization.dust",
        ),
        (
            "scene.model_fields.aerosol_depolarization={ marine = -0.01 }",
            "scene.model_fields.aerosol_depolarization.marine",
        ),
        (
            "scene.model_fields.ice_depolarization=nan",
            "scene.model_fields.ice_depolarization",
        ),
        (
            "scene.model_fields.liquid_depolarization=1.5",
            "scene.model_fields.liquid_depolarization",
        ),
    ] {
        match lidarsim::loaded::load(&config_path(CONFIG), &[set.to_string()]) {
            Err(e @ Error::Config { .. }) => {
                let Error::Config { file, key: k, .. } = &e else {
                    unreachable!()
                };
                assert_eq!(k, key, "{e}");
                assert_eq!(file, &format!("--set {set}"), "{e}");
                assert!(!e.to_string().contains('\n'), "{e}");
            }
            Err(e) => panic!("{set}: not a config error: {e}"),
            Ok(_) => panic!("{set}: accepted"),
        }
    }
    let e = lidarsim::loaded::load(
        &config_path(CONFIG),
        &["scene.model_fields.aerosol_depolarization={ sand = 0.3 }".to_string()],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("sand"), "{e}");
}

#[test]
fn a_raman_channel_sees_each_species_at_its_line() {
    let text = config_text(
        "\n[[instrument.channels]]\nname = \"532_total\"\n\n\
         [[instrument.channels]]\nname = \"607_raman_N2\"\nkind = \"raman\"\nfilter_width_nm = 3.0\n",
    );
    let only_dust = "scene.model_fields.aerosol_species=[\"aermr04\",\"aermr05\",\"aermr06\"]";
    let f = run("species_raman", Some(&text), &[only_dust]);
    let (nc, nch, nb) = sizes(&f, 2);
    let line_m: f64 = 1.0 / (1.0 / 532e-9 - 233_070.0);
    assert!((line_m * 1e9 - 607.3).abs() < 0.05, "{line_m}");
    let (w532, w865) = (wavelength(532e-9), wavelength(865e-9));
    let wl = table("wavelength_mono");
    let frac = (line_m / wl[w532]).ln() / (wl[w865] / wl[w532]).ln();
    let total = floats(&f, "alpha_aer");
    let mut want_total = vec![0.0; total.len()];
    let mut checked = 0;
    for (n, t) in DUST {
        let a = floats(&f, &format!("alpha_aer_{n}"));
        let ratio = (phobic("mass_ext", t, w865) / phobic("mass_ext", t, w532)).powf(frac);
        for c in 0..nc {
            for i in 0..nb {
                let (elastic, raman) = ((c * nch) * nb + i, (c * nch + 1) * nb + i);
                let want = a[elastic] * ratio;
                assert!(
                    rel(a[raman], want) < 1e-9,
                    "{n} column {c} bin {i}: {} at the line vs {want} by hand",
                    a[raman]
                );
                want_total[raman] += want;
                checked += usize::from(want > 0.0);
            }
        }
    }
    assert!(checked > 100, "{checked}");
    for c in 0..nc {
        for i in 0..nb {
            let k = (c * nch + 1) * nb + i;
            assert!(
                rel(total[k], want_total[k]) < 1e-9,
                "column {c} bin {i}: alpha_aer {} at the line vs {} by hand",
                total[k],
                want_total[k]
            );
        }
    }
}

/// The shipped pass from 42 N south into the plume: its first columns carry no dust, its
/// last do. The file names every species the scene carries before its first column is
/// built (the columns come lazily, docs/file-format.md): seven `alpha_aer_aermrNN`, the
/// dust ones 0 in the first column and not in the last, the species summing to
/// `alpha_aer` in every column.
#[test]
fn a_species_the_first_columns_lack_is_in_the_file_with_zeros_there() {
    let dir = scratch("species_later");
    let f = simulate_with(&dir, &config_path(CONFIG), "a.h5", "200", &[]);
    let total = floats(&f, "alpha_aer");
    let names: Vec<String> = (f.member_names().unwrap().into_iter())
        .filter(|n| n.starts_with("alpha_aer_aermr"))
        .collect();
    assert_eq!(names.len(), 7, "{names:?}");
    let (n_columns, _, nb) = sizes(&f, 1);
    // (profile, slot), -1 in unused slots: each profile's first column
    let ds = f.dataset("profile_column").unwrap();
    let slots = ds.shape()[1];
    let col = ds.read_raw::<i64>().unwrap();
    let (first, last) = (col[0] as usize, col[col.len() - slots] as usize);
    let dust = floats(&f, "alpha_aer_aermr04");
    let of = |c: usize| &dust[c * nb..(c + 1) * nb];
    assert!(
        of(first).iter().all(|x| *x == 0.0),
        "dust in column {first}"
    );
    assert!(
        of(last).iter().any(|x| *x > 0.0),
        "no dust in column {last}"
    );
    let parts: Vec<Vec<f64>> = names.iter().map(|n| floats(&f, n)).collect();
    assert_eq!(total.len(), n_columns * nb);
    for (i, t) in total.iter().enumerate() {
        let sum: f64 = parts.iter().map(|p| p[i]).sum();
        assert!(rel(sum, *t) < 1e-12, "value {i}: Σ species {sum} vs {t}");
    }
}
