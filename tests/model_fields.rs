//! Model fields as the scene (issue 39; `src/scene/fields/`, docs/scenes.md "Model
//! fields"): the fixture files of `tools/make_model_fields.py` read back against
//! hand calculation from their raw numbers (read here with `hdf5` and `netcdf3`, not
//! through the code under test), and bad files refused in one line.

mod common;

use std::path::{Path, PathBuf};

use lidarsim::config::{CloudPhase, FieldsInterpolation, ModelFieldsConfig, ScenarioConfig};
use lidarsim::scene::fields::{FieldColumn, Sample, layers, profile_samples, read};
use lidarsim::scene::orbit::Orbit;

const CONFIG: &str = "instruments/caliop_fields.toml";
/// 1900-01-01T00:00:00Z in Unix seconds (70 years of which 17 leap: 25,567 days).
const UNIX_1900: f64 = -2_208_988_800.0;
const RD: f64 = 287.0597;
const G0: f64 = 9.80665;

fn fixture(name: &str) -> PathBuf {
    common::config_path(&format!("fields/{name}"))
}

/// The shipped config, its model fields and the samples of its 200 profiles.
fn shipped() -> (ScenarioConfig, ModelFieldsConfig, Vec<Sample>) {
    let cfg = lidarsim::loaded::load(&common::config_path(CONFIG), &[])
        .unwrap()
        .config;
    let m = cfg.scene.as_ref().unwrap().model_fields.clone().unwrap();
    let orbit = Orbit::from_config(cfg.orbit.as_ref().unwrap(), 705e3).unwrap();
    let samples = profile_samples(
        &cfg,
        &lidarsim::scene::track::AlongTrack::Orbit(orbit),
        15,
        200,
    )
    .unwrap();
    (cfg, m, samples.iter().map(|s| s.0).collect())
}

/// The hand rule: `(i, w)` pairs of `x` on the monotonic `axis`, linear (two) or
/// nearest (one), found by a linear search.
fn hand_weights(axis: &[f64], x: f64, nearest: bool) -> Vec<(usize, f64)> {
    for i in 0..axis.len() - 1 {
        let (a, b) = (axis[i], axis[i + 1]);
        if (a <= x && x <= b) || (b <= x && x <= a) {
            let w = (x - a) / (b - a);
            return if !nearest {
                vec![(i, 1.0 - w), (i + 1, w)]
            } else if w > 0.5 {
                vec![(i + 1, 1.0)]
            } else {
                vec![(i, 1.0)]
            };
        }
    }
    panic!("{x} outside {axis:?}");
}

/// The raw grid of a fixture: axes (time in Unix seconds) and the reader of a field.
struct Raw {
    time: Vec<f64>,
    lat: Vec<f64>,
    lon: Vec<f64>,
    levels: usize,
}

