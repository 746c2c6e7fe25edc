//! Tests of the raw file's header check.

use super::*;
use crate::output::raw_file::spec::CHANNEL_NAME;

fn scratch(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-raw-read-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A minimal raw file: P profiles, 1 channel, B bins; `edit` changes it before closing.
fn minimal(path: &Path, p: usize, b: usize, edit: impl FnOnce(&hdf5::File)) {
    minimal_of_version(path, FORMAT_VERSION, p, b, edit)
}

/// [`minimal`] in the layout of `version`: the channels numbered with `channel_name`
/// from format 5, named by `channel` before.
fn minimal_of_version(
    path: &Path,
    version: i32,
    p: usize,
    b: usize,
    edit: impl FnOnce(&hdf5::File),
) {
    let f = hdf5::File::create(path).unwrap();
    f.new_attr::<i32>()
        .create("lidarsim_format_version")
        .unwrap()
        .write_scalar(&version)
        .unwrap();
    let u = |name: &str, shape: &[usize], v: &[u64]| {
        f.new_dataset::<u64>()
            .shape(shape)
            .create(name)
            .unwrap()
            .write_raw(v)
            .unwrap();
    };
    let x = |name: &str, v: &[f64]| {
        f.new_dataset::<f64>()
            .shape(v.len())
            .create(name)
            .unwrap()
            .write_raw(v)
            .unwrap();
    };
    u("counts", &[p, 1, b], &vec![3; p * b]);
    u("n_shots", &[p], &vec![10; p]);
    x("time", &(0..p).map(|i| i as f64).collect::<Vec<_>>());
    f.new_dataset::<f64>()
        .shape([p, 1])
        .create("pulse_energy")
        .unwrap()
        .write_raw(&vec![0.1; p])
        .unwrap();
    x(
        "altitude",
        &(0..b).map(|i| 30.0 * i as f64).collect::<Vec<_>>(),
    );
    x(
        "range",
        &(0..b).map(|i| 30.0 * i as f64).collect::<Vec<_>>(),
    );
    let names = [VarLenUnicode::from_str("532_total").unwrap()];
    let text_name = match version {
        5.. => {
            f.new_dataset::<i64>()
                .shape(1)
                .create(CHANNEL_DIM)
                .unwrap()
                .write_raw(&[0i64])
                .unwrap();
            CHANNEL_NAME
        }
        _ => CHANNEL_DIM,
    };
    f.new_dataset::<VarLenUnicode>()
        .shape(1)
        .create(text_name)
        .unwrap()
        .write_raw(&names)
        .unwrap();
    edit(&f);
}

use std::str::FromStr;

fn refusal(name: &str, edit: impl FnOnce(&hdf5::File)) -> String {
    let d = scratch(name);
    let path = d.join("raw.h5");
    minimal(&path, 4, 5, edit);
    let f = hdf5::File::open(&path).unwrap();
    let e = check(&path, &f)
        .map(|_| String::new())
        .unwrap_or_else(|e| e.to_string());
    drop(f);
    std::fs::remove_dir_all(&d).ok();
    assert!(!e.contains('\n'), "{e}");
    e
}

#[test]
fn a_consistent_file_is_accepted_with_its_header() {
    let d = scratch("ok");
    let path = d.join("raw.h5");
    minimal(&path, 4, 5, |_| {});
    let f = hdf5::File::open(&path).unwrap();
    let h = check(&path, &f).unwrap();
    assert_eq!((h.n_profiles, h.n_bins, h.count_bytes), (4, 5, 8));
    assert_eq!(h.channels, vec!["532_total".to_string()]);
    assert!(!h.along_track);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_format_4_file_names_its_channels_by_the_coordinate() {
    let d = scratch("v4");
    let path = d.join("raw.h5");
    minimal_of_version(&path, 4, 4, 5, |_| {});
    let f = hdf5::File::open(&path).unwrap();
    let h = check(&path, &f).unwrap();
    assert_eq!(h.channels, vec!["532_total".to_string()]);
    drop(f);
    // format 5 with the names in `channel` is refused, naming it
    minimal_of_version(&path, 5, 4, 5, |f| {
        f.unlink(CHANNEL_DIM).unwrap();
        f.new_dataset::<VarLenUnicode>()
            .shape(1)
            .create(CHANNEL_DIM)
            .unwrap()
            .write_raw(&[VarLenUnicode::from_str("532_total").unwrap()])
            .unwrap();
    });
    let f = hdf5::File::open(&path).unwrap();
    let e = check(&path, &f).unwrap_err().to_string();
    assert!(
        e.contains("`channel` holds strings, not signed integers"),
        "{e}"
    );
    drop(f);
    // numbers that do not count from 0
    minimal_of_version(&path, 5, 4, 5, |f| {
        f.dataset(CHANNEL_DIM).unwrap().write_raw(&[3i64]).unwrap();
    });
    let f = hdf5::File::open(&path).unwrap();
    let e = check(&path, &f).unwrap_err().to_string();
    assert!(e.contains("`channel` value 0 is 3, not 0"), "{e}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn inconsistent_or_crafted_headers_are_refused_naming_the_variable() {
    let replace = |f: &hdf5::File, name: &str, v: &[f64]| {
        f.unlink(name).unwrap();
        f.new_dataset::<f64>()
            .shape(v.len())
            .create(name)
            .unwrap()
            .write_raw(v)
            .unwrap();
    };
    let e = refusal("short-time", |f| replace(f, "time", &[0.0, 1.0]));
    assert!(
        e.contains("`time` is 2,") && e.contains("(profile) = 4"),
        "{e}"
    );
    let e = refusal("nan-time", |f| {
        replace(f, "time", &[0.0, f64::NAN, 2.0, 3.0])
    });
    assert!(e.contains("`time` value 1 is NaN"), "{e}");
    let e = refusal("inf-alt", |f| {
        replace(f, "altitude", &[0.0, 1.0, f64::INFINITY, 3.0, 4.0])
    });
    assert!(e.contains("`altitude` value 2 is inf"), "{e}");
    let e = refusal("short-alt", |f| replace(f, "altitude", &[0.0, 1.0]));
    assert!(e.contains("`altitude` is 2,"), "{e}");
    let e = refusal("zero-shots", |f| {
        f.dataset("n_shots")
            .unwrap()
            .write_raw(&[10u64, 0, 10, 10])
            .unwrap()
    });
    assert!(e.contains("`n_shots` value 1 is 0"), "{e}");
    let e = refusal("version", |f| {
        f.attr("lidarsim_format_version")
            .unwrap()
            .write_scalar(&(FORMAT_VERSION + 1))
            .unwrap()
    });
    assert!(
        e.contains(&format!("format version {}", FORMAT_VERSION + 1)),
        "{e}"
    );
    let e = refusal("float-counts", |f| {
        f.unlink("counts").unwrap();
        f.new_dataset::<f64>()
            .shape([4, 1, 5])
            .create("counts")
            .unwrap()
            .write_raw(&[1.5; 20])
            .unwrap();
    });
    assert!(e.contains("`counts` holds floating-point"), "{e}");
    // 1e12 profiles declared, none stored (chunks never written)
    let e = refusal("huge", |f| {
        for name in ["counts", "n_shots", "time", "pulse_energy"] {
            f.unlink(name).unwrap();
        }
        let p = 1_000_000_000_000usize;
        f.new_dataset::<u16>()
            .chunk([1, 1, 5])
            .shape([p, 1, 5])
            .create("counts")
            .unwrap();
        f.new_dataset::<u64>()
            .chunk(1)
            .shape(p)
            .create("n_shots")
            .unwrap();
    });
    assert!(
        e.contains("`counts` declares") && e.contains("crafted"),
        "{e}"
    );
    let e = refusal("stray", |f| {
        f.new_dataset::<f64>()
            .shape([3, 5])
            .create("expected_signal")
            .unwrap();
    });
    assert!(e.contains("`expected_signal` is 3 × 5,"), "{e}");
}
