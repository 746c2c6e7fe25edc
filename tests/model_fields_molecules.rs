//! The molecules of a model-field scene from the fields themselves (issue 39 item 5,
//! `scene.model_fields.molecules = "fields"`, docs/model.md §4k): each profile's
//! pressure and temperature in the raw file equal its model column's levels mapped onto
//! the range bins by the stated rule — ln p and ln N linear in height between levels
//! (N = p/(k_B·T) at each level), T = p/(k_B·N) between them — within 1e-9 relative, the
//! rule written here. The levels themselves are checked against the fixture's raw
//! numbers by `tests/model_fields.rs`. The water vapour's mixing ratio is each level's
//! q/(1 − q), linear in height. With `molecules = "config"` the file holds US76's and no
//! water vapour.
//! (A 1 % error in the levels' pressure, or T interpolated linearly instead, fails it:
//! the interpolated T between levels 1 km apart differs from linear by ~1e-4.)

mod common;

use common::cli::{lidarsim, ok, scratch};
use common::config_path;
use lidarsim::scene::fields::{FieldColumn, Sample, profile_samples, read};
use lidarsim::scene::orbit::Orbit;

const K_B: f64 = 1.380649e-23;
const PROFILES: usize = 6;

/// The columns of the shipped pass's first profiles, as the run samples them.
fn columns() -> Vec<FieldColumn> {
    let cfg = lidarsim::loaded::load(&config_path("instruments/caliop_fields.toml"), &[])
        .unwrap()
        .config;
    let m = cfg.scene.as_ref().unwrap().model_fields.clone().unwrap();
    let orbit = Orbit::from_config(cfg.orbit.as_ref().unwrap(), 705e3).unwrap();
    let samples: Vec<_> = profile_samples(
        &cfg,
        &lidarsim::scene::track::AlongTrack::Orbit(orbit),
        15,
        PROFILES as u64,
    )
    .unwrap()
    .iter()
    .map(|s| s.0)
    .collect();
    let files = [config_path("fields/era5_like_model_levels.nc")];
    read::columns(&m, &files, &samples).unwrap()
}

/// The water vapour's mass mixing ratio to dry air, g/kg, at `z`: r = q/(1 − q) of each
/// level's specific humidity, linear in height between levels; `None` outside them.
fn mixing_ratio_by_the_rule(c: &FieldColumn, z: f64) -> Option<f64> {
    let l = &c.levels;
    let i = (0..l.len() - 1).find(|&i| l[i].height_m <= z && z <= l[i + 1].height_m)?;
    let w = (z - l[i].height_m) / (l[i + 1].height_m - l[i].height_m);
    let r = |k: usize| 1e3 * l[k].q / (1.0 - l[k].q);
    Some(r(i) * (1.0 - w) + r(i + 1) * w)
}

/// (p, T) at height `z` from the levels by the rule above; `None` outside them.
fn by_the_rule(c: &FieldColumn, z: f64) -> Option<(f64, f64)> {
    let l = &c.levels;
    let i = (0..l.len() - 1).find(|&i| l[i].height_m <= z && z <= l[i + 1].height_m)?;
    let w = (z - l[i].height_m) / (l[i + 1].height_m - l[i].height_m);
    let lerp_ln = |a: f64, b: f64| (a.ln() * (1.0 - w) + b.ln() * w).exp();
    let n = |k: usize| l[k].p_pa / (K_B * l[k].t_k);
    let p = lerp_ln(l[i].p_pa, l[i + 1].p_pa);
    let number = lerp_ln(n(i), n(i + 1));
    Some((p, p / (K_B * number)))
}

/// The file's (p, T) of profile `j` at height `z` equal the rule's within 1e-9.
fn assert_state((j, z): (usize, f64), (pf, tf): (f64, f64), (p_rule, t_rule): (f64, f64)) {
    assert!(
        (pf / p_rule - 1.0).abs() < 1e-9,
        "profile {j} at {z} m: p {pf} vs {p_rule}"
    );
    assert!(
        (tf / t_rule - 1.0).abs() < 1e-9,
        "profile {j} at {z} m: T {tf} vs {t_rule}"
    );
}

fn floats(f: &hdf5::File, name: &str) -> Vec<f64> {
    f.dataset(name).unwrap().read_raw::<f64>().unwrap()
}

