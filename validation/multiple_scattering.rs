//! Multiple scattering through a cirrus and a stratocumulus (issue 22, docs/model.md
//! §4j): the bin-averaged attenuated backscatter of single scattering, of the
//! `constant` model with the usual η (0.6 for cirrus, 0.7 for stratocumulus), of the
//! `small_angle` model and of the `small_and_wide_angle` model, side by side. Writes `multiple_scattering.png` into the output
//! folder and prints the values at a few altitudes.
//!
//! ```text
//! cargo run --release --example multiple_scattering -- [--out validation/reports]
//! ```
//!
//! Left: `configs/ground/cirrus_small_angle.toml` (zenith, 1 mrad field of view, a
//! 9–11 km ice cirrus of optical depth 1, 30 µm). Right: the CALIOP-like preset
//! (`configs/instruments/caliop_532.toml`, 705 km, 130 µrad, beam 1/e half-width 50 µrad)
//! over a 0.8–1.5 km water stratocumulus of 8 km⁻¹ (τ = 5.6, 10 µm), the shipped
//! orbit's broken cells.

#[path = "figure.rs"]
mod figure;

use std::path::{Path, PathBuf};

use figure::FONT;
use lidarsim::scenario::{ExpectedProfile, Scenario};
use plotters::prelude::*;

/// One panel: a config, its overrides, the constant model's η and the altitude range.
struct Panel {
    title: &'static str,
    config: &'static str,
    overrides: Vec<String>,
    layer: &'static str,
    eta: f64,
    altitude_km: (f64, f64),
}

fn expected(config: &str, overrides: &[String]) -> ExpectedProfile {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(config);
    Scenario::load(&path, overrides)
        .and_then(|s| s.expected())
        .unwrap_or_else(|e| panic!("{config}: {e}"))
}

/// (single scattering, constant η, small angle, small and wide angle) attenuated
/// backscatter of the panel.
fn profiles(p: &Panel) -> [ExpectedProfile; 4] {
    let with = |model: &str, eta: f64| {
        let mut ov = p.overrides.clone();
        ov.push(format!("multiple_scattering.model=\"{model}\""));
        ov.push(format!(
            "atmosphere.layers=[{{ {}, multiple_scattering = {eta} }}]",
            p.layer
        ));
        expected(p.config, &ov)
    };
    [
        with("constant", 1.0),
        with("constant", p.eta),
        with("small_angle", 1.0),
        with("small_and_wide_angle", 1.0),
    ]
}

fn main() {
    let mut out = PathBuf::from("validation/reports");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--out" {
            out = PathBuf::from(args.next().expect("--out DIR"));
        }
    }
    let panels = [
        Panel {
            title: "Ground lidar, cirrus (τ = 1, 30 µm, 1 mrad)",
            config: "ground/cirrus_small_angle.toml",
            overrides: vec![],
            layer: "kind = \"cloud\", phase = \"ice\", base_km = 9.0, top_km = 11.0, \
                    extinction_per_km = 0.5, lidar_ratio_sr = 25.0, depolarization = 0.4, \
                    effective_radius_um = 30.0",
            eta: 0.6,
            altitude_km: (8.0, 13.0),
        },
        Panel {
            title: "CALIOP-like, stratocumulus (τ = 5.6, 10 µm, 130 µrad)",
            config: "instruments/caliop_532.toml",
            overrides: vec!["instrument.beam_divergence_rad=5e-5".into()],
            layer: "kind = \"cloud\", base_km = 0.8, top_km = 1.5, extinction_per_km = 8.0, \
                    lidar_ratio_sr = 18.0, depolarization = 0.03",
            eta: 0.7,
            altitude_km: (0.0, 2.5),
        },
    ];
    let all: Vec<[ExpectedProfile; 4]> = panels.iter().map(profiles).collect();
    for (p, e) in panels.iter().zip(&all) {
        println!(
            "{}\n  altitude_km  single  constant(eta={})  small_angle  small_and_wide_angle",
            p.title, p.eta
        );
        for i in (0..e[0].n_bins()).step_by(if p.eta < 0.65 { 40 } else { 4 }) {
            let z = e[0].altitude_m[i] / 1e3;
            if z >= p.altitude_km.0 && z <= p.altitude_km.1 {
                println!(
                    "  {z:8.2}  {:.3e}  {:.3e}  {:.3e}  {:.3e}",
                    e[0].attenuated_backscatter[i],
                    e[1].attenuated_backscatter[i],
                    e[2].attenuated_backscatter[i],
                    e[3].attenuated_backscatter[i]
                );
            }
        }
    }
    let path = out.join("multiple_scattering.png");
    plot(&panels, &all, &path);
    println!("wrote {}", path.display());
}

fn plot(panels: &[Panel], all: &[[ExpectedProfile; 4]], path: &Path) {
    const W: u32 = 1200;
    const H: u32 = 650;
    figure::register();
    let mut rgb = vec![255u8; (W * H * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (W, H)).into_drawing_area();
        root.fill(&WHITE).expect("fill");
        let halves = root.split_evenly((1, 2));
        for ((area, p), e) in halves.iter().zip(panels).zip(all) {
            let in_view = |i: usize| {
                let z = e[0].altitude_m[i] / 1e3;
                z >= p.altitude_km.0 && z <= p.altitude_km.1
            };
            let values = e.iter().flat_map(|x| {
                (0..x.n_bins())
                    .filter(|&i| in_view(i))
                    .map(|i| x.attenuated_backscatter[i])
            });
            let top = values.clone().fold(0.0, f64::max) * 3.0;
            let least = values.filter(|v| *v > 0.0).fold(f64::MAX, f64::min);
            let bottom = (top * 1e-9).max(least * 0.5);
            let mut chart = ChartBuilder::on(area)
                .caption(p.title, (FONT, 19))
                .margin(14)
                .x_label_area_size(55)
                .y_label_area_size(60)
                .build_cartesian_2d((bottom..top).log_scale(), p.altitude_km.0..p.altitude_km.1)
                .expect("chart");
            chart
                .configure_mesh()
                .x_desc("attenuated backscatter (m⁻¹ sr⁻¹)")
                .y_desc("altitude (km)")
                .x_label_formatter(&|x| format!("{x:.0e}"))
                .label_style((FONT, 15))
                .axis_desc_style((FONT, 16))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .expect("mesh");
            let names = [
                "single scattering".to_string(),
                format!("constant η = {}", p.eta),
                "small angle (Hogan 2008)".to_string(),
                "small + wide angle (Hogan & Battaglia 2008)".to_string(),
            ];
            let colours = [
                RGBColor(120, 120, 120),
                RGBColor(31, 119, 180),
                RGBColor(214, 39, 40),
                RGBColor(44, 160, 44),
            ];
            for ((x, name), colour) in e.iter().zip(names).zip(colours) {
                let line: Vec<(f64, f64)> = (0..x.n_bins())
                    .filter(|&i| in_view(i) && x.attenuated_backscatter[i] > bottom)
                    .map(|i| (x.attenuated_backscatter[i], x.altitude_m[i] / 1e3))
                    .collect();
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        line,
                        colour.stroke_width(2),
                    )))
                    .expect("line")
                    .label(name)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .label_font((FONT, 14))
                .background_style(WHITE.mix(0.9))
                .border_style(BLACK)
                .draw()
                .expect("legend");
        }
        root.present().expect("present");
    }
    figure::write_png(&rgb, W, H, path);
}
