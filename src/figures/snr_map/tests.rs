//! Tests of the S/N map.

use super::contours::{dash, seg_len};
use super::layout::{PLOT_B, PLOT_L, PLOT_R, PLOT_T};
use super::*;
use std::path::{Path, PathBuf};

/// A fresh scratch directory for one test.
fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lidarsim_snr_map_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn log_times(n: usize) -> Vec<f64> {
    (0..n)
        .map(|j| 10f64.powf(3.0 * j as f64 / (n - 1) as f64))
        .collect()
}

/// snr = s1(z)·sqrt(TC): s1 falls from 30 at 0 km to 0.01 at 30 km, ×10 in a
/// cloud at 10–12 km and 0 in its shadow at 8.5–10 km; 300 m bins.
fn synthetic_map() -> SnrMap {
    let altitude_km: Vec<f64> = (0..=100).map(|i| i as f64 * 0.3).collect();
    let accumulation_time_s = log_times(80);
    let s1 = |z: f64| {
        let clear = 30.0 * (-z / 3.747).exp();
        if (10.0..=12.0).contains(&z) {
            10.0 * clear
        } else if (8.5..10.0).contains(&z) {
            0.0
        } else {
            clear
        }
    };
    let snr = altitude_km
        .iter()
        .map(|&z| {
            accumulation_time_s
                .iter()
                .map(|&t| s1(z) * t.sqrt())
                .collect()
        })
        .collect();
    SnrMap {
        altitude_km,
        accumulation_time_s,
        snr,
        title: "Scenario 1 — cirrus 10–12 km + polluted aerosol".into(),
        subtitle: "E0 = 1 J, fL = 10 Hz, A = 0.1 m², 532 nm, night".into(),
    }
}

fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Renders `map` and writes it to `path` (the command goes through safe_file).
fn write_png(path: &Path, map: &SnrMap) -> std::result::Result<(), String> {
    std::fs::write(path, png_bytes(map)?).map_err(|e| e.to_string())
}

#[test]
fn snr_contours_follow_the_analytic_curve() {
    // snr = 30·exp(-z/5)·sqrt(TC) is linear in (log10 TC, z) after log10, so the
    // contour is exact: S/N = L at z = 5·ln(30·sqrt(TC)/L). Altitudes descending.
    let altitude_km: Vec<f64> = (0..=100).rev().map(|i| i as f64 * 0.3).collect();
    let accumulation_time_s = log_times(61);
    let snr = altitude_km
        .iter()
        .map(|&z| {
            accumulation_time_s
                .iter()
                .map(|&t| 30.0 * (-z / 5.0f64).exp() * t.sqrt())
                .collect()
        })
        .collect();
    let map = SnrMap {
        altitude_km,
        accumulation_time_s,
        snr,
        title: String::new(),
        subtitle: String::new(),
    };
    let grid = Grid::new(&map).unwrap();
    assert!(grid.y.windows(2).all(|w| w[0] < w[1]));
    for level in CONTOUR_LEVELS {
        // the lines the figure draws (before they are mapped to pixels)
        let lines = grid.contours(level);
        assert_eq!(lines.len(), 1, "level {level}");
        for &(lx, z) in &lines[0] {
            let want = 5.0 * (30.0 * 10f64.powf(lx).sqrt() / level).ln();
            assert!(
                (z - want).abs() < 1e-9,
                "S/N {level} at TC {}: z {z} vs {want}",
                10f64.powf(lx)
            );
        }
        // Runs from TC = 1 s to the right edge (1000 s) or, for S/N = 1, out of the top (30 km).
        let (a, b) = (lines[0][0], lines[0][lines[0].len() - 1]);
        let (start, end) = if a.0 < b.0 { (a, b) } else { (b, a) };
        assert!(start.0.abs() < 1e-12, "level {level} starts at {start:?}");
        assert!(
            (end.0 - 3.0).abs() < 1e-12 || (end.1 - 30.0).abs() < 1e-12,
            "level {level} ends at {end:?}"
        );
    }
}

#[test]
fn axis_ticks_are_round() {
    // plot's 1-2-5 steps (this file's own had 2.5 too; none of these spans used it)
    use crate::figures::plot::ticks::nice_step;
    assert_eq!(nice_step(30.0, 7.0), 5.0);
    assert_eq!(nice_step(39.9, 7.0), 5.0);
    assert_eq!(nice_step(6.0, 7.0), 1.0);
    assert_eq!(nice_step(0.9, 7.0), 0.1);
    assert_eq!(nice_step(600.0, 7.0), 100.0);
    // the ticks the figure labels
    let grid = Grid::new(&synthetic_map()).unwrap();
    let z: Vec<f64> = (0..=6).map(|k| 5.0 * k as f64).collect();
    assert_eq!(grid.z_ticks(), z);
    assert_eq!(grid.tc_ticks(), vec![1.0, 10.0, 100.0, 1000.0]);
}

#[test]
fn dashes_alternate_with_gaps() {
    let dashes = dash(&[(0.0, 0.0), (50.0, 0.0), (50.0, 50.0)], 9.0, 6.0);
    // 100 px with period 15: 6 full dashes and a 10 px remainder (9 on, 1 off) -> 7.
    assert_eq!(dashes.len(), 7);
    let len: f64 = dashes
        .iter()
        .map(|d| d.windows(2).map(|w| seg_len(w[0], w[1])).sum::<f64>())
        .sum();
    assert!((len - 63.0).abs() < 1e-9, "{len}");
}

