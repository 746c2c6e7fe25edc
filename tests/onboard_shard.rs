//! `lidarsim onboard` in shards (docs/scale.md): product shards cut at whole frames and
//! merged are the whole run's product byte for byte, the partials of their report
//! combined are the whole run's report byte for byte, on a static and on a changing
//! scene, with leftover shots; bad merges and combines are refused naming the file.

mod common;

use std::path::Path;

use common::cli::{lidarsim, ok, refused, scratch};
use common::config_path;

/// CALIOP's window for the `caliop` scheme (40 to −2 km).
const WINDOW: [&str; 4] = [
    "--set",
    "acquisition.top_altitude_km=40",
    "--set",
    "acquisition.bottom_altitude_km=-2",
];

/// The `onboard` arguments of `cfg` with `extra`.
fn onboard_args(cfg: &str, extra: &[&str]) -> Vec<String> {
    let c = config_path(cfg);
    ["onboard", c.to_str().unwrap()]
        .iter()
        .chain(WINDOW.iter())
        .chain(extra)
        .map(|s| s.to_string())
        .collect()
}

/// `args` then `more`, as `lidarsim` takes them.
fn run_args<'a>(args: &'a [String], more: &[&'a str]) -> Vec<&'a str> {
    args.iter()
        .map(String::as_str)
        .chain(more.iter().copied())
        .collect()
}

fn run(dir: &Path, args: &[String], more: &[&str]) -> std::process::Output {
    lidarsim(dir, &run_args(args, more), &[])
}

fn read(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap()
}

/// The whole run (`whole.h5`, `whole.csv`), its `n` shards (`sK.h5`, `pK.json`), their
/// merge (`merged.h5`) and combined report (`combined.csv`), shards given in reverse
/// order; asserts both equal the whole run's byte for byte; returns the report.
fn whole_and_shards(dir: &Path, cfg: &str, extra: &[&str], n: usize) -> String {
    let args = onboard_args(cfg, extra);
    ok(run(
        dir,
        &args,
        &["-o", "whole.h5", "--report", "whole.csv"],
    ));
    for k in 0..n {
        let (shard, out, part) = (format!("{k}/{n}"), format!("s{k}.h5"), format!("p{k}.json"));
        ok(run(
            dir,
            &args,
            &["--shard", &shard, "-o", &out, "--partial", &part],
        ));
    }
    let shards: Vec<String> = (0..n).rev().map(|k| format!("s{k}.h5")).collect();
    let parts: Vec<String> = (0..n).rev().map(|k| format!("p{k}.json")).collect();
    let merge: Vec<&str> = ["merge", "merged.h5"]
        .into_iter()
        .chain(shards.iter().map(String::as_str))
        .collect();
    ok(lidarsim(dir, &merge, &[]));
    let combine: Vec<&str> = ["onboard", "--combine"]
        .into_iter()
        .chain(parts.iter().map(String::as_str))
        .chain(["--report", "combined.csv"])
        .collect();
    ok(lidarsim(dir, &combine, &[]));
    let (whole, merged) = (read(dir, "whole.h5"), read(dir, "merged.h5"));
    assert!(
        whole == merged,
        "{} and {} bytes",
        whole.len(),
        merged.len()
    );
    let report = String::from_utf8(read(dir, "whole.csv")).unwrap();
    assert_eq!(
        report,
        String::from_utf8(read(dir, "combined.csv")).unwrap()
    );
    report
}

fn group_values<T: hdf5::H5Type>(dir: &Path, file: &str, group: &str, name: &str) -> Vec<T> {
    let f = hdf5::File::open(dir.join(file)).unwrap();
    f.group(group)
        .unwrap()
        .dataset(name)
        .unwrap()
        .read_raw()
        .unwrap()
}

fn root_u64(dir: &Path, file: &str, name: &str) -> u64 {
    let f = hdf5::File::open(dir.join(file)).unwrap();
    f.attr(name).unwrap().read_scalar().unwrap()
}

/// The CALIOP scheme (15, 5, 3, 1 and 1 shots: frames of 15 shots) and `uniform:15` over
/// 90 shots in 3 shards of 2 frames; each shard a product of its own profiles at the
/// run's indices and times; the thread count does not change a shard's bytes.
#[test]
fn caliop_product_shards_merge_into_the_whole_product() {
    let dir = scratch("onboard-caliop");
    let extra = [
        "--set",
        "acquisition.profiles=6",
        "--scheme",
        "caliop",
        "--scheme",
        "uniform:15",
        "--seed",
        "4",
    ];
    let report = whole_and_shards(&dir, "instruments/caliop_532.toml", &extra, 3);
    assert_eq!(report.lines().count(), 1 + 5 + 1, "{report}");
    let attrs = [
        "shard_index",
        "shard_count",
        "shard_first_profile",
        "run_profiles",
        "frame_shots",
    ];
    let values: Vec<u64> = attrs.iter().map(|a| root_u64(&dir, "s1.h5", a)).collect();
    assert_eq!(values, [1, 3, 30, 90, 15]);
    // region 3 (one shot per profile) of shard 1: profiles 30–59 of the run
    let profile: Vec<i64> = group_values(&dir, "s1.h5", "region_3", "profile");
    assert_eq!(profile, (30..60).collect::<Vec<i64>>());
    let time: Vec<f64> = group_values(&dir, "s1.h5", "region_3", "time");
    let whole_time: Vec<f64> = group_values(&dir, "whole.h5", "region_3", "time");
    assert_eq!(time, whole_time[30..60]);
    let counts: Vec<u32> = group_values(&dir, "s1.h5", "region_0", "counts");
    let whole_counts: Vec<u32> = group_values(&dir, "whole.h5", "region_0", "counts");
    assert_eq!(counts, whole_counts[2 * 33..4 * 33]);
    // one thread, the same bytes
    let args = onboard_args("instruments/caliop_532.toml", &extra);
    let one = run_args(&args, &["--shard", "1/3", "-o", "t1.h5"]);
    ok(lidarsim(&dir, &one, &[("RAYON_NUM_THREADS", "1")]));
    assert!(read(&dir, "t1.h5") == read(&dir, "s1.h5"));
    std::fs::remove_dir_all(&dir).ok();
}

/// `uniform:3` and `uniform:7` (frames of 21 shots) over 90 shots in 4 shards: 4 whole
/// frames, the last shard with the 6 shots after them (two more profiles of
/// `uniform:3`; none of `uniform:7`, whose last 6 shots fill no profile, as in the whole
/// run).
#[test]
fn an_uneven_split_with_leftover_shots_merges_into_the_whole_product() {
    let dir = scratch("onboard-uneven");
    let extra = [
        "--set",
        "acquisition.profiles=6",
        "--scheme",
        "uniform:3",
        "--scheme",
        "uniform:7",
    ];
    let report = whole_and_shards(&dir, "instruments/caliop_532.toml", &extra, 4);
    let profiles = |f: &str| group_values::<i64>(&dir, f, "region_0", "profile");
    assert_eq!(profiles("s3.h5"), (21..30).collect::<Vec<i64>>());
    assert_eq!(profiles("whole.h5").len(), 30);
    assert_eq!(root_u64(&dir, "s3.h5", "shard_first_profile"), 63);
    assert!(report.contains("\nuniform:7,0,"), "{report}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Scenes that change along the track: broken cloud (the averaging bias, exact sums of
/// floating-point terms, not zero for `uniform:7`) over 600 shots in 4 shards (frames of
/// 105 shots, 75 left over), and the orbit of `caliop_orbit.toml` in 3 shards.
#[test]
fn a_changing_scene_merges_and_combines_into_the_whole_run() {
    let dir = scratch("onboard-scene");
    let cloud = "atmosphere.layers=[{kind=\"cloud\", base_km=1.0, top_km=1.5, \
                 extinction_per_km=10.0, lidar_ratio_sr=18.0, cloud_fraction=0.4, \
                 cell_length_km=2.0}]";
    let extra = [
        "--set",
        "acquisition.profiles=40",
        "--set",
        cloud,
        "--scheme",
        "caliop",
        "--scheme",
        "uniform:7",
    ];
    let report = whole_and_shards(&dir, "instruments/caliop_532.toml", &extra, 4);
    let bias: f64 = report
        .lines()
        .last()
        .and_then(|l| l.rsplit(',').next())
        .and_then(|b| b.parse().ok())
        .unwrap();
    assert!(bias > 0.0, "{report}");
    let orbit = ["--set", "acquisition.profiles=6", "--scheme", "caliop"];
    whole_and_shards(&dir, "instruments/caliop_orbit.toml", &orbit, 3);
    std::fs::remove_dir_all(&dir).ok();
}

/// Refused, each in one line naming the file and leaving no output: a gap, shards and
/// partials of another run, raw and product shards mixed, more shards than frames, and
/// options that need the whole run.
#[test]
fn bad_onboard_shards_are_refused() {
    let dir = scratch("onboard-refuse");
    let cfg = "instruments/caliop_532.toml";
    let args = onboard_args(
        cfg,
        &["--set", "acquisition.profiles=6", "--scheme", "uniform:15"],
    );
    for k in 0..3 {
        let (shard, out, part) = (format!("{k}/3"), format!("s{k}.h5"), format!("p{k}.json"));
        ok(run(
            &dir,
            &args,
            &["--shard", &shard, "-o", &out, "--partial", &part],
        ));
    }
    let seed = [
        "--seed",
        "5",
        "--shard",
        "1/3",
        "-o",
        "x1.h5",
        "--partial",
        "x1.json",
    ];
    ok(run(&dir, &args, &seed));
    let c = config_path("paper/scenario1.toml");
    let raw = [
        "simulate",
        c.to_str().unwrap(),
        "--profiles",
        "4",
        "--shard",
        "0/2",
        "-o",
        "r0.h5",
    ];
    ok(lidarsim(&dir, &raw, &[]));
    fn merge<'a>(files: &[&'a str]) -> Vec<&'a str> {
        [&["merge", "m.h5"][..], files].concat()
    }
    refused(
        &dir,
        &merge(&["s0.h5", "s2.h5"]),
        &["gap", "shard 1/3", "shots 30–59"],
        "m.h5",
    );
    refused(
        &dir,
        &merge(&["s0.h5", "x1.h5", "s2.h5"]),
        &["x1.h5", "another run", "seed"],
        "m.h5",
    );
    refused(
        &dir,
        &merge(&["s0.h5", "r0.h5"]),
        &["r0.h5", "raw shard", "s0.h5", "product shard"],
        "m.h5",
    );
    refused(
        &dir,
        &merge(&["r0.h5", "s0.h5"]),
        &["s0.h5", "product shard", "apart"],
        "m.h5",
    );
    fn combine<'a>(files: &[&'a str]) -> Vec<&'a str> {
        [&["onboard", "--combine"][..], files, &["--report", "r.csv"]].concat()
    }
    refused(
        &dir,
        &combine(&["p0.json", "p2.json"]),
        &["gap", "shard 1/3"],
        "r.csv",
    );
    refused(
        &dir,
        &combine(&["p0.json", "x1.json", "p2.json"]),
        &["x1.json", "another run"],
        "r.csv",
    );
    refused(
        &dir,
        &combine(&["p0.json", "p1.json", "p2.json", "p1.json"]),
        &["p1.json: given twice"],
        "r.csv",
    );
    refused(
        &dir,
        &run_args(&args, &["--shard", "0/7", "-o", "q.h5"]),
        &["7 shards of 6 frames of 15 shots"],
        "q.h5",
    );
    refused(
        &dir,
        &run_args(
            &args,
            &["--shard", "0/3", "-o", "q.h5", "--report", "q.csv"],
        ),
        &["--report", "--partial"],
        "q.h5",
    );
    refused(
        &dir,
        &run_args(&args, &["--shard", "0/3", "-o", "q.h5", "--raw", "q.raw"]),
        &["--raw", "--shard"],
        "q.h5",
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// 10,500 shots: the 1-shot regions have 10,500 profiles, so their per-profile truth is
/// written in three blocks (chunks) of 4,096 rows; the merge writes them at the same
/// rows in the same order, byte for byte.
#[test]
fn a_long_product_merges_across_its_truth_blocks() {
    let dir = scratch("onboard-long");
    let extra = ["--set", "acquisition.profiles=700", "--scheme", "caliop"];
    whole_and_shards(&dir, "instruments/caliop_532.toml", &extra, 3);
    let rows = group_values::<i32>(&dir, "whole.h5", "region_3", "profile_column");
    assert_eq!(rows.len(), 10_500);
    std::fs::remove_dir_all(&dir).ok();
}

/// Copies product shard `from` to `to` and rewrites one value of `region_0/name` (its
/// first profile row, first slot) to `value`.
fn edit_shard<T: hdf5::H5Type + Copy>(dir: &Path, from: &str, to: &str, name: &str, value: T) {
    std::fs::copy(dir.join(from), dir.join(to)).unwrap();
    let f = hdf5::File::open_rw(dir.join(to)).unwrap();
    let d = f.dataset(&format!("region_0/{name}")).unwrap();
    let mut v: ndarray::Array2<T> = d.read().unwrap();
    v[[0, 0]] = value;
    d.write(&v).unwrap();
    f.close().unwrap();
}

/// A product shard whose profile columns are impossible (a weight of 0.7 alone, a column
/// the scene does not have), that lacks a truth variable or that records another command
/// line is refused, naming it.
#[test]
fn product_shards_with_impossible_truth_are_refused() {
    let dir = scratch("onboard-refuse-truth");
    let args = onboard_args(
        "instruments/caliop_532.toml",
        &["--set", "acquisition.profiles=6", "--scheme", "uniform:15"],
    );
    for k in 0..3 {
        let (shard, out) = (format!("{k}/3"), format!("s{k}.h5"));
        ok(run(&dir, &args, &["--shard", &shard, "-o", &out]));
    }
    // the same run (same config, seed, schemes) asked for in other words
    let again = [
        "--set",
        "acquisition.profiles=6",
        "--shard",
        "1/3",
        "-o",
        "c1.h5",
    ];
    ok(run(&dir, &args, &again));
    edit_shard(&dir, "s1.h5", "w1.h5", "profile_column_weight", 0.7f64);
    edit_shard(&dir, "s1.h5", "k1.h5", "profile_column", 5i32);
    let merge = |middle: &'static str| ["merge", "m.h5", "s0.h5", middle, "s2.h5"];
    refused(
        &dir,
        &merge("w1.h5"),
        &["w1.h5", "region_0", "profile row 0", "sum to 0.7"],
        "m.h5",
    );
    refused(
        &dir,
        &merge("k1.h5"),
        &["k1.h5", "region_0", "column 5 is not one of the 1 columns"],
        "m.h5",
    );
    refused(
        &dir,
        &merge("c1.h5"),
        &["c1.h5", "history", "one command line"],
        "m.h5",
    );
    std::fs::copy(dir.join("s1.h5"), dir.join("t1.h5")).unwrap();
    let f = hdf5::File::open_rw(dir.join("t1.h5")).unwrap();
    f.unlink("region_0/t2").unwrap();
    f.close().unwrap();
    refused(
        &dir,
        &merge("t1.h5"),
        &["t1.h5", "region_0/t2", "not a product of this version"],
        "m.h5",
    );
    ok(lidarsim(&dir, &merge("s1.h5"), &[]));
    std::fs::remove_dir_all(&dir).ok();
}
