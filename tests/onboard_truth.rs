//! The truth of the onboard product (docs/file-format.md, "The truth of the onboard
//! product"), checked against references that do not use it: the native raw file of the
//! same draw (`onboard --raw`, one shot per profile), shot shares worked out by hand from
//! the ground speed, the counts themselves (the ideal-detector identity over many shots),
//! and the raw file's geolocation at the same profile centres.

mod common;

use std::path::Path;

use common::cli::{lidarsim, ok, scratch};
use common::config_path;

/// CALIOP's window for the `caliop` scheme (40 to −2 km).
const WINDOW: [&str; 4] = [
    "--set",
    "acquisition.top_altitude_km=40",
    "--set",
    "acquisition.bottom_altitude_km=-2",
];

/// `lidarsim onboard CFG WINDOW extra` in `dir`.
fn onboard(dir: &Path, cfg: &str, extra: &[&str]) {
    let c = config_path(cfg);
    let mut args = vec!["onboard", c.to_str().unwrap()];
    args.extend(WINDOW);
    args.extend(extra);
    ok(lidarsim(dir, &args, &[]));
}

/// Dataset `name` of `group` ("" for the root) of `file`, as f64 (or `T`), and its shape.
fn read<T: hdf5::H5Type>(file: &Path, group: &str, name: &str) -> (Vec<T>, Vec<usize>) {
    let f = hdf5::File::open(file).unwrap();
    let d = match group {
        "" => f.dataset(name),
        g => f.group(g).and_then(|g| g.dataset(name)),
    }
    .unwrap_or_else(|e| panic!("{group}/{name}: {e}"));
    (d.read_raw().unwrap(), d.shape())
}

fn f64s(file: &Path, group: &str, name: &str) -> Vec<f64> {
    read::<f64>(file, group, name).0
}

fn region_attr(file: &Path, group: &str, name: &str) -> f64 {
    let f = hdf5::File::open(file).unwrap();
    f.group(group)
        .unwrap()
        .attr(name)
        .unwrap()
        .read_scalar()
        .unwrap()
}

fn groups(file: &Path) -> Vec<String> {
    let f = hdf5::File::open(file).unwrap();
    let n = f.groups().unwrap().len();
    (0..n).map(|k| format!("region_{k}")).collect()
}

/// Along-track spacing of CALIOP's shots, m: the ground speed of a circular orbit at
/// 705 km (R/(R+h)·√(GM/(R+h))) over 20.16 Hz.
fn shot_spacing_m() -> f64 {
    let (r, gm, h) = (6_371_008.8f64, 3.986_004_418e14f64, 705e3);
    r / (r + h) * (gm / (r + h)).sqrt() / 20.16
}

/// A two-segment scene whose boundary falls half-way between shots 23 and 24: clear air,
/// then a cirrus at 9–11 km.
fn two_segments() -> String {
    let first_km = 23.5 * shot_spacing_m() / 1e3;
    format!(
        "scene.segments=[{{length_km={first_km}, layers=[]}}, {{length_km=500.0, layers=[\
         {{kind=\"cloud\", base_km=9.0, top_km=11.0, extinction_per_km=0.3, \
         lidar_ratio_sr=25.0, depolarization=0.4}}]}}]"
    )
}

/// The native bins of a region: `(first, merge)` found from the altitudes alone (the
/// region bin's altitude is the mean of its native bins' altitudes).
fn native_bins(raw_altitude: &[f64], region_altitude: &[f64], resolution_m: f64) -> (usize, usize) {
    let step = (raw_altitude[0] - raw_altitude[1]).abs();
    let merge = (resolution_m / step).round() as usize;
    let mean = |i: usize| raw_altitude[i..i + merge].iter().sum::<f64>() / merge as f64;
    let first = (0..=raw_altitude.len() - merge)
        .min_by(|&a, &b| {
            let d = |i| (mean(i) - region_altitude[0]).abs();
            d(a).total_cmp(&d(b))
        })
        .unwrap();
    assert!((mean(first) - region_altitude[0]).abs() < 1e-6);
    (first, merge)
}

