//! The SCC export of the Δ90 calibration measurement (`export-scc-calibration`,
//! `src/output/scc/calibration.rs`): the two ±45° runs of a PollyXT-like total + cross
//! receiver in one file, read back with the `netcdf3` crate and compared with the runs'
//! own counts read with HDF5; refusals.

mod common;

use std::path::Path;

use common::cli::{lidarsim, ok, refused, scratch};
use common::config_path;
use netcdf3::FileReader;

const CONFIG: &str = "ground/pollyxt_like.toml";
/// A short run: 2 profiles of 20 shots, up to 5 km.
const SMALL: [&str; 6] = [
    "--set",
    "acquisition.accumulation_time_s=1",
    "--set",
    "acquisition.top_altitude_km=5",
    "--set",
    "acquisition.profiles=2",
];

fn calibration_run(dir: &Path, which: &str, out: &str, extra: &[&str]) {
    let config = config_path(CONFIG);
    let mut args = vec![
        "simulate",
        config.to_str().unwrap(),
        "--calibration",
        which,
        "-o",
        out,
    ];
    args.extend(SMALL);
    args.extend(extra);
    ok(lidarsim(dir, &args, &[]));
}

fn counts(path: &Path) -> (Vec<String>, Vec<usize>, Vec<u64>) {
    let f = hdf5::File::open(path).unwrap();
    let ds = f.dataset("counts").unwrap();
    let names = common::h5::strings(&f, "channel_name");
    (names, ds.shape(), ds.read_raw::<u64>().unwrap())
}