impl Raw {
    /// `field` (time, level, lat, lon) or (time, lat, lon) at sample `s`, level `k`.
    fn at(&self, field: &[f64], per_level: bool, s: &Sample, k: usize, nearest: bool) -> f64 {
        let (ny, nx) = (self.lat.len(), self.lon.len());
        let nl = if per_level { self.levels } else { 1 };
        let mut v = 0.0;
        for (t, wt) in hand_weights(&self.time, s.time_s, nearest) {
            for (y, wy) in hand_weights(&self.lat, s.latitude_deg, nearest) {
                for (x, wx) in hand_weights(&self.lon, s.longitude_deg, nearest) {
                    v += wt * wy * wx * field[((t * nl + k) * ny + y) * nx + x];
                }
            }
        }
        v
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The netCDF-4 model-level fixture's numbers, read with `hdf5`.
fn model_level_raw() -> (Raw, impl Fn(&str) -> Vec<f64>) {
    let f = hdf5::File::open(fixture("era5_like_model_levels.nc")).unwrap();
    let read = move |n: &str| f.dataset(n).unwrap().read_raw::<f64>().unwrap();
    let raw = Raw {
        time: read("time")
            .iter()
            .map(|h| UNIX_1900 + 3600.0 * h)
            .collect(),
        lat: read("latitude"),
        lon: read("longitude"),
        levels: read("hyam").len(),
    };
    (raw, read)
}

/// The water layer of level `i` (bottom up) of column `c`, if any.
fn water_extinction_per_m(m: &ModelFieldsConfig, c: &FieldColumn, i: usize) -> Option<f64> {
    let base = c.interfaces_m[i] / 1e3;
    layers(m, c)
        .iter()
        .find(|l| l.phase == Some(CloudPhase::Water) && l.base_km == base)
        .map(|l| l.extinction_per_km / 1e3)
}

/// Along the shipped pass, every level of every profile: temperature and pressure
/// equal the fields interpolated by the stated rule (bilinear in latitude and
/// longitude, linear in time; p = a + b·p_s) within 1e-9 relative, and a liquid
/// cloud's extinction equals (3/4)·Q·ρ_air·q/(ρ_w·r_e) with Q = 2, r_e = 10 µm,
/// ρ_air = p/(R_d·T·(1 + 0.6078·q)) within 1e-6 relative. (Made 1 % wrong — the
/// extinction efficiency 2 → 2.02 in `cloud_optics::extinction_per_m`, or T scaled by
/// 1.01 in the sampling — this test fails.)
#[test]
fn temperature_pressure_and_liquid_extinction_are_the_hand_values() {
    let (_, m, samples) = shipped();
    let cols = read::columns(&m, &[fixture("era5_like_model_levels.nc")], &samples).unwrap();
    let (raw, read) = model_level_raw();
    let (t, q, clwc, sp) = (read("t"), read("q"), read("clwc"), read("sp"));
    let (a, b) = (read("hyam"), read("hybm"));
    let nl = raw.levels;
    let mut liquid = 0;
    for (s, c) in samples.iter().zip(&cols) {
        assert_eq!(c.levels.len(), nl);
        let ps = raw.at(&sp, false, s, 0, false);
        for k in 0..nl {
            // the file's levels run top down, the column's bottom up
            let i = nl - 1 - k;
            let l = &c.levels[i];
            let t_ref = raw.at(&t, true, s, k, false);
            let p_ref = a[k] + b[k] * ps;
            assert!(rel(l.t_k, t_ref) < 1e-9, "T {} vs {t_ref}", l.t_k);
            assert!(rel(l.p_pa, p_ref) < 1e-9, "p {} vs {p_ref}", l.p_pa);
            let ql = raw.at(&clwc, true, s, k, false);
            let qv = raw.at(&q, true, s, k, false);
            let rho = p_ref / (RD * t_ref * (1.0 + (1.0 / 0.622 - 1.0) * qv));
            let alpha_ref = 0.75 * 2.0 * rho * ql / (1000.0 * 10e-6);
            match water_extinction_per_m(&m, c, i) {
                Some(alpha) => {
                    assert!(rel(alpha, alpha_ref) < 1e-6, "{alpha} vs {alpha_ref}");
                    liquid += 1;
                }
                None => assert_eq!(ql, 0.0),
            }
        }
    }
    // the front and the stratocumulus: many liquid levels checked
    assert!(liquid > 300, "{liquid} liquid levels");
}

/// The fields read in runs of profiles (a box per run, memory flat in the track) give
/// the same columns, bit for bit, whatever the run's bound: one box for the whole pass,
/// one per profile, and runs of a few profiles; the model-level (netCDF-4) and
/// pressure-level (netCDF-3) fixtures. (With the box's index made to drop the latitude
/// offset, `Slab::index`, the per-profile reads go wrong and this test fails.)
#[test]
fn the_columns_are_the_same_whatever_the_runs_the_fields_are_read_in() {
    let (_, m, mut samples) = shipped();
    // the pass's points at times across the whole file
    let (raw, _) = model_level_raw();
    let (t0, t1) = (raw.time[0], raw.time[raw.time.len() - 1]);
    let n = samples.len() as f64;
    for (i, s) in samples.iter_mut().enumerate() {
        s.time_s = t0 + (t1 - t0) * i as f64 / n;
    }
    for file in ["era5_like_model_levels.nc", "era5_like_pressure_levels.nc"] {
        let files = [fixture(file)];
        let whole = read::columns_in_runs(&m, &files, &samples, usize::MAX).unwrap();
        for cap in [1, 5_000, 40_000] {
            let runs = read::columns_in_runs(&m, &files, &samples, cap).unwrap();
            assert!(whole == runs, "{file}: runs of at most {cap} cells differ");
        }
    }
}

/// The netCDF-3 pressure-level fixture (temperature packed as int16 with
/// scale_factor / add_offset, latitudes north to south): temperature, pressure (the
/// level coordinate, hPa) and height (geopotential / g₀) equal the hand values within
/// 1e-9 relative, bilinear-linear and nearest.
#[test]
fn the_netcdf3_pressure_levels_read_by_the_stated_rule() {
    let (_, mut m, samples) = shipped();
    let path = fixture("era5_like_pressure_levels.nc");
    let mut r = netcdf3::FileReader::open(&path).unwrap();
    let floats = |r: &mut netcdf3::FileReader, n: &str| -> Vec<f64> {
        match r.read_var(n).unwrap() {
            netcdf3::DataVector::F32(v) => v.into_iter().map(f64::from).collect(),
            netcdf3::DataVector::I32(v) => v.into_iter().map(f64::from).collect(),
            netcdf3::DataVector::F64(v) => v,
            other => panic!("{n}: {:?}", other.data_type()),
        }
    };
    let t_var = r.data_set().get_var("t").unwrap();
    let scale = t_var.get_attr_f64("scale_factor").unwrap()[0];
    let offset = t_var.get_attr_f64("add_offset").unwrap()[0];
    let packed = r.read_var("t").unwrap().get_i16_into().unwrap();
    let t: Vec<f64> = packed
        .iter()
        .map(|&x| f64::from(x) * scale + offset)
        .collect();
    let z = floats(&mut r, "z");
    let plev = floats(&mut r, "level");
    let raw = Raw {
        time: floats(&mut r, "time")
            .iter()
            .map(|h| UNIX_1900 + 3600.0 * h)
            .collect(),
        lat: floats(&mut r, "latitude"),
        lon: floats(&mut r, "longitude"),
        levels: plev.len(),
    };
    let nl = raw.levels;
    for rule in [FieldsInterpolation::Linear, FieldsInterpolation::Nearest] {
        m.interpolation = rule;
        let nearest = rule == FieldsInterpolation::Nearest;
        let cols = read::columns(&m, std::slice::from_ref(&path), &samples).unwrap();
        for (s, c) in samples.iter().zip(&cols) {
            for (k, &p_hpa) in plev.iter().enumerate() {
                let l = &c.levels[nl - 1 - k];
                let t_ref = raw.at(&t, true, s, k, nearest);
                assert!(rel(l.t_k, t_ref) < 1e-9, "T {} vs {t_ref}", l.t_k);
                assert!(rel(l.p_pa, p_hpa * 100.0) < 1e-12, "p {}", l.p_pa);
                let z_ref = raw.at(&z, true, s, k, nearest) / G0;
                assert!(rel(l.height_m, z_ref) < 1e-9, "z {} vs {z_ref}", l.height_m);
            }
        }
    }
}

/// The shipped pass simulates (a short run), its layers come from the fields, and the
/// model's surface height sets the surface.
#[test]
fn the_shipped_pass_simulates() {
    let dir = common::cli::scratch("model-fields-run");
    let config = common::config_path(CONFIG);
    let o = common::cli::lidarsim(
        &dir,
        &[
            "simulate",
            config.to_str().unwrap(),
            "--set",
            "acquisition.profiles=60",
            "-o",
            "f.h5",
        ],
        &[],
    );
    common::cli::ok(o);
    let f = hdf5::File::open(dir.join("f.h5")).unwrap();
    let cld = common::h5::floats(&f, "alpha_cld_bin_mean");
    assert!(cld.iter().any(|&x| x > 0.0), "no cloud along the pass");
}

/// A small netCDF-4-like HDF5 file of 2 times × 3 hybrid levels × 2 × 2 points around
/// the shipped pass's start, broken as `how` says.
fn synthetic(path: &Path, how: &str) {
    use hdf5::types::VarLenUnicode;
    let f = hdf5::File::create(path).unwrap();
    let put = |name: &str, shape: &[usize], v: &[f64], units: &str| {
        let d = f.new_dataset::<f64>().shape(shape).create(name).unwrap();
        d.write_raw(v).unwrap();
        d.new_attr::<VarLenUnicode>()
            .shape(())
            .create("units")
            .unwrap()
            .write_scalar(&units.parse::<VarLenUnicode>().unwrap())
            .unwrap();
    };
    let time_units = if how == "time" {
        "hours since 2024-02-01 00:00:00"
    } else {
        "hours since 2024-01-15 00:00:00"
    };
    put("time", &[2], &[0.0, 1.0], time_units);
    put("level", &[3], &[1.0, 2.0, 3.0], "1");
    let lat = if how == "outside" {
        [47.0, 45.0]
    } else {
        [43.0, 41.0]
    };
    put("latitude", &[2], &lat, "degrees_north");
    put("longitude", &[2], &[-2.0, 0.0], "degrees_east");
    let a = if how == "order" {
        [1e4, 8e4, 5e4]
    } else {
        [1e4, 5e4, 8e4]
    };
    put("hyam", &[3], &a, "Pa");
    put("hybm", &[3], &[0.0; 3], "1");
    let n = 2 * 3 * 2 * 2;
    put(
        "t",
        &[2, 3, 2, 2],
        &vec![250.0; n],
        if how == "units" { "degC" } else { "K" },
    );
    put("q", &[2, 3, 2, 2], &vec![1e-3; n], "kg kg**-1");
    if how != "missing" {
        let mut clwc = vec![1e-4; n];
        if how == "nan" {
            clwc[5] = f64::NAN;
        }
        put("clwc", &[2, 3, 2, 2], &clwc, "kg kg**-1");
    }
    put("ciwc", &[2, 3, 2, 2], &vec![0.0; n], "kg kg**-1");
    put("sp", &[2, 2, 2], &[1e5; 8], "Pa");
}

/// Bad files: one line naming the file, the variable and the reason, exit 2, no output.
#[test]
fn bad_fields_are_refused_in_one_line() {
    let dir = common::cli::scratch("model-fields-bad");
    let config = common::config_path(CONFIG);
    // the good file runs
    let good = dir.join("good.nc");
    synthetic(&good, "");
    let args = |file: &Path| -> Vec<String> {
        [
            "simulate",
            config.to_str().unwrap(),
            "--set",
            &format!("scene.model_fields.files=[{:?}]", file.to_str().unwrap()),
            "--set",
            "acquisition.profiles=2",
            "-o",
            "out.h5",
        ]
        .map(String::from)
        .to_vec()
    };
    let a = args(&good);
    common::cli::ok(common::cli::lidarsim(
        &dir,
        &a.iter().map(String::as_str).collect::<Vec<_>>(),
        &[],
    ));
    std::fs::remove_file(dir.join("out.h5")).unwrap();
    for (how, words) in [
        (
            "units",
            &["`t`", "\"degC\" are not units of temperature"][..],
        ),
        ("nan", &["`clwc`", "NaN or fill value"]),
        ("order", &["levels out of order", "pressure"]),
        (
            "outside",
            &["`t`", "outside the fields' latitude", "profile 0"],
        ),
        (
            "time",
            &["`t`", "outside the fields' time", "2024-02-01T00:00:00Z"],
        ),
        ("missing", &["no liquid variable", "`clwc`"]),
    ] {
        let file = dir.join(format!("{how}.nc"));
        synthetic(&file, how);
        let mut words = words.to_vec();
        let name = file.file_name().unwrap().to_str().unwrap().to_string();
        words.push(&name);
        let a = args(&file);
        common::cli::refused(
            &dir,
            &a.iter().map(String::as_str).collect::<Vec<_>>(),
            &words,
            "out.h5",
        );
    }
}
