//! Format 5's channel coordinate (docs/file-format.md, "Format 5: numbered channels"):
//! `channel` numbers the channels 0, 1, … (integers, strictly increasing, as CF wants a
//! coordinate variable), `channel_name` labels them (CF §6.1) and every variable with the
//! channel dimension lists it in `coordinates`; an onboard product's regions number
//! their channels as the raw file does. The reference is the config's own
//! `[[instrument.channels]]` names, read from its TOML here. Every reader refuses a
//! `channel_name` of the wrong length, not strings, or with a name twice, and numbers
//! out of order; a format-4 file (`channel` the names) is still read.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::config_path;
use hdf5::types::VarLenUnicode;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim_channel_labels_{name}"));
    std::fs::remove_dir_all(&d).ok();
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn lidarsim(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn ok(o: Output) -> String {
    let text =
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{text}");
    text
}

/// The channel names of a config, from its TOML (not through lidarsim).
fn config_names(rel: &str) -> Vec<String> {
    let text = std::fs::read_to_string(config_path(rel)).unwrap();
    let v: toml::Table = toml::from_str(&text).unwrap();
    v["instrument"]["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap().to_string())
        .collect()
}

fn names(g: &hdf5::Group) -> Vec<String> {
    let v: Vec<VarLenUnicode> = g.dataset("channel_name").unwrap().read_raw().unwrap();
    v.iter().map(|s| s.as_str().to_string()).collect()
}

fn text_attr(d: &hdf5::Dataset, name: &str) -> Option<String> {
    let a = d.attr(name).ok()?;
    Some(a.read_scalar::<VarLenUnicode>().ok()?.as_str().to_string())
}

/// Every dataset of `g` whose shape has the channel dimension (the only length `n`
/// among its dimensions: the tests choose the other lengths apart) lists
/// `channel_name` among its coordinates; `channel` and `channel_name` list none.
fn assert_labelled(g: &hdf5::Group, n: usize, what: &str) {
    let mut labelled = 0;
    for d in g.datasets().unwrap() {
        let name = d.name().rsplit('/').next().unwrap().to_string();
        if name == "channel" || name == "channel_name" {
            assert_eq!(text_attr(&d, "coordinates"), None, "{what}: {name}");
        } else if d.shape().contains(&n) {
            let c = text_attr(&d, "coordinates").unwrap_or_default();
            assert!(
                c.split(' ').any(|w| w == "channel_name"),
                "{what}: {name} lists {c:?}"
            );
            labelled += 1;
        }
    }
    assert!(labelled >= 5, "{what}: only {labelled} channel variables");
}

#[test]
fn raw_file_and_products_number_their_channels_and_name_them() {
    let dir = scratch("structure");
    let cfg = config_path("instruments/caliop_3ch.toml");
    let cfg = cfg.to_str().unwrap();
    let want = config_names("instruments/caliop_3ch.toml");
    ok(lidarsim(
        &dir,
        &["simulate", cfg, "--profiles", "2", "-o", "raw.h5"],
    ));
    let f = hdf5::File::open(dir.join("raw.h5")).unwrap();
    assert_eq!(
        f.attr("lidarsim_format_version")
            .unwrap()
            .read_scalar::<i32>()
            .unwrap(),
        5
    );
    let channel = f.dataset("channel").unwrap();
    assert_eq!(channel.read_raw::<i64>().unwrap(), [0, 1, 2]);
    assert!(channel.dtype().unwrap().is::<i64>());
    assert_eq!(names(&f), want);
    assert_labelled(&f, 3, "raw file");
    // the caliop layout: the 532 nm pair in regions of their own, 1064 nm in others
    let window = [
        "--set",
        "acquisition.top_altitude_km=40",
        "--set",
        "acquisition.bottom_altitude_km=-2",
    ];
    let mut args = vec!["onboard", cfg, "--scheme", "caliop", "-o", "p.h5"];
    // 45 shots: 3, 9, 15 or 45 profiles a region, never 2 (the 532 nm pair's channels)
    args.extend(["--set", "acquisition.profiles=45"]);
    args.extend(window);
    ok(lidarsim(&dir, &args));
    let p = hdf5::File::open(dir.join("p.h5")).unwrap();
    let mut seen = vec![false; 3];
    for r in p.member_names().unwrap() {
        let g = p.group(&r).unwrap();
        let numbers = g.dataset("channel").unwrap().read_raw::<i64>().unwrap();
        assert!(numbers.windows(2).all(|w| w[0] < w[1]), "{r}: {numbers:?}");
        let held = names(&g);
        for (&k, name) in numbers.iter().zip(&held) {
            assert_eq!(name, &want[k as usize], "{r}: channel {k}");
            seen[k as usize] = true;
        }
        if numbers.len() > 1 {
            assert_labelled(&g, numbers.len(), &r);
        }
        for name in ["counts", "lidar_constant", "expected_background", "t2"] {
            let c = text_attr(&g.dataset(name).unwrap(), "coordinates").unwrap();
            assert!(c.split(' ').any(|w| w == "channel_name"), "{r}/{name}: {c}");
        }
    }
    assert_eq!(seen, [true; 3]);
    std::fs::remove_dir_all(&dir).ok();
}

/// `f` of `path` rewritten by `edit` (opened read-write, closed for certain after).
fn edited(src: &Path, path: &Path, edit: impl FnOnce(&hdf5::File)) {
    std::fs::copy(src, path).unwrap();
    let f = hdf5::File::open_rw(path).unwrap();
    edit(&f);
    f.close().unwrap();
}

fn text_dataset(f: &hdf5::File, name: &str, values: &[&str]) {
    let v: Vec<VarLenUnicode> = values.iter().map(|s| s.parse().unwrap()).collect();
    f.new_dataset::<VarLenUnicode>()
        .shape(v.len())
        .create(name)
        .unwrap()
        .write_raw(&v)
        .unwrap();
}

#[test]
fn hostile_channel_labels_are_refused_and_format_4_is_read() {
    let dir = scratch("hostile");
    let cfg = config_path("ground/pollyxt_like.toml");
    let want = config_names("ground/pollyxt_like.toml");
    let n = want.len();
    assert!(n > 2);
    ok(lidarsim(
        &dir,
        &[
            "simulate",
            cfg.to_str().unwrap(),
            "--profiles",
            "2",
            "-o",
            "v5.h5",
        ],
    ));
    let v5 = dir.join("v5.h5");
    let refused = |name: &str, edit: &dyn Fn(&hdf5::File), why: &str| {
        let path = dir.join(format!("{name}.h5"));
        edited(&v5, &path, edit);
        for reader in [&["validate", "--file"][..], &["export-scc"]] {
            let mut args = reader.to_vec();
            args.push(path.file_name().unwrap().to_str().unwrap());
            if reader[0] == "export-scc" {
                args.push("scc.nc");
            }
            let o = lidarsim(&dir, &args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{name} {reader:?}: {err}");
            assert!(
                err.contains(why) && err.lines().count() == 1,
                "{name} {reader:?}: {err}"
            );
        }
        assert!(!dir.join("scc.nc").exists());
    };
    let names_as = |v: Vec<String>| {
        move |f: &hdf5::File| {
            f.unlink("channel_name").unwrap();
            let v: Vec<&str> = v.iter().map(String::as_str).collect();
            text_dataset(f, "channel_name", &v);
        }
    };
    let with_last = |last: &str| {
        let mut v = want.clone();
        v[n - 1] = last.to_string();
        v
    };
    let short = format!("`channel_name` is {}", n - 1);
    refused("short", &names_as(want[..n - 1].to_vec()), &short);
    refused("twice", &names_as(with_last(&want[0])), "given twice");
    refused("empty", &names_as(with_last("")), "is empty");
    let floats = |f: &hdf5::File| {
        f.unlink("channel_name").unwrap();
        let v = vec![0.0; n];
        let d = f.new_dataset::<f64>().shape(n).create("channel_name");
        d.unwrap().write_raw(&v).unwrap();
    };
    refused(
        "numbers",
        &floats,
        "`channel_name` holds floating-point numbers, not strings",
    );
    let numbered =
        |v: Vec<i64>| move |f: &hdf5::File| f.dataset("channel").unwrap().write_raw(&v).unwrap();
    let mut swapped: Vec<i64> = (0..n as i64).collect();
    swapped.swap(0, 1);
    refused("order", &numbered(swapped), "strictly increasing");
    refused(
        "from_one",
        &numbered((1..=n as i64).collect()),
        "numbers its channels 0, 1",
    );
    refused(
        "unnamed",
        &|f: &hdf5::File| f.unlink("channel_name").unwrap(),
        "no `channel_name`",
    );
    // format 4: `channel` the names, no `channel_name`; read as before
    let v4 = dir.join("v4.h5");
    edited(&v5, &v4, |f| {
        f.unlink("channel_name").unwrap();
        f.unlink("channel").unwrap();
        let names: Vec<&str> = want.iter().map(String::as_str).collect();
        text_dataset(f, "channel", &names);
        f.attr("lidarsim_format_version")
            .unwrap()
            .write_scalar(&4i32)
            .unwrap();
    });
    let verdict = ok(lidarsim(&dir, &["validate", "--file", "v4.h5"]));
    assert!(
        verdict.contains("CONSISTENT") && !verdict.contains("INCONSISTENT"),
        "{verdict}"
    );
    for (path, version) in [(&v4, 4), (&v5, 5)] {
        let q = lidarsim::figures::quicklook::read(path, Some(&want[1]), false).unwrap();
        assert!(!q.signal.means().is_empty(), "format {version}");
    }
    // a format-4 file with numbers in `channel` is refused as not of its format
    edited(&v4, &dir.join("v4n.h5"), |f| {
        f.unlink("channel").unwrap();
        let v: Vec<i64> = (0..n as i64).collect();
        let d = f.new_dataset::<i64>().shape(n).create("channel");
        d.unwrap().write_raw(&v).unwrap();
    });
    let o = lidarsim(&dir, &["validate", "--file", "v4n.h5"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(2) && err.contains("`channel` holds signed integers, not strings"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
