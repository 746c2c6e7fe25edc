//! Shards and scale-out (docs/scale.md): shards
//! merged are the whole run byte for byte, any split gives the whole run's counts, bad
//! merges are refused naming the file, and `validate --combine` over shards prints the
//! single run's verdict.

mod common;

use std::path::Path;
use std::process::Output;

use common::cli::{lidarsim, ok, refused, scratch};
use common::config_path;

/// Runs `simulate CONFIG -o OUT EXTRA...` in `dir`.
fn simulate(dir: &Path, cfg: &str, out: &str, extra: &[&str]) -> Output {
    let c = config_path(cfg);
    let mut args = vec!["simulate", c.to_str().unwrap(), "-o", out];
    args.extend_from_slice(extra);
    lidarsim(dir, &args, &[])
}

/// The whole run, its N shards and their merge (shards given in reverse order); returns
/// the whole run's and the merged file's bytes.
fn whole_and_merged(dir: &Path, cfg: &str, extra: &[&str], n: usize) -> (Vec<u8>, Vec<u8>) {
    ok(simulate(dir, cfg, "whole.h5", extra));
    let mut shards = vec![];
    for k in 0..n {
        let name = format!("s{k}.h5");
        let shard = format!("{k}/{n}");
        let mut args = extra.to_vec();
        args.extend_from_slice(&["--shard", &shard]);
        ok(simulate(dir, cfg, &name, &args));
        shards.push(name);
    }
    let mut args = vec!["merge", "merged.h5"];
    args.extend(shards.iter().rev().map(String::as_str));
    ok(lidarsim(dir, &args, &[]));
    (
        std::fs::read(dir.join("whole.h5")).unwrap(),
        std::fs::read(dir.join("merged.h5")).unwrap(),
    )
}

fn read_u64(path: &Path, name: &str) -> Vec<u64> {
    let f = hdf5::File::open(path).unwrap();
    f.dataset(name).unwrap().read_raw::<u64>().unwrap()
}

fn read_f64(path: &Path, name: &str) -> Vec<f64> {
    let f = hdf5::File::open(path).unwrap();
    f.dataset(name).unwrap().read_raw::<f64>().unwrap()
}

