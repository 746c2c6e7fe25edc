//! One check of a file's integrity for every reader (issue 36, item 14): each class of
//! damage that `merge` refuses, made in a raw file (a raw shard, so that `merge` reads
//! it too), an analog raw file or an onboard product shard, run through every reader of
//! that kind of file. Each is refused in one line naming the file and the variable,
//! exit 2, nothing left behind: nothing that `merge` refuses is drawn, validated or
//! exported.
//!
//! The files are made once by the binary under test (`simulate --shard 0/1`, `onboard
//! --shard 0/1`, a few profiles) and copied into each case's scratch directory, where one
//! variable is damaged with the `hdf5` crate.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use hdf5::types::VarLenUnicode;

use super::{Case, Run, Scratch, Want, bin, cfg};

/// The kinds of file damaged.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Kind {
    /// A raw shard of two photon-counting channels (∥, ⊥, no dead time) with its
    /// components.
    Raw,
    /// A raw shard of the same ground lidar recording analog.
    Analog,
    /// An onboard product shard (the `caliop` scheme).
    Product,
}

/// One class of damage: its name, the file it is made in, the text the refusal names,
/// and how it is made.
struct Damage {
    name: &'static str,
    kind: Kind,
    names: &'static str,
    make: fn(&hdf5::File),
}

const fn d(name: &'static str, kind: Kind, names: &'static str, make: fn(&hdf5::File)) -> Damage {
    Damage {
        name,
        kind,
        names,
        make,
    }
}

