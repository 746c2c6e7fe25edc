//! Sweep metrics, values outside documented ranges, plausibility warnings and messages (issue 18, items 6 to 9).

use std::fs;
use std::process::{Command, Stdio};

use super::{Case, Run, Scratch, Want, args, bin, cfg};

const CALIOP: &str = "instruments/caliop_532.toml";
const GROUND: &str = "ground/ground_532_overlap.toml";

/// A ground run started on 2024-07-14 for the SCC export cases (`in/raw.h5`).
const SCC_START: &str = "acquisition.start_time=\"2024-07-14T21:30:00Z\"";

/// One refused case: the needle is what the one line must contain (the argument or key).
fn refused(name: &'static str, needle: &'static str, run: Run) -> Case {
    Case {
        name,
        want: Want::Refused(needle),
        env: vec![],
        run,
    }
}

/// A sweep of scenario 1 over the pulse energy with these extra arguments.
fn sweep(extra: &[&str]) -> Run {
    let mut v = vec!["sweep", "@S1", "--csv", "-"];
    v.extend_from_slice(extra);
    args(&v)
}

/// An onboard run of the CALIOP config (one profile) with the scheme file `in/scheme.toml`.
fn onboard_scheme(extra: &[&'static str]) -> Vec<String> {
    let mut v: Vec<String> = [
        "onboard",
        &cfg(CALIOP),
        "--scheme",
        "@D/in/scheme.toml",
        "-o",
        "@D/p.h5",
        "--set",
        "acquisition.profiles=1",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    v.extend(extra.iter().map(|s| s.to_string()));
    v
}

/// An `--shard auto` simulate with this Slurm environment.
fn slurm(name: &'static str, needle: &'static str, env: Vec<(&'static str, &'static str)>) -> Case {
    Case {
        name,
        want: Want::Refused(needle),
        env,
        run: args(&[
            "simulate",
            "@S1",
            "-o",
            "@D/out.h5",
            "--profiles",
            "2",
            "--shard",
            "auto",
        ]),
    }
}

/// This topic's cases, run after the older ones.
pub fn cases() -> Vec<Case> {
    const E: &str = "--vary";
    const M: &str = "--metric";
    const VARY: &str = "instrument.pulse_energy_j=0.1..1:2";
    vec![
        // --- sweep (item 6) ---
        refused(
            "sweep --vary with three dots",
            "START..STOP",
            sweep(&[E, "instrument.pulse_energy_j=0.1...1:5", M, "snr_at:5km"]),
        ),
        refused(
            "sweep --vary key given twice",
            "given twice",
            sweep(&[
                E,
                VARY,
                E,
                "instrument.pulse_energy_j=0.2..1:2",
                M,
                "snr_at:5km",
            ]),
        ),
        refused(
            "sweep --vary with an empty key",
            "KEY=START..STOP",
            sweep(&[E, "=0.1..1:2", M, "snr_at:5km"]),
        ),
        refused(
            "sweep --vary START = STOP with N > 1",
            "give N = 1",
            sweep(&[E, "instrument.pulse_energy_j=0.1..0.1:3", M, "snr_at:5km"]),
        ),
        refused(
            "sweep --metric snr_at below the window",
            "snr_at:Zkm",
            sweep(&[E, VARY, M, "snr_at:-5km"]),
        ),
        refused(
            "sweep --metric snr_at above the window",
            "outside the acquisition window",
            sweep(&[E, VARY, M, "snr_at:500km"]),
        ),
        refused(
            "sweep --metric time_to_snr:0",
            "time_to_snr:X@Zkm",
            sweep(&[E, VARY, M, "time_to_snr:0@5km"]),
        ),
        refused(
            "sweep --metric negative S/N target",
            "X > 0",
            sweep(&[E, VARY, M, "time_to_snr:-3@5km"]),
        ),
        refused(
            "sweep --metric max_altitude:snr=-1",
            "max_altitude:snr=X",
            sweep(&[E, VARY, M, "max_altitude:snr=-1"]),
        ),
        refused(
            "sweep --metric given twice",
            "given twice",
            sweep(&[E, VARY, M, "snr_at:5km", M, "snr_at:5km"]),
        ),
        // --- values outside documented ranges (item 7) ---
        refused(
            "instrument.channels = []",
            "instrument.channels",
            args(&["expect", "@S1", "--set", "instrument.channels=[]"]),
        ),
        refused(
            "--word-bits 0",
            "--word-bits",
            args(&[
                "onboard",
                "@S1",
                "--scheme",
                "none",
                "-o",
                "@D/p.h5",
                "--word-bits",
                "0",
            ]),
        ),
        refused(
            "--word-bits 65",
            "from 1 to 64",
            args(&[
                "onboard",
                "@S1",
                "--scheme",
                "none",
                "-o",
                "@D/p.h5",
                "--word-bits",
                "65",
            ]),
        ),
        slurm(
            "SLURM_ARRAY_TASK_STEP=0",
            "SLURM_ARRAY_TASK_STEP=0",
            vec![
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
                ("SLURM_ARRAY_TASK_STEP", "0"),
            ],
        ),
        slurm(
            "SLURM_ARRAY_TASK_STEP negative",
            "SLURM_ARRAY_TASK_STEP",
            vec![
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
                ("SLURM_ARRAY_TASK_STEP", "-2"),
            ],
        ),
        slurm(
            "SLURM_ARRAY_TASK_STEP not a number",
            "SLURM_ARRAY_TASK_STEP",
            vec![
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
                ("SLURM_ARRAY_TASK_STEP", "two"),
            ],
        ),
        slurm(
            "SLURM task id off MIN + k·STEP",
            "SLURM_ARRAY_TASK_STEP",
            vec![
                ("SLURM_ARRAY_TASK_ID", "4"),
                ("SLURM_ARRAY_TASK_MIN", "1"),
                ("SLURM_ARRAY_TASK_STEP", "2"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ],
        ),
        refused(
            "--measurement-id with month 13",
            "not a calendar date",
            args(&[
                "export-scc",
                "@D/in/raw.h5",
                "@D/out.nc",
                "--measurement-id",
                "20241301ls00",
            ]),
        ),
        refused(
            "--measurement-id of another day",
            "20240714",
            args(&[
                "export-scc",
                "@D/in/raw.h5",
                "@D/out.nc",
                "--measurement-id",
                "20240715ls00",
            ]),
        ),
        refused(
            "scheme resolution 31 m on 29.93 m bins",
            "vertical_resolution_m",
            Run::Args(onboard_scheme(&[])),
        ),
        refused(
            "scheme region thinner than one bin",
            "regions[0]",
            Run::Args(onboard_scheme(&[])),
        ),
        // --- messages (item 9) ---
        refused(
            "scheme runs past the window at bottom -2 km",
            "-2.06 km",
            Run::Args(onboard_scheme(&[
                "--set",
                "acquisition.bottom_altitude_km=-2",
            ])),
        ),
        refused(
            "molecular profile file missing: key and resolved path",
            "atmosphere.molecular.model.file",
            args(&["expect", "@IN"]),
        ),
    ]
}

/// Writes a scheme file of one region from 8.2 km down to `bottom_km`.
fn scheme(dir: &Scratch, bottom_km: f64, resolution_m: f64) {
    fs::write(
        dir.0.join("in/scheme.toml"),
        format!(
            "[[regions]]\ntop_km = 8.2\nbottom_km = {bottom_km}\n\
             vertical_resolution_m = {resolution_m}\nshots_averaged = 1\n"
        ),
    )
    .unwrap();
}

/// Prepares the scratch directory of one of this topic's cases: `None` when the case
/// is not this topic's, `Some(false)` when its preparation is not possible here.
pub fn prepare(name: &str, dir: &Scratch) -> Option<bool> {
    match name {
        "--measurement-id with month 13" | "--measurement-id of another day" => {
            let ok = Command::new(bin())
                .args(["simulate", &cfg(GROUND), "--profiles", "1", "-o"])
                .arg(dir.0.join("in/raw.h5"))
                .args(["--set", SCC_START])
                .env_remove("SOURCE_DATE_EPOCH")
                .stdin(Stdio::null())
                .stderr(Stdio::null())
                .status()
                .is_ok_and(|s| s.success());
            assert!(ok, "the SCC cases' raw file could not be made");
        }
        "scheme resolution 31 m on 29.93 m bins" => scheme(dir, -0.5, 31.0),
        "scheme region thinner than one bin" => scheme(dir, 8.19, 29.93),
        // 29.7 m is 0.8 % from one native bin (accepted); 343 of them (10.27 km) reach below -2 km
        "scheme runs past the window at bottom -2 km" => scheme(dir, -2.0, 29.7),
        "molecular profile file missing: key and resolved path" => {
            let text = fs::read_to_string(super::s1())
                .unwrap()
                .replace("model = \"us76\"", "model = { file = \"nope.txt\" }");
            fs::write(dir.0.join("in/cfg.toml"), text).unwrap();
        }
        _ => return None,
    }
    Some(true)
}

/// Runs the binary; its exit status and stderr lines.
fn run(a: &[&str]) -> (Option<i32>, Vec<String>) {
    let o = Command::new(bin())
        .args(a)
        .env_remove("SOURCE_DATE_EPOCH")
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr)
        .lines()
        .map(str::to_string)
        .collect();
    (o.status.code(), err)
}

/// The lines of `stderr` that start with `lidarsim: warning: KEY`.
fn warnings<'a>(stderr: &'a [String], key: &str) -> Vec<&'a String> {
    let prefix = format!("lidarsim: warning: {key}");
    stderr.iter().filter(|l| l.starts_with(&prefix)).collect()
}

