//! The `sweep` and `curtain` figures (issue 23), checked without eyes: one panel per
//! metric (the image grows with the metrics), a field and a colour bar (many distinct
//! colours; a pixel column right of the field running through viridis once), decodable
//! PNGs.

mod common;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::image::Image;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lidarsim-figures-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn lidarsim(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_lidarsim"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn sweep(dir: &Path, name: &str, vary: &[&str], metrics: &[&str]) -> Image {
    let cfg = common::config_path("paper/scenario1.toml");
    let png = dir.join(format!("{name}.png"));
    let csv = dir.join(format!("{name}.csv"));
    let mut args = vec![
        "sweep".to_string(),
        cfg.to_str().unwrap().into(),
        "--csv".into(),
        csv.to_str().unwrap().into(),
        "--png".into(),
        png.to_str().unwrap().into(),
    ];
    for v in vary {
        args.extend(["--vary".into(), v.to_string()]);
    }
    for m in metrics {
        args.extend(["--metric".into(), m.to_string()]);
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    lidarsim(&args);
    Image::read(&png)
}

/// Two varied keys: a heatmap per metric, stacked; each with a field and a colour bar.
#[test]
fn a_two_key_sweep_draws_one_heatmap_per_metric() {
    let dir = scratch("sweep2");
    let vary = [
        "instrument.pulse_energy_j=1e-4..1e-1:log:6",
        "instrument.rep_rate_hz=10..250:5",
    ];
    let one = sweep(&dir, "one", &vary, &["snr_at:11km"]);
    let two = sweep(&dir, "two", &vary, &["snr_at:11km", "max_altitude:snr=3"]);
    assert_eq!(one.w, two.w);
    assert_eq!(two.h, 2 * one.h, "{} then {}", one.h, two.h);
    assert!(one.distinct() > 150, "{} colours", one.distinct());
    // each panel's colour bar: the strip at the right of the panel
    for k in 0..2 {
        let (y0, y1) = (k * one.h, (k + 1) * one.h);
        assert!(
            two.has_colour_bar(two.w - 160, two.w, y0, y1, 100),
            "panel {k} has no colour bar"
        );
        // and a field: many colours left of the bar
        let field: HashSet<[u8; 3]> = (y0..y1)
            .flat_map(|y| (0..two.w - 160).map(move |x| (x, y)))
            .map(|(x, y)| two.rgb[y * two.w + x])
            .filter(|c| !(c[0] == c[1] && c[1] == c[2]))
            .collect();
        assert!(field.len() > 20, "panel {k}: {} colours", field.len());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// One varied key: a line chart per metric, stacked; the line drawn in its colour.
#[test]
fn a_one_key_sweep_draws_one_line_per_metric() {
    let dir = scratch("sweep1");
    let vary = ["instrument.pulse_energy_j=1e-4..1e-1:log:12"];
    let one = sweep(&dir, "one", &vary, &["time_to_snr:10@10km"]);
    let three = sweep(
        &dir,
        "three",
        &vary,
        &["time_to_snr:10@10km", "snr_at:10km", "mean_laser_power_w"],
    );
    assert_eq!(one.w, three.w);
    assert_eq!(three.h, 3 * one.h, "{} then {}", one.h, three.h);
    let line = [31u8, 119, 180];
    for k in 0..3 {
        let drawn = (k * one.h..(k + 1) * one.h)
            .flat_map(|y| (0..three.w).map(move |x| y * three.w + x))
            .filter(|&i| three.rgb[i] == line)
            .count();
        assert!(drawn > 500, "panel {k}: {drawn} line pixels");
    }
    // anti-aliased text gives greys, but the figure is not blank
    assert!(one.distinct() > 20, "{} colours", one.distinct());
    std::fs::remove_dir_all(&dir).ok();
}

/// The curtain of a short simulated run: a field of many colours and a colour bar.
#[test]
fn a_curtain_has_a_field_and_a_colour_bar() {
    let dir = scratch("curtain");
    let cfg = common::config_path("paper/scenario1.toml");
    let raw = dir.join("raw.h5");
    let png = dir.join("curtain.png");
    lidarsim(&[
        "simulate",
        cfg.to_str().unwrap(),
        "-o",
        raw.to_str().unwrap(),
        "--profiles",
        "4",
        "--seed",
        "7",
    ]);
    lidarsim(&[
        "curtain",
        raw.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
    ]);
    let img = Image::read(&png);
    assert_eq!((img.w, img.h), (1200, 600));
    assert!(img.distinct() > 150, "{} colours", img.distinct());
    assert!(img.has_colour_bar(img.w - 120, img.w, 0, img.h, 100));
    // the field: four profiles side by side, many colours down each
    let field: HashSet<[u8; 3]> = (0..img.h)
        .flat_map(|y| (0..img.w - 120).map(move |x| (x, y)))
        .map(|(x, y)| img.rgb[y * img.w + x])
        .filter(|c| !(c[0] == c[1] && c[1] == c[2]))
        .collect();
    assert!(field.len() > 30, "{} colours in the field", field.len());
    std::fs::remove_dir_all(&dir).ok();
}
