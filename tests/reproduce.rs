//! The file says how it was made (docs/file-format.md, "Reproducing a file from its
//! config"): the `config` root attribute holds the resolved config after every `--set`
//! and every option that changes the content, so that `simulate` on it with no option
//! writes the same file; only `history` (the command line) and `config_file` (the
//! config's path) tell the two apart. `onboard` products, which record neither, come
//! out byte for byte.

mod common;

use std::path::Path;

use common::cli::{lidarsim, ok, scratch};
use common::config_path;
use hdf5::types::{TypeDescriptor, VarLenUnicode};

/// Root attributes that say how a file was asked for, not what it holds.
const HOW_ASKED: [&str; 2] = ["history", "config_file"];

/// The root attribute `name` of `path` as text.
fn text_attr(path: &Path, name: &str) -> String {
    let f = hdf5::File::open(path).unwrap();
    f.attr(name)
        .unwrap()
        .read_scalar::<VarLenUnicode>()
        .unwrap()
        .to_string()
}

/// The stored config of `path`, parsed.
fn stored_config(path: &Path) -> toml::Table {
    text_attr(path, "config").parse().unwrap()
}

/// A value read whatever its HDF5 type: the class and every element, bit for bit
/// (integers widened, floats as their bits, so that NaN equals NaN).
#[derive(Debug, PartialEq)]
enum Values {
    Unsigned(Vec<u64>),
    Signed(Vec<i64>),
    Float(Vec<u64>),
    Text(Vec<String>),
    /// A type this test does not read (the dimension scales' references): its size.
    Other(usize),
}

fn values_of(c: &hdf5::Container) -> Values {
    let t = c.dtype().unwrap();
    match t.to_descriptor() {
        Ok(TypeDescriptor::Unsigned(_)) => Values::Unsigned(c.read_raw::<u64>().unwrap()),
        Ok(TypeDescriptor::Integer(_)) => Values::Signed(c.read_raw::<i64>().unwrap()),
        Ok(TypeDescriptor::Float(_)) => Values::Float(
            c.read_raw::<f64>()
                .unwrap()
                .into_iter()
                .map(f64::to_bits)
                .collect(),
        ),
        Ok(TypeDescriptor::VarLenUnicode) => Values::Text(
            c.read_raw::<VarLenUnicode>()
                .unwrap()
                .iter()
                .map(|s| s.to_string())
                .collect(),
        ),
        _ => Values::Other(t.size()),
    }
}

/// Every attribute of `loc` but `skip`, by name.
fn attributes(loc: &hdf5::Location, skip: &[&str]) -> Vec<(String, Values)> {
    let mut names = loc.attr_names().unwrap();
    names.sort();
    names
        .into_iter()
        .filter(|n| !skip.contains(&n.as_str()))
        .map(|n| {
            let a = loc.attr(&n).unwrap();
            (n, values_of(&a))
        })
        .collect()
}

/// Asserts that `a` and `b` hold the same variables (shape, type and values), the same
/// attributes of each, and the same root attributes but `history` and `config_file`.
fn assert_same_content(a: &Path, b: &Path) {
    let (fa, fb) = (hdf5::File::open(a).unwrap(), hdf5::File::open(b).unwrap());
    let root = |f: &hdf5::File| attributes(f, &HOW_ASKED);
    assert_eq!(root(&fa), root(&fb), "root attributes");
    let mut names = fa.member_names().unwrap();
    names.sort();
    let mut other = fb.member_names().unwrap();
    other.sort();
    assert_eq!(names, other, "variables");
    assert!(names.iter().any(|n| n == "counts"));
    for n in &names {
        let (da, db) = (fa.dataset(n).unwrap(), fb.dataset(n).unwrap());
        assert_eq!(da.shape(), db.shape(), "{n}: shape");
        assert_eq!(
            da.dtype().unwrap().to_descriptor().ok(),
            db.dtype().unwrap().to_descriptor().ok(),
            "{n}: type"
        );
        assert!(values_of(&da) == values_of(&db), "{n}: values differ");
        assert_eq!(
            attributes(&da, &[]),
            attributes(&db, &[]),
            "{n}: attributes"
        );
    }
}