/// Every class of damage (docs/hostile-inputs.md, "One check of a file's integrity").
fn damages() -> Vec<Damage> {
    use Kind::{Analog, Product, Raw};
    vec![
        // --- a raw file's profile columns ---
        d(
            "profile_column 1 of 1 column",
            Raw,
            "`profile_column`",
            |f| set_i32(f, "profile_column", 1, 1),
        ),
        d(
            "profile_column -1 in the first slot",
            Raw,
            "slot 0 is unused",
            |f| set_i32(f, "profile_column", 0, -1),
        ),
        d("profile_column -7", Raw, "`profile_column`", |f| {
            set_i32(f, "profile_column", 2, -7)
        }),
        d("weight 0.5", Raw, "sum to 0.5", |f| {
            set_f64(f, "profile_column_weight", 2, 0.5)
        }),
        d("weight NaN", Raw, "`profile_column_weight`", |f| {
            set_f64(f, "profile_column_weight", 0, f64::NAN)
        }),
        d("weight 2", Raw, "not in (0, 1]", |f| {
            set_f64(f, "profile_column_weight", 1, 2.0)
        }),
        d("weight -1", Raw, "not in (0, 1]", |f| {
            set_f64(f, "profile_column_weight", 1, -1.0)
        }),
        // --- a raw file's words ---
        d("channel_kind garbage", Raw, "`channel_kind`", |f| {
            set_text(f, "channel_kind", 1, "laser beam")
        }),
        d("detection_mode garbage", Raw, "`detection_mode`", |f| {
            set_text(f, "detection_mode", 0, "quantum")
        }),
        d("acquisition_mode garbage", Raw, "`acquisition_mode`", |f| {
            set_text(f, "acquisition_mode", 1, "digital")
        }),
        d("glue_partner garbage", Raw, "`glue_partner`", |f| {
            set_text(f, "glue_partner", 0, "nobody")
        }),
        d("glue_partner itself", Raw, "`glue_partner`", |f| {
            set_text(f, "glue_partner", 0, "532_parallel")
        }),
        d("dead_time_model garbage", Raw, "`dead_time_model`", |f| {
            set_text(f, "dead_time_model", 1, "sticky")
        }),
        d("polarization garbage", Raw, "`polarization`", |f| {
            set_text(f, "polarization", 1, "circular")
        }),
        // --- a raw file's calibration ---
        d("lidar_constant NaN", Raw, "`lidar_constant`", |f| {
            set_f64(f, "lidar_constant", 0, f64::NAN)
        }),
        d("lidar_constant negative", Raw, "`lidar_constant`", |f| {
            set_f64(f, "lidar_constant", 1, -3.0)
        }),
        d("range_weight negative", Raw, "`range_weight`", |f| {
            set_f64(f, "range_weight", 300, -1e-9)
        }),
        d("range_weight NaN", Raw, "`range_weight`", |f| {
            set_f64(f, "range_weight", 300, f64::NAN)
        }),
        d(
            "nominal_pulse_energy 0",
            Raw,
            "`nominal_pulse_energy`",
            |f| set_f64(f, "nominal_pulse_energy", 0, 0.0),
        ),
        // --- a raw file's rows ---
        d(
            "components not summing to the counts",
            Raw,
            "components sum",
            |f| {
                let ds = f.dataset("signal_counts").unwrap();
                let mut v: Vec<u64> = ds.read_raw().unwrap();
                v[500] += 1;
                write_u_like(&ds, &v);
            },
        ),
        d("pulse_energy NaN", Raw, "`pulse_energy`", |f| {
            set_f64(f, "pulse_energy", 3, f64::NAN)
        }),
        // --- an analog raw file's chain ---
        d(
            "analog_counts_per_photoelectron 0",
            Analog,
            "`analog_counts_per_photoelectron`",
            |f| set_f64(f, "analog_counts_per_photoelectron", 0, 0.0),
        ),
        d(
            "analog_counts_per_photoelectron NaN",
            Analog,
            "`analog_counts_per_photoelectron`",
            |f| set_f64(f, "analog_counts_per_photoelectron", 1, f64::NAN),
        ),
        d(
            "analog_counts_per_photoelectron negative",
            Analog,
            "`analog_counts_per_photoelectron`",
            |f| set_f64(f, "analog_counts_per_photoelectron", 0, -2.0),
        ),
        d(
            "adc_volts_per_count 0",
            Analog,
            "`adc_volts_per_count`",
            |f| set_f64(f, "adc_volts_per_count", 1, 0.0),
        ),
        // --- an onboard product's region ---
        d("region time inf", Product, "`region_0/time`", |f| {
            set_f64(&region(f, 0), "time", 1, f64::INFINITY)
        }),
        d("region time NaN", Product, "`region_1/time`", |f| {
            set_f64(&region(f, 1), "time", 0, f64::NAN)
        }),
        d("region altitude NaN", Product, "`region_2/altitude`", |f| {
            set_f64(&region(f, 2), "altitude", 4, f64::NAN)
        }),
        d("region n_shots 0", Product, "`region_0/n_shots`", |f| {
            let g = region(f, 0);
            let ds = g.dataset("n_shots").unwrap();
            let mut v: Vec<u64> = ds.read_raw().unwrap();
            v[0] = 0;
            write_u_like(&ds, &v);
        }),
        // --- a coordinate of crafted length is named, not the first variable on its
        // dimension (issue 36, item 18) ---
        d("column declared 2^40", Raw, "`column` declares", |f| {
            declare_huge(f, "column")
        }),
        d("k declared 2^40", Raw, "`k` declares", |f| {
            declare_huge(f, "k")
        }),
        d("column one too long", Raw, "coordinate `column`", |f| {
            lengthen(f, "column")
        }),
        d(
            "region column declared 2^40",
            Product,
            "`region_0/column` declares",
            |f| declare_huge(&region(f, 0), "column"),
        ),
        d(
            "region column one too long",
            Product,
            "coordinate `region_0/column`",
            |f| lengthen(&region(f, 0), "column"),
        ),
        d(
            "region profile one too long",
            Product,
            "`profile` is",
            |f| lengthen(&region(f, 0), "profile"),
        ),
        d("region bin one too long", Product, "`bin` is", |f| {
            lengthen(&region(f, 0), "bin")
        }),
        d("region 2^40 rows declared", Product, "crafted", |f| {
            let g = region(f, 0);
            let shape = g.dataset("counts").unwrap().shape();
            let p = 1usize << 40;
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
        }),
        d(
            "region profile_column 3 of 1 column",
            Product,
            "`region_1/profile_column`",
            |f| set_i32(&region(f, 1), "profile_column", 0, 3),
        ),
        d(
            "region profile_column -1 in the first slot",
            Product,
            "slot 0 is unused",
            |f| set_i32(&region(f, 0), "profile_column", 0, -1),
        ),
        d("region weight 0.5", Product, "sum to 0.5", |f| {
            set_f64(&region(f, 2), "profile_column_weight", 0, 0.5)
        }),
        d(
            "region weight NaN",
            Product,
            "`profile_column_weight` of profile row 0",
            |f| set_f64(&region(f, 0), "profile_column_weight", 0, f64::NAN),
        ),
        d(
            "region lidar_constant NaN",
            Product,
            "`region_0/lidar_constant`",
            |f| set_f64(&region(f, 0), "lidar_constant", 0, f64::NAN),
        ),
        d(
            "region lidar_constant negative",
            Product,
            "`region_1/lidar_constant`",
            |f| set_f64(&region(f, 1), "lidar_constant", 0, -1.0),
        ),
        d(
            "region range_weight NaN",
            Product,
            "`region_2/range_weight`",
            |f| set_f64(&region(f, 2), "range_weight", 1, f64::NAN),
        ),
        d(
            "region nominal_pulse_energy 0",
            Product,
            "`region_0/nominal_pulse_energy`",
            |f| set_f64(&region(f, 0), "nominal_pulse_energy", 0, 0.0),
        ),
        d(
            "region expected_background NaN",
            Product,
            "`expected_background`",
            |f| set_f64(&region(f, 1), "expected_background", 0, f64::NAN),
        ),
    ]
}

