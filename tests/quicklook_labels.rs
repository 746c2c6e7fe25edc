//! The quicklook's labels and panels read off the PNG (issue 40, docs/figures.md): the
//! tick labels' text — the UTC clock, an orbit's latitude and longitude — found by exact
//! template matching of the embedded font's glyphs, at the pixel of the value they
//! name; the title's instrument, date and place; one panel per channel (and truth),
//! counted by their axis lines; the S/N mask against the file's Eq. 4 S/N; bad values
//! refused in one line. Every expected string is computed here from the file's own
//! `time`, `latitude`, `longitude`, `start_time` and `config`, not by the tick code.

mod common;

use std::path::Path;

use common::cli::{lidarsim, ok, refused, scratch};
use common::config_path;
use common::h5::floats;
use common::image::{Image, axis_rows, find_text_at, rendered_at};
use lidarsim::figures::quicklook::{self, PANEL_HEIGHT, TITLE_HEIGHT, View, XAxis};

/// A text attribute of the file's root.
fn text_attr(f: &hdf5::File, name: &str) -> String {
    f.attr(name)
        .unwrap()
        .read_scalar::<hdf5::types::VarLenUnicode>()
        .unwrap()
        .as_str()
        .to_string()
}

/// Unix seconds of an RFC 3339 time.
fn unix(t: &str) -> f64 {
    humantime::parse_rfc3339(t)
        .unwrap()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
}

/// `HH:MM` or `HH:MM:SS` of Unix seconds (UTC: seconds of the day).
fn clock(t: f64, seconds: bool) -> String {
    let s = t.round() as i64 % 86400;
    if seconds {
        format!("{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{:02}:{:02}", s / 3600, s / 60 % 60)
    }
}

/// A latitude with `d` decimals, `62.02°S`; a longitude to 0.1°, `8.8°W` (`0.0°` at 0).
fn lat_text(v: f64, d: usize) -> String {
    format!("{:.*}°{}", d, v.abs(), if v > 0.0 { 'N' } else { 'S' })
}
fn lon_text(v: f64) -> String {
    let t = format!("{:.1}", v.abs());
    if t == "0.0" {
        return "0.0°".into();
    }
    format!("{t}°{}", if v > 0.0 { 'E' } else { 'W' })
}

/// The x axis of the panel whose axis line is row `y` of `img`: its first and last
/// pixel columns (the unbroken dark run along that row).
fn axis_ends(img: &Image, y: usize) -> (usize, usize) {
    let dark = |x: usize| img.rgb[y * img.w + x].iter().all(|&v| v < 80);
    let (mut best, mut run_start, mut out) = (0, 0, (0, 0));
    for x in 0..img.w {
        if !dark(x) {
            run_start = x + 1;
        } else if x + 1 - run_start > best {
            best = x + 1 - run_start;
            out = (run_start, x);
        }
    }
    out
}

/// Checks that `labels` — `(text, value)` along x, the value in the axis' unit spanning
/// `span` — are each drawn once under the first panel's axis line, centred within 3
/// pixels of the value's column; returns how many were found there.
fn check_ticks(img: &Image, labels: &[(String, f64)], span: (f64, f64)) {
    let axis = axis_rows(img, 1000)[0];
    let (x0, x1) = axis_ends(img, axis);
    for (text, v) in labels {
        let found = find_text_at(img, text, 13, axis + 2, axis + 30);
        assert_eq!(found.len(), 1, "{text} found at {found:?}");
        let width = rendered_at(text, 13)[0].len() as f64;
        let centre = found[0].0 as f64 + 0.5 * width;
        let want = x0 as f64 + (v - span.0) / (span.1 - span.0) * (x1 - x0) as f64;
        assert!(
            (centre - want).abs() <= 3.0,
            "{text}: centred at {centre}, its value at {want}"
        );
    }
}

