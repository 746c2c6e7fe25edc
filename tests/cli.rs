//! The `lidarsim` binary as users call it (docs/config.md).

mod common;
use std::process::Command;

use common::config_path;

fn lidarsim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .args(args)
        .output()
        .expect("runs")
}

fn scratch_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn expect_csv_has_the_interface_columns() {
    let cfg = config_path("paper/scenario3.toml");
    let out = lidarsim(&["expect", cfg.to_str().unwrap(), "--csv", "-"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for col in [
        "altitude_m",
        "range_m",
        "beta_mol",
        "beta_aer",
        "beta_cld",
        "alpha_total",
        "t2",
        "signal",
        "background",
        "dark",
        "snr",
    ] {
        assert!(header.contains(&col), "missing column {col}");
    }
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 334);
    assert!(rows.iter().flatten().all(|v| v.is_finite()));
    // altitudes decrease from the window top for a space-borne lidar
    assert!(rows[0][0] > rows[1][0] && (rows[0][0] - 99_850.1).abs() < 1.0);
}

#[test]
fn set_overrides_work_on_the_command_line() {
    let cfg = config_path("paper/scenario1.toml");
    let run = |extra: &[&str]| {
        let mut args = vec!["expect", cfg.to_str().unwrap(), "--csv", "-"];
        args.extend_from_slice(extra);
        let out = lidarsim(&args);
        assert!(out.status.success());
        let text = String::from_utf8(out.stdout).unwrap();
        // the lowest bin (the first ones, above the atmosphere, hold no signal)
        text.lines()
            .last()
            .unwrap()
            .split(',')
            .nth(7)
            .unwrap()
            .parse::<f64>()
            .unwrap()
    };
    let full = run(&[]);
    let tenth = run(&["--set", "instrument.pulse_energy_j=0.1"]);
    assert!((tenth / full - 0.1).abs() < 1e-12);
}

#[test]
fn bad_input_is_one_clear_line_and_exit_2() {
    let cfg = config_path("paper/scenario1.toml");
    let out = lidarsim(&[
        "expect",
        cfg.to_str().unwrap(),
        "--set",
        "instrument.pulse_energy_j=-1",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("--set instrument.pulse_energy_j=-1: must be")
            && !err.contains("scenario1.toml")
            && !err.contains("panicked"),
        "{err}"
    );
    let out = lidarsim(&["expect", "/no/such/file.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/no/such/file.toml"));
}

/// Every entry under `dir` (recursively), with its size.
fn listing(dir: &std::path::Path) -> Vec<(std::path::PathBuf, u64)> {
    let mut out = vec![];
    for e in std::fs::read_dir(dir).unwrap() {
        let e = e.unwrap();
        let m = e.metadata().unwrap();
        out.push((e.path(), m.len()));
        if m.is_dir() {
            out.extend(listing(&e.path()));
        }
    }
    out.sort();
    out
}

/// A CSV that cannot be written (its directory missing, its parent a file, the path a
/// directory): exit 2, one `lidarsim: error:` line naming the path, nothing on stdout,
/// and the directory exactly as before (no partial file, no lock, nothing created).
#[test]
fn unwritable_csv_leaves_nothing_behind() {
    let dir = scratch_dir("unwritable-csv");
    std::fs::write(dir.join("a-file"), b"keep me").unwrap();
    std::fs::create_dir_all(dir.join("a-dir")).unwrap();
    std::fs::write(dir.join("a-dir/inside"), b"and me").unwrap();
    let before = listing(&dir);
    let cfg = config_path("paper/scenario1.toml");
    for target in ["missing-dir/x.csv", "a-file/x.csv", "a-dir"] {
        let path = dir.join(target);
        let out = lidarsim(&[
            "expect",
            cfg.to_str().unwrap(),
            "--csv",
            path.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{target}: {err}");
        assert_eq!(err.lines().count(), 1, "{target}: {err}");
        assert!(err.starts_with("lidarsim: error: "), "{target}: {err}");
        assert!(err.contains(path.to_str().unwrap()), "{target}: {err}");
        assert!(out.stdout.is_empty(), "{target}");
        assert_eq!(listing(&dir), before, "{target} left something behind");
    }
    assert_eq!(std::fs::read(dir.join("a-file")).unwrap(), b"keep me");
    assert_eq!(std::fs::read(dir.join("a-dir/inside")).unwrap(), b"and me");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn snr_map_writes_a_png_and_csv() {
    let dir = scratch_dir("snrmap");
    let png = dir.join("s1.png");
    let csv = dir.join("s1.csv");
    let cfg = config_path("paper/scenario1.toml");
    let out = lidarsim(&[
        "snr-map",
        cfg.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(
        text.lines().next(),
        Some("altitude_m,accumulation_time_s,snr")
    );
    // S/N grows as sqrt(TC): 1 s and 100 s rows of the lowest bin differ by 10×
    let lines: Vec<&str> = text.lines().collect();
    let first: Vec<f64> = lines[lines.len() - 61..]
        .iter()
        .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
        .collect();
    assert!((first[40] / first[0] - 10.0).abs() < 1e-9);
    // nothing left under a temporary name
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("partial"))
        .collect();
    assert!(leftovers.is_empty());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn validate_exits_0_when_consistent_and_writes_json() {
    let dir = scratch_dir("validate");
    let json = dir.join("v.json");
    let cfg = config_path("paper/scenario2.toml");
    let out = lidarsim(&[
        "validate",
        cfg.to_str().unwrap(),
        "--realizations",
        "300",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("CONSISTENT") && text.contains("snr_known_background"));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["consistent"], serde_json::Value::Bool(true));
    assert_eq!(report["bins"].as_array().unwrap().len(), 334);
    let out = lidarsim(&["validate", cfg.to_str().unwrap(), "--realizations", "3"]);
    assert_eq!(out.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

/// `args` run under an address-space limit of `bytes` (`ulimit -v`, RLIMIT_AS set
/// before exec) on two threads.
fn lidarsim_limited(args: &[&str], bytes: u64) -> std::process::Output {
    use std::os::unix::process::CommandExt;
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lidarsim"));
    cmd.args(args).env("RAYON_NUM_THREADS", "2");
    // SAFETY: only async-signal-safe calls between fork and exec.
    unsafe {
        cmd.pre_exec(move || {
            let rl = libc::rlimit {
                rlim_cur: bytes,
                rlim_max: bytes,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &rl) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    cmd.output().expect("runs")
}

/// Scenario 1's 40 km window at `bin_width_s` 2e-9 (133,426 bins along 1.15e6 slabs of
/// the path): its `expect --csv` and `simulate --profiles 2` in `dir`.
struct LargeWindow {
    cfg: String,
    csv: std::path::PathBuf,
    h5: std::path::PathBuf,
}

impl LargeWindow {
    const SETS: [&'static str; 4] = [
        "--set",
        "instrument.bin_width_s=2e-9",
        "--set",
        "acquisition.top_altitude_km=40",
    ];

    fn in_dir(dir: &std::path::Path) -> Self {
        LargeWindow {
            cfg: config_path("paper/scenario1.toml")
                .to_str()
                .unwrap()
                .to_string(),
            csv: dir.join("e.csv"),
            h5: dir.join("s.h5"),
        }
    }

    fn expect(&self) -> Vec<&str> {
        let head = ["expect", &self.cfg, "--csv", self.csv.to_str().unwrap()];
        head.into_iter().chain(Self::SETS).collect()
    }

    fn simulate(&self) -> Vec<&str> {
        let head = ["simulate", &self.cfg, "-o", self.h5.to_str().unwrap()];
        head.into_iter()
            .chain(["--profiles", "2"])
            .chain(Self::SETS)
            .collect()
    }
}

/// The model's memory estimate is honest (issue 36, item 15): `expect` and `simulate`
/// of a large-bin window (scenario 1's 40 km at `bin_width_s` 2e-9: 133,425 bins along
/// 1.15e6 slabs of the path, ~150 MB) under address-space limits from 150 to 450 MB
/// either succeed or are refused up front, in one line naming the estimate (exit 2, no
/// output); none runs out of memory partway. Today's main estimated 1,100 B a bin (146
/// MB) and needed ~1.9 kB (its model's bins held twice, its vectors grown by doubling):
/// between ~250 and ~330 MB it started and died "out of memory".
#[test]
fn a_large_model_under_an_address_space_limit_fits_or_is_refused_up_front() {
    let dir = scratch_dir("rlimit-as");
    let run = LargeWindow::in_dir(&dir);
    let (csv, h5) = (&run.csv, &run.h5);
    let (expect, simulate) = (run.expect(), run.simulate());
    let (mut ran, mut refused) = (0, 0);
    for mb in [150u64, 200, 250, 300, 350, 450] {
        for (args, out) in [(&expect, csv), (&simulate, h5)] {
            let o = lidarsim_limited(args, mb * 1_000_000);
            let stderr = String::from_utf8_lossy(&o.stderr);
            let what = format!("{} under {mb} MB: {stderr}", args[0]);
            match o.status.code() {
                Some(0) => {
                    assert!(out.exists(), "{what}");
                    ran += 1;
                }
                Some(2) => {
                    let lines: Vec<&str> = stderr.lines().collect();
                    assert_eq!(lines.len(), 1, "{what}");
                    assert!(
                        lines[0].contains("needs about") && lines[0].contains("ulimit -v"),
                        "not refused up front: {what}"
                    );
                    assert!(!out.exists(), "{what}");
                    refused += 1;
                }
                _ => panic!("{what} ({:?})", o.status),
            }
            std::fs::remove_file(out).ok();
        }
    }
    assert!(ran > 0 && refused > 0, "{ran} ran, {refused} refused");
    std::fs::remove_dir_all(&dir).ok();
}

/// The model's memory back down (issue 36, item 15): `expect` of scenario 1's 40 km
/// window at `bin_width_s` 2e-9 (133,426 bins) runs under a 200 MB address-space limit
/// and `simulate --profiles 2` under 450 MB, their outputs written. Today's main kept the
/// whole beam path, 96 bytes a slab over the 86 km atmosphere (1.15e6 slabs, 110 MB),
/// estimated 175 MB for the model and 344 MB for the run's buffers (64 profiles a batch
/// counted where the run draws 2), and refused both; its peaks were 164 and 276 MB RSS
/// (now 77 and 189 MB: `/usr/bin/time -v`). That they run, not die partway, also shows
/// the estimate is not below what they take.
#[test]
fn a_large_model_runs_under_an_address_space_limit_that_main_refused() {
    let dir = scratch_dir("rlimit-as-fits");
    let run = LargeWindow::in_dir(&dir);
    let (csv, h5) = (&run.csv, &run.h5);
    let (expect, simulate) = (run.expect(), run.simulate());
    for (args, out, mb) in [(&expect, csv, 200u64), (&simulate, h5, 450)] {
        let o = lidarsim_limited(args, mb * 1_000_000);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{} under {mb} MB: {stderr}",
            args[0]
        );
        assert!(out.exists(), "{} under {mb} MB wrote nothing", args[0]);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `tools/check_raw_file.py` without `ncdump` on PATH (optional, README): the ncdump
/// check is skipped and said so on stderr, the file's other checks pass (issue 36, item
/// 18; before, a missing ncdump failed the file).
#[test]
fn check_raw_file_skips_ncdump_loudly_when_it_is_absent() {
    if !common::python_has(
        "cli: tools/check_raw_file.py without ncdump",
        &["numpy", "h5py", "xarray", "h5netcdf"],
    ) {
        return;
    }
    let dir = scratch_dir("no-ncdump");
    let raw = dir.join("r.h5");
    let cfg = config_path("paper/scenario3.toml");
    let out = lidarsim(&[
        "simulate",
        cfg.to_str().unwrap(),
        "-o",
        raw.to_str().unwrap(),
        "--profiles",
        "2",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let python = Command::new("python3")
        .args(["-c", "import sys; print(sys.executable)"])
        .output()
        .unwrap();
    let python = String::from_utf8(python.stdout).unwrap().trim().to_string();
    let tool = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/check_raw_file.py");
    // no directory on PATH: no ncdump
    let o = Command::new(&python)
        .arg(tool)
        .arg(&raw)
        .env("PATH", dir.join("nothing"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success(),
        "{}{stderr}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(stderr.contains("SKIPPED the ncdump -h check"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// docs/model.md says what US76's number density is (issue 36, item 18): not "from its
/// definition" (the Standard's Eq. 29, `N_A·P/(R*·T)`) but `P/(k_B·T)` with CODATA's k_B,
/// 2.18e-5 below it: `N_A/R* = 6.022169e26/8314.32` against `1/k_B = 1/1.380649e-23`.
#[test]
fn the_model_docs_say_how_us76_number_density_is_computed() {
    let ratio: f64 = (6.022169e26 / 8314.32) * 1.380_649e-23 - 1.0;
    assert!((ratio - 2.18e-5).abs() < 0.01e-5, "{ratio}");
    let doc = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/model.md"),
    )
    .unwrap();
    let start = doc.find("* **Molecules** (`us76.rs`").unwrap();
    let para: String = doc[start..].chars().take(700).collect();
    assert!(
        para.contains("CODATA k_B") && para.contains("2.18e-5"),
        "{para}"
    );
}