// --- PNG ----------------------------------------------------------------

#[test]
fn writes_a_decodable_png_of_the_right_size_with_text_and_colour() {
    let dir = scratch_dir("png");
    let path = dir.join("snr.png");
    write_png(&path, &synthetic_map()).unwrap();
    let (w, h, rgb) = decode(&path);
    assert_eq!((w, h), (WIDTH, HEIGHT));
    let at = |x: u32, y: u32| {
        let i = ((y * w + x) * 3) as usize;
        (rgb[i], rgb[i + 1], rgb[i + 2])
    };
    // The title was rendered: dark pixels in its band, above the plot.
    let dark = (0..PLOT_T as u32 - 40)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let (r, g, b) = at(x, y);
            r < 100 && g < 100 && b < 100
        })
        .count();
    assert!(dark > 300, "title band has only {dark} dark pixels");
    // Near the ground at TC = 1000 s S/N ≈ 950: bright yellow-green.
    let (r, g, b) = at(PLOT_R as u32 - 3, PLOT_B as u32 - 3);
    assert!(g > 200 && b < 100 && r > 150, "({r}, {g}, {b})");
    // In the cloud shadow S/N = 0: the bottom colour of the scale.
    let y_shadow = PLOT_B as f64 - 9.25 / 30.0 * (PLOT_B - PLOT_T) as f64;
    assert_eq!(
        at(((PLOT_L + PLOT_R) / 2) as u32 + 17, y_shadow as u32),
        (68, 1, 84)
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn odd_but_valid_maps_are_drawn() {
    let dir = scratch_dir("odd");
    let base = || SnrMap {
        altitude_km: vec![5.0, 1.0],
        accumulation_time_s: vec![1.0, 1000.0],
        snr: vec![vec![0.0, 0.0], vec![0.0, 0.0]],
        title: String::new(),
        subtitle: String::new(),
    };
    let mut cases = vec![("all_zero", base())];
    let mut m = base();
    m.snr = vec![vec![1e12, 1e12], vec![1e12, 1e12]];
    m.title = "x".repeat(400);
    cases.push(("huge_snr_long_title", m));
    let mut m = base();
    m.accumulation_time_s = vec![2.0, 5.0];
    m.snr = vec![vec![0.5, 2.0], vec![5.0, 20.0]];
    cases.push(("under_a_decade", m));
    let mut m = base();
    m.altitude_km = vec![-0.5, 1e-3];
    m.accumulation_time_s = vec![1e-3, 1e-2];
    m.snr = vec![vec![3.0, 3.0], vec![3.0, 3.0]];
    cases.push(("flat_at_a_level", m));
    for (name, map) in cases {
        let path = dir.join(format!("{name}.png"));
        write_png(&path, &map).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(decode(&path).0, WIDTH, "{name}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_inputs_are_errors_and_write_nothing() {
    let dir = scratch_dir("bad");
    let path = dir.join("bad.png");
    let good = synthetic_map();
    let mut cases: Vec<(&str, SnrMap, &str)> = Vec::new();
    let empty = SnrMap {
        altitude_km: vec![],
        accumulation_time_s: vec![],
        snr: vec![],
        title: String::new(),
        subtitle: String::new(),
    };
    cases.push(("empty", empty, "at least 2"));
    let mut m = good.clone();
    m.altitude_km.truncate(1);
    m.snr.truncate(1);
    cases.push(("one altitude", m, "at least 2"));
    let mut m = good.clone();
    m.accumulation_time_s.truncate(1);
    m.snr.iter_mut().for_each(|r| r.truncate(1));
    cases.push(("one time", m, "at least 2"));
    for (what, v) in [
        ("NaN", f64::NAN),
        ("inf", f64::INFINITY),
        ("negative", -1.0),
    ] {
        let mut m = good.clone();
        m.snr[7][3] = v;
        cases.push((what, m, "snr[7][3]"));
    }
    let mut m = good.clone();
    m.snr[4].pop();
    cases.push(("ragged", m, "snr[4]"));
    let mut m = good.clone();
    m.snr.pop();
    cases.push(("rows", m, "rows"));
    let mut m = good.clone();
    m.accumulation_time_s.swap(3, 4);
    cases.push(("not increasing", m, "strictly increasing"));
    let mut m = good.clone();
    m.accumulation_time_s[0] = 0.0;
    cases.push(("zero time", m, "accumulation_time_s[0]"));
    let mut m = good.clone();
    m.altitude_km[5] = m.altitude_km[6];
    cases.push(("duplicate altitude", m, "more than once"));
    let mut m = good.clone();
    m.altitude_km[2] = f64::NAN;
    cases.push(("NaN altitude", m, "altitude_km[2]"));
    for (what, map, needle) in cases {
        let reason = write_png(&path, &map).expect_err(what);
        assert!(
            reason.contains(needle),
            "{what}: {reason:?} lacks {needle:?}"
        );
        assert!(!path.exists(), "{what}: a file was written");
    }
    std::fs::remove_dir_all(dir).unwrap();
}
