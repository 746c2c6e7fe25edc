//! Each truth at the size of what it depends on (issue 38, format 4): a changing scene's
//! file stores `expected_signal` and `attenuated_backscatter` per column, the sky
//! background per (profile, channel), the recorded counts of a dead-time detector per
//! profile only under the sun, and nothing of an ideal detector's `expected_counts` or of
//! `snr_eq4`; `simulate --truth per-profile` writes format 3's (profile, channel, bin)
//! arrays. "Nothing lost": every array rebuilt from the compact file
//! (`raw_file::per_profile::PerProfileReader`, the rule every reader uses) equals the
//! `--truth per-profile` file's bit for bit, and every other variable is the same.

mod common;

use std::path::{Path, PathBuf};

use common::config_path;
use lidarsim::output::raw_file::per_profile::{PER_PROFILE_NAMES, PerProfileReader};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-compact-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `simulate CFG -o OUT` with `extra` in `dir`; the file.
fn simulate(dir: &Path, cfg: &str, out: &str, extra: &[&str]) -> hdf5::File {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .current_dir(dir)
        .args(["simulate", config_path(cfg).to_str().unwrap(), "-o", out])
        .args(extra)
        .env("SOURCE_DATE_EPOCH", "1700000000")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    hdf5::File::open(dir.join(out)).unwrap()
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

fn shape(f: &hdf5::File, name: &str) -> Option<Vec<usize>> {
    f.dataset(name).ok().map(|d| d.shape())
}

/// Simulates `cfg` with `extra` in both forms and compares them; returns the compact
/// file's shapes of the five per-profile names (None: not stored).
fn both_forms(name: &str, cfg: &str, extra: &[&str]) -> Vec<Option<Vec<usize>>> {
    let dir = scratch(name);
    let compact = simulate(&dir, cfg, "compact.h5", extra);
    let extra_p: Vec<&str> = extra
        .iter()
        .copied()
        .chain(["--truth", "per-profile"])
        .collect();
    let full = simulate(&dir, cfg, "full.h5", &extra_p);
    let path = dir.join("compact.h5");
    let h = lidarsim::output::raw_file::read::check(&path, &compact).unwrap();
    let reader = PerProfileReader::new(&path, &compact, &h).unwrap();
    let p = h.n_profiles;
    for n in PER_PROFILE_NAMES {
        let rebuilt = reader.rows(n, 0..p).unwrap();
        let want = full.dataset(n).unwrap();
        let want = match want.ndim() {
            3 => want.read_raw::<f64>().unwrap(),
            // a static scene: (channel, bin) in both forms
            _ => want.read_raw::<f64>().unwrap().repeat(p),
        };
        assert_eq!(rebuilt.len(), want.len(), "{name}: {n}");
        let differ = rebuilt
            .iter()
            .zip(&want)
            .filter(|(a, b)| a.to_bits() != b.to_bits())
            .count();
        assert_eq!(differ, 0, "{name}: {n} rebuilt differs in {differ} values");
    }
    // every other variable the same, to the bit
    for d in full.datasets().unwrap() {
        let n = d.name().trim_start_matches('/').to_string();
        if PER_PROFILE_NAMES.contains(&n.as_str()) {
            continue;
        }
        let c = compact
            .dataset(&n)
            .unwrap_or_else(|_| panic!("{name}: {n} missing"));
        assert_eq!(c.shape(), d.shape(), "{name}: {n}");
        if let (Ok(a), Ok(b)) = (c.read_raw::<f64>(), d.read_raw::<f64>()) {
            assert_eq!(bits(&a), bits(&b), "{name}: {n}");
        } else if let (Ok(a), Ok(b)) = (c.read_raw::<u64>(), d.read_raw::<u64>()) {
            assert_eq!(a, b, "{name}: {n}");
        }
    }
    PER_PROFILE_NAMES
        .iter()
        .map(|n| shape(&compact, n))
        .collect()
}

#[test]
fn the_orbit_rebuilds_bit_for_bit_from_its_columns() {
    // solar background, ideal detector, segments and broken cloud
    let shapes = both_forms(
        "orbit",
        "instruments/caliop_orbit.toml",
        &["--profiles", "120", "--method", "shot"],
    );
    let n_columns = shapes[0].as_ref().unwrap()[0];
    assert!(n_columns > 1, "{shapes:?}");
    assert_eq!(shapes[0].as_ref().unwrap()[1..], [1, 3358]);
    assert_eq!(shapes[1], Some(vec![120, 1]), "{shapes:?}");
    assert_eq!(
        shapes[2], None,
        "an ideal detector's expected_counts: {shapes:?}"
    );
    assert_eq!(shapes[3], None, "snr_eq4: {shapes:?}");
    assert_eq!(shapes[4].as_ref().unwrap()[0], n_columns);
}

#[test]
fn a_dead_time_detector_keeps_its_recorded_counts_per_column_or_under_the_sun_per_profile() {
    // without the sun: the recorded counts of each column, mixed
    let night = both_forms(
        "orbit-dead",
        "instruments/caliop_orbit.toml",
        &[
            "--profiles",
            "60",
            "--set",
            "background.model=\"fixed\"",
            "--set",
            "instrument.detector.dead_time_s=5e-9",
        ],
    );
    assert_eq!(night[2].as_ref().unwrap()[1..], [1, 3358], "{night:?}");
    assert_ne!(night[2].as_ref().unwrap()[0], 60);
    // under the sun: per profile
    let day = both_forms(
        "orbit-dead-solar",
        "instruments/caliop_orbit.toml",
        &[
            "--profiles",
            "20",
            "--set",
            "instrument.detector.dead_time_s=5e-9",
        ],
    );
    assert_eq!(day[1].as_ref().unwrap()[0], 20, "{day:?}");
    assert_eq!(day[2].as_ref().unwrap().len(), 3, "{day:?}");
    assert_eq!(day[2].as_ref().unwrap()[0], 20, "{day:?}");
}

#[test]
fn static_scenes_are_one_column_in_both_forms() {
    // dead time (ground_532_depol), afterpulses and pre-trigger bins (mpl_like): a static
    // scene's truth is (channel, bin) in both forms
    for (name, cfg) in [
        ("depol", "ground/ground_532_depol.toml"),
        ("mpl", "ground/mpl_like.toml"),
    ] {
        let shapes = both_forms(
            name,
            cfg,
            &[
                "--profiles",
                "2",
                "--set",
                "acquisition.accumulation_time_s=1",
            ],
        );
        for s in &shapes {
            assert_eq!(s.as_ref().map(Vec::len), Some(2), "{name}: {shapes:?}");
        }
    }
}
