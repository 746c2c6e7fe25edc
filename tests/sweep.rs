//! `lidarsim sweep` (issue 10): the grid, the metrics of the deterministic model, the
//! CSV and the figure, and bad specifications refused in one line.

mod common;

use std::process::Command;

fn sweep(args: &[&str]) -> std::process::Output {
    let cfg = common::config_path("paper/scenario1.toml");
    Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .arg("sweep")
        .arg(&cfg)
        .args(args)
        .output()
        .unwrap()
}

/// A 3 × 2 grid: one row per point (the last key fastest); `snr_at` is Eq. 4 of the bin
/// at 10 km as `expect` computes it; `time_to_snr` is the accumulation time at which
/// Eq. 4 reaches the asked S/N (checked by recomputing with that time); the laser
/// power is E0·fL; one pulse in flight at 10–100 Hz from 600 km.
#[test]
fn the_grid_and_its_metrics() {
    let dir = std::env::temp_dir().join(format!("lidarsim-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("s.png");
    let o = sweep(&[
        "--vary",
        "instrument.pulse_energy_j=1e-3..1e-1:log:3",
        "--vary",
        "instrument.rep_rate_hz=10..100:2",
        "--metric",
        "snr_at:10km",
        "--metric",
        "time_to_snr:10@15km",
        "--metric",
        "mean_laser_power_w",
        "--metric",
        "pulses_in_flight",
        "--csv",
        "-",
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 6);
    assert!(text.starts_with("instrument.pulse_energy_j,instrument.rep_rate_hz,snr_at:10km,"));
    assert_eq!((rows[1][0], rows[1][1]), (rows[0][0], 100.0));
    for r in &rows {
        let set = |k: &str, v: f64| format!("{k}={v}");
        let sc = common::scenario(
            "paper/scenario1.toml",
            &[
                &set("instrument.pulse_energy_j", r[0]),
                &set("instrument.rep_rate_hz", r[1]),
            ],
        );
        let e = sc.expected().unwrap();
        let shots = r[1] * sc.accumulation_time_s();
        let near = |z: f64| {
            (0..e.n_bins())
                .min_by(|&a, &b| {
                    (e.altitude_m[a] - z)
                        .abs()
                        .total_cmp(&(e.altitude_m[b] - z).abs())
                })
                .unwrap()
        };
        let i = near(10e3);
        let snr = lidarsim::snr::eq4(e.signal[i], e.background, e.dark, shots);
        assert!((r[2] / snr - 1.0).abs() < 1e-12);
        let j = near(15e3);
        let m = r[3] * r[1];
        let reached = lidarsim::snr::eq4(e.signal[j], e.background, e.dark, m);
        assert!((reached - 10.0).abs() < 1e-9, "{reached}");
        assert!((r[4] - r[0] * r[1]).abs() < 1e-15);
        assert_eq!(r[5], 1.0);
    }
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_sweeps_are_refused_in_one_line() {
    for (args, needle) in [
        (
            vec![
                "--vary",
                "instrument.pulse_energy_j=1..2",
                "--metric",
                "snr_at:10km",
            ],
            ":N",
        ),
        (
            vec![
                "--vary",
                "instrument.pulse_energy_j=0..1:log:3",
                "--metric",
                "snr_at:10km",
            ],
            "positive",
        ),
        (
            vec![
                "--vary",
                "instrument.pulse_energy_j=1e-3..1e-2:3",
                "--metric",
                "snr_at:10",
            ],
            "--metric",
        ),
        (
            vec![
                "--vary",
                "instrument.bogus=1..2:2",
                "--metric",
                "snr_at:10km",
            ],
            "bogus",
        ),
        (
            vec![
                "--vary",
                "instrument.pulse_energy_j=-1..1:3",
                "--metric",
                "snr_at:10km",
            ],
            "pulse_energy_j",
        ),
        (
            vec![
                "--vary",
                "a=1..2:1000",
                "--vary",
                "b=1..2:1001",
                "--metric",
                "snr_at:10km",
            ],
            "grid points",
        ),
    ] {
        let mut all = args.clone();
        all.extend(["--csv", "-"]);
        let o = sweep(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(needle) && err.lines().count() == 1,
            "{args:?}: {err}"
        );
        assert!(o.stdout.is_empty(), "{args:?}: a half-written CSV");
    }
}