/// Every reader of a kind of file: its name and arguments (`@D/in/file.h5` the damaged
/// file).
fn readers(kind: Kind) -> Vec<(&'static str, Vec<&'static str>)> {
    let raw = vec![
        (
            "validate --file",
            vec!["validate", "--file", "@D/in/file.h5"],
        ),
        (
            "quicklook",
            vec!["quicklook", "@D/in/file.h5", "--png", "@D/out.png"],
        ),
        (
            "curtain",
            vec!["curtain", "@D/in/file.h5", "--png", "@D/out.png"],
        ),
        (
            "export-scc",
            vec!["export-scc", "@D/in/file.h5", "@D/out.nc"],
        ),
        ("merge", vec!["merge", "@D/out.h5", "@D/in/file.h5"]),
    ];
    match kind {
        Kind::Raw | Kind::Analog => raw,
        Kind::Product => vec![
            (
                "quicklook",
                vec!["quicklook", "@D/in/file.h5", "--png", "@D/out.png"],
            ),
            ("merge", vec!["merge", "@D/out.h5", "@D/in/file.h5"]),
        ],
    }
}

/// This topic's cases: every damage through every reader of its kind of file.
pub fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    for damage in damages() {
        for (reader, argv) in readers(damage.kind) {
            let name: &'static str =
                Box::leak(format!("integrity: {} — {reader}", damage.name).into_boxed_str());
            out.push(Case {
                name,
                want: Want::Refused(damage.names),
                env: vec![],
                run: Run::Args(argv.iter().map(|s| s.to_string()).collect()),
            });
        }
    }
    out
}

/// The undamaged file of `kind`, made once (None where it cannot be made).
fn base(kind: Kind) -> Option<PathBuf> {
    static FILES: OnceLock<Vec<Option<PathBuf>>> = OnceLock::new();
    let files = FILES.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("lidarsim-integrity-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let ground = cfg("ground/ground_532_depol.toml");
        let short = [
            "--set",
            "acquisition.accumulation_time_s=0.1",
            "--set",
            "acquisition.top_altitude_km=15",
            "--profiles",
            "3",
            "--shard",
            "0/1",
        ];
        let analog = "instrument.detector={ mode = \"analog\", gain = 3e6, excess_noise_factor = 1.3, \
                      electronic_noise_v = 5e-5, offset_v = 5e-3, adc_bits = 12, adc_range_v = 0.1 }";
        let make = |out: &str, extra: &[&str]| -> Option<PathBuf> {
            let path = dir.join(out);
            let mut argv: Vec<&str> = vec!["simulate", &ground, "-o"];
            let p = path.to_string_lossy().into_owned();
            argv.push(&p);
            argv.extend(short);
            argv.extend(extra);
            run(&dir, &argv).then_some(path)
        };
        let product = dir.join("product.h5");
        let c = cfg("instruments/caliop_532.toml");
        let p = product.to_string_lossy().into_owned();
        let made = run(
            &dir,
            &[
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
                &p,
            ],
        );
        vec![
            // no dead time: with the components (a dead-time count is no sum of them)
            make(
                "raw.h5",
                &["--set", "instrument.detector.dead_time_s=0", "--components"],
            ),
            make("analog.h5", &["--set", analog]),
            made.then_some(product),
        ]
    });
    let k = match kind {
        Kind::Raw => 0,
        Kind::Analog => 1,
        Kind::Product => 2,
    };
    files[k].clone()
}