/// The elastic channels the Δ90 method takes, read from the config's TOML text (not
/// through lidarsim): the `[[instrument.channels]]` without a `kind` at a wavelength
/// that has a `perpendicular` or `parallel` channel (each inherits the root wavelength
/// when it gives none).
fn calibration_channels_of_config() -> Vec<String> {
    let text = std::fs::read_to_string(config_path(CONFIG)).unwrap();
    let t: toml::Table = text.parse().unwrap();
    let root = t["instrument"]["wavelength_nm"].as_float().unwrap();
    let channels = t["instrument"]["channels"].as_array().unwrap();
    let wavelength = |c: &toml::Value| {
        c.get("wavelength_nm")
            .map_or(root, |w| w.as_float().unwrap())
    };
    let polarized: Vec<f64> = channels
        .iter()
        .filter(|c| {
            c.get("polarization")
                .is_some_and(|p| p.as_str() != Some("total"))
        })
        .map(wavelength)
        .collect();
    channels
        .iter()
        .filter(|c| c.get("kind").is_none() && polarized.contains(&wavelength(c)))
        .map(|c| c["name"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn the_two_runs_become_one_calibration_measurement_of_their_polarization_channels() {
    let dir = scratch("scc-calibration");
    calibration_run(&dir, "plus45", "p45.h5", &[]);
    // the −45° run a minute after the +45° one
    let later = ["--set", "acquisition.start_time=\"2000-01-01T00:01:00Z\""];
    calibration_run(&dir, "minus45", "m45.h5", &later);
    ok(lidarsim(
        &dir,
        &[
            "export-scc-calibration",
            "p45.h5",
            "m45.h5",
            "cal.nc",
            "--pol-calib-range",
            "1000,2500",
        ],
        &[],
    ));
    let (names, shape, plus) = counts(&dir.join("p45.h5"));
    let (_, _, minus) = counts(&dir.join("m45.h5"));
    let wanted = calibration_channels_of_config();
    assert_eq!(
        wanted,
        [
            "355_total",
            "355_perpendicular",
            "532_total",
            "532_perpendicular"
        ]
    );
    let index: Vec<usize> = wanted
        .iter()
        .map(|w| names.iter().position(|n| n == w).unwrap())
        .collect();
    let (n_p, n_ch, n_b) = (shape[0], shape[1], shape[2]);
    let mut r = FileReader::open(dir.join("cal.nc")).unwrap();
    let ds = r.data_set();
    let k = wanted.len();
    assert_eq!(ds.dim_size("channels"), Some(2 * k));
    assert_eq!(ds.dim_size("time"), Some(n_p));
    assert_eq!(ds.dim_size("points"), Some(n_b));
    assert_eq!(ds.dim_size("nb_of_time_scales"), Some(1));
    let data = r.read_var_f64("Raw_Lidar_Data").unwrap();
    for p in 0..n_p {
        for (run, counts) in [&plus, &minus].into_iter().enumerate() {
            for (j, &c) in index.iter().enumerate() {
                let got = &data[(p * 2 * k + run * k + j) * n_b..][..n_b];
                let want = &counts[(p * n_ch + c) * n_b..][..n_b];
                assert!(
                    got.iter().zip(want).all(|(g, &w)| *g == w as f64),
                    "profile {p}, run {run}, channel {}",
                    wanted[j]
                );
            }
        }
    }
    assert_eq!(
        r.read_var_f64("Pol_Calib_Range_Min").unwrap(),
        vec![1000.0; 2 * k]
    );
    assert_eq!(
        r.read_var_f64("Pol_Calib_Range_Max").unwrap(),
        vec![2500.0; 2 * k]
    );
    assert_eq!(r.read_var_i32("id_timescale").unwrap(), vec![0; 2 * k]);
    assert_eq!(
        r.read_var_i32("channel_ID").unwrap(),
        (1..=2 * k as i32).collect::<Vec<_>>()
    );
    // one time scale from the +45° run's start: its starts, the −45° run's stops
    // (1 s profiles, the second run 60 s later)
    assert_eq!(r.read_var_i32("Raw_Data_Start_Time").unwrap(), vec![0, 1]);
    assert_eq!(r.read_var_i32("Raw_Data_Stop_Time").unwrap(), vec![61, 62]);
    assert_eq!(
        r.read_var_i32("Laser_Shots").unwrap(),
        vec![20; 2 * k * n_p]
    );
    let attr = |n: &str| r.data_set().get_global_attr_as_string(n).unwrap();
    assert_eq!(attr("RawData_Start_Time_UT"), "000000");
    assert_eq!(attr("RawData_Stop_Time_UT"), "000102");
    common::check_scc_file_with_python("scc_calibration", &dir.join("cal.nc"));
}

#[test]
fn runs_that_are_not_a_calibration_pair_are_refused() {
    let dir = scratch("scc-calibration-refusals");
    calibration_run(&dir, "plus45", "p45.h5", &[]);
    calibration_run(&dir, "minus45", "m45.h5", &[]);
    let other_bins = ["--set", "acquisition.top_altitude_km=4"];
    calibration_run(&dir, "minus45", "m45_short.h5", &other_bins);
    let config = config_path(CONFIG);
    let mut measurement = vec!["simulate", config.to_str().unwrap(), "-o", "meas.h5"];
    measurement.extend(SMALL);
    ok(lidarsim(&dir, &measurement, &[]));
    let export = |p: &'static str, m: &'static str, range: &'static str| {
        vec![
            "export-scc-calibration",
            p,
            m,
            "out.nc",
            "--pol-calib-range",
            range,
        ]
    };
    let cases: [(Vec<&str>, &[&str]); 6] = [
        (
            export("m45.h5", "p45.h5", "1000,2500"),
            &["m45.h5", "+45° calibration run"],
        ),
        (
            export("p45.h5", "meas.h5", "1000,2500"),
            &["meas.h5", "-45° calibration run"],
        ),
        (
            export("p45.h5", "m45_short.h5", "1000,2500"),
            &["m45_short.h5", "bins"],
        ),
        (
            export("p45.h5", "m45.h5", "1000,9000"),
            &["p45.h5", "--pol-calib-range"],
        ),
        (
            export("p45.h5", "m45.h5", "2500,1000"),
            &["--pol-calib-range", "MIN < MAX"],
        ),
        (export("p45.h5", "missing.h5", "1000,2500"), &["missing.h5"]),
    ];
    for (args, words) in &cases {
        refused(&dir, args, words, "out.nc");
    }
    let mut ids = export("p45.h5", "m45.h5", "1000,2500");
    ids.extend(["--channel-ids", "1,2,3"]);
    refused(&dir, &ids, &["3 SCC channel IDs", "8 channels"], "out.nc");
}
