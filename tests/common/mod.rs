//! Shared helpers for the integration tests.
#![allow(dead_code)]

pub mod cli;
pub mod h5;
pub mod image;
pub mod reference;

use std::path::{Path, PathBuf};

use lidarsim::scenario::{Lidar, Scenario};

/// The error `loaded::load_str` gives for a config `text` it must refuse (`what` names
/// the case in the panic if it is accepted), checked to be one line.
pub fn refusal(text: &str, what: &str) -> String {
    match lidarsim::loaded::load_str(text, Path::new("config.toml"), &[]) {
        Ok(_) => panic!("accepted: {what}"),
        Err(e) => {
            let e = e.to_string();
            assert!(!e.contains('\n'), "{what}: {e}");
            e
        }
    }
}

/// Numbers as a TOML array's items: `1.0, 2.5, -3.0`.
pub fn toml_list(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:?}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Where every skip is recorded, one line each, so that it shows after the harness
/// (which hides a passing test's output): `.ci/run` empties it before the tests and
/// prints it after them.
pub fn skip_log_path() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("skipped-tests.log")
}

fn record_skip(line: &str) {
    use std::io::Write;
    eprintln!("{line}");
    if let Ok(mut f) = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(skip_log_path())
    {
        let _ = writeln!(f, "{line}");
    }
}

/// Whether this is a CI run (`CI=true`, set by CI services and by `.ci/run`'s caller),
/// where every test must run.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// A check that cannot run here: under `CI=true` a failure (CI installs everything the
/// tests need), elsewhere a loud line on stderr and in [`skip_log_path`]. The caller
/// returns after it.
pub fn skip(test: &str, reason: &str) {
    assert!(
        !in_ci(),
        "{test}: cannot run here ({reason}), and CI=true requires it to"
    );
    record_skip(&format!("SKIPPED {test}: {reason}"));
}

/// A check that cannot run here for a reason documented as acceptable in CI too
/// (`why_acceptable` says why, e.g. a privilege an unprivileged container lacks):
/// never fails, always recorded in [`skip_log_path`].
pub fn skip_acceptable_in_ci(test: &str, reason: &str, why_acceptable: &str) {
    record_skip(&format!(
        "SKIPPED {test}: {reason} (acceptable in CI: {why_acceptable})"
    ));
}

/// Whether `python3` imports every module of `modules`; under `CI=true` a missing one
/// fails (`.ci/run` installs them in a venv), elsewhere it is a recorded skip.
pub fn python_has(test: &str, modules: &[&str]) -> bool {
    let o = std::process::Command::new("python3")
        .args(["-c", &format!("import {}", modules.join(", "))])
        .output();
    match o {
        Ok(o) if o.status.success() => true,
        Ok(o) => {
            skip(
                test,
                &format!(
                    "python3 cannot import {}: {}",
                    modules.join(", "),
                    String::from_utf8_lossy(&o.stderr)
                        .lines()
                        .last()
                        .unwrap_or("")
                ),
            );
            false
        }
        Err(e) => {
            skip(test, &format!("no python3 ({e})"));
            false
        }
    }
}

/// Path of a shipped config, e.g. `config_path("paper/scenario1.toml")`.
pub fn config_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(rel)
}

/// Loads a shipped config with overrides.
pub fn scenario(rel: &str, overrides: &[&str]) -> Scenario {
    let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scenario::load(&config_path(rel), &ov).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Loads a shipped config with overrides, every channel.
pub fn lidar(rel: &str, overrides: &[&str]) -> Lidar {
    let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Lidar::load(&config_path(rel), &ov).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Brute-force signal of every bin, independent of the code under test: the midpoint
/// rule with steps of at most `step_m` on the point optics of [`reference`] (own
/// geometry, US76, Bucholtz Rayleigh, AFGL ozone, Elterman aerosol, overlap), T² by the
/// same rule, times the signal constant computed from the config's values.
pub fn brute_force_signal(sc: &Scenario, step_m: f64) -> Vec<f64> {
    let c = reference::signal_constant(&sc.loaded.config);
    reference::brute_force(sc, step_m)
        .integral
        .iter()
        .map(|i| c * i)
        .collect()
}

/// Chunk index, filter mask and stored size of every chunk of a dataset
/// (`H5Dget_chunk_info`), in the order HDF5 lists them.
pub fn chunk_info(ds: &hdf5::Dataset) -> Vec<(Vec<u64>, u32, u64)> {
    use hdf5_sys::h5d::{H5Dget_chunk_info, H5Dget_num_chunks};
    use hdf5_sys::h5s::H5S_ALL;
    hdf5::sync::sync(|| unsafe {
        let mut n = 0;
        assert!(H5Dget_num_chunks(ds.id(), H5S_ALL, &mut n) >= 0);
        (0..n)
            .map(|k| {
                let mut offset = vec![0u64; ds.ndim()];
                let (mut mask, mut addr, mut size) = (0u32, 0u64, 0u64);
                assert!(
                    H5Dget_chunk_info(
                        ds.id(),
                        H5S_ALL,
                        k,
                        offset.as_mut_ptr(),
                        &mut mask,
                        &mut addr,
                        &mut size,
                    ) >= 0
                );
                (offset, mask, size)
            })
            .collect()
    })
}

/// The stored bytes of one chunk (`H5Dread_chunk`).
pub fn raw_chunk(ds: &hdf5::Dataset, offset: &[u64], size: u64) -> Vec<u8> {
    use hdf5_sys::h5d::H5Dread_chunk;
    use hdf5_sys::h5p::H5P_DEFAULT;
    let mut buf = vec![0u8; size as usize];
    let mut filters = 0u32;
    let mut len = size as usize;
    hdf5::sync::sync(|| unsafe {
        assert!(
            H5Dread_chunk(
                ds.id(),
                H5P_DEFAULT,
                offset.as_ptr(),
                &mut filters,
                buf.as_mut_ptr().cast(),
                &mut len,
            ) >= 0
        );
    });
    assert_eq!(filters, 0, "every filter applied");
    buf
}

/// netCDF4-python's view of an SCC file (`tools/check_scc_file.py`), when installed
/// (under CI it is, or `python_has` fails the test); `test` names the caller.
pub fn check_scc_file_with_python(test: &str, out: &Path) {
    if !python_has(test, &["netCDF4"]) {
        return;
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/check_scc_file.py");
    let (script, out) = (script.to_str().unwrap(), out.to_str().unwrap());
    let said = cli::python_in(Path::new("."), &[script, out]);
    println!("netCDF4-python: {}", said.trim());
}
