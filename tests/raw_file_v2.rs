//! The raw file, format version 2 (docs/file-format.md): CF time, coordinates, the
//! bin-averaged truth consistent with the counts, reproducible bytes.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{config_path, reference};
use hdf5::types::VarLenUnicode;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-v2-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `simulate` on a shipped config with SOURCE_DATE_EPOCH fixed.
fn simulate(cfg: &str, out: &Path, extra: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .args(["simulate", config_path(cfg).to_str().unwrap(), "-o"])
        .arg(out)
        .args(extra)
        .env("SOURCE_DATE_EPOCH", "1700000000")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn str_attr(loc: &hdf5::Location, name: &str) -> String {
    let v: VarLenUnicode = loc.attr(name).unwrap().read_scalar().unwrap();
    v.as_str().to_string()
}

fn f64s(f: &hdf5::File, name: &str) -> Vec<f64> {
    f.dataset(name).unwrap().read_raw::<f64>().unwrap()
}

#[test]
fn same_arguments_and_source_date_epoch_give_identical_bytes() {
    let dir = scratch("bytes");
    let (a, b) = (dir.join("a"), dir.join("b"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    for d in [&a, &b] {
        let o = Command::new(env!("CARGO_BIN_EXE_lidarsim"))
            .current_dir(d)
            .args([
                "simulate",
                config_path("paper/scenario1.toml").to_str().unwrap(),
            ])
            .args(["-o", "x.nc", "--profiles", "50", "--method", "shot"])
            .env("SOURCE_DATE_EPOCH", "1700000000")
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let (x, y) = (
        std::fs::read(a.join("x.nc")).unwrap(),
        std::fs::read(b.join("x.nc")).unwrap(),
    );
    assert!(
        x == y,
        "two runs differ ({} and {} bytes)",
        x.len(),
        y.len()
    );
    let f = hdf5::File::open(a.join("x.nc")).unwrap();
    assert_eq!(str_attr(&f, "date_created"), "2023-11-14T22:13:20Z");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_layout_is_format_version_5() {
    let dir = scratch("layout");
    let out = dir.join("s1.h5");
    simulate(
        "paper/scenario1.toml",
        &out,
        &[
            "--profiles",
            "4",
            "--set",
            "acquisition.start_time=\"2004-03-21T06:30:00Z\"",
        ],
    );
    let f = hdf5::File::open(&out).unwrap();
    let v: i32 = f
        .attr("lidarsim_format_version")
        .unwrap()
        .read_scalar()
        .unwrap();
    assert_eq!(v, 5);
    assert_eq!(f.dataset("pulse_energy").unwrap().shape(), vec![4, 1]);
    assert!(str_attr(&f, "Conventions").starts_with("CF-1."));
    let counts = f.dataset("counts").unwrap();
    assert_eq!(counts.shape(), vec![4, 1, 334]);
    assert_eq!(
        str_attr(&counts, "coordinates"),
        "time altitude range channel_name"
    );
    let ch: Vec<i64> = f.dataset("channel").unwrap().read_raw().unwrap();
    assert_eq!(ch, [0]);
    let ch: Vec<VarLenUnicode> = f.dataset("channel_name").unwrap().read_raw().unwrap();
    assert_eq!(ch[0].as_str(), "532_total");
    let time = f.dataset("time").unwrap();
    assert_eq!(
        str_attr(&time, "units"),
        "seconds since 2004-03-21 06:30:00"
    );
    assert_eq!(str_attr(&time, "standard_name"), "time");
    // 100 shots at 10 Hz: profile centres at 5, 15, 25, 35 s
    assert_eq!(f64s(&f, "time"), vec![5.0, 15.0, 25.0, 35.0]);
    let alt = f.dataset("altitude").unwrap();
    assert_eq!(str_attr(&alt, "standard_name"), "altitude");
    assert_eq!(str_attr(&alt, "positive"), "up");
    assert_eq!(f.dataset("expected_signal").unwrap().shape(), vec![1, 334]);
    assert_eq!(f.dataset("lidar_constant").unwrap().shape(), vec![1]);
    std::fs::remove_dir_all(&dir).ok();
}

/// The file's truth against this test's own calculation (`tests/common/reference.rs`:
/// own geometry, optics and T² by quadrature; C from the config's values): the lidar
/// constant, the range weight `1/a − 1/b`, the bin-averaged attenuated backscatter
/// `∫βT²/r² / ∫1/r²`, the expected signal, T² at bin centres, each within 1e-3 (a 1 %
/// error in any of them fails); and the total is signal + background + dark.
#[test]
fn expected_signal_attenuated_backscatter_and_range_weight_match_an_independent_calculation() {
    let dir = scratch("truth");
    let out = dir.join("s3.h5");
    simulate("paper/scenario3.toml", &out, &["--profiles", "2"]);
    let f = hdf5::File::open(&out).unwrap();
    let sc = common::scenario("paper/scenario3.toml", &[]);
    let cfg = &sc.loaded.config;
    let c_ref = reference::signal_constant(cfg);
    let c = f64s(&f, "lidar_constant")[0];
    assert!((c / c_ref - 1.0).abs() < 1e-12, "C {c} vs {c_ref}");
    let brute = reference::brute_force(&sc, 0.05);
    let bins = reference::bins(cfg);
    let (s, ab, rw, t2) = (
        f64s(&f, "expected_signal"),
        f64s(&f, "attenuated_backscatter"),
        f64s(&f, "range_weight"),
        f64s(&f, "t2"),
    );
    assert_eq!(s.len(), bins.len());
    let close = |x: f64, y: f64, tol: f64| (x - y).abs() <= tol * y.abs();
    let mut checked = 0;
    for (i, &(a, b)) in bins.iter().enumerate() {
        let weight = 1.0 / a - 1.0 / b;
        assert!(
            close(rw[i], weight, 1e-9),
            "range weight, bin {i}: {} vs {weight}",
            rw[i]
        );
        assert!(
            close(brute.range_weight[i], weight, 1e-6),
            "the test's own quadrature"
        );
        let signal = c_ref * brute.integral[i];
        if signal < 1e-12 {
            continue;
        }
        checked += 1;
        assert!(
            close(s[i], signal, 1e-3),
            "signal, bin {i}: {} vs {signal}",
            s[i]
        );
        let averaged = brute.integral[i] / weight;
        assert!(
            close(ab[i], averaged, 1e-3),
            "attenuated backscatter, bin {i}: {} vs {averaged}",
            ab[i]
        );
        if brute.t2_centre[i] > 1e-6 {
            assert!(
                close(t2[i], brute.t2_centre[i], 1e-3),
                "T², bin {i}: {} vs {}",
                t2[i],
                brute.t2_centre[i]
            );
        }
    }
    // 86 km of atmosphere in 300 m bins
    assert!(checked > 280, "{checked}");
    let total: Vec<f64> = f64s(&f, "expected_counts");
    let (bk, d) = (f64s(&f, "expected_background"), f64s(&f, "expected_dark"));
    for i in 0..s.len() {
        assert!((total[i] - (s[i] + bk[i] + d[i])).abs() <= 1e-12 * total[i]);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_bin_averaged_truth_follows_a_cut_cloud_edge_where_the_point_truth_does_not() {
    // scenario 1's cirrus spans 10-12 km; move its top to cut a 300 m bin in the middle
    let dir = scratch("edge");
    let out = dir.join("edge.h5");
    simulate(
        "paper/scenario1.toml",
        &out,
        &[
            "--profiles",
            "2",
            "--set",
            "atmosphere.layers.0.top_km=11.9151",
        ],
    );
    let f = hdf5::File::open(&out).unwrap();
    let (alt, ab) = (f64s(&f, "altitude"), f64s(&f, "attenuated_backscatter"));
    let (bm, ba, bc, t2) = (
        f64s(&f, "beta_mol"),
        f64s(&f, "beta_aer"),
        f64s(&f, "beta_cld"),
        f64s(&f, "t2"),
    );
    let i = alt
        .iter()
        .position(|z| (z - 11_915.1).abs() < 150.0)
        .expect("a bin holds the cloud top");
    let point = (bm[i] + ba[i] + bc[i]) * t2[i];
    let rel = (ab[i] - point).abs() / ab[i];
    assert!(
        rel > 0.2,
        "bin {i} at {} m: averaged {} point {point}",
        alt[i],
        ab[i]
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Channels of different energies (the PollyXT-like preset: 60 mJ at 354.7 nm, 110 mJ at
/// 532 nm, 180 mJ at 1064 nm, its header's figures, independent of the code): the file
/// gives every channel the energy of its laser line, `nominal_pulse_energy` and
/// `pulse_energy` (profile, channel), and the documented expectation `n_shots ·
/// (expected_counts + (pulse_energy/nominal_pulse_energy − 1) · expected_signal)` (ideal
/// photon counters) is what the counts are, per channel. With 5 % jitter over 4 profiles
/// of 6,000 shots, the sum over each channel's bins against that expectation has
/// |z| < 4.5 (a false alarm 7e-6 per channel); version 3 gave every channel the first
/// channel's 60 mJ, so its 532 and 1064 nm expectations were ×0.55 and ×0.33: z in the
/// thousands.
#[test]
fn each_channel_has_the_energy_of_its_laser_line() {
    let dir = scratch("energy");
    let out = dir.join("polly.h5");
    simulate(
        "ground/pollyxt_like.toml",
        &out,
        &[
            "--profiles",
            "4",
            "--set",
            "instrument.pulse_energy_jitter=0.05",
        ],
    );
    let f = hdf5::File::open(&out).unwrap();
    let emission = f64s(&f, "emission_wavelength");
    let line_energy = |nm: f64| match nm.round() as i64 {
        355 => 0.060,
        532 => 0.110,
        1064 => 0.180,
        other => panic!("laser line {other} nm"),
    };
    let nominal = f64s(&f, "nominal_pulse_energy");
    let channels = nominal.len();
    assert_eq!(channels, 8);
    for (c, e0) in nominal.iter().enumerate() {
        assert_eq!(*e0, line_energy(emission[c]), "channel {c}");
    }
    let energy = f.dataset("pulse_energy").unwrap();
    assert_eq!(energy.shape(), vec![4, channels]);
    let energy: Vec<f64> = energy.read_raw().unwrap();
    let shots: Vec<u64> = f.dataset("n_shots").unwrap().read_raw().unwrap();
    let counts: Vec<u64> = f.dataset("counts").unwrap().read_raw().unwrap();
    let (signal, total) = (f64s(&f, "expected_signal"), f64s(&f, "expected_counts"));
    let bins = signal.len() / channels;
    for c in 0..channels {
        let (mut observed, mut expected) = (0.0, 0.0);
        for p in 0..4 {
            let factor = energy[p * channels + c] / nominal[c];
            // one laser: every channel of a profile sees the same factor
            assert!((factor / (energy[p * channels] / nominal[0]) - 1.0).abs() < 1e-12);
            for b in 0..bins {
                let j = c * bins + b;
                expected += shots[p] as f64 * (total[j] + (factor - 1.0) * signal[j]);
                observed += counts[(p * channels + c) * bins + b] as f64;
            }
        }
        let z = (observed - expected) / expected.sqrt();
        assert!(
            z.abs() < 4.5,
            "channel {c}: {observed} counts, {expected} expected (z = {z})"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Readers of older files keep working: the PollyXT-like file made a format-3 file
/// (`pulse_energy` (profile), the first channel's, and `channel` the names, as version
/// 3 wrote them; the version attribute 3) is read by `validate --file` (consistent), `quicklook` (every channel at
/// its own energy: the same figure as the format-4 file's), `curtain` and `export-scc`.
#[test]
fn a_format_3_file_is_still_read_by_every_reader() {
    let dir = scratch("format3");
    let (v4, v3) = (dir.join("v4.h5"), dir.join("v3.h5"));
    simulate(
        "ground/pollyxt_like.toml",
        &v4,
        &[
            "--profiles",
            "3",
            "--set",
            "instrument.pulse_energy_jitter=0.05",
        ],
    );
    std::fs::copy(&v4, &v3).unwrap();
    {
        let f = hdf5::File::open_rw(&v3).unwrap();
        let energy = f.dataset("pulse_energy").unwrap();
        let channels = energy.shape()[1];
        let first: Vec<f64> = energy
            .read_raw::<f64>()
            .unwrap()
            .iter()
            .step_by(channels)
            .copied()
            .collect();
        drop(energy);
        f.unlink("pulse_energy").unwrap();
        f.new_dataset::<f64>()
            .shape(first.len())
            .create("pulse_energy")
            .unwrap()
            .write_raw(&first)
            .unwrap();
        f.attr("lidarsim_format_version")
            .unwrap()
            .write_scalar(&3i32)
            .unwrap();
        // before format 5, `channel` held the names (no `channel_name`)
        let names: Vec<VarLenUnicode> = f.dataset("channel_name").unwrap().read_raw().unwrap();
        f.unlink("channel_name").unwrap();
        f.unlink("channel").unwrap();
        f.new_dataset::<VarLenUnicode>()
            .shape(names.len())
            .create("channel")
            .unwrap()
            .write_raw(&names)
            .unwrap();
        // closed for certain before the readers open it (a handle still open here, with
        // the other tests of this binary running beside it, left the file locked: "not
        // HDF5", once under load)
        f.close().unwrap();
    }
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_lidarsim"))
            .current_dir(&dir)
            .args(args)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let verdict = run(&["validate", "--file", "v3.h5"]);
    assert!(
        verdict.contains("CONSISTENT") && !verdict.contains("INCONSISTENT"),
        "{verdict}"
    );
    run(&[
        "quicklook",
        "v3.h5",
        "--png",
        "q.png",
        "--channel",
        "1064_total",
    ]);
    run(&["curtain", "v3.h5", "--png", "c.png"]);
    run(&["export-scc", "v3.h5", "scc.nc"]);
    for channel in ["532_total", "1064_total"] {
        let means = |p: &Path| {
            lidarsim::figures::quicklook::read(p, Some(channel), false)
                .unwrap()
                .signal
                .means()
        };
        let (a, b) = (means(&v3), means(&v4));
        let same = a
            .iter()
            .zip(&b)
            .all(|(x, y)| x.to_bits() == y.to_bits() || (x - y).abs() <= 1e-12 * y.abs());
        assert!(same, "{channel}: the format-3 figure differs");
    }
    std::fs::remove_dir_all(&dir).ok();
}
