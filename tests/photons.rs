//! `simulate --photons` and `lidarsim histogram` (issue 42, docs/photons.md): the
//! histogram of the events is the raw file's counts bit for bit (at the run's resolution,
//! and summed at whole multiples of it); the raw file is the same bytes with and without
//! the photons; the refusals.

mod common;

use common::cli::{lidarsim, ok, python_in, refused, scratch, simulate_with_photons};
use common::config_path;

/// The raw file's `counts`, as u64, C order (profile, channel, bin).
fn raw_counts(path: &std::path::Path) -> Vec<u64> {
    hdf5::File::open(path)
        .unwrap()
        .dataset("counts")
        .unwrap()
        .read_raw::<u64>()
        .unwrap()
}

/// The events' histogram at the run's resolution equals the raw counts, bit for bit;
/// at twice the bin width and twice the shots, the raw counts summed in pairs of bins
/// and of profiles.
fn histogram_is_counts(name: &str, config: &str, profiles: usize, more: &[&str]) {
    let dir = scratch(name);
    simulate_with_photons(&dir, config, &profiles.to_string(), more);
    let counts = raw_counts(&dir.join("raw.h5"));
    assert!(
        counts.iter().sum::<u64>() > 1000,
        "{name}: too few counts to judge"
    );
    let h = lidarsim::photons::histogram::histogram(&dir.join("ph.h5"), None, None).unwrap();
    assert_eq!(h.profiles, profiles);
    assert_eq!(h.counts.len(), counts.len());
    assert!(
        h.counts == counts,
        "{name}: the events' histogram is not the raw counts"
    );
    // the origins add up to the counts
    for i in 0..counts.len() {
        let s: u64 = h.by_origin.iter().map(|o| o[i]).sum();
        assert_eq!(s, counts[i], "{name}: origins of element {i}");
    }
    // the CLI writes the same histogram
    ok(lidarsim(&dir, &["histogram", "ph.h5", "-o", "h.h5"], &[]));
    assert!(raw_counts(&dir.join("h.h5")) == counts);
    // twice the bin width and twice the shots: sums of the raw counts
    let (nc, nb) = (h.channels.len(), h.bins);
    let shots = hdf5::File::open(dir.join("raw.h5"))
        .unwrap()
        .dataset("n_shots")
        .unwrap()
        .read_raw::<u64>()
        .unwrap()[0];
    let dr = h.bin_range_m;
    let h2 = lidarsim::photons::histogram::histogram(
        &dir.join("ph.h5"),
        Some(2.0 * dr),
        Some(2 * shots),
    )
    .unwrap();
    let (nb2, np2) = (nb.div_ceil(2), profiles.div_ceil(2));
    assert_eq!((h2.bins, h2.profiles), (nb2, np2));
    let mut want = vec![0u64; np2 * nc * nb2];
    for p in 0..profiles {
        for c in 0..nc {
            for b in 0..nb {
                want[((p / 2) * nc + c) * nb2 + b / 2] += counts[(p * nc + c) * nb + b];
            }
        }
    }
    assert!(
        h2.counts == want,
        "{name}: 2x histogram is not the summed counts"
    );
}

#[test]
fn histogram_equals_counts_mpl_like() {
    // dead time (non-paralyzable, 2 channels) and afterpulsing; 1,000-shot profiles
    histogram_is_counts(
        "ph-mpl",
        "ground/mpl_like.toml",
        3,
        &["--set", "acquisition.accumulation_time_s=0.4"],
    );
}

#[test]
fn histogram_equals_counts_ground_532_depol() {
    histogram_is_counts(
        "ph-depol",
        "ground/ground_532_depol.toml",
        3,
        &["--set", "acquisition.accumulation_time_s=0.4"],
    );
}

#[test]
fn histogram_equals_counts_icesat2_like() {
    // 16 pixels, each with its dead time; day background for many events
    histogram_is_counts(
        "ph-is2",
        "instruments/icesat2_like.toml",
        4,
        &["--set", "background.radiance=7e17"],
    );
}

#[test]
fn histogram_equals_counts_through_the_walk() {
    // a paralyzable detector on bins narrower than 2τ: the arrival walk draws the
    // shots, and the events are its registrations
    histogram_is_counts(
        "ph-walk",
        "instruments/icesat2_like.toml",
        2,
        &[
            "--set",
            "background.radiance=7e17",
            "--set",
            "instrument.detector.dead_time_model=\"paralyzable\"",
            "--set",
            "instrument.detector.dead_time_s=1.5e-8",
        ],
    );
    // the walk's registrations: a paralyzable detector records an arrival only τ or
    // more after the one before, so a pixel's events of one shot are τ apart at least
    // (events placed in their bins without the walk would not be)
    let f = hdf5::File::open(scratch_path("ph-walk").join("ph.h5")).unwrap();
    let read_u = |n: &str| f.dataset(n).unwrap().read_raw::<u64>().unwrap();
    let (pulse, channel, pixel) = (
        read_u("heights/ph_id_pulse"),
        read_u("heights/ph_id_channel"),
        read_u("heights/ph_id_pixel"),
    );
    let tof = f
        .dataset("heights/time_of_flight")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    let mut last: std::collections::HashMap<(u64, u64, u64), f64> = Default::default();
    let mut pairs = 0;
    for i in 0..tof.len() {
        let key = (pulse[i], channel[i], pixel[i]);
        if let Some(t) = last.insert(key, tof[i]) {
            assert!(tof[i] >= t, "events out of time order");
            assert!(
                tof[i] - t >= 1.5e-8 - 1e-12,
                "two events {} s apart",
                tof[i] - t
            );
            pairs += 1;
        }
    }
    assert!(pairs > 1000, "too few pairs ({pairs}) to judge the spacing");
}