/// The CALIOP-like orbit segment, 200 profiles (2.5 min from 62°S southwards): its
/// default x axis reads latitude and longitude at every 2° of latitude (the track
/// crosses 8.4° of latitude; the 1-2-5 step giving about six ticks is 2°), each label
/// at the along-track distance where the file's sub-satellite latitude crosses it, the
/// longitude there interpolated linearly between the two profiles; `--x-axis time` reads
/// the UTC clock every 30 s (HH:MM:SS); the title names the config's instrument, the
/// date and times of the first and last profile and the track's ends. One panel.
#[test]
fn an_orbit_reads_latitude_longitude_and_utc() {
    let dir = scratch("ql-labels-orbit");
    let config = config_path("instruments/caliop_orbit.toml");
    let args = ["simulate", config.to_str().unwrap(), "-o", "orbit.h5"];
    ok(lidarsim(
        &dir,
        &[&args[..], &["--profiles", "200"]].concat(),
        &[],
    ));
    let f = hdf5::File::open(dir.join("orbit.h5")).unwrap();
    let (x, lat, lon) = (
        floats(&f, "along_track_distance"),
        floats(&f, "latitude"),
        floats(&f, "longitude"),
    );
    let time = floats(&f, "time");
    let n = x.len();
    let half = |v: &[f64]| 0.5 * (v[n - 1] - v[0]) / (n - 1) as f64;
    let span_km = ((x[0] - half(&x)) / 1e3, (x[n - 1] + half(&x)) / 1e3);
    // where the track crosses every multiple of 2° of latitude
    let mut labels = Vec::new();
    for k in 0..n - 1 {
        let (a, b) = (lat[k], lat[k + 1]);
        for m in -45..=45 {
            let v = 2.0 * m as f64;
            if (a.min(b) < v) && (v <= a.max(b)) {
                let s = (v - a) / (b - a);
                let lo = lon[k] + s * (lon[k + 1] - lon[k]);
                let km = (x[k] + s * (x[k + 1] - x[k])) / 1e3;
                labels.push((format!("{} {}", lat_text(v, 0), lon_text(lo)), km));
            }
        }
    }
    assert_eq!(labels.len(), 4, "{labels:?}");
    ok(lidarsim(
        &dir,
        &["quicklook", "orbit.h5", "--png", "lat.png"],
        &[],
    ));
    let img = Image::read(&dir.join("lat.png"));
    assert_eq!(axis_rows(&img, 1000).len(), 1, "one panel");
    check_ticks(&img, &labels, span_km);

    // the title: instrument — date and times — track
    let config: toml::Table = text_attr(&f, "config").parse().unwrap();
    let t0 = unix(&text_attr(&f, "start_time"));
    let (ta, tb) = (t0 + time[0] - half(&time), t0 + time[n - 1] + half(&time));
    let date = humantime::format_rfc3339_seconds(
        std::time::UNIX_EPOCH + std::time::Duration::from_secs_f64(ta),
    )
    .to_string();
    let title = format!(
        "{} — {} {}–{} UTC — track {} {} to {} {}",
        config["name"].as_str().unwrap(),
        &date[..10],
        clock(ta.floor(), false),
        clock(tb.floor(), false),
        lat_text(lat[0], 2),
        lon_text(lon[0]),
        lat_text(lat[n - 1], 2),
        lon_text(lon[n - 1]),
    );
    let found = find_text_at(&img, &title, 18, 0, TITLE_HEIGHT as usize);
    assert_eq!(found.len(), 1, "title {title:?} found at {found:?}");

    // the UTC clock every 30 s
    ok(lidarsim(
        &dir,
        &[
            "quicklook",
            "orbit.h5",
            "--png",
            "time.png",
            "--x-axis",
            "time",
        ],
        &[],
    ));
    let img = Image::read(&dir.join("time.png"));
    let (lo, hi) = (time[0] - half(&time), time[n - 1] + half(&time));
    let ticks: Vec<(String, f64)> = (((t0 + lo) / 30.0).ceil() as i64..=((t0 + hi) / 30.0) as i64)
        .map(|k| (clock(k as f64 * 30.0, true), k as f64 * 30.0 - t0))
        .collect();
    assert_eq!(ticks.len(), 5, "{ticks:?}");
    check_ticks(&img, &ticks, (lo, hi));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A ground lidar's 30 min from 11:40 UTC (`ground_532_depol`, 60 profiles of 30 s, at a
/// station set to 45°N 6°E): `--channels 532_parallel,532_perpendicular --truth` draws
/// four panels (each channel's signal and truth), each titled with its channel; every
/// panel's x axis reads the UTC clock every 5 min; the title names the instrument, the
/// date and times and the station.
#[test]
fn a_ground_file_draws_a_panel_per_channel_on_the_utc_clock() {
    let dir = scratch("ql-labels-ground");
    let raw = ground(&dir);
    ok(lidarsim(
        &dir,
        &[
            "quicklook",
            "g.h5",
            "--png",
            "q.png",
            "--channels",
            "532_parallel,532_perpendicular",
            "--truth",
        ],
        &[],
    ));
    let img = Image::read(&dir.join("q.png"));
    let axes = axis_rows(&img, 1000);
    assert_eq!(axes.len(), 4, "axis lines at rows {axes:?}");
    for (k, channel) in [
        "532_parallel",
        "532_parallel",
        "532_perpendicular",
        "532_perpendicular",
    ]
    .iter()
    .enumerate()
    {
        let y0 = (TITLE_HEIGHT + PANEL_HEIGHT * k as u32) as usize;
        let words = if k % 2 == 0 {
            format!("{channel}: background-subtracted")
        } else {
            format!("{channel}: truth")
        };
        let found = find_text_at(&img, &words, 17, y0, y0 + 40);
        assert_eq!(found.len(), 1, "panel {k}: {words:?} at {found:?}");
        assert!(axes[k] > y0 && axes[k] < y0 + PANEL_HEIGHT as usize);
    }
    let f = hdf5::File::open(&raw).unwrap();
    let time = floats(&f, "time");
    let n = time.len();
    let half = 0.5 * (time[n - 1] - time[0]) / (n - 1) as f64;
    let t0 = unix(&text_attr(&f, "start_time"));
    let (lo, hi) = (time[0] - half, time[n - 1] + half);
    let ticks: Vec<(String, f64)> = (((t0 + lo) / 300.0).floor() as i64 + 1
        ..((t0 + hi) / 300.0).ceil() as i64)
        .map(|k| (clock(k as f64 * 300.0, false), k as f64 * 300.0 - t0))
        .collect();
    assert!(ticks.iter().any(|(t, _)| t == "12:00"), "{ticks:?}");
    check_ticks(&img, &ticks, (lo, hi));
    let config: toml::Table = text_attr(&f, "config").parse().unwrap();
    let title = format!(
        "{} — 2024-03-15 {}–{} UTC — station 45.00°N 6.0°E",
        config["name"].as_str().unwrap(),
        clock(t0 + lo, false),
        clock(t0 + hi, false)
    );
    let found = find_text_at(&img, &title, 18, 0, TITLE_HEIGHT as usize);
    assert_eq!(found.len(), 1, "title {title:?} found at {found:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `ground_532_depol`, 60 profiles of 30 s from 11:40 UTC at 45°N 6°E (without dead
/// time, so that the aggregate method is exact): `g.h5` in `dir`.
fn ground(dir: &Path) -> std::path::PathBuf {
    let config = config_path("ground/ground_532_depol.toml");
    ok(lidarsim(
        dir,
        &[
            "simulate",
            config.to_str().unwrap(),
            "-o",
            "g.h5",
            "--profiles",
            "60",
            "--method",
            "aggregate",
            "--set",
            "instrument.detector.dead_time_s=0",
            "--set",
            "acquisition.start_time=2024-03-15T11:40:00Z",
            "--set",
            "platform.latitude_deg=45",
            "--set",
            "platform.longitude_deg=6",
        ],
        &[],
    ));
    dir.join("g.h5")
}

/// `--mask-snr X` greys the cells whose bins' S/N, estimated from the counts, is below
/// X: against the file's Eq. 4 S/N of a profile (`snr_eq4`, the truth), every row of
/// the grid whose bins all have an Eq. 4 S/N below X − 4 is masked in every column (more
/// than half its bins below X), every row whose bins are all above X + 4 in none. The
/// estimate's error is about 1 in S/N (the noise of the counts), so a bin 4 from X falls
/// on the wrong side with a probability of 3e-5, and a cell (about 3 bins of one profile)
/// needs half of its bins to do so: a false alarm below 1e-6 over the test's ~200 rows.
#[test]
fn the_snr_mask_follows_the_files_eq4_snr() {
    let dir = scratch("ql-labels-mask");
    let raw = ground(&dir);
    let f = hdf5::File::open(&raw).unwrap();
    let snr = floats(&f, "snr_eq4"); // (channel, bin): the first channel's first
    let altitude = floats(&f, "altitude");
    // bins the overlap hides (range_weight 0) are drawn grey whatever the mask
    let seen = floats(&f, "range_weight");
    let n_bins = altitude.len();
    let x = 10.0;
    let view = View {
        mask_snr: Some(x),
        ..View::default()
    };
    let q = quicklook::read_view(&raw, None, false, view).unwrap();
    let (threshold, mask) = q.mask.as_ref().unwrap();
    assert_eq!(*threshold, x);
    let share = mask.means();
    let (z0, z1) = mask.z;
    let rows = mask.rows;
    let dz = (z1 - z0) / rows as f64;
    let (mut masked_rows, mut clear_rows) = (0, 0);
    for r in 0..rows {
        let (top, bottom) = (z1 - r as f64 * dz, z1 - (r + 1) as f64 * dz);
        let bins: Vec<f64> = (0..n_bins)
            .filter(|&i| {
                let z = altitude[i] / 1e3;
                z > bottom + 0.01 && z < top - 0.01 && seen[i] > 0.0
            })
            .map(|i| snr[i])
            .collect();
        if bins.is_empty() {
            continue;
        }
        let row = &share[r * mask.cols..(r + 1) * mask.cols];
        if bins.iter().all(|&s| s < x - 4.0) {
            masked_rows += 1;
            assert!(
                row.iter().all(|&s| s > 0.5),
                "row {r} at {bottom} km not masked"
            );
        } else if bins.iter().all(|&s| s > x + 4.0) {
            clear_rows += 1;
            assert!(
                row.iter().all(|&s| s <= 0.5),
                "row {r} at {bottom} km masked"
            );
        }
    }
    eprintln!("{masked_rows} rows masked, {clear_rows} clear");
    assert!(
        masked_rows > 20 && clear_rows > 20,
        "{masked_rows} {clear_rows}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad values are refused in one line, exit 2, no PNG: an unknown channel, a negative or
/// NaN S/N, an unknown axis, a latitude axis on a ground file.
#[test]
fn bad_values_are_refused_in_one_line() {
    let dir = scratch("ql-labels-bad");
    ground(&dir);
    fn q<'a>(more: &[&'a str]) -> Vec<&'a str> {
        [&["quicklook", "g.h5", "--png", "bad.png"][..], more].concat()
    }
    let cases: [(&[&str], &[&str]); 6] = [
        (
            &["--channels", "532_parallel,1064_total"],
            &["g.h5", "1064_total"],
        ),
        (&["--channel", "355"], &["g.h5", "355"]),
        (&["--mask-snr", "-1"], &["--mask-snr", "S/N"]),
        (&["--mask-snr", "nan"], &["--mask-snr", "S/N"]),
        (&["--x-axis", "lat"], &["--x-axis", "latitude, along-track"]),
        (&["--x-axis", "latitude"], &["g.h5", "along_track_distance"]),
    ];
    for (more, words) in cases {
        refused(&dir, &q(more), words, "bad.png");
    }
    assert_eq!(XAxis::parse("profile"), Some(XAxis::Profile));
    let _ = std::fs::remove_dir_all(&dir);
}
