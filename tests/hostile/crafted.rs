//! Crafted and inconsistent files refused before work (issue 18, item 2; item 7's
//! unevenly spaced curtain altitudes and impossible partial sums).
//!
//! Each case's file is made in its scratch directory by the binary under test
//! (`simulate`, `onboard`, `validate --shard`, a few profiles) or copied from the
//! repository, then edited here with the `hdf5` crate (or `serde_json`): one dataset,
//! attribute or field made inconsistent, as a crafted or damaged file would be.

use std::fs;
use std::process::{Command, Stdio};

use super::{Case, Scratch, Want, args, bin, cfg, s1};

/// This topic's cases, run after the older ones.
pub fn cases() -> Vec<Case> {
    use Want::Refused;
    let c = |name, want, run| Case {
        name,
        want,
        env: vec![],
        run,
    };
    let curtain = || args(&["curtain", "@D/in/raw.h5", "--png", "@D/out.png"]);
    let scc = || args(&["export-scc", "@D/in/raw.h5", "@D/out.nc"]);
    let merge = || args(&["merge", "@D/out.h5", "@D/in/shard.h5"]);
    let scene = || args(&["simulate", "@IN", "-o", "@D/out.h5", "--profiles", "2"]);
    let combine = || args(&["validate", "--combine", "@D/in/part.json"]);
    let onboard_combine = || args(&["onboard", "--combine", "@D/in/part.json"]);
    vec![
        // --- raw files read by `curtain` ---
        c(
            "curtain: fewer counts rows than profiles",
            Refused("counts"),
            curtain(),
        ),
        c(
            "curtain: NaN in time",
            Refused("`time` value 1 is NaN"),
            curtain(),
        ),
        c(
            "curtain: inf in time",
            Refused("`time` value 2 is inf"),
            curtain(),
        ),
        c(
            "curtain: NaN in altitude",
            Refused("`altitude` value 7 is NaN"),
            curtain(),
        ),
        c(
            "curtain: inf in along_track_distance",
            Refused("`along_track_distance` value 1 is inf"),
            curtain(),
        ),
        c(
            "curtain: n_shots 0",
            Refused("`n_shots` value 0 is 0"),
            curtain(),
        ),
        c(
            "curtain: altitude of the wrong length",
            Refused("`altitude` is 100"),
            curtain(),
        ),
        c(
            "curtain: format version 6",
            Refused("format version 6"),
            curtain(),
        ),
        c(
            "curtain: float counts",
            Refused("`counts` holds floating-point"),
            curtain(),
        ),
        c(
            "curtain: 1e12 profiles declared",
            Refused("crafted"),
            curtain(),
        ),
        c(
            "curtain: time spanning -1e308 to 1e308",
            Refused("`time` spans -1e308 to 1e308"),
            curtain(),
        ),
        // --- raw files read by `export-scc` ---
        c(
            "export-scc: n_shots 0",
            Refused("`n_shots` value 1 is 0"),
            scc(),
        ),
        c(
            "export-scc: NaN in range",
            Refused("`range` value 5 is NaN"),
            scc(),
        ),
        c(
            "export-scc: 1e12 profiles declared",
            Refused("crafted"),
            scc(),
        ),
        // --- shards read by `merge` ---
        c(
            "merge: raw shard of format version 6",
            Refused("format version 6"),
            merge(),
        ),
        c(
            "merge: raw shard with NaN time",
            Refused("`time` value 0 is NaN"),
            merge(),
        ),
        c(
            "merge: raw shard with n_shots 0",
            Refused("`n_shots` value 2 is 0"),
            merge(),
        ),
        c(
            "merge: product shard with NaN altitude",
            Refused("`region_0/altitude` value 3 is NaN"),
            merge(),
        ),
        c(
            "merge: product shard with too few times",
            Refused("`time` is 2"),
            merge(),
        ),
        c(
            "merge: product shard with 1e12 profiles declared",
            Refused("crafted"),
            merge(),
        ),
        // --- [scene] curtain files ---
        c(
            "scene curtain: unevenly spaced altitudes",
            Refused("`altitude_km` is not evenly spaced"),
            scene(),
        ),
        c(
            "scene curtain: NaN in altitude_km",
            Refused("altitude_km"),
            scene(),
        ),
        c(
            "scene curtain: extinction of the wrong shape",
            Refused("`extinction_aerosol` is 40 × 29"),
            scene(),
        ),
        c(
            "scene curtain: 1e12 columns declared",
            Refused("cells"),
            scene(),
        ),
        // --- partials of `validate --combine` and `onboard --combine` ---
        c(
            "validate --combine: negative variance",
            Refused("`sums.bins[300]`: `total` 1000 and `squares` 1000"),
            combine(),
        ),
        c(
            "validate --combine: squares below total",
            Refused("`sums.bins[7]`: `squares` 5 is less"),
            combine(),
        ),
        c(
            "validate --combine: 1e15 realizations",
            Refused("realizations"),
            combine(),
        ),
        c(
            "onboard --combine: squares below counts",
            Refused("`sums[0].regions[0][1]`: `squares` 0"),
            onboard_combine(),
        ),
        c(
            "onboard --combine: NaN bias",
            Refused("`bias` is not finite"),
            onboard_combine(),
        ),
    ]
}

