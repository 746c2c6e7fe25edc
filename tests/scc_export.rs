//! The SCC export (`src/output/scc/`): a small ground run exported and read back with
//! the `netcdf3` crate (and with netCDF4-python when it is installed); refusals.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::config_path;
use lidarsim::output::scc::{SCC_VARIABLES, SccOptions, SccType, export_scc};
use lidarsim::simulate::RunOptions;
use netcdf3::{DataType, FileReader};

/// The tests of this file run one at a time: files written, read and deleted by
/// concurrent tests in one process can reuse an inode that the HDF5 library still
/// associates with a file it had open (seen once as a failed open of a valid file).
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-scc-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `simulate` through the library on a shipped config.
fn simulate(cfg: &str, out: &Path, overrides: &[&str], profiles: usize) {
    let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let opts = RunOptions {
        output: out.to_path_buf(),
        profiles: Some(profiles),
        command_line: "scc_export test".into(),
        ..Default::default()
    };
    lidarsim::commands::simulate(&config_path(cfg), &ov, &opts, Some(1))
        .unwrap_or_else(|e| panic!("{cfg}: {e}"));
}

fn ground_run(dir: &Path) -> PathBuf {
    let raw = dir.join("ground.h5");
    simulate(
        "ground/ground_532_overlap.toml",
        &raw,
        &[
            "instrument.channel=\"parallel\"",
            "acquisition.start_time=\"2024-07-14T21:30:00Z\"",
            "acquisition.accumulation_time_s=5",
            "acquisition.top_altitude_km=6",
            "instrument.detector={dead_time_s=4e-9, dead_time_model=\"paralyzable\"}",
        ],
        3,
    );
    raw
}

fn counts_of(raw: &Path) -> (Vec<usize>, Vec<u64>) {
    let f = hdf5::File::open(raw).unwrap();
    let ds = f.dataset("counts").unwrap();
    (ds.shape(), ds.read_raw::<u64>().unwrap())
}

fn check_layout(r: &FileReader, shape: &[usize]) {
    let ds = r.data_set();
    assert_eq!(ds.dim_size("time"), Some(shape[0]));
    assert_eq!(ds.dim_size("channels"), Some(shape[1]));
    assert_eq!(ds.dim_size("points"), Some(shape[2]));
    assert_eq!(ds.dim_size("nb_of_time_scales"), Some(1));
    assert_eq!(ds.dim_size("scan_angles"), Some(1));
    assert_eq!(ds.get_unlimited_dim().unwrap().name(), "time");
    for (name, dims, ty) in SCC_VARIABLES {
        let v = ds.get_var(name).unwrap_or_else(|| panic!("missing {name}"));
        let want = match ty {
            SccType::Int => DataType::I32,
            SccType::Double => DataType::F64,
        };
        assert_eq!(v.data_type(), want, "{name}");
        assert_eq!(v.dim_names(), dims.to_vec(), "{name}");
    }
    assert_eq!(ds.num_vars(), SCC_VARIABLES.len());
}

fn text(r: &FileReader, name: &str) -> String {
    r.data_set().get_global_attr_as_string(name).unwrap()
}

#[test]
fn a_ground_run_exports_with_the_scc_layout_and_its_counts() {
    let _serial = serial();
    let dir = scratch("ground");
    let raw = ground_run(&dir);
    let out = dir.join("out.nc");
    export_scc(&raw, &out, &SccOptions::default()).unwrap();
    let (shape, counts) = counts_of(&raw);
    let mut r = FileReader::open(&out).unwrap();
    check_layout(&r, &shape);
    let data = r.read_var_f64("Raw_Lidar_Data").unwrap();
    assert_eq!(data.len(), counts.len());
    assert!(data.iter().zip(&counts).all(|(d, &c)| *d == c as f64));
    assert_eq!(text(&r, "Measurement_ID"), "20240714ls00");
    assert_eq!(text(&r, "RawData_Start_Date"), "20240714");
    assert_eq!(text(&r, "RawData_Start_Time_UT"), "213000");
    assert_eq!(text(&r, "RawData_Stop_Time_UT"), "213015");
    assert_eq!(
        r.read_var_i32("Raw_Data_Start_Time").unwrap(),
        vec![0, 5, 10]
    );
    assert_eq!(
        r.read_var_i32("Raw_Data_Stop_Time").unwrap(),
        vec![5, 10, 15]
    );
    assert_eq!(r.read_var_i32("Laser_Shots").unwrap(), vec![100; 3]);
    assert_eq!(r.read_var_i32("Dead_Time_Corr_Type").unwrap(), vec![1]);
    let dead = r.read_var_f64("Dead_Time").unwrap()[0];
    assert!((dead - 4.0).abs() < 1e-9, "{dead}");
    assert_eq!(r.read_var_i32("Molecular_Calc").unwrap(), vec![4]);
    let res = r.read_var_f64("Raw_Data_Range_Resolution").unwrap()[0];
    assert!((res - 7.494811).abs() < 1e-6, "{res}");
    assert_eq!(r.read_var_f64("Trigger_Delay").unwrap(), vec![0.0]);
    let (lo, hi) = (
        r.read_var_f64("Background_Low").unwrap()[0],
        r.read_var_f64("Background_High").unwrap()[0],
    );
    assert!(lo < hi && hi > 5_900.0, "{lo} {hi}");
    let p = r.read_var_f64("Pressure_at_Lidar_Station").unwrap()[0];
    assert!((p - 1013.25).abs() < 0.01, "{p}");
    python_check(&out);
    std::fs::remove_dir_all(&dir).ok();
}

