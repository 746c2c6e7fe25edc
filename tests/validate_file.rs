//! `lidarsim validate --file RAW.h5` (issue 19, deliverable 9): a raw file's counts
//! against the expectation and detector law it carries. Accepted: the genuine file, the
//! merge of its shards, a copy, a file whose counts another tool re-encoded (false-alarm
//! rate below 1e-3 each, fixed seeds). Rejected: counts scaled by 2 %, counts of a run
//! at another pulse energy, expectations of another run. Hostile files: one line, exit 2.

mod common;

use std::path::Path;
use std::process::Output;

use common::cli::{lidarsim, ok, refused, scratch};
use common::config_path;

/// The run every check here starts from: scenario 1 (100 shots a profile, 334 bins),
/// 200 profiles, seed 11 (unless `extra` gives one): 0.05 s to simulate.
const PROFILES: &str = "200";

fn simulate(dir: &Path, out: &str, extra: &[&str]) {
    let c = config_path("paper/scenario1.toml");
    let mut args = vec!["simulate", c.to_str().unwrap(), "-o", out];
    args.extend_from_slice(&["--profiles", PROFILES]);
    if !extra.contains(&"--seed") {
        args.extend_from_slice(&["--seed", "11"]);
    }
    args.extend_from_slice(extra);
    ok(lidarsim(dir, &args, &[]));
}

/// `validate --file NAME` in `dir`.
fn check(dir: &Path, name: &str) -> Output {
    lidarsim(dir, &["validate", "--file", name], &[])
}

fn consistent(dir: &Path, name: &str) {
    let o = check(dir, name);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{name}: {out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.contains("CONSISTENT"), "{out}");
}