/// With uniform:10 over a segment boundary after shot 23, profile 2 (shots 20–29) saw
/// the clear column 4 times and the cirrus 6: weights 0.4 and 0.6; the others one column.
/// Every region truth is the mean of the native raw file's truth of its column over the
/// merged bins (the expected signal the sum), `expected_signal = C·atb·range_weight` to
/// 1e-12, and the per-profile background, dark and pulse energy the means of the raw
/// file's over the profile's shots.
#[test]
fn a_straddling_profile_has_the_shares_of_its_shots_and_the_mean_native_truth() {
    let dir = scratch("onboard-truth-segments");
    let scene = two_segments();
    onboard(
        &dir,
        "instruments/caliop_532.toml",
        &[
            "--set",
            "acquisition.profiles=4",
            "--set",
            "instrument.pulse_energy_jitter=0.05",
            "--set",
            &scene,
            "--scheme",
            "uniform:10",
            "-o",
            "u.h5",
            "--raw",
            "raw.h5",
        ],
    );
    let (p, raw) = (dir.join("u.h5"), dir.join("raw.h5"));
    let (columns, shape) = read::<i32>(&p, "region_0", "profile_column");
    assert_eq!(shape, vec![6, 2]);
    assert_eq!(columns, vec![0, -1, 0, -1, 0, 1, 1, -1, 1, -1, 1, -1]);
    let weights = f64s(&p, "region_0", "profile_column_weight");
    assert_eq!(
        weights,
        vec![1.0, 0.0, 1.0, 0.0, 0.4, 0.6, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0]
    );
    // the cirrus is in column 1 only
    let beta_cld = f64s(&p, "region_0", "beta_cld");
    let bins = beta_cld.len() / 2;
    assert!(beta_cld[..bins].iter().all(|&b| b == 0.0));
    assert!(beta_cld[bins..].iter().any(|&b| b > 0.0));
    compare_with_native(&p, &raw, "region_0", 10);
    // the caliop scheme of the same draw: merged bins
    onboard(
        &dir,
        "instruments/caliop_532.toml",
        &[
            "--set",
            "acquisition.profiles=4",
            "--set",
            "instrument.pulse_energy_jitter=0.05",
            "--set",
            &scene,
            "--scheme",
            "caliop",
            "-o",
            "c.h5",
        ],
    );
    let c = dir.join("c.h5");
    for g in groups(&c) {
        let shots = region_attr(&c, &g, "shots_averaged") as usize;
        compare_with_native(&c, &raw, &g, shots);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The channel names of `group` of `file`.
fn channel_names(file: &Path, group: &str) -> Vec<String> {
    let names = read::<hdf5::types::VarLenUnicode>(file, group, "channel_name").0;
    names.iter().map(|n| n.as_str().to_string()).collect()
}

/// Region `g` (of `shots` shots a profile) of `product` against the native `raw` file,
/// every channel the region holds against the raw file's channel of that name.
fn compare_with_native(product: &Path, raw: &Path, g: &str, shots: usize) {
    let close = |a: f64, b: f64, what: &str| {
        assert!(
            (a - b).abs() <= 1e-12 * a.abs().max(b.abs()) + 1e-300,
            "{g} {what}: {a} against {b}"
        );
    };
    let raw_alt = f64s(raw, "", "altitude");
    let n = raw_alt.len();
    let alt = f64s(product, g, "altitude");
    let res = region_attr(product, g, "vertical_resolution_m");
    let (first, merge) = native_bins(&raw_alt, &alt, res);
    let raw_channels = channel_names(raw, "");
    let nch = raw_channels.len();
    let held: Vec<usize> = channel_names(product, g)
        .iter()
        .map(|h| raw_channels.iter().position(|r| r == h).unwrap())
        .collect();
    let (_, col_shape) = read::<f64>(product, g, "alpha_mol");
    let [columns, channels, bins] = col_shape[..] else {
        panic!("{col_shape:?}")
    };
    assert_eq!(channels, held.len());
    // the mean of `v` over region bin j's native bins, from native row `row`
    let mean = |v: &[f64], row: usize, j: usize| {
        let base = row * n + first + j * merge;
        v[base..base + merge].iter().sum::<f64>() / merge as f64
    };
    // every (column, held channel, bin) of the region with its raw row
    let mut cells = Vec::new();
    for col in 0..columns {
        for (h, &c) in held.iter().enumerate() {
            for j in 0..bins {
                cells.push(((col * channels + h) * bins + j, col * nch + c, j));
            }
        }
    }
    for name in [
        "alpha_mol",
        "alpha_aer",
        "alpha_cld",
        "alpha_o3",
        "alpha_total",
        "beta_mol",
        "beta_aer",
        "beta_cld",
        "t2",
        "lidar_ratio_cld",
        "ms_factor_cld",
        "depol_cld",
        "depol_mol",
        "depol_volume",
        "alpha_aer_bin_mean",
        "alpha_cld_bin_mean",
        "beta_aer_bin_mean",
        "beta_cld_bin_mean",
    ] {
        let (native, region) = (f64s(raw, "", name), f64s(product, g, name));
        assert_eq!(native.len(), columns * nch * n, "{name}");
        assert_eq!(region.len(), columns * channels * bins, "{name}");
        for &(i, row, j) in &cells {
            close(region[i], mean(&native, row, j), name);
        }
    }
    // a region bin's multiple-scattering factor weights its native bins' by extinction
    for species in ["aer", "cld"] {
        let name = format!("ms_factor_{species}_bin_mean");
        let (factor, region) = (f64s(raw, "", &name), f64s(product, g, &name));
        let alpha = f64s(raw, "", &format!("alpha_{species}_bin_mean"));
        let weighted: Vec<f64> = factor.iter().zip(&alpha).map(|(m, a)| m * a).collect();
        for &(i, row, j) in &cells {
            let a = mean(&alpha, row, j);
            let want = if a > 0.0 {
                mean(&weighted, row, j) / a
            } else {
                1.0
            };
            close(region[i], want, &name);
        }
    }
    let rw = f64s(raw, "", "range_weight");
    let region_rw = f64s(product, g, "range_weight");
    let constant = f64s(product, g, "lidar_constant");
    let raw_constant = f64s(raw, "", "lidar_constant");
    let (signal, atb) = (
        f64s(product, g, "expected_signal"),
        f64s(product, g, "attenuated_backscatter"),
    );
    for (j, w) in region_rw.iter().enumerate() {
        close(*w, mean(&rw, 0, j) * merge as f64, "range_weight");
    }
    for (i, (s, a)) in signal.iter().zip(&atb).enumerate() {
        let h = i / bins % channels;
        close(constant[h], raw_constant[held[h]], "lidar_constant");
        close(
            *s,
            constant[h] * a * region_rw[i % bins],
            "C·atb·range_weight",
        );
    }
    // the per-shot truth of the raw file's one-shot profiles, averaged over the shots:
    // the expected signal of each column (a static scene: its one column, (channel, bin))
    // and the background of each (profile, channel) in a changing scene (a static
    // scene: (channel, bin))
    let raw_signal = f64s(raw, "", "expected_signal");
    let raw_bkg = f64s(raw, "", "expected_background");
    let raw_dark = f64s(raw, "", "expected_dark");
    let bkg_per_profile = raw_bkg.len() != nch * n;
    let bkg_of = |shot: usize, c: usize| {
        if bkg_per_profile {
            raw_bkg[shot * nch + c]
        } else {
            raw_bkg[c * n]
        }
    };
    let raw_columns = read::<i32>(raw, "", "profile_column").0;
    let raw_slots = raw_columns.len() / f64s(raw, "", "time").len();
    let column_of = |shot: usize| raw_columns[shot * raw_slots] as usize;
    for shot in 0..30 {
        let col = column_of(shot);
        for (h, &c) in held.iter().enumerate() {
            for j in 0..bins {
                // one shot: its profile's signal is its column's
                let s = mean(&raw_signal, col * nch + c, j) * merge as f64;
                let i = (col * channels + h) * bins + j;
                close(signal[i], s, "expected_signal of the shot's column");
            }
        }
    }
    let raw_energy = f64s(raw, "", "pulse_energy");
    let (bkg, dark, energy) = (
        f64s(product, g, "expected_background"),
        f64s(product, g, "expected_dark"),
        f64s(product, g, "pulse_energy"),
    );
    // (profile, channel): each channel's laser line in both files
    assert_eq!(
        energy.len(),
        bkg.len(),
        "pulse_energy is (profile, channel)"
    );
    for p in 0..energy.len() / channels {
        let mean_of = |f: &dyn Fn(usize) -> f64| {
            (p * shots..(p + 1) * shots).map(f).sum::<f64>() / shots as f64
        };
        for (h, &c) in held.iter().enumerate() {
            let e = energy[p * channels + h];
            close(e, mean_of(&|s| raw_energy[s * nch + c]), "pulse_energy");
        }
        for (h, &c) in held.iter().enumerate() {
            let b = mean_of(&|s| bkg_of(s, c));
            close(bkg[p * channels + h], b, "expected_background");
            close(dark[p * channels + h], raw_dark[c * n], "expected_dark");
        }
    }
}

/// Every region of a three-channel product (CALIOP's per-channel layouts: 1064 nm in
/// regions of its own) holds the native truth of its own channels, averaged.
#[test]
fn every_channel_of_a_region_has_its_own_native_truth() {
    let dir = scratch("onboard-truth-channels");
    onboard(
        &dir,
        "instruments/caliop_3ch.toml",
        &[
            "--set",
            "acquisition.profiles=2",
            "--scheme",
            "caliop",
            "-o",
            "p.h5",
            "--raw",
            "raw.h5",
        ],
    );
    let (p, raw) = (dir.join("p.h5"), dir.join("raw.h5"));
    let held: Vec<usize> = groups(&p)
        .iter()
        .map(|g| channel_names(&p, g).len())
        .collect();
    assert_eq!(held, vec![2, 3, 3, 2, 1, 3]);
    for g in groups(&p) {
        let shots = region_attr(&p, &g, "shots_averaged") as usize;
        compare_with_native(&p, &raw, &g, shots);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// E[counts] = n_shots·(E/E0·Σ_k w_k·expected_signal[k] + merge·(background + dark)) for
/// an ideal detector: the counts summed over every profile of each region against the
/// sum of that expectation, in every bin with at least 100 expected counts (Bonferroni
/// over the bins, a false alarm 1e-3 of the time: 4.9 σ) and over each region (3.3 σ,
/// 1e-3), on a static scene with a jittered laser and a two-column scene (fixed seed). A
/// 1 % error in the expectation is ≥ 10 σ of the product's total (1.7e6 counts).
#[test]
fn the_ideal_detector_identity_holds_over_many_shots() {
    let dir = scratch("onboard-truth-identity");
    let scene = two_segments();
    let runs: [&[&str]; 2] = [
        &[
            "--set",
            "instrument.pulse_energy_jitter=0.1",
            "-o",
            "static.h5",
        ],
        &["--set", &scene, "-o", "scene.h5"],
    ];
    for extra in runs {
        let mut args = vec!["--set", "acquisition.profiles=200", "--scheme", "caliop"];
        args.extend(extra);
        onboard(&dir, "instruments/caliop_532.toml", &args);
        let p = dir.join(extra[extra.len() - 1]);
        let expected: f64 = groups(&p).iter().map(|g| check_identity(&p, g)).sum();
        // a 1 % error in the expectation is ≥ 10 σ of the product's total
        assert!(0.01 * expected.sqrt() > 10.0, "{expected} counts expected");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The identity over region `g` of `p` (one channel); returns the counts expected.
fn check_identity(p: &Path, g: &str) -> f64 {
    let (counts, shape) = read::<u64>(p, g, "counts");
    let [profiles, _, bins] = shape[..] else {
        panic!()
    };
    let shots = region_attr(p, g, "shots_averaged");
    let merge = (region_attr(p, g, "vertical_resolution_m") / 30.0).round();
    assert_eq!(region_attr(p, g, "native_bins_merged"), merge);
    let signal = f64s(p, g, "expected_signal");
    let (bkg, dark) = (
        f64s(p, g, "expected_background"),
        f64s(p, g, "expected_dark"),
    );
    let energy = f64s(p, g, "pulse_energy");
    let e0 = f64s(p, g, "nominal_pulse_energy")[0];
    let columns = read::<i32>(p, g, "profile_column").0;
    let weights = f64s(p, g, "profile_column_weight");
    let slots = columns.len() / profiles;
    let (mut observed, mut expected) = (vec![0.0f64; bins], vec![0.0f64; bins]);
    for q in 0..profiles {
        for j in 0..bins {
            let mut s = 0.0;
            for k in 0..slots {
                if columns[q * slots + k] >= 0 {
                    let col = columns[q * slots + k] as usize;
                    s += weights[q * slots + k] * signal[col * bins + j];
                }
            }
            // one channel: pulse_energy (profile, channel) is one value a profile
            expected[j] += shots * (energy[q] / e0 * s + merge * (bkg[q] + dark[q]));
            observed[j] += counts[q * bins + j] as f64;
        }
    }
    for j in 0..bins {
        if expected[j] >= 100.0 {
            let z = (observed[j] - expected[j]) / expected[j].sqrt();
            assert!(
                z.abs() < 4.9,
                "{g} bin {j}: {} counts, {} expected",
                observed[j],
                expected[j]
            );
        }
    }
    let (o, e) = (observed.iter().sum::<f64>(), expected.iter().sum::<f64>());
    let z = (o - e) / e.sqrt();
    assert!(z.abs() < 3.3, "{g}: {o} counts, {e} expected (z = {z})");
    e
}

/// Each region profile's latitude, longitude and along-track distance are those the raw
/// file gives a profile of the same shots (`simulate` with 15-shot profiles against the
/// 15-shot region), and `counts` names them in its `coordinates`; under the sun along the
/// orbit, every region's truth, background included, is the native truth averaged.
#[test]
fn region_profiles_are_geolocated_at_their_centres() {
    let dir = scratch("onboard-truth-geolocation");
    onboard(
        &dir,
        "instruments/caliop_orbit.toml",
        &[
            "--set",
            "acquisition.profiles=4",
            "--scheme",
            "caliop",
            "-o",
            "p.h5",
            "--raw",
            "native.h5",
        ],
    );
    // the orbit's scene (segments, broken cloud) under the sun: the background changes
    // from shot to shot, every region's truth is still the native truth averaged
    let (p, native) = (dir.join("p.h5"), dir.join("native.h5"));
    let bkg = f64s(&native, "", "expected_background");
    let last = bkg[bkg.len() - 1];
    assert!(bkg[0] > 0.0 && bkg[0] != last, "{} {last}", bkg[0]);
    for g in groups(&p) {
        let shots = region_attr(&p, &g, "shots_averaged") as usize;
        compare_with_native(&p, &native, &g, shots);
    }
    let c = config_path("instruments/caliop_orbit.toml");
    ok(lidarsim(
        &dir,
        &[
            "simulate",
            c.to_str().unwrap(),
            "--profiles",
            "4",
            "-o",
            "raw.h5",
        ],
        &[],
    ));
    let raw = dir.join("raw.h5");
    assert_eq!(region_attr(&p, "region_0", "shots_averaged"), 15.0);
    for name in ["latitude", "longitude", "along_track_distance"] {
        let (a, b) = (f64s(&p, "region_0", name), f64s(&raw, "", name));
        assert_eq!(a.len(), 4);
        for (x, y) in a.iter().zip(&b) {
            assert!(
                (x - y).abs() <= 1e-9 * y.abs().max(1.0),
                "{name}: {x} against {y}"
            );
        }
    }
    let f = hdf5::File::open(&p).unwrap();
    let coords: hdf5::types::VarLenUnicode = f
        .dataset("region_3/counts")
        .unwrap()
        .attr("coordinates")
        .unwrap()
        .read_scalar()
        .unwrap();
    assert_eq!(
        coords.as_str(),
        "time latitude longitude along_track_distance altitude channel_name"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `tools/product_curtain.py`'s `stitch` puts every region's counts per shot and metre
/// into a 30 m grid of the 1-shot profiles' times: each grid cell holds the value of the
/// region bin and profile that contains it, read here from the file with h5py.
#[test]
fn the_stitched_curtain_holds_every_region_at_its_resolution() {
    if !common::python_has(
        "the_stitched_curtain_holds_every_region_at_its_resolution",
        &["numpy", "h5py", "xarray", "h5netcdf"],
    ) {
        return;
    }
    let dir = scratch("onboard-truth-curtain");
    onboard(
        &dir,
        "instruments/caliop_532.toml",
        &[
            "--set",
            "acquisition.profiles=2",
            "--scheme",
            "caliop",
            "-o",
            "p.h5",
        ],
    );
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools");
    let script = r#"
import sys, h5py, numpy as np
sys.path.insert(0, sys.argv[1])
from product_curtain import stitch
c = stitch("p.h5", "532_total")
assert c.dims == ("altitude", "time"), c.dims
assert c.shape == (1400, 30), c.shape
assert not np.isnan(c.values).any()
step = np.diff(c.altitude.values)
assert np.allclose(step, step[0]) and abs(abs(step[0]) - 29.95) < 0.1, step[0]
f = h5py.File("p.h5")
checked = 0
for g in f:
    r = f[g]
    counts, alt = r["counts"][:, 0, :], r["altitude"][:]
    shots, res = r.attrs["shots_averaged"], r.attrs["vertical_resolution_m"]
    for p in range(counts.shape[0]):
        cells = c.isel(time=slice(p * shots, (p + 1) * shots))
        for j in range(counts.shape[1]):
            inside = np.abs(c.altitude.values - alt[j]) < res / 2 - 1.0
            want = counts[p, j] / shots / res
            got = cells.values[inside]
            assert got.size >= shots and np.all(got == want), (g, p, j, got, want)
            checked += 1
print(checked)
"#;
    let out = common::cli::python_in(&dir, &["-c", script, tools.to_str().unwrap()]);
    let checked: usize = out.trim().parse().unwrap();
    // 2 × 33 + 6 × 55 + 10 × 200 + 30 × 290 + 30 × 5 region cells
    assert_eq!(checked, 2 * 33 + 6 * 55 + 10 * 200 + 30 * 290 + 30 * 5);
    std::fs::remove_dir_all(&dir).ok();
}