/// netCDF4-python's view of the file (`tools/check_scc_file.py`), when installed.
fn python_check(out: &Path) {
    if !common::python_has("scc_export: tools/check_scc_file.py", &["netCDF4"]) {
        return;
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/check_scc_file.py");
    let o = Command::new("python3")
        .arg(script)
        .arg(out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    println!(
        "netCDF4-python: {}",
        String::from_utf8_lossy(&o.stdout).trim()
    );
}

#[test]
fn options_are_checked() {
    let _serial = serial();
    let dir = scratch("opts");
    let raw = ground_run(&dir);
    let out = dir.join("out.nc");
    let ids = SccOptions {
        measurement_id: Some("20240714ab07".into()),
        station_id: "ab".into(),
        channel_ids: Some(vec![2205]),
    };
    export_scc(&raw, &out, &ids).unwrap();
    let mut r = FileReader::open(&out).unwrap();
    assert_eq!(text(&r, "Measurement_ID"), "20240714ab07");
    assert_eq!(r.read_var_i32("channel_ID").unwrap(), vec![2205]);
    let two = SccOptions {
        channel_ids: Some(vec![1, 2]),
        ..SccOptions::default()
    };
    let e = export_scc(&raw, &out, &two).unwrap_err().to_string();
    assert!(e.contains("2 SCC channel IDs given for 1 channels"), "{e}");
    let bad_id = SccOptions {
        measurement_id: Some("2024-07-14".into()),
        ..SccOptions::default()
    };
    let e = export_scc(&raw, &out, &bad_id).unwrap_err().to_string();
    assert!(e.contains("YYYYMMDDccNN"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_spaceborne_run_is_refused() {
    let _serial = serial();
    let dir = scratch("space");
    let raw = dir.join("space.h5");
    simulate("paper/scenario1.toml", &raw, &[], 1);
    let out = dir.join("out.nc");
    let e = export_scc(&raw, &out, &SccOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("space.h5") && e.contains("spaceborne"), "{e}");
    assert!(!e.contains('\n'), "{e}");
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn files_that_are_not_lidarsim_raw_files_are_refused() {
    let _serial = serial();
    let dir = scratch("bad");
    let out = dir.join("out.nc");
    let text_file = dir.join("notes.h5");
    std::fs::write(&text_file, "not HDF5 at all\n").unwrap();
    let e = export_scc(&text_file, &out, &SccOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("notes.h5") && e.contains("not a lidarsim raw file"),
        "{e}"
    );
    let other = dir.join("other.h5");
    hdf5::File::create(&other).unwrap();
    let e = export_scc(&other, &out, &SccOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("lidarsim_format_version"), "{e}");
    let v1 = dir.join("v1.h5");
    let f = hdf5::File::create(&v1).unwrap();
    f.new_attr::<i32>()
        .create("lidarsim_format_version")
        .unwrap()
        .write_scalar(&1)
        .unwrap();
    drop(f);
    let e = export_scc(&v1, &out, &SccOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("format version 1"), "{e}");
    let missing = dir.join("missing.h5");
    let e = export_scc(&missing, &out, &SccOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("missing.h5") && e.contains("no such file"),
        "{e}"
    );
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// `simulate --format scc` on the two-polarization preset: one SCC file with both
/// channels, each with its own wavelength and dead time from the receiver's config, and
/// no scratch file left beside it. A spaceborne config is refused before any work.
#[test]
fn simulate_writes_scc_for_every_channel() {
    let _serial = serial();
    let dir = scratch("format");
    let out = dir.join("depol.nc");
    let run = |cfg: &str, out: &Path| {
        Command::new(env!("CARGO_BIN_EXE_lidarsim"))
            .args(["simulate", config_path(cfg).to_str().unwrap(), "-o"])
            .arg(out)
            .args(["--profiles", "2", "--format", "scc"])
            .args(["--set", "acquisition.accumulation_time_s=0.2"])
            .output()
            .unwrap()
    };
    let o = run("ground/ground_532_depol.toml", &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut r = FileReader::open(&out).unwrap();
    assert_eq!(r.data_set().dim_size("channels"), Some(2));
    assert_eq!(r.read_var_f64("Dead_Time").unwrap(), vec![3.5, 3.5]);
    assert_eq!(
        r.read_var_f64("Emitted_Wavelength").unwrap(),
        vec![532.0, 532.0]
    );
    assert_eq!(r.read_var_i32("Laser_Shots").unwrap(), vec![500; 4]);
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("depol.nc")], "{left:?}");
    let o = run("paper/scenario1.toml", &dir.join("space.nc"));
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("platform.kind"));
    assert!(!dir.join("space.nc").exists());
    std::fs::remove_dir_all(&dir).ok();
}