fn inconsistent(dir: &Path, name: &str) -> String {
    let o = check(dir, name);
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert_eq!(
        o.status.code(),
        Some(1),
        "{name}: {out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.contains("INCONSISTENT"), "{out}");
    out
}

/// Replaces datasets `names` of `path` by `values` (same shapes), as another tool would
/// rewrite them: unsigned integers for `counts`, floats otherwise, no filter. One open
/// per file: HDF5 keeps a file it has opened in this process locked.
fn rewrite_all<T: hdf5::H5Type>(path: &Path, names: &[&str], values: &[Vec<T>]) {
    let f = hdf5::File::open_rw(path).unwrap();
    for (name, v) in names.iter().zip(values) {
        let name: &str = name;
        let shape = f.dataset(name).unwrap().shape();
        f.unlink(name).unwrap();
        f.new_dataset::<T>()
            .shape(shape)
            .create(name)
            .unwrap()
            .write_raw(v)
            .unwrap();
    }
    // closed here, every handle with it, so the child process reads it whole (a file
    // left to `Drop` may still be open while another test thread holds HDF5's lock)
    f.close().unwrap();
}

fn rewrite<T: hdf5::H5Type + Clone>(path: &Path, name: &str, values: &[T]) {
    rewrite_all(path, &[name], &[values.to_vec()]);
}

fn read<T: hdf5::H5Type>(path: &Path, name: &str) -> Vec<T> {
    hdf5::File::open(path)
        .unwrap()
        .dataset(name)
        .unwrap()
        .read_raw::<T>()
        .unwrap()
}

#[test]
fn the_genuine_file_its_merge_a_copy_and_a_reencoding_are_consistent() {
    let dir = scratch("vfile-accept");
    simulate(&dir, "whole.h5", &[]);
    consistent(&dir, "whole.h5");
    for k in 0..3 {
        simulate(&dir, &format!("s{k}.h5"), &["--shard", &format!("{k}/3")]);
    }
    ok(lidarsim(
        &dir,
        &["merge", "merged.h5", "s2.h5", "s0.h5", "s1.h5"],
        &[],
    ));
    consistent(&dir, "merged.h5");
    // a shard is a raw file of its own profiles
    consistent(&dir, "s1.h5");
    std::fs::copy(dir.join("whole.h5"), dir.join("copy.h5")).unwrap();
    consistent(&dir, "copy.h5");
    // the same counts rewritten by another tool: uint64, contiguous, no filter
    let counts: Vec<u64> = read(&dir.join("whole.h5"), "counts");
    std::fs::copy(dir.join("whole.h5"), dir.join("retyped.h5")).unwrap();
    rewrite(&dir.join("retyped.h5"), "counts", &counts);
    consistent(&dir, "retyped.h5");
    std::fs::remove_dir_all(&dir).ok();
}

/// Pulse-energy jitter (5 % rms): each profile's count is Poisson at its own
/// `pulse_energy`, which the check reads; without that correction the bright bins'
/// extra variance (M·σ²·s² per profile) would be rejected.
#[test]
fn a_jittered_laser_is_judged_at_each_profiles_energy() {
    let dir = scratch("vfile-jitter");
    simulate(
        &dir,
        "j.h5",
        &["--set", "instrument.pulse_energy_jitter=0.05"],
    );
    consistent(&dir, "j.h5");
    // the same counts said to be at the nominal energy every profile: rejected
    let (p, q) = (dir.join("j.h5"), dir.join("nominal.h5"));
    let e0: Vec<f64> = read(&p, "nominal_pulse_energy");
    let n: Vec<f64> = read(&p, "pulse_energy");
    assert!(n.iter().any(|&e| e != e0[0]));
    std::fs::copy(&p, &q).unwrap();
    rewrite(&q, "pulse_energy", &vec![e0[0]; n.len()]);
    inconsistent(&dir, "nominal.h5");
    std::fs::remove_dir_all(&dir).ok();
}

/// Power: counts scaled by 1.02 (rounded) are rejected at 200 profiles of 100 shots:
/// the mean's z in the cloud bin alone is 0.02·√(200·5.2e4) ≈ 64.
#[test]
fn counts_scaled_by_two_percent_are_rejected() {
    let dir = scratch("vfile-scaled");
    simulate(&dir, "x.h5", &[]);
    let p = dir.join("x.h5");
    let counts: Vec<u64> = read(&p, "counts");
    let scaled: Vec<u64> = counts
        .iter()
        .map(|&c| (c as f64 * 1.02).round() as u64)
        .collect();
    std::fs::copy(&p, dir.join("scaled.h5")).unwrap();
    rewrite(&dir.join("scaled.h5"), "counts", &scaled);
    let out = inconsistent(&dir, "scaled.h5");
    assert!(
        out.lines()
            .any(|l| l.starts_with("mean") && l.ends_with("INCONSISTENT")),
        "{out}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Counts of another run (another seed, the pulse energy 3 % higher) under this file's
/// expectation, and this file's counts under another run's expectation: both rejected.
#[test]
fn counts_and_expectations_of_another_run_are_rejected() {
    let dir = scratch("vfile-other");
    simulate(&dir, "x.h5", &[]);
    let other = ["--seed", "12", "--set", "instrument.pulse_energy_j=0.103"];
    simulate(&dir, "y.h5", &other);
    // y.h5 on its own is consistent: the rejections below are of the mix
    consistent(&dir, "y.h5");
    let (x, y) = (dir.join("x.h5"), dir.join("y.h5"));
    std::fs::copy(&x, dir.join("counts.h5")).unwrap();
    rewrite(&dir.join("counts.h5"), "counts", &read::<u64>(&y, "counts"));
    inconsistent(&dir, "counts.h5");
    std::fs::copy(&x, dir.join("expected.h5")).unwrap();
    let names = ["expected_counts", "expected_signal"];
    let values: Vec<Vec<f64>> = names.iter().map(|n| read(&y, n)).collect();
    rewrite_all(&dir.join("expected.h5"), &names, &values);
    inconsistent(&dir, "expected.h5");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn hostile_files_are_refused_in_one_line() {
    let dir = scratch("vfile-hostile");
    refused(
        &dir,
        &["validate", "--file", "missing.h5"],
        &["missing.h5"],
        "x",
    );
    // an HDF5 file that is not a raw file
    {
        let f = hdf5::File::create(dir.join("other.h5")).unwrap();
        f.new_dataset::<f64>().shape(3).create("x").unwrap();
    }
    refused(
        &dir,
        &["validate", "--file", "other.h5"],
        &["other.h5", "not a lidarsim raw file"],
        "x",
    );
    std::fs::write(dir.join("text.h5"), "not hdf5").unwrap();
    refused(
        &dir,
        &["validate", "--file", "text.h5"],
        &["text.h5", "not HDF5"],
        "x",
    );
    // NaN in an expectation
    simulate(&dir, "x.h5", &[]);
    let mut e: Vec<f64> = read(&dir.join("x.h5"), "expected_counts");
    e[7] = f64::NAN;
    std::fs::copy(dir.join("x.h5"), dir.join("nan.h5")).unwrap();
    rewrite(&dir.join("nan.h5"), "expected_counts", &e);
    refused(
        &dir,
        &["validate", "--file", "nan.h5"],
        &["nan.h5", "`expected_counts`", "bin 7", "NaN"],
        "x",
    );
    // a FIFO is refused before it is opened (opening it would block)
    let fifo = dir.join("fifo.h5");
    if std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        refused(
            &dir,
            &["validate", "--file", "fifo.h5"],
            &["fifo.h5", "FIFO"],
            "x",
        );
    } else {
        common::skip("validate --file of a FIFO", "mkfifo failed");
    }
    // --file with a config: a usage error
    let c = config_path("paper/scenario1.toml");
    let o = lidarsim(
        &dir,
        &["validate", c.to_str().unwrap(), "--file", "nan.h5"],
        &[],
    );
    assert_eq!(o.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

/// A dead-time detector (scenario 1 with τ = 3.5 ns, 100 profiles by the shot method:
/// 1.7 s): mean and variance against the recorded law; profiles whose pulse energy is not
/// the nominal one cannot be judged from the file (the recorded mean is non-linear in each
/// shot's energy), and the table says so; a file with none judged is refused.
#[test]
fn dead_time_is_judged_at_the_nominal_energy_only() {
    let dir = scratch("vfile-dead");
    let c = config_path("paper/scenario1.toml");
    let args = [
        "simulate",
        c.to_str().unwrap(),
        "-o",
        "d.h5",
        "--profiles",
        "100",
        "--seed",
        "4",
        "--set",
        "instrument.detector.dead_time_s=3.5e-9",
    ];
    ok(lidarsim(&dir, &args, &[]));
    consistent(&dir, "d.h5");
    let p = dir.join("d.h5");
    let counts: Vec<u64> = read(&p, "counts");
    let e0: Vec<f64> = read(&p, "nominal_pulse_energy");
    for name in ["scaled.h5", "half.h5", "none.h5"] {
        std::fs::copy(&p, dir.join(name)).unwrap();
    }
    let scaled: Vec<u64> = counts
        .iter()
        .map(|&c| (c as f64 * 1.02).round() as u64)
        .collect();
    rewrite(&dir.join("scaled.h5"), "counts", &scaled);
    inconsistent(&dir, "scaled.h5");
    let half: Vec<f64> = (0..100)
        .map(|i| if i < 50 { e0[0] } else { 1.01 * e0[0] })
        .collect();
    rewrite(&dir.join("half.h5"), "pulse_energy", &half);
    let o = ok(check(&dir, "half.h5"));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("50 of 100 profiles not judged from the file alone"),
        "{out}"
    );
    rewrite(
        &dir.join("none.h5"),
        "pulse_energy",
        &vec![1.01 * e0[0]; 100],
    );
    refused(
        &dir,
        &["validate", "--file", "none.h5"],
        &["none.h5", "no profile can be judged"],
        "x",
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A scene that changes along the track with a solar background (the orbit config, 200
/// profiles): each profile against its own (profile, channel, bin) expectation.
#[test]
fn a_changing_scene_is_judged_profile_by_profile() {
    let dir = scratch("vfile-orbit");
    let c = config_path("instruments/caliop_orbit.toml");
    let args = [
        "simulate",
        c.to_str().unwrap(),
        "-o",
        "o.h5",
        "--profiles",
        "200",
        "--seed",
        "5",
    ];
    ok(lidarsim(&dir, &args, &[]));
    consistent(&dir, "o.h5");
    let counts: Vec<u64> = read(&dir.join("o.h5"), "counts");
    let scaled: Vec<u64> = counts
        .iter()
        .map(|&c| (c as f64 * 1.02).round() as u64)
        .collect();
    std::fs::copy(dir.join("o.h5"), dir.join("scaled.h5")).unwrap();
    rewrite(&dir.join("scaled.h5"), "counts", &scaled);
    inconsistent(&dir, "scaled.h5");
    std::fs::remove_dir_all(&dir).ok();
}