#[test]
fn three_shards_merged_are_the_whole_run_byte_for_byte() {
    let dir = scratch("bytes");
    let (whole, merged) = whole_and_merged(&dir, "paper/scenario1.toml", &["--profiles", "10"], 3);
    assert!(
        whole == merged,
        "{} and {} bytes",
        whole.len(),
        merged.len()
    );
    // each shard is a raw file of its own profiles, at the run's indices and times
    let s1 = dir.join("s1.h5");
    let profile: Vec<i64> = hdf5::File::open(&s1)
        .unwrap()
        .dataset("profile")
        .unwrap()
        .read_raw()
        .unwrap();
    assert_eq!(profile, vec![3, 4, 5]);
    assert_eq!(
        read_f64(&s1, "time"),
        read_f64(&dir.join("whole.h5"), "time")[3..6]
    );
    let counts = read_u64(&dir.join("whole.h5"), "counts");
    let per_profile = counts.len() / 10;
    assert_eq!(
        read_u64(&s1, "counts"),
        counts[3 * per_profile..6 * per_profile]
    );
    let f = hdf5::File::open(&s1).unwrap();
    let attr = |n: &str| f.attr(n).unwrap().read_scalar::<u64>().unwrap();
    assert_eq!(
        [
            attr("shard_index"),
            attr("shard_count"),
            attr("run_profiles")
        ],
        [1, 3, 10]
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_scene_along_the_orbit_merges_byte_for_byte() {
    let dir = scratch("orbit");
    let (whole, merged) = whole_and_merged(
        &dir,
        "instruments/caliop_orbit.toml",
        &["--profiles", "12"],
        3,
    );
    assert!(
        whole == merged,
        "{} and {} bytes",
        whole.len(),
        merged.len()
    );
    let lat = read_f64(&dir.join("s2.h5"), "latitude");
    assert_eq!(lat, read_f64(&dir.join("whole.h5"), "latitude")[8..12]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_model_field_scene_merges_byte_for_byte_across_its_column_batches() {
    // 130 profiles: three batches of the run's 64, the shards cut inside them; each
    // shard builds only the columns its profiles see, the merge builds them again at the
    // run's own points (a change of either order or of the batches changes the bytes)
    let dir = scratch("fields");
    let cfg = "instruments/caliop_fields.toml";
    let extra = [
        "--profiles",
        "130",
        "--method",
        "shot",
        "--set",
        "acquisition.top_altitude_km=12",
    ];
    let (whole, merged) = whole_and_merged(&dir, cfg, &extra, 3);
    assert!(
        whole == merged,
        "{} and {} bytes",
        whole.len(),
        merged.len()
    );
    // a shard's file holds NaN for the columns its profiles do not see, and the truth
    // of those they see
    let (w, s) = (dir.join("whole.h5"), dir.join("s0.h5"));
    let (t2_whole, t2_shard) = (read_f64(&w, "t2"), read_f64(&s, "t2"));
    assert_eq!(t2_whole.len(), t2_shard.len());
    assert!(t2_shard.iter().any(|x| x.is_nan()) && t2_whole.iter().all(|x| x.is_finite()));
    let seen = t2_shard.iter().zip(&t2_whole).filter(|(a, _)| !a.is_nan());
    assert!(seen.clone().count() > 0 && seen.clone().all(|(a, b)| a == b));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn any_split_gives_the_whole_runs_counts() {
    // 4 shards of 10 profiles (2, 3, 2, 3), drawn shot by shot with component counts
    let dir = scratch("split");
    let extra = ["--profiles", "10", "--method", "shot", "--components"];
    let (whole, merged) = whole_and_merged(&dir, "paper/scenario2.toml", &extra, 4);
    assert!(whole == merged);
    let rows: Vec<usize> = (0..4)
        .map(|k| read_u64(&dir.join(format!("s{k}.h5")), "n_shots").len())
        .collect();
    assert_eq!(rows, vec![2, 3, 2, 3]);
    let mut joined = vec![];
    for k in 0..4 {
        joined.extend(read_u64(&dir.join(format!("s{k}.h5")), "signal_counts"));
    }
    assert_eq!(joined, read_u64(&dir.join("whole.h5"), "signal_counts"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_output_name_and_thread_count_do_not_change_the_bytes() {
    let dir = scratch("history");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    ok(simulate(
        &dir,
        "paper/scenario1.toml",
        "a.h5",
        &["--profiles", "3"],
    ));
    let threads = ["--profiles", "3", "--threads", "1"];
    ok(simulate(&dir, "paper/scenario1.toml", "sub/b.nc", &threads));
    assert!(
        std::fs::read(dir.join("a.h5")).unwrap() == std::fs::read(dir.join("sub/b.nc")).unwrap()
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn shard_auto_reads_slurm_and_kubernetes_indices() {
    let dir = scratch("auto");
    let c = config_path("paper/scenario1.toml");
    let run = |out: &str, env: &[(&str, &str)]| {
        let args = [
            "simulate",
            c.to_str().unwrap(),
            "--profiles",
            "9",
            "--shard",
            "auto",
            "-o",
            out,
        ];
        lidarsim(&dir, &args, env)
    };
    ok(simulate(
        &dir,
        "paper/scenario1.toml",
        "fixed.h5",
        &["--profiles", "9", "--shard", "1/3"],
    ));
    // an array submitted as --array=1-3: task 2 is shard 1
    let slurm = [
        ("SLURM_ARRAY_TASK_ID", "2"),
        ("SLURM_ARRAY_TASK_COUNT", "3"),
        ("SLURM_ARRAY_TASK_MIN", "1"),
    ];
    ok(run("slurm.h5", &slurm));
    ok(run(
        "k8s.h5",
        &[("JOB_COMPLETION_INDEX", "1"), ("LIDARSIM_SHARD_COUNT", "3")],
    ));
    let fixed = std::fs::read(dir.join("fixed.h5")).unwrap();
    assert!(fixed == std::fs::read(dir.join("slurm.h5")).unwrap());
    assert!(fixed == std::fs::read(dir.join("k8s.h5")).unwrap());
    let none = run("none.h5", &[]);
    assert_eq!(none.status.code(), Some(2));
    let err = String::from_utf8_lossy(&none.stderr);
    assert!(
        err.contains("SLURM_ARRAY_TASK_ID") && err.contains("JOB_COMPLETION_INDEX"),
        "{err}"
    );
    assert!(!dir.join("none.h5").exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn merge_refuses_other_runs_gaps_overlaps_and_strangers() {
    let dir = scratch("refuse");
    let p = ["--profiles", "6"];
    for k in 0..3 {
        let shard = format!("{k}/3");
        ok(simulate(
            &dir,
            "paper/scenario1.toml",
            &format!("s{k}.h5"),
            &[&p[..], &["--shard", &shard]].concat(),
        ));
    }
    ok(simulate(
        &dir,
        "paper/scenario1.toml",
        "seed.h5",
        &["--profiles", "6", "--shard", "1/3", "--seed", "5"],
    ));
    ok(simulate(
        &dir,
        "paper/scenario1.toml",
        "n4.h5",
        &["--profiles", "6", "--shard", "1/4"],
    ));
    ok(simulate(&dir, "paper/scenario1.toml", "whole.h5", &p));
    fn m<'a>(shards: &[&'a str]) -> Vec<&'a str> {
        [&["merge", "m.h5"][..], shards].concat()
    }
    refused(
        &dir,
        &m(&["s0.h5", "seed.h5", "s2.h5"]),
        &["seed.h5", "another run", "seed"],
        "m.h5",
    );
    refused(
        &dir,
        &m(&["s0.h5", "n4.h5"]),
        &["n4.h5", "another run", "shard count"],
        "m.h5",
    );
    refused(
        &dir,
        &m(&["s0.h5", "s2.h5"]),
        &["gap", "shard 1/3", "profiles 2–3"],
        "m.h5",
    );
    std::fs::copy(dir.join("s1.h5"), dir.join("t1.h5")).unwrap();
    refused(
        &dir,
        &m(&["s0.h5", "s1.h5", "s2.h5", "t1.h5"]),
        &["t1.h5: overlaps s1.h5", "shard 1/3"],
        "m.h5",
    );
    refused(
        &dir,
        &m(&["s0.h5", "s1.h5", "s2.h5", "s1.h5"]),
        &["s1.h5: given twice"],
        "m.h5",
    );
    refused(
        &dir,
        &m(&["s0.h5", "whole.h5"]),
        &["whole.h5", "not a shard"],
        "m.h5",
    );
    let cfg = config_path("paper/scenario1.toml");
    refused(
        &dir,
        &m(&["s0.h5", cfg.to_str().unwrap()]),
        &["not a lidarsim raw file"],
        "m.h5",
    );
    refused(
        &dir,
        &["merge", "s1.h5", "s0.h5", "s1.h5", "s2.h5"],
        &["s1.h5", "input"],
        "m.h5",
    );
    let c = cfg.to_str().unwrap();
    refused(
        &dir,
        &["simulate", c, "-o", "q.h5", "--shard", "3/3"],
        &["--shard", "0 to N-1"],
        "q.h5",
    );
    refused(
        &dir,
        &[
            "simulate",
            c,
            "-o",
            "q.h5",
            "--profiles",
            "3",
            "--shard",
            "0/4",
        ],
        &["4 shards of 3 profiles"],
        "q.h5",
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn merge_refuses_a_run_it_would_rebuild_differently() {
    // the config names a molecular profile file, changed between the shards and the merge
    let dir = scratch("rebuild");
    std::fs::create_dir_all(dir.join("cfg")).unwrap();
    std::fs::create_dir_all(dir.join("atmospheres")).unwrap();
    std::fs::copy(
        config_path("ground/profile_file_example.toml"),
        dir.join("cfg/run.toml"),
    )
    .unwrap();
    let profile = dir.join("atmospheres/us76_1km.txt");
    std::fs::copy(config_path("atmospheres/us76_1km.txt"), &profile).unwrap();
    for k in 0..2 {
        let (shard, out) = (format!("{k}/2"), format!("s{k}.h5"));
        let args = [
            "simulate",
            "cfg/run.toml",
            "--profiles",
            "4",
            "--shard",
            &shard,
            "-o",
            &out,
        ];
        ok(lidarsim(&dir, &args, &[]));
    }
    ok(lidarsim(&dir, &["merge", "same.h5", "s0.h5", "s1.h5"], &[]));
    // the same file with the pressure of its first row 1 % higher
    let text = std::fs::read_to_string(&profile).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let row = lines
        .iter()
        .position(|l| {
            l.split_whitespace()
                .next()
                .is_some_and(|x| x.parse::<f64>().is_ok())
        })
        .unwrap();
    lines[row] = lines[row]
        .split_whitespace()
        .enumerate()
        .map(|(i, x)| match (i, x.parse::<f64>()) {
            (1, Ok(v)) => format!("{:e}", v * 1.01),
            _ => x.to_string(),
        })
        .collect::<Vec<_>>()
        .join(" ");
    std::fs::write(&profile, lines.join("\n") + "\n").unwrap();
    refused(
        &dir,
        &["merge", "m.h5", "s0.h5", "s1.h5"],
        &["s0.h5", "cannot rebuild its run"],
        "m.h5",
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `validate` on `cfg`: whole, then 4 shards combined; both outputs (stdout, exit code).
fn validate_whole_and_combined(
    dir: &Path,
    cfg: &str,
    extra: &[&str],
) -> [(String, Option<i32>); 2] {
    let c = config_path(cfg);
    let base = [&["validate", c.to_str().unwrap()][..], extra].concat();
    let single = lidarsim(dir, &base, &[]);
    let mut parts = vec![];
    for k in 0..4 {
        let (shard, part) = (format!("{k}/4"), format!("p{k}.json"));
        ok(lidarsim(
            dir,
            &[&base[..], &["--shard", &shard, "--partial", &part]].concat(),
            &[],
        ));
        parts.push(part);
    }
    let mut args = vec!["validate", "--combine"];
    args.extend(parts.iter().rev().map(String::as_str));
    let combined = lidarsim(dir, &args, &[]);
    [single, combined].map(|o| {
        (
            String::from_utf8_lossy(&o.stdout).into_owned(),
            o.status.code(),
        )
    })
}

#[test]
fn validate_combine_over_four_shards_prints_the_single_runs_verdict() {
    let dir = scratch("validate");
    let extra = ["--realizations", "300", "--seed", "11", "--method", "shot"];
    let [single, combined] = validate_whole_and_combined(&dir, "paper/scenario2.toml", &extra);
    assert_eq!(single.1, Some(0), "{}", single.0);
    assert!(single.0.contains("CONSISTENT") && single.0.contains("seed 11"));
    assert_eq!(single, combined);
    // a scene that changes along the track: its exact float sums too
    let extra = ["--realizations", "100"];
    let [single, combined] =
        validate_whole_and_combined(&dir, "instruments/caliop_orbit.toml", &extra);
    assert!(single.0.contains("100 realizations"), "{}", single.0);
    assert_eq!(single, combined);
    // partials of another seed and a gap are refused
    let c = config_path("paper/scenario2.toml");
    let other = [
        "validate",
        c.to_str().unwrap(),
        "--realizations",
        "300",
        "--seed",
        "12",
        "--method",
        "shot",
    ];
    ok(lidarsim(
        &dir,
        &[&other[..], &["--shard", "1/4", "--partial", "x1.json"]].concat(),
        &[],
    ));
    for k in 0..4 {
        let _ = std::fs::remove_file(dir.join(format!("p{k}.json")));
    }
    let extra = ["--realizations", "300", "--seed", "11", "--method", "shot"];
    let base = [&["validate", c.to_str().unwrap()][..], &extra[..]].concat();
    for k in [0, 2] {
        let (shard, part) = (format!("{k}/4"), format!("p{k}.json"));
        ok(lidarsim(
            &dir,
            &[&base[..], &["--shard", &shard, "--partial", &part]].concat(),
            &[],
        ));
    }
    refused(
        &dir,
        &["validate", "--combine", "p0.json", "x1.json"],
        &["x1.json", "another run"],
        "none",
    );
    refused(
        &dir,
        &["validate", "--combine", "p0.json", "p2.json"],
        &["gap", "shard 1/4", "shard 3/4"],
        "none",
    );
    std::fs::remove_dir_all(&dir).ok();
}
