//! The figure `speed_vs_error.png`: time per profile against the max KS distance, per
//! method and (fL, TC).

use std::path::Path;

use plotters::prelude::*;

use crate::cases::Method;
use crate::figure::{self, FONT};
use crate::measure::ks_floor;
use crate::report::sci;
use crate::{Mode, Row};

const W: u32 = 1200;
const H: u32 = 800;

fn method_colour(m: Method) -> RGBColor {
    match m {
        Method::ShotDense => RGBColor(31, 119, 180),
        Method::ShotSparse => RGBColor(255, 127, 14),
        Method::ShotAuto => RGBColor(44, 160, 44),
        Method::Aggregate => RGBColor(0, 0, 0),
        Method::AggregateNormal(t) => {
            if t >= 0.1 {
                RGBColor(214, 39, 40)
            } else if t >= 0.01 {
                RGBColor(148, 103, 189)
            } else if t >= 0.001 {
                RGBColor(140, 86, 75)
            } else {
                RGBColor(227, 119, 194)
            }
        }
    }
}

pub(crate) fn plot(rows: &[Row], path: &Path, mode: &Mode) {
    figure::register();
    let mut rgb = vec![255u8; (W * H * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (W, H)).into_drawing_area();
        root.fill(&WHITE).expect("fill");
        let (tmin, tmax) = rows.iter().fold((f64::INFINITY, 0.0f64), |a, r| {
            (a.0.min(r.time_s), a.1.max(r.time_s))
        });
        let xmin = 1e-5;
        let xmax = 1.0;
        let ymin = 10f64.powf(tmin.log10().floor());
        let ymax = 10f64.powf(tmax.log10().ceil());
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "Time per profile against error, paper scenarios 1, 3, 4 (one thread{})",
                    if mode.quick { ", quick mode" } else { "" }
                ),
                (FONT, 26),
            )
            .margin(16)
            .x_label_area_size(60)
            .y_label_area_size(90)
            .build_cartesian_2d((xmin..xmax).log_scale(), (ymin..ymax).log_scale())
            .expect("chart");
        chart
            .configure_mesh()
            .x_desc("max over bins of the KS distance to the exact Poisson law (filled: measured with R profiles; open: exact bound)")
            .y_desc("time per profile (s)")
            .x_label_formatter(&|x| sci(*x, 0))
            .y_label_formatter(&|y| sci(*y, 0))
            .label_style((FONT, 17))
            .axis_desc_style((FONT, 18))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .expect("mesh");
        // noise floor of the largest R
        let r_max = rows.iter().map(|r| r.r).max().unwrap_or(1);
        let bins = rows.first().map(|r| r.bins).unwrap_or(1);
        let fl = ks_floor(bins, r_max);
        // dashed vertical line (log y: dashes of equal ratio)
        let grey = RGBColor(120, 120, 120);
        let n_dash = 40;
        let ly =
            |i: usize| 10f64.powf(ymin.log10() + (ymax / ymin).log10() * i as f64 / n_dash as f64);
        chart
            .draw_series((0..n_dash).step_by(2).map(|i| {
                PathElement::new(vec![(fl, ly(i)), (fl, ly(i + 1))], grey.stroke_width(2))
            }))
            .expect("floor")
            .label(format!("KS floor at R = {r_max} (95 %)"))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(2))
            });
        let cfg_of = |r: &Row| match (r.rep_rate_hz as u64, r.accumulation_s as u64) {
            (10, 1) => 0,
            (10, 100) => 1,
            _ => 2,
        };
        for m in Method::all() {
            let c = method_colour(m);
            let pts: Vec<&Row> = rows.iter().filter(|r| r.method == m).collect();
            // (x, y, configuration, filled): measured KS filled, exact bound open
            let mut marks: Vec<(f64, f64, usize, bool)> = pts
                .iter()
                .map(|r| (r.max_ks.max(xmin), r.time_s, cfg_of(r), true))
                .collect();
            marks.extend(pts.iter().filter_map(|r| {
                r.ks_bound
                    .filter(|b| b.1 > 0)
                    .map(|b| (b.0.max(xmin), r.time_s, cfg_of(r), false))
            }));
            let style = |f: bool| if f { c.filled() } else { c.stroke_width(2) };
            chart
                .draw_series(
                    marks
                        .iter()
                        .filter(|p| p.2 == 0)
                        .map(|p| Circle::new((p.0, p.1), 6, style(p.3))),
                )
                .expect("points")
                .label(m.name())
                .legend(move |(x, y)| Circle::new((x + 10, y), 6, c.filled()));
            chart
                .draw_series(
                    marks
                        .iter()
                        .filter(|p| p.2 == 1 && p.3)
                        .map(|p| TriangleMarker::new((p.0, p.1), 8, style(true))),
                )
                .expect("points");
            // TriangleMarker is always filled: open triangles as a closed path
            chart
                .draw_series(marks.iter().filter(|p| p.2 == 1 && !p.3).map(|p| {
                    EmptyElement::at((p.0, p.1))
                        + PathElement::new(vec![(0, -8), (7, 4), (-7, 4), (0, -8)], style(false))
                }))
                .expect("points");
            chart
                .draw_series(marks.iter().filter(|p| p.2 == 2).map(|p| {
                    EmptyElement::at((p.0, p.1)) + Rectangle::new([(-6, -6), (6, 6)], style(p.3))
                }))
                .expect("points");
        }
        let dark = RGBColor(60, 60, 60);
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .expect("legend")
            .label("(fL, TC) = 10 Hz × 1 s")
            .legend(move |(x, y)| Circle::new((x + 10, y), 6, dark.filled()));
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .expect("legend")
            .label("(fL, TC) = 10 Hz × 100 s")
            .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 8, dark.filled()));
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .expect("legend")
            .label("(fL, TC) = 250 Hz × 10 s")
            .legend(move |(x, y)| Rectangle::new([(x + 4, y - 6), (x + 16, y + 6)], dark.filled()));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(180, 180, 180))
            .label_font((FONT, 16))
            .draw()
            .expect("legend");
        root.present().expect("present");
    }
    figure::write_png(&rgb, W, H, path);
}