/// Runs the binary with `argv` in `dir` (output discarded); whether it succeeded.
fn run(dir: &Scratch, argv: &[&str]) -> bool {
    Command::new(bin())
        .args(argv)
        .current_dir(&dir.0)
        .env_remove("SOURCE_DATE_EPOCH")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// A raw file of 3 profiles of `config` at `in/NAME`, with `extra` arguments.
fn raw(dir: &Scratch, config: &str, name: &str, extra: &[&str]) -> bool {
    let out = dir.p(&format!("in/{name}"));
    let mut argv = vec!["simulate", config, "-o", &out, "--profiles", "3"];
    argv.extend(extra);
    run(dir, &argv)
}

/// Opens `in/NAME` of `dir` for writing.
fn open(dir: &Scratch, name: &str) -> hdf5::File {
    hdf5::File::open_rw(dir.0.join("in").join(name)).expect("open the file to craft")
}

/// Replaces 1-D f64 dataset `name` of `g` by `values`.
fn replace_f64(g: &hdf5::Group, name: &str, values: &[f64]) {
    let _ = g.unlink(name);
    g.new_dataset::<f64>()
        .shape(values.len())
        .create(name)
        .unwrap()
        .write_raw(values)
        .unwrap();
}

/// Sets value `i` of 1-D f64 dataset `name` of `g` to `x`.
fn set_f64(g: &hdf5::Group, name: &str, i: usize, x: f64) {
    let mut v: Vec<f64> = g.dataset(name).unwrap().read_raw().unwrap();
    v[i] = x;
    g.dataset(name).unwrap().write_raw(&v).unwrap();
}

/// Sets value `i` of the unsigned 1-D dataset `name` of `g` to 0.
fn zero_u64(g: &hdf5::Group, name: &str, i: usize) {
    let mut v: Vec<u64> = g.dataset(name).unwrap().read_raw().unwrap();
    v[i] = 0;
    g.dataset(name).unwrap().write_raw(&v).unwrap();
}

/// Declares `profiles` rows of every per-profile variable of raw file `f` (chunked,
/// never written: the file stays small).
fn declare_profiles(f: &hdf5::File, profiles: usize) {
    let counts = f.dataset("counts").unwrap().shape();
    for name in ["counts", "time", "n_shots", "pulse_energy", "profile"] {
        let _ = f.unlink(name);
    }
    f.new_dataset::<u16>()
        .chunk([1, counts[1], counts[2]])
        .shape([profiles, counts[1], counts[2]])
        .create("counts")
        .unwrap();
    for name in ["time", "pulse_energy"] {
        f.new_dataset::<f64>()
            .chunk(1024)
            .shape(profiles)
            .create(name)
            .unwrap();
    }
    f.new_dataset::<u64>()
        .chunk(1024)
        .shape(profiles)
        .create("n_shots")
        .unwrap();
}

/// Edits field `path` (JSON pointer) of the partial `in/part.json` to `value`.
fn edit_partial(dir: &Scratch, pointer: &str, value: serde_json::Value) {
    let file = dir.0.join("in/part.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&file).unwrap()).unwrap();
    *v.pointer_mut(pointer)
        .unwrap_or_else(|| panic!("no {pointer} in the partial")) = value;
    fs::write(&file, serde_json::to_string(&v).unwrap()).unwrap();
}

/// The example curtain copied to `in/curtain.h5` and a copy of the CALIOP curtain config
/// reading it as `in/cfg.toml`.
fn scene_curtain(dir: &Scratch) -> hdf5::File {
    fs::copy(
        cfg("atmospheres/curtain_example.h5"),
        dir.0.join("in/curtain.h5"),
    )
    .unwrap();
    let text = fs::read_to_string(cfg("instruments/caliop_curtain.toml")).unwrap();
    let text = text.replace("../atmospheres/curtain_example.h5", "curtain.h5");
    assert!(text.contains("\"curtain.h5\""));
    fs::write(dir.0.join("in/cfg.toml"), text).unwrap();
    open(dir, "curtain.h5")
}

/// CALIOP's onboard window and a 6-profile run of the `caliop` scheme, one shard.
fn product_shard(dir: &Scratch, partial: bool) -> bool {
    let c = cfg("instruments/caliop_532.toml");
    let (out, part) = (dir.p("in/shard.h5"), dir.p("in/part.json"));
    let mut argv = vec![
        "onboard",
        &c,
        "--set",
        "acquisition.top_altitude_km=40",
        "--set",
        "acquisition.bottom_altitude_km=-2",
        "--set",
        "acquisition.profiles=6",
        "--scheme",
        "caliop",
        "--shard",
        "0/1",
        "-o",
        &out,
    ];
    if partial {
        argv.extend(["--partial", &part]);
    }
    let ok = run(dir, &argv);
    if partial {
        let _ = fs::remove_file(&out);
    }
    ok
}

/// Prepares the scratch directory of one of this topic's cases: `None` when the case
/// is not this topic's, `Some(false)` when its preparation is not possible here.
pub fn prepare(name: &str, dir: &Scratch) -> Option<bool> {
    let s1 = s1();
    let ground = cfg("ground/ground_532_overlap.toml");
    let made = match name {
        n if n.starts_with("curtain: ") => raw(dir, &s1, "raw.h5", &[]),
        n if n.starts_with("export-scc: ") => raw(dir, &ground, "raw.h5", &[]),
        n if n.starts_with("merge: raw shard") => raw(dir, &s1, "shard.h5", &["--shard", "0/1"]),
        n if n.starts_with("merge: product shard") => product_shard(dir, false),
        n if n.starts_with("validate --combine") => run(
            dir,
            &[
                "validate",
                &s1,
                "--realizations",
                "100",
                "--shard",
                "0/1",
                "--partial",
                &dir.p("in/part.json"),
            ],
        ),
        n if n.starts_with("onboard --combine") => product_shard(dir, true),
        n if n.starts_with("scene curtain: ") => true,
        _ => return None,
    };
    if !made {
        return Some(false);
    }
    match name {
        "curtain: fewer counts rows than profiles" => {
            let f = open(dir, "raw.h5");
            let _ = f.unlink("counts");
            f.new_dataset::<u32>()
                .shape([2, 1, 334])
                .create("counts")
                .unwrap()
                .write_raw(&vec![1u32; 2 * 334])
                .unwrap();
        }
        "curtain: NaN in time" => set_f64(&open(dir, "raw.h5"), "time", 1, f64::NAN),
        "curtain: inf in time" => set_f64(&open(dir, "raw.h5"), "time", 2, f64::INFINITY),
        "curtain: NaN in altitude" => set_f64(&open(dir, "raw.h5"), "altitude", 7, f64::NAN),
        "curtain: inf in along_track_distance" => replace_f64(
            &open(dir, "raw.h5"),
            "along_track_distance",
            &[0.0, f64::INFINITY, 2e4],
        ),
        "curtain: n_shots 0" => zero_u64(&open(dir, "raw.h5"), "n_shots", 0),
        "curtain: altitude of the wrong length" => {
            replace_f64(&open(dir, "raw.h5"), "altitude", &[1.0; 100])
        }
        "curtain: format version 6" | "merge: raw shard of format version 6" => {
            let file = if name.starts_with("merge") {
                "shard.h5"
            } else {
                "raw.h5"
            };
            open(dir, file)
                .attr("lidarsim_format_version")
                .unwrap()
                .write_scalar(&6i32)
                .unwrap();
        }
        "curtain: float counts" => {
            let f = open(dir, "raw.h5");
            let counts: Vec<u32> = f.dataset("counts").unwrap().read_raw().unwrap();
            let floats: Vec<f64> = counts.iter().map(|&c| f64::from(c) + 0.5).collect();
            let _ = f.unlink("counts");
            f.new_dataset::<f64>()
                .shape([3, 1, 334])
                .create("counts")
                .unwrap()
                .write_raw(&floats)
                .unwrap();
        }
        "curtain: 1e12 profiles declared" | "export-scc: 1e12 profiles declared" => {
            declare_profiles(&open(dir, "raw.h5"), 1_000_000_000_000)
        }
        "curtain: time spanning -1e308 to 1e308" => {
            let f = open(dir, "raw.h5");
            set_f64(&f, "time", 0, -1e308);
            set_f64(&f, "time", 2, 1e308);
        }
        "export-scc: n_shots 0" => zero_u64(&open(dir, "raw.h5"), "n_shots", 1),
        "export-scc: NaN in range" => set_f64(&open(dir, "raw.h5"), "range", 5, f64::NAN),
        "merge: raw shard with NaN time" => set_f64(&open(dir, "shard.h5"), "time", 0, f64::NAN),
        "merge: raw shard with n_shots 0" => zero_u64(&open(dir, "shard.h5"), "n_shots", 2),
        "merge: product shard with NaN altitude" => {
            let g = open(dir, "shard.h5").group("region_0").unwrap();
            set_f64(&g, "altitude", 3, f64::NAN);
        }
        "merge: product shard with too few times" => {
            let g = open(dir, "shard.h5").group("region_1").unwrap();
            replace_f64(&g, "time", &[0.1, 0.2]);
        }
        "merge: product shard with 1e12 profiles declared" => {
            let g = open(dir, "shard.h5").group("region_0").unwrap();
            let shape = g.dataset("counts").unwrap().shape();
            let p = 1_000_000_000_000usize;
            for n in ["counts", "time", "n_shots", "profile"] {
                let _ = g.unlink(n);
            }
            g.new_dataset::<u32>()
                .chunk([1, shape[1], shape[2]])
                .shape([p, shape[1], shape[2]])
                .create("counts")
                .unwrap();
            g.new_dataset::<f64>()
                .chunk(1024)
                .shape(p)
                .create("time")
                .unwrap();
            g.new_dataset::<u32>()
                .chunk(1024)
                .shape(p)
                .create("n_shots")
                .unwrap();
        }
        "scene curtain: unevenly spaced altitudes" => {
            // 0.25, 0.75, ... with one centre moved by 10 % of the spacing
            set_f64(&scene_curtain(dir), "altitude_km", 10, 5.3)
        }
        "scene curtain: NaN in altitude_km" => {
            set_f64(&scene_curtain(dir), "altitude_km", 4, f64::NAN)
        }
        "scene curtain: extinction of the wrong shape" => {
            let f = scene_curtain(dir);
            let _ = f.unlink("extinction_aerosol");
            f.new_dataset::<f64>()
                .shape([40, 29])
                .create("extinction_aerosol")
                .unwrap()
                .write_raw(&vec![0.01; 40 * 29])
                .unwrap();
        }
        "scene curtain: 1e12 columns declared" => {
            let f = scene_curtain(dir);
            let _ = f.unlink("along_track_km");
            f.new_dataset::<f64>()
                .chunk(1024)
                .shape(1_000_000_000_000usize)
                .create("along_track_km")
                .unwrap();
        }
        "validate --combine: negative variance" => {
            // 100 counts summing to 1000 with squares summing to 1000: (Σc)² > n·Σc²
            edit_partial(dir, "/sums/bins/300/total", serde_json::json!("1000"));
            edit_partial(dir, "/sums/bins/300/squares", serde_json::json!("1000"));
        }
        "validate --combine: squares below total" => {
            edit_partial(dir, "/sums/bins/7/squares", serde_json::json!("5"));
            edit_partial(dir, "/sums/bins/7/total", serde_json::json!("9"));
        }
        "validate --combine: 1e15 realizations" => {
            edit_partial(
                dir,
                "/realizations",
                serde_json::json!(1_000_000_000_000_000u64),
            );
            edit_partial(dir, "/end", serde_json::json!(1_000_000_000_000_000u64));
        }
        "onboard --combine: squares below counts" => {
            edit_partial(dir, "/sums/0/regions/0/1/squares", serde_json::json!("0"))
        }
        "onboard --combine: NaN bias" => edit_partial(
            dir,
            "/sums/0/regions/0/0/bias",
            serde_json::json!({ "partials": [f64::NAN.to_bits()] }),
        ),
        _ => {}
    }
    Some(true)
}
