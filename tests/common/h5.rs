//! Reading a raw file's variables in tests, with the hdf5 crate.

use std::path::Path;

use super::cli::{lidarsim, ok};

/// A float variable's values, C order.
pub fn floats(f: &hdf5::File, name: &str) -> Vec<f64> {
    f.dataset(name)
        .unwrap_or_else(|_| panic!("no `{name}`"))
        .read_raw::<f64>()
        .unwrap()
}

/// A string variable's values.
pub fn strings(f: &hdf5::File, name: &str) -> Vec<String> {
    f.dataset(name)
        .unwrap_or_else(|_| panic!("no `{name}`"))
        .read_raw::<hdf5::types::VarLenUnicode>()
        .unwrap()
        .iter()
        .map(|s| s.as_str().to_string())
        .collect()
}

/// A (channel, bin) variable, or a one-column file's (column, channel, bin), as one row
/// per channel.
pub fn channel_rows(f: &hdf5::File, name: &str, channels: usize) -> Vec<Vec<f64>> {
    let v = floats(f, name);
    let bins = v.len() / channels;
    v.chunks(bins).map(<[f64]>::to_vec).collect()
}

/// `lidarsim simulate CONFIG -o OUT --profiles N` in `dir`, opened.
pub fn simulate(dir: &Path, config: &Path, out: &str, profiles: &str) -> hdf5::File {
    simulate_with(dir, config, out, profiles, &[])
}

/// [`simulate`] with more arguments after `--profiles N` (`--method`, `--set`, …).
pub fn simulate_with(
    dir: &Path,
    config: &Path,
    out: &str,
    profiles: &str,
    more: &[&str],
) -> hdf5::File {
    let mut args = vec![
        "simulate",
        config.to_str().unwrap(),
        "-o",
        out,
        "--profiles",
        profiles,
    ];
    args.extend_from_slice(more);
    ok(lidarsim(dir, &args, &[]));
    hdf5::File::open(dir.join(out)).unwrap()
}

/// `lidarsim validate CONFIG --realizations 200 --set ACCUMULATION` is CONSISTENT (exit
/// 0; its statistics' false-alarm rate is `validate`'s own; fixed seed): a preset on
/// short profiles, `accumulation` the `acquisition.accumulation_time_s=…` override.
pub fn validate_preset_consistent(dir: &Path, config: &Path, accumulation: &str) {
    let args = [
        "validate",
        config.to_str().unwrap(),
        "--realizations",
        "200",
        "--set",
        accumulation,
    ];
    let o = lidarsim(dir, &args, &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}");
    assert!(out.contains("CONSISTENT"), "{out}");
}

/// `lidarsim validate CONFIG --method M` is CONSISTENT (exit 0) for the aggregate and the
/// shot path (its statistics' false-alarm rate is `validate`'s own; fixed seed).
pub fn validate_consistent_both_ways(dir: &Path, config: &Path) {
    for method in ["aggregate", "shot"] {
        let args = ["validate", config.to_str().unwrap(), "--method", method];
        let o = lidarsim(dir, &args, &[]);
        let out = String::from_utf8_lossy(&o.stdout).to_string();
        assert_eq!(o.status.code(), Some(0), "{method}: {out}");
        assert!(out.contains("CONSISTENT"), "{out}");
    }
}

/// Variable `name` of every profile, (profile, channel, bin) C order, rebuilt from
/// whatever form the file holds (format 3's rows, one column's (channel, bin), format
/// 4's compact form): the readers' rule, `raw_file::per_profile`, which
/// tests/compact_truth.rs checks bit for bit against `simulate --truth per-profile`.
pub fn per_profile(f: &hdf5::File, name: &str) -> Vec<f64> {
    use lidarsim::output::raw_file::{per_profile::PerProfileReader, read};
    let path = std::path::PathBuf::from(f.filename());
    let h = read::check(&path, f).unwrap();
    let reader = PerProfileReader::new(&path, f, &h).unwrap();
    reader.rows(name, 0..h.n_profiles).unwrap()
}