/// Item 8: a legal value that is almost surely a unit slip gets one warning line naming
/// the key and the reason, once per run (two channels, a sweep of three points), and
/// the run goes on (exit 0). The thresholds are written here: 10 J; the window against
/// the distance to the ground + 100 km; c/(2 fL) = 299792458/(2·10000) m = 14.99 km.
#[test]
fn unit_slips_are_warned_once_and_the_run_goes_on() {
    // one at a time with the case tables: the machine's two cores and HDF5's locks
    let _one = crate::ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let dir = std::env::temp_dir().join(format!("lidarsim-values-warn-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    let s1 = super::s1();
    let ground = cfg(GROUND);
    // 50 J: above 10 J
    let (st, err) = run(&["expect", &s1, "--set", "instrument.pulse_energy_j=50"]);
    assert_eq!(st, Some(0), "{err:?}");
    let w = warnings(&err, "instrument.pulse_energy_j = 50 J");
    assert_eq!(w.len(), 1, "{err:?}");
    assert!(w[0].contains("above 10 J"), "{err:?}");
    // 10 J itself is not warned
    let (st, err) = run(&["expect", &s1, "--set", "instrument.pulse_energy_j=10"]);
    assert_eq!(st, Some(0), "{err:?}");
    assert!(
        warnings(&err, "instrument.pulse_energy_j").is_empty(),
        "{err:?}"
    );
    // a ground window of 150 km: longer than 0 km + 100 km
    let (st, err) = run(&[
        "expect",
        &ground,
        "--set",
        "acquisition.top_altitude_km=150",
    ]);
    assert_eq!(st, Some(0), "{err:?}");
    let w = warnings(&err, "acquisition.top_altitude_km = 150");
    assert_eq!(w.len(), 1, "{err:?}");
    assert!(w[0].contains("150.0 km along the beam"), "{err:?}");
    // 99 km is not warned, nor is a space-borne window of 100 km from 600 km
    let (_, err) = run(&["expect", &ground, "--set", "acquisition.top_altitude_km=99"]);
    assert!(
        warnings(&err, "acquisition.top_altitude_km").is_empty(),
        "{err:?}"
    );
    let (_, err) = run(&["expect", &s1]);
    assert!(
        !err.iter().any(|l| l.contains("warning: acquisition")),
        "{err:?}"
    );
    // 10 kHz on a 20 km ground window: beyond c/(2 fL) = 14.99 km
    let (st, err) = run(&["expect", &ground, "--set", "instrument.rep_rate_hz=10000"]);
    assert_eq!(st, Some(0), "{err:?}");
    let w = warnings(&err, "instrument.rep_rate_hz = 10000 Hz");
    assert_eq!(w.len(), 1, "{err:?}");
    let unambiguous_km = 299_792_458.0 / (2.0 * 10_000.0) / 1e3;
    assert!(
        w[0].contains(&format!("c/(2 fL) = {unambiguous_km:.1} km")),
        "{err:?}"
    );
    // 7000 Hz: c/(2 fL) = 21.4 km holds the 20 km window
    let (_, err) = run(&["expect", &ground, "--set", "instrument.rep_rate_hz=7000"]);
    assert!(
        warnings(&err, "instrument.rep_rate_hz").is_empty(),
        "{err:?}"
    );
    // two channels (2500 Hz, c/(2 fL) = 60 km) and a 70 km window: one warning per run
    let out = dir.join("two.h5");
    let (st, err) = run(&[
        "simulate",
        &cfg("ground/ground_532_depol.toml"),
        "--profiles",
        "1",
        "-o",
        out.to_str().unwrap(),
        "--set",
        "acquisition.top_altitude_km=70",
    ]);
    assert_eq!(st, Some(0), "{err:?}");
    assert_eq!(warnings(&err, "instrument.rep_rate_hz").len(), 1, "{err:?}");
    assert!(out.exists());
    // a sweep of three points, each of them above 10 J: one warning
    let csv = dir.join("sweep.csv");
    let (st, err) = run(&[
        "sweep",
        &s1,
        "--set",
        "instrument.pulse_energy_j=20",
        "--vary",
        "instrument.rep_rate_hz=10..30:3",
        "--metric",
        "snr_at:5km",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(st, Some(0), "{err:?}");
    assert_eq!(
        warnings(&err, "instrument.pulse_energy_j").len(),
        1,
        "{err:?}"
    );
    assert_eq!(fs::read_to_string(&csv).unwrap().lines().count(), 4);
    let _ = fs::remove_dir_all(&dir);
}
