//! Pre-trigger bins (`acquisition.pretrigger_bins`, docs/file-format.md "Pre-trigger
//! bins"): a ground recorder's bins before the pulse leaves hold background and dark
//! counts only, come first in the file at negative range, shift the window's bins
//! without changing them, and are the first background bins; and the refusals where
//! they have no meaning.

mod common;

use std::path::{Path, PathBuf};

use common::cli::{lidarsim, ok, refused, scratch};
use common::{config_path, scenario};

const GROUND: &str = "ground/ground_532_overlap.toml";
/// The shipped ground config's pre-trigger bins.
const N: usize = 256;

fn simulate(dir: &Path, out: &str, args: &[&str]) -> PathBuf {
    let cfg = config_path(GROUND);
    let mut all = vec!["simulate", cfg.to_str().unwrap(), "-o", out];
    all.extend_from_slice(args);
    ok(lidarsim(dir, &all, &[]));
    dir.join(out)
}

fn read(f: &hdf5::File, name: &str) -> Vec<f64> {
    f.dataset(name)
        .unwrap_or_else(|_| panic!("no `{name}`"))
        .read_raw::<f64>()
        .unwrap()
}

/// The file's first N bins are the pre-trigger bins: their ranges continue the window's
/// grid below 0, they see nothing (signal, range weight, overlap, attenuated backscatter
/// and every extinction and backscatter exactly 0, T² = 1), and the window's bins after
/// them are bit for bit those of the same run without pre-trigger bins.
#[test]
fn pretrigger_bins_precede_the_window_and_see_nothing() {
    let dir = scratch("pretrigger-grid");
    let common = ["--profiles", "2", "--set", "acquisition.top_altitude_km=3"];
    let with = simulate(&dir, "with.h5", &common);
    let mut args = common.to_vec();
    args.extend(["--set", "acquisition.pretrigger_bins=0"]);
    let without = simulate(&dir, "without.h5", &args);
    let (f, g) = (
        hdf5::File::open(&with).unwrap(),
        hdf5::File::open(&without).unwrap(),
    );
    let n: i32 = f.attr("pretrigger_bins").unwrap().read_scalar().unwrap();
    assert_eq!(n as usize, N);
    let n0: i32 = g.attr("pretrigger_bins").unwrap().read_scalar().unwrap();
    assert_eq!(n0, 0);
    let (range, range0) = (read(&f, "range"), read(&g, "range"));
    assert_eq!(range.len(), range0.len() + N);
    // 7.5 m bins (50 ns): centres from -(N - 0.5)·Δr to -Δr/2, then the window's
    let dr = 299_792_458.0 * 5e-8 / 2.0;
    for (i, r) in range[..N].iter().enumerate() {
        let want = (i as f64 - N as f64 + 0.5) * dr;
        assert!((r - want).abs() < 1e-9, "bin {i}: range {r}, want {want}");
    }
    for name in [
        "range",
        "altitude",
        "range_weight",
        "overlap",
        "expected_signal",
        "attenuated_backscatter",
        "t2",
        "beta_aer",
        "alpha_total",
        "pressure",
    ] {
        let (a, b) = (read(&f, name), read(&g, name));
        let nb = range.len();
        let rows = a.len() / nb;
        assert_eq!(b.len(), rows * (nb - N), "{name}");
        for row in 0..rows {
            let (pre, window) = a[row * nb..(row + 1) * nb].split_at(N);
            assert_eq!(window, &b[row * (nb - N)..(row + 1) * (nb - N)], "{name}");
            let nothing = match name {
                "range" | "altitude" | "pressure" => continue,
                "t2" => 1.0,
                _ => 0.0,
            };
            assert!(pre.iter().all(|&v| v == nothing), "{name}: {pre:?}");
        }
    }
    // the state in the pre-trigger bins is the station's: the first window bin's air,
    // to within its 3.75 m of height (1.2e-4 of the pressure over 8 km scale height)
    let p = read(&f, "pressure");
    assert!(p[..N].iter().all(|&v| v == p[0]));
    assert!((p[0] / p[N] - 1.0).abs() < 1e-3 && p[0] > p[N]);
    std::fs::remove_dir_all(&dir).ok();
}