#[test]
fn the_file_s_pressure_and_temperature_are_each_profile_s_levels() {
    let dir = scratch("fields_molecules");
    let cfg = config_path("instruments/caliop_fields.toml");
    let n = PROFILES.to_string();
    let run = |out: &str, extra: &[&str]| {
        let mut a = vec![
            "simulate",
            cfg.to_str().unwrap(),
            "-o",
            out,
            "--profiles",
            &n,
        ];
        a.extend_from_slice(extra);
        ok(lidarsim(&dir, &a, &[]));
        hdf5::File::open(dir.join(out)).unwrap()
    };
    let f = run("fields.h5", &[]);
    let cols = columns();
    let altitude = floats(&f, "altitude");
    let bins = altitude.len();
    let (p, t) = (floats(&f, "pressure"), floats(&f, "temperature"));
    let wv = floats(&f, "water_vapour_mixing_ratio");
    // one column per profile here (the first profiles are clear or overcast)
    assert_eq!(p.len(), PROFILES * bins);
    let mut judged = 0;
    for (j, c) in cols.iter().enumerate() {
        for (b, &z) in altitude.iter().enumerate() {
            let Some((p_rule, t_rule)) = by_the_rule(c, z) else {
                continue;
            };
            let (pf, tf) = (p[j * bins + b], t[j * bins + b]);
            assert_state((j, z), (pf, tf), (p_rule, t_rule));
            let r_rule = mixing_ratio_by_the_rule(c, z).unwrap();
            let rf = wv[j * bins + b];
            assert!(
                (rf - r_rule).abs() <= 1e-9 * r_rule.abs().max(1e-6),
                "profile {j} at {z} m: r {rf} vs {r_rule} g/kg"
            );
            judged += 1;
        }
    }
    assert!(judged > PROFILES * 300, "{judged} bins judged");

    // the config's molecules instead: US76 at sea level, not the fields'
    let g = run(
        "config.h5",
        &["--set", "scene.model_fields.molecules=\"config\""],
    );
    let p_us = floats(&g, "pressure");
    assert!(
        !g.link_exists("water_vapour_mixing_ratio"),
        "the config's scene has no water vapour"
    );
    let sea = (0..bins)
        .min_by(|&a, &b| altitude[a].abs().total_cmp(&altitude[b].abs()))
        .unwrap();
    let us76 = lidarsim::atmosphere::us76::state(altitude[sea])
        .unwrap()
        .pressure_pa;
    assert!(
        (p_us[sea] / us76 - 1.0).abs() < 1e-9,
        "{} vs {us76}",
        p_us[sea]
    );
    assert!(
        (p[sea] / us76 - 1.0).abs() > 1e-3,
        "the fields' pressure is US76's"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A ground lidar under the fields (issue 39 item 2, `configs/ground/ground_fields.toml`):
/// each profile samples them at the station (`platform.latitude_deg`, `longitude_deg`)
/// at its middle time, t₀ + (p + ½)·60 s, so the scene changes in time as the fields
/// do. The file's pressure and temperature of each profile's columns are those of the
/// column read at that place and time, by the rule above, within 1e-9; the same samples
/// a minute late, or 0.1° off, give other numbers.
#[test]
fn a_ground_lidar_sees_the_fields_over_its_station_in_time() {
    let dir = scratch("fields_ground");
    let path = config_path("ground/ground_fields.toml");
    let cfg = lidarsim::loaded::load(&path, &[]).unwrap().config;
    let m = cfg.scene.as_ref().unwrap().model_fields.clone().unwrap();
    let (lat, lon) = (39.51, -0.42);
    assert_eq!(cfg.platform.latitude_deg, Some(lat));
    assert_eq!(cfg.platform.longitude_deg, Some(lon));
    let t0 = 1_705_276_800.0; // 2024-01-15T00:00:00Z
    let profiles = 12;
    let sample = |p: usize, late_s: f64, off_deg: f64| Sample {
        time_s: t0 + (p as f64 + 0.5) * 60.0 + late_s,
        latitude_deg: lat + off_deg,
        longitude_deg: lon,
    };
    let files = [config_path("fields/era5_like_model_levels.nc")];
    let read = |late_s: f64, off_deg: f64| {
        let s: Vec<_> = (0..profiles).map(|p| sample(p, late_s, off_deg)).collect();
        read::columns(&m, &files, &s).unwrap()
    };
    let (cols, late, off) = (read(0.0, 0.0), read(60.0, 0.0), read(0.0, 0.1));

    let n = profiles.to_string();
    let cfg_s = path.to_str().unwrap();
    ok(lidarsim(
        &dir,
        &["simulate", cfg_s, "-o", "g.h5", "--profiles", &n],
        &[],
    ));
    let f = hdf5::File::open(dir.join("g.h5")).unwrap();
    let altitude = floats(&f, "altitude");
    let bins = altitude.len();
    let (p, t) = (floats(&f, "pressure"), floats(&f, "temperature"));
    // the bins after the pulse (the pre-trigger bins below the station hold no air)
    let range = floats(&f, "range");
    let profile_column = f
        .dataset("profile_column")
        .unwrap()
        .read_2d::<i64>()
        .unwrap();
    let (mut judged, mut late_differs, mut off_differs) = (0, 0, 0);
    for (j, c) in cols.iter().enumerate() {
        for &col in profile_column.row(j).iter().filter(|&&c| c >= 0) {
            for (b, &z) in altitude.iter().enumerate().filter(|&(b, _)| range[b] > 0.0) {
                let Some((p_rule, t_rule)) = by_the_rule(c, z) else {
                    continue;
                };
                let (pf, tf) = (p[col as usize * bins + b], t[col as usize * bins + b]);
                assert_state((j, z), (pf, tf), (p_rule, t_rule));
                let differs = |o: &FieldColumn| {
                    by_the_rule(o, z).is_some_and(|(po, _)| (pf / po - 1.0).abs() > 1e-7)
                };
                late_differs += usize::from(differs(&late[j]));
                off_differs += usize::from(differs(&off[j]));
                judged += 1;
            }
        }
    }
    assert!(judged > profiles * 300, "{judged} bins judged");
    assert!(
        late_differs > judged / 2,
        "a minute late: {late_differs} of {judged} differ"
    );
    assert!(
        off_differs > judged / 2,
        "0.1 deg off: {off_differs} of {judged} differ"
    );
    std::fs::remove_dir_all(&dir).ok();
}