/// `simulate CONFIG -o OUT OPTIONS...` in `dir`, then `simulate` on its stored config,
/// written to `rerun/stored.toml` (another directory), with no option: the same content.
/// Returns the stored config.
fn reproduce(dir: &Path, cfg: &str, options: &[&str]) -> toml::Table {
    let c = config_path(cfg);
    let mut args = vec!["simulate", c.to_str().unwrap(), "-o", "first.h5"];
    args.extend_from_slice(options);
    ok(lidarsim(dir, &args, &[]));
    let first = dir.join("first.h5");
    std::fs::create_dir_all(dir.join("rerun")).unwrap();
    std::fs::write(dir.join("rerun/stored.toml"), text_attr(&first, "config")).unwrap();
    let again = ["simulate", "rerun/stored.toml", "-o", "again.h5"];
    ok(lidarsim(dir, &again, &[]));
    let again = dir.join("again.h5");
    assert_same_content(&first, &again);
    // the two differ in how they were asked for only
    let created = text_attr(&again, "date_created");
    assert_eq!(
        text_attr(&again, "history"),
        format!("{created} lidarsim simulate rerun/stored.toml")
    );
    assert_eq!(text_attr(&again, "config_file"), "rerun/stored.toml");
    assert_eq!(
        text_attr(&first, "config_file"),
        c.display().to_string(),
        "{cfg}"
    );
    stored_config(&first)
}

fn key<'a>(t: &'a toml::Table, section: &str, key: &str) -> &'a toml::Value {
    &t[section][key]
}

