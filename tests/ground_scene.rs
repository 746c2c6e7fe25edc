//! A ground lidar's scene that changes in time (issue 39 item 2, docs/scenes.md "A
//! ground lidar's changing scene"): `[[scene.segments]]` pass over the station at
//! `scene.advection_speed_m_per_s`, so a segment of `length_km` lasts
//! `length_km·1000/u` seconds. Judged on the file's `profile_column` and
//! `profile_column_weight`: with 3 s profiles (7,500 shots at 2.5 kHz) and a clear first
//! segment of 100 m, the cloud arrives at 10 s at 10 m/s (profile 3: 1/3 clear, 2/3
//! cloudy) and at 5 s at 20 m/s (profile 1: 2/3 clear, 1/3 cloudy), computed here from
//! the shot times alone.

mod common;

use common::cli::{lidarsim, ok, refused, scratch};
use common::config_path;

const SCENE: &str = "scene={segments=[{length_km=0.1, layers=[]}, {length_km=1.0}]}";

/// `profile_column` and `profile_column_weight` of the first `profiles` rows of a run of
/// `ground_532_depol` with the scene above at `speed` m/s.
fn columns(dir: &std::path::Path, speed: &str) -> (Vec<Vec<i64>>, Vec<Vec<f64>>) {
    let cfg = config_path("ground/ground_532_depol.toml");
    let speed = format!("scene.advection_speed_m_per_s={speed}");
    let out = format!("g{}.h5", speed.len());
    ok(lidarsim(
        dir,
        &[
            "simulate",
            cfg.to_str().unwrap(),
            "-o",
            &out,
            "--set",
            SCENE,
            "--set",
            &speed,
            "--set",
            "acquisition.accumulation_time_s=3.0",
            "--set",
            "acquisition.profiles=6",
            "--set",
            "instrument.detector={}",
        ],
        &[],
    ));
    let f = hdf5::File::open(dir.join(out)).unwrap();
    let c = f
        .dataset("profile_column")
        .unwrap()
        .read_2d::<i64>()
        .unwrap();
    let w = f
        .dataset("profile_column_weight")
        .unwrap()
        .read_2d::<f64>()
        .unwrap();
    (
        c.rows().into_iter().map(|r| r.to_vec()).collect(),
        w.rows().into_iter().map(|r| r.to_vec()).collect(),
    )
}

/// The share of profile `p`'s shots (7,500 at 2.5 kHz, shot k at k/2500 s) that come
/// before the time the second segment arrives, `arrival_s`.
fn clear_share(p: usize, arrival_s: f64) -> f64 {
    let shots = 7500;
    let before = (0..shots)
        .filter(|k| ((p * shots + k) as f64) / 2500.0 < arrival_s)
        .count();
    before as f64 / shots as f64
}

#[test]
fn segments_pass_over_the_station_at_the_advection_speed() {
    let dir = scratch("ground_scene");
    for (speed, arrival_s) in [("10.0", 10.0), ("20.0", 5.0)] {
        let (c, w) = columns(&dir, speed);
        for p in 0..6 {
            let share = clear_share(p, arrival_s);
            let (cols, weights): (Vec<i64>, Vec<f64>) = c[p]
                .iter()
                .zip(&w[p])
                .filter(|(c, _)| **c >= 0)
                .map(|(c, w)| (*c, *w))
                .unzip();
            let want: Vec<(i64, f64)> = [(0, share), (1, 1.0 - share)]
                .into_iter()
                .filter(|(_, s)| *s > 0.0)
                .collect();
            assert_eq!(cols.len(), want.len(), "{speed} m/s, profile {p}: {cols:?}");
            for ((c, w), (cw, sw)) in cols.iter().zip(&weights).zip(&want) {
                assert_eq!(c, cw, "{speed} m/s, profile {p}");
                assert!(
                    (w - sw).abs() < 1e-12,
                    "{speed} m/s, profile {p}: {w} vs {sw}"
                );
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `simulate CONFIG -o x.h5 --set S…` is refused in one line holding `words`.
fn refused_with(dir: &std::path::Path, config: &str, sets: &[&str], words: &[&str]) {
    let mut args = vec!["simulate", config, "-o", "x.h5"];
    for s in sets {
        args.extend(["--set", s]);
    }
    refused(dir, &args, words, "x.h5");
}

#[test]
fn a_ground_scene_s_keys_are_checked() {
    let dir = scratch("ground_scene_keys");
    let ground = config_path("ground/ground_532_depol.toml");
    let ground = ground.to_str().unwrap();
    refused_with(
        &dir,
        ground,
        &[SCENE, "scene.advection_speed_m_per_s=0"],
        &["scene.advection_speed_m_per_s", "within [0.1, 200]"],
    );
    refused_with(
        &dir,
        ground,
        &["scene={segments=[{length_km=1.0, surface={kind=\"land\", albedo=0.2}}]}"],
        &["surface", "looks up and sees no surface"],
    );
    let space = config_path("paper/scenario1.toml");
    refused_with(
        &dir,
        space.to_str().unwrap(),
        &["scene.advection_speed_m_per_s=10"],
        &["scene.advection_speed_m_per_s", "ground lidar's"],
    );
    // model fields over a station that has no latitude and longitude
    let fields = std::fs::read_to_string(config_path("ground/ground_fields.toml")).unwrap();
    let nc = config_path("fields/era5_like_model_levels.nc");
    let fields: String = fields
        .lines()
        .filter(|l| !l.starts_with("latitude_deg") && !l.starts_with("longitude_deg"))
        .map(|l| l.replace("../fields/era5_like_model_levels.nc", nc.to_str().unwrap()) + "\n")
        .collect();
    std::fs::write(dir.join("no_station.toml"), fields).unwrap();
    refused(
        &dir,
        &["simulate", "no_station.toml", "-o", "x.h5"],
        &[
            "scene.model_fields",
            "platform.latitude_deg and platform.longitude_deg",
        ],
        "x.h5",
    );
    std::fs::remove_dir_all(&dir).ok();
}