/// The scratch directory `scratch(name)` made (without emptying it).
fn scratch_path(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("lidarsim-shard-{name}-{}", std::process::id()))
}

#[test]
fn raw_file_is_the_same_bytes_with_and_without_photons() {
    let dir = scratch("ph-bytes");
    let cfg = config_path("ground/mpl_like.toml");
    let base = [
        "simulate",
        cfg.to_str().unwrap(),
        "--profiles",
        "3",
        "--method",
        "shot",
        "--set",
        "acquisition.accumulation_time_s=0.4",
    ];
    let mut with = base.to_vec();
    with.extend(["-o", "a.h5", "--photons", "ph.h5"]);
    let mut without = base.to_vec();
    without.extend(["-o", "b.h5"]);
    ok(lidarsim(&dir, &with, &[]));
    ok(lidarsim(&dir, &without, &[]));
    let a = std::fs::read(dir.join("a.h5")).unwrap();
    let b = std::fs::read(dir.join("b.h5")).unwrap();
    assert!(a == b, "the raw file changes with --photons");
    // and the photon file itself is the same bytes for the same seed
    let mut again = base.to_vec();
    again.extend(["-o", "c.h5", "--photons", "ph2.h5", "--threads", "1"]);
    ok(lidarsim(&dir, &again, &[]));
    let p1 = std::fs::read(dir.join("ph.h5")).unwrap();
    let p2 = std::fs::read(dir.join("ph2.h5")).unwrap();
    assert!(p1 == p2, "the photon file depends on the thread count");
}

#[test]
fn refusals() {
    let dir = scratch("ph-refuse");
    let paper = config_path("paper/scenario1.toml");
    let is2 = config_path("instruments/icesat2_like.toml");
    let (p, i) = (paper.to_str().unwrap(), is2.to_str().unwrap());
    // `simulate CONFIG -o raw.h5 --profiles N MORE --photons ph.h5`
    let photons = |config: &str, profiles: &str, more: &[&str], words: &[&str]| {
        let mut args = vec!["simulate", config, "-o", "raw.h5", "--profiles", profiles];
        args.extend_from_slice(more);
        args.extend(["--photons", "ph.h5"]);
        refused(&dir, &args, words, "ph.h5");
        assert!(!dir.join("raw.h5").exists(), "{args:?} left raw.h5");
    };
    photons(
        p,
        "2",
        &["--method", "aggregate"],
        &["--photons", "--method shot"],
    );
    let components = ["--method", "shot", "--components"];
    photons(p, "2", &components, &["--photons", "--components"]);
    // a day of ICESat-2 day-time events (~1e11): the photon file cannot fit
    photons(
        i,
        "2e6",
        &["--set", "background.radiance=7e17"],
        &["--photons"],
    );
    // the histogram's own inputs
    refused(
        &dir,
        &["histogram", p, "-o", "h.h5"],
        &["photon file"],
        "h.h5",
    );
}

/// What a retrieval developer's xarray makes of the two files: the histogram with the
/// raw file's named dimensions and coordinates (profile, channel with `channel_name`,
/// bin with `range`), `time` decoded to datetime64 from the run's start, the counts'
/// total the events'; the photon file's `heights` and `pulse` groups indexed by their
/// `delta_time`, the origin a CF flag (values 1..8 with meanings). Read by xarray (h5netcdf)
/// and netCDF4 (the netCDF-C library), skipped loudly where they are missing (a failure
/// under CI).
#[test]
fn xarray_reads_the_histogram_and_the_photon_file_by_name() {
    if !common::python_has("photons xarray", &["xarray", "h5netcdf", "netCDF4"]) {
        return;
    }
    let dir = scratch("photons_xarray");
    simulate_with_photons(&dir, "instruments/icesat2_like.toml", "4", &[]);
    let n_events = hdf5::File::open(dir.join("ph.h5"))
        .unwrap()
        .dataset("heights/ph_id_pulse")
        .unwrap()
        .size();
    ok(lidarsim(
        &dir,
        &[
            "histogram",
            "ph.h5",
            "-o",
            "h.h5",
            "--bin-width",
            "30",
            "--shots",
            "400",
        ],
        &[],
    ));
    let script = format!(
        r#"
import numpy as np, xarray as xr
for engine in ("h5netcdf", "netcdf4"):
    h = xr.open_dataset("h.h5", engine=engine)
    assert h.counts.dims == ("profile", "channel", "bin"), h.counts.dims
    assert list(h.channel.values) == [0] and str(h.channel_name.values[0]) == "532_total"
    assert np.issubdtype(h.time.dtype, np.datetime64), h.time.dtype
    assert h.range.dims == ("bin",) and h.sizes["bin"] == 417, h.sizes
    assert int(h.counts.sel(channel=0).sum()) == {n_events}
    origins = [v for v in h.data_vars if v.endswith("_counts")]
    assert int(sum(h[v] for v in origins).sum()) == {n_events}, origins
    e = xr.open_dataset("ph.h5", engine=engine, group="heights")
    assert e.ph_id_pulse.dims == ("delta_time",) and e.sizes["delta_time"] == {n_events}
    assert np.issubdtype(e.delta_time.dtype, np.datetime64)
    assert list(e.truth_origin.attrs["flag_values"]) == list(range(1, 9))
    assert len(e.truth_origin.attrs["flag_meanings"].split()) == 8
    p = xr.open_dataset("ph.h5", engine=engine, group="pulse")
    assert p.energy.dims == ("delta_time",) and p.sizes["delta_time"] == 1600
print("ok")
"#
    );
    python_in(&dir, &["-c", &script]);
}