/// Runs the binary with `argv` in `dir`; whether it succeeded.
fn run(dir: &Path, argv: &[&str]) -> bool {
    std::process::Command::new(bin())
        .args(argv)
        .current_dir(dir)
        .env_remove("SOURCE_DATE_EPOCH")
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Prepares the scratch directory of one of this topic's cases: `None` when the case
/// is not this topic's, `Some(false)` when its file cannot be made here.
pub fn prepare(name: &str, dir: &Scratch) -> Option<bool> {
    let rest = name.strip_prefix("integrity: ")?;
    let damage = damages()
        .into_iter()
        .find(|d| rest.starts_with(&format!("{} — ", d.name)))?;
    let Some(file) = base(damage.kind) else {
        return Some(false);
    };
    let target = dir.0.join("in/file.h5");
    fs::copy(file, &target).unwrap();
    let f = hdf5::File::open_rw(&target).expect("open the file to damage");
    (damage.make)(&f);
    Some(true)
}

/// Replaces int64 coordinate `name` of `g` by one that declares 2^40 values and stores
/// none (chunked, never written).
fn declare_huge(g: &hdf5::Group, name: &str) {
    g.unlink(name).unwrap();
    g.new_dataset::<i64>()
        .chunk(1024)
        .shape(1usize << 40)
        .create(name)
        .unwrap();
}

/// Replaces int64 coordinate `name` of `g` by its values and one more (0, 1, …, n).
fn lengthen(g: &hdf5::Group, name: &str) {
    let n = g.dataset(name).unwrap().shape()[0];
    g.unlink(name).unwrap();
    let v: Vec<i64> = (0..=n as i64).collect();
    g.new_dataset_builder().with_data(&v).create(name).unwrap();
}

/// Region group `k` of a product.
fn region(f: &hdf5::File, k: usize) -> hdf5::Group {
    f.group(&format!("region_{k}")).unwrap()
}

/// Sets element `i` (of the flattened values) of f64 dataset `name` of `g` to `x`.
fn set_f64(g: &hdf5::Group, name: &str, i: usize, x: f64) {
    let ds = g.dataset(name).unwrap();
    let mut v: Vec<f64> = ds.read_raw().unwrap();
    v[i] = x;
    ds.write_raw(&v).unwrap();
}

/// Sets element `i` of i32 dataset `name` of `g` to `x`.
fn set_i32(g: &hdf5::Group, name: &str, i: usize, x: i32) {
    let ds = g.dataset(name).unwrap();
    let mut v: Vec<i32> = ds.read_raw().unwrap();
    v[i] = x;
    ds.write_raw(&v).unwrap();
}

/// Writes `v` into unsigned dataset `ds` of whatever width it has.
fn write_u_like(ds: &hdf5::Dataset, v: &[u64]) {
    match ds.dtype().unwrap().size() {
        2 => ds
            .write_raw(&v.iter().map(|&x| x as u16).collect::<Vec<_>>())
            .unwrap(),
        4 => ds
            .write_raw(&v.iter().map(|&x| x as u32).collect::<Vec<_>>())
            .unwrap(),
        _ => ds.write_raw(v).unwrap(),
    }
}

/// Sets string `i` of (channel) text variable `name` of `f` to `text`.
fn set_text(f: &hdf5::File, name: &str, i: usize, text: &str) {
    let ds = f.dataset(name).unwrap();
    let mut v: Vec<VarLenUnicode> = ds.read_raw().unwrap();
    v[i] = text.parse().unwrap();
    ds.write_raw(&v).unwrap();
}
