//! `simulate` writes the same bytes with one and two threads (issue 11, part 2): the
//! writer's chunks are compressed on the run's pool, in whatever order its workers take
//! them, and stored in a fixed order. The files pass `tools/check_raw_file.py` where its
//! Python modules are installed.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::config_path;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-writer-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `simulate` in `dir` with `RAYON_NUM_THREADS` (the same command line, so the same
/// `history`) and returns the file's bytes.
fn simulate_bytes(dir: &Path, threads: usize, cfg: &str, extra: &[&str]) -> Vec<u8> {
    std::fs::create_dir_all(dir).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .current_dir(dir)
        .args(["simulate", config_path(cfg).to_str().unwrap(), "-o", "x.h5"])
        .args(extra)
        .env("SOURCE_DATE_EPOCH", "1700000000")
        .env("RAYON_NUM_THREADS", threads.to_string())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read(dir.join("x.h5")).unwrap()
}

#[test]
fn one_and_two_threads_write_the_same_bytes() {
    let dir = scratch("threads");
    for (k, (cfg, extra)) in [
        // 250 profiles of 334 u32 counts: 392 rows per chunk, so one (edge) chunk; with
        // components, four count variables
        (
            "paper/scenario1.toml",
            vec!["--profiles", "250", "--components"],
        ),
        // a changing scene: u32 counts (96 rows per chunk) and five f64 truth variables
        // (48 rows), 100 profiles: edge chunks of 4
        (
            "instruments/caliop_orbit.toml",
            vec!["--profiles", "100", "--method", "shot"],
        ),
        // 10,000-shot profiles: the counts' low bytes are noise, stored (`planes.rs`);
        // two full chunks and an edge chunk
        (
            "paper/scenario1.toml",
            vec![
                "--profiles",
                "800",
                "--method",
                "aggregate",
                "--set",
                "acquisition.accumulation_time_s=1000",
            ],
        ),
        // issue 21's detectors: dead time (its fast paths), afterpulses and jitter over
        // two shot blocks of 75,000-shot profiles; a both pair's analog and photon
        // counts; analog codes with a low-pass and signal-induced noise, aggregate
        (
            "ground/mpl_like.toml",
            vec![
                "--profiles",
                "2",
                "--set",
                "acquisition.accumulation_time_s=30",
            ],
        ),
        (
            "ground/pollyxt_like_glued.toml",
            vec![
                "--profiles",
                "2",
                "--set",
                "acquisition.accumulation_time_s=5",
            ],
        ),
        (
            "ground/ground_532_depol.toml",
            vec![
                "--profiles",
                "50",
                "--method",
                "aggregate",
                "--set",
                "instrument.pulse_energy_jitter=0",
                "--set",
                "instrument.detector={mode=\"analog\", bandwidth_hz=1e7, signal_induced_noise={model=\"exponential\", fraction=1e-3, time_constant_s=2e-5}}",
            ],
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let one = simulate_bytes(&dir.join(format!("{k}-1")), 1, cfg, &extra);
        let two = simulate_bytes(&dir.join(format!("{k}-2")), 2, cfg, &extra);
        assert!(one == two, "{cfg}: 1 and 2 threads differ");
        let f = hdf5::File::open(dir.join(format!("{k}-2/x.h5"))).unwrap();
        for name in f.member_names().unwrap() {
            let ds = f.dataset(&name).unwrap();
            if ds.ndim() == 3 {
                assert!(
                    common::chunk_info(&ds)
                        .iter()
                        .all(|(_, mask, _)| *mask == 0),
                    "{name}"
                );
            }
        }
        if extra.contains(&"acquisition.accumulation_time_s=1000") {
            // zlib header, then a stored block of 65,535 bytes
            let ds = f.dataset("counts").unwrap();
            let (offset, _, size) = &common::chunk_info(&ds)[0];
            let stored = common::raw_chunk(&ds, offset, *size);
            assert_eq!(stored[..7], [0x78, 0x01, 0x00, 0xFF, 0xFF, 0x00, 0x00]);
        }
        if extra.contains(&"--components") {
            let counts: Vec<u64> = f.dataset("counts").unwrap().read_raw().unwrap();
            let sum = ["signal_counts", "background_counts", "dark_counts"]
                .iter()
                .map(|v| f.dataset(v).unwrap().read_raw::<u64>().unwrap())
                .fold(vec![0u64; counts.len()], |acc, v| {
                    acc.iter().zip(&v).map(|(a, b)| a + b).collect()
                });
            assert_eq!(sum, counts);
            assert!(counts.iter().sum::<u64>() > 0);
        }
        python_check(&dir.join(format!("{k}-2/x.h5")));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `tools/check_raw_file.py` (h5py, xarray with h5netcdf, netCDF4 and `ncdump` where
/// installed), when its Python modules are.
fn python_check(path: &Path) {
    if !common::python_has(
        "raw_writer_threads: tools/check_raw_file.py",
        &["numpy", "h5py", "xarray", "h5netcdf", "netCDF4"],
    ) {
        return;
    }
    let ncdump = Command::new("ncdump").arg("-h").output().is_ok();
    let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/check_raw_file.py");
    let mut cmd = Command::new("python3");
    cmd.arg(tool).arg(path);
    if !ncdump {
        common::skip(
            "raw_writer_threads: ncdump's view in tools/check_raw_file.py",
            "ncdump (Debian: netcdf-bin) not installed",
        );
        cmd.arg("--no-ncdump");
    }
    let o = cmd.output().unwrap();
    assert!(
        o.status.success(),
        "check_raw_file.py {}:\n{}{}",
        path.display(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}
