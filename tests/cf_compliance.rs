//! The files pass the community's CF checker (issue 40): compliance-checker
//! (`--test cf:1.10`, the IOOS checker, installed by `.ci/run`) exits 0 on a
//! three-channel raw file (the numbered `channel` coordinate with its `channel_name`
//! label, format 5) and on its single-region onboard product; on a `caliop` product of
//! five region groups with its one defective check skipped (docs/file-format.md
//! "Checked with outside tools"). The checker can fail here: the raw file with the
//! `units` of `altitude` removed exits 1, naming them.
//! `bash tools/cf_check_all.sh` does the same for every shipped config.

mod common;

use std::path::Path;
use std::process::Command;

use common::cli::{lidarsim, ok, scratch};
use common::config_path;

/// compliance-checker's exit status on `file` and its report.
fn checker(file: &Path, extra: &[&str]) -> (i32, String) {
    let o = Command::new("compliance-checker")
        .args(["--test", "cf:1.10"])
        .args(extra)
        .arg(file)
        .output()
        .expect("compliance-checker runs");
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    (o.status.code().unwrap_or(-1), text)
}

#[test]
fn raw_files_and_products_of_three_channels_are_cf_clean() {
    let test = "raw_files_and_products_of_three_channels_are_cf_clean";
    if !common::python_has(test, &["compliance_checker", "h5py"]) {
        return;
    }
    let dir = scratch("cf-compliance");
    let cfg = config_path("instruments/caliop_3ch.toml");
    let cfg = cfg.to_str().unwrap();
    ok(lidarsim(
        &dir,
        &["simulate", cfg, "--profiles", "2", "-o", "raw.nc"],
        &[],
    ));
    // 20 shots a profile at 20.16 Hz
    let short = [
        "--set",
        "acquisition.profiles=2",
        "--set",
        "acquisition.accumulation_time_s=0.992",
    ];
    let mut uniform = vec!["onboard", cfg, "--scheme", "uniform:10", "-o", "uniform.nc"];
    uniform.extend_from_slice(&short);
    ok(lidarsim(&dir, &uniform, &[]));
    let mut caliop = vec![
        "onboard",
        cfg,
        "--scheme",
        "caliop",
        "-o",
        "caliop.nc",
        "--set",
        "acquisition.top_altitude_km=40",
        "--set",
        "acquisition.bottom_altitude_km=-2",
    ];
    caliop.extend_from_slice(&short);
    ok(lidarsim(&dir, &caliop, &[]));

    for (file, extra) in [
        ("raw.nc", &[][..]),
        ("uniform.nc", &[][..]),
        (
            "caliop.nc",
            &[
                "--skip-checks",
                "check_invalid_same_named_dimension_across_groups",
            ][..],
        ),
    ] {
        let (rc, report) = checker(&dir.join(file), extra);
        assert_eq!(rc, 0, "{file}: compliance-checker exit {rc}:\n{report}");
        assert!(report.contains("All tests passed!"), "{file}:\n{report}");
    }

    // the checker fails a file that breaks CF: altitude without its units
    std::fs::copy(dir.join("raw.nc"), dir.join("broken.nc")).unwrap();
    let o = Command::new("python3")
        .current_dir(&dir)
        .args([
            "-c",
            "import h5py; f = h5py.File('broken.nc', 'r+'); del f['altitude'].attrs['units']",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (rc, report) = checker(&dir.join("broken.nc"), &[]);
    assert_eq!(rc, 1, "{report}");
    assert!(
        report.contains("altitude's units must be defined"),
        "{report}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