#[test]
fn a_run_with_options_is_reproduced_by_its_stored_config() {
    let dir = scratch("reproduce-options");
    // 400 profiles where the file says 100; auto with a tolerance (aggregate-normal here)
    let stored = reproduce(
        &dir,
        "paper/scenario1.toml",
        &[
            "--profiles",
            "400",
            "--seed",
            "7",
            "--method",
            "auto",
            "--tolerance",
            "1e-2",
            "--set",
            "acquisition.accumulation_time_s=100",
        ],
    );
    assert_eq!(
        key(&stored, "acquisition", "profiles").as_integer(),
        Some(400)
    );
    assert_eq!(key(&stored, "simulation", "seed").as_integer(), Some(7));
    assert_eq!(key(&stored, "simulation", "method").as_str(), Some("auto"));
    assert_eq!(
        key(&stored, "simulation", "tolerance").as_float(),
        Some(1e-2)
    );
    assert_eq!(
        key(&stored, "simulation", "components").as_bool(),
        Some(false)
    );
    assert_eq!(
        key(&stored, "acquisition", "accumulation_time_s").as_integer(),
        Some(100)
    );
    assert_eq!(
        text_attr(&dir.join("first.h5"), "method"),
        "aggregate-normal"
    );
    std::fs::remove_dir_all(&dir).ok();

    // shot by shot with component counts, and a seed beyond a TOML integer (stored as
    // the string of its digits)
    let dir = scratch("reproduce-shot");
    let stored = reproduce(
        &dir,
        "paper/scenario2.toml",
        &[
            "--profiles",
            "5",
            "--seed",
            "18446744073709551615",
            "--method",
            "shot",
            "--components",
            "--set",
            "acquisition.accumulation_time_s=2",
        ],
    );
    assert_eq!(
        key(&stored, "simulation", "seed").as_str(),
        Some("18446744073709551615")
    );
    assert_eq!(key(&stored, "simulation", "method").as_str(), Some("shot"));
    assert_eq!(
        key(&stored, "simulation", "components").as_bool(),
        Some(true)
    );
    assert_eq!(
        key(&stored, "acquisition", "profiles").as_integer(),
        Some(5)
    );
    std::fs::remove_dir_all(&dir).ok();

    // a scene along the orbit, with no option but the profiles: the config's seed and
    // method written in
    let dir = scratch("reproduce-orbit");
    let stored = reproduce(&dir, "instruments/caliop_orbit.toml", &["--profiles", "6"]);
    assert_eq!(
        key(&stored, "acquisition", "profiles").as_integer(),
        Some(6)
    );
    assert!(key(&stored, "simulation", "seed").is_integer());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_config_naming_files_reruns_beside_the_original() {
    // the molecular profile is named relative to the config: the stored config finds it
    // from the original's directory (`config_file`), not from elsewhere
    let dir = scratch("reproduce-files");
    for sub in ["cfg", "atmospheres", "elsewhere/deeper"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    std::fs::copy(
        config_path("ground/profile_file_example.toml"),
        dir.join("cfg/run.toml"),
    )
    .unwrap();
    std::fs::copy(
        config_path("atmospheres/us76_1km.txt"),
        dir.join("atmospheres/us76_1km.txt"),
    )
    .unwrap();
    let first = ["simulate", "cfg/run.toml", "--profiles", "3", "--seed", "5"];
    ok(lidarsim(
        &dir,
        &[&first[..], &["-o", "first.h5"]].concat(),
        &[],
    ));
    let config = text_attr(&dir.join("first.h5"), "config");
    std::fs::write(dir.join("cfg/stored.toml"), &config).unwrap();
    ok(lidarsim(
        &dir,
        &["simulate", "cfg/stored.toml", "-o", "again.h5"],
        &[],
    ));
    assert_same_content(&dir.join("first.h5"), &dir.join("again.h5"));
    std::fs::write(dir.join("elsewhere/deeper/stored.toml"), &config).unwrap();
    let o = lidarsim(
        &dir,
        &["simulate", "elsewhere/deeper/stored.toml", "-o", "lost.h5"],
        &[],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("us76_1km.txt"), "{err}");
    assert!(!dir.join("lost.h5").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// `onboard` on a product's stored config writes the same product (every group,
/// variable, value and attribute) but for `history`, which records the new command line.
#[test]
fn an_onboard_product_is_reproduced_by_its_stored_config() {
    let dir = scratch("reproduce-onboard");
    let c = config_path("instruments/caliop_532.toml");
    let scheme = ["--scheme", "uniform:15"];
    let window = [
        "--set",
        "acquisition.top_altitude_km=40",
        "--set",
        "acquisition.bottom_altitude_km=-2",
        "--set",
        "acquisition.profiles=4",
    ];
    let first = [
        &["onboard", c.to_str().unwrap()][..],
        &scheme,
        &window,
        &["--seed", "11", "-o", "first.h5"],
    ]
    .concat();
    ok(lidarsim(&dir, &first, &[]));
    let stored = text_attr(&dir.join("first.h5"), "config");
    let table: toml::Table = stored.parse().unwrap();
    assert_eq!(key(&table, "simulation", "seed").as_integer(), Some(11));
    std::fs::write(dir.join("stored.toml"), &stored).unwrap();
    let again = [
        &["onboard", "stored.toml"][..],
        &scheme,
        &["-o", "again.h5"],
    ]
    .concat();
    ok(lidarsim(&dir, &again, &[]));
    // the same product but for `history`, the new command line (as a raw file)
    let (a, b) = (dir.join("first.h5"), dir.join("again.h5"));
    let history = text_attr(&b, "history");
    assert!(
        history.ends_with(" lidarsim onboard stored.toml --scheme uniform:15"),
        "{history}"
    );
    let (fa, fb) = (hdf5::File::open(&a).unwrap(), hdf5::File::open(&b).unwrap());
    assert_eq!(attributes(&fa, &["history"]), attributes(&fb, &["history"]));
    let groups = fa.member_names().unwrap();
    assert_eq!(groups, fb.member_names().unwrap());
    for g in &groups {
        let (ga, gb) = (fa.group(g).unwrap(), fb.group(g).unwrap());
        assert_eq!(attributes(&ga, &[]), attributes(&gb, &[]), "{g}");
        let names = ga.member_names().unwrap();
        assert_eq!(names, gb.member_names().unwrap(), "{g}");
        assert!(names.iter().any(|n| n == "counts"));
        for n in &names {
            let (da, db) = (ga.dataset(n).unwrap(), gb.dataset(n).unwrap());
            assert_eq!(da.shape(), db.shape(), "{g}/{n}: shape");
            assert!(values_of(&da) == values_of(&db), "{g}/{n}: values differ");
            assert_eq!(attributes(&da, &[]), attributes(&db, &[]), "{g}/{n}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