/// The counts of the pre-trigger bins are background and dark alone: over 40 profiles of
/// 256 bins their sum is Poisson with the mean `Σ (expected_background + expected_dark)
/// · n_shots` (a sky brightened so that the mean passes 2e5 and the test is sharp). The
/// sum's z-score is within ±4: false-alarm rate 6e-5, seed fixed. A leak of signal of
/// 1 % of the background into these bins moves z by more than 4.5 and fails it.
#[test]
fn pretrigger_counts_are_background_and_dark() {
    let dir = scratch("pretrigger-counts");
    let path = simulate(
        &dir,
        "bright.h5",
        &[
            "--profiles",
            "40",
            "--seed",
            "11",
            "--set",
            "acquisition.top_altitude_km=2",
            "--set",
            "background.radiance=2e14",
        ],
    );
    let f = hdf5::File::open(&path).unwrap();
    let counts: Vec<u64> = f.dataset("counts").unwrap().read_raw::<u64>().unwrap();
    let shots: Vec<u64> = f.dataset("n_shots").unwrap().read_raw::<u64>().unwrap();
    let bkg = read(&f, "expected_background");
    let dark = read(&f, "expected_dark");
    let nb = read(&f, "range").len();
    // static scene: (channel, bin) expectations, one channel
    assert_eq!(bkg.len(), nb);
    let mut sum = 0u64;
    let mut mean = 0.0;
    for (p, &m) in shots.iter().enumerate() {
        for i in 0..N {
            sum += counts[p * nb + i];
            mean += (bkg[i] + dark[i]) * m as f64;
        }
    }
    assert!(mean > 2e5, "too dim a sky for a sharp test: {mean}");
    let z = (sum as f64 - mean) / mean.sqrt();
    assert!(
        z.abs() < 4.0,
        "pre-trigger counts {sum}, expected {mean:.1}: z = {z:.2}"
    );
    assert_eq!(shots.len(), 40);
    std::fs::remove_dir_all(&dir).ok();
}

/// The pre-trigger bins are the first background bins, in order, before any bin above
/// the atmosphere (here a 100 km window has both).
#[test]
fn pretrigger_bins_come_first_among_the_background_bins() {
    let sc = scenario(
        GROUND,
        &[
            "acquisition.top_altitude_km=100",
            "instrument.bin_width_s=2e-6",
            "acquisition.pretrigger_bins=4",
        ],
    );
    let e = sc.expected().unwrap();
    let bins = &e.background_bin_indices;
    assert_eq!(&bins[..4], &[0, 1, 2, 3]);
    assert!(bins.len() > 40, "{}", bins.len());
    assert!(bins[4..].iter().all(|&i| e.altitude_m[i] > 86_000.0));
    assert_eq!(e.background_bins, bins.len());
    // a cap keeps the pre-trigger bins
    let capped = scenario(
        GROUND,
        &[
            "acquisition.top_altitude_km=100",
            "instrument.bin_width_s=2e-6",
            "acquisition.pretrigger_bins=4",
            "acquisition.background_bins=6",
        ],
    );
    assert_eq!(
        capped.expected().unwrap().background_bin_indices[..4],
        [0, 1, 2, 3]
    );
}

/// Where pre-trigger bins mean nothing the config is refused, naming the file and the
/// key: a space-borne window, a ground window that does not start at the station, and
/// more bins than the grid allows (before anything is allocated).
#[test]
fn pretrigger_bins_are_refused_where_they_mean_nothing() {
    let dir = scratch("pretrigger-refused");
    let ground = config_path(GROUND);
    let space = config_path("paper/scenario1.toml");
    for (cfg, set, words) in [
        (
            &space,
            "acquisition.pretrigger_bins=10",
            &["acquisition.pretrigger_bins", "space-borne"][..],
        ),
        (
            &ground,
            "acquisition.bottom_altitude_km=0.5",
            &["acquisition.pretrigger_bins", "station"][..],
        ),
        (
            &ground,
            "acquisition.pretrigger_bins=9999999",
            &["acquisition.pretrigger_bins", "allowed"][..],
        ),
        (
            &ground,
            "acquisition.pretrigger_bins=-1",
            &["pretrigger_bins"][..],
        ),
    ] {
        refused(
            &dir,
            &[
                "simulate",
                cfg.to_str().unwrap(),
                "-o",
                "x.h5",
                "--set",
                set,
            ],
            words,
            "x.h5",
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
