//! The small-angle multiple-scattering model's cost (issue 22, docs/model.md §4j): the
//! PVC pass over a 3,400-gate column (CALIOP's 30 m bins from 100 km down, a
//! stratocumulus and a cirrus), and the whole expectation of the CALIOP-like preset
//! with `small_angle` against `constant` (the model adds its bin pass to the exact bin
//! integrals).
//!
//! `RAYON_NUM_THREADS=1 cargo bench --bench multiple_scattering`

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use lidarsim::atmosphere::multiple_scattering::{Footprint, Step, small_angle_ratios};
use lidarsim::atmosphere::wide_angle::{Gate, MAX_GATES, wide_angle_backscatter};
use lidarsim::scenario::Scenario;

/// 3,400 gates of 30 m from 705 km down: cirrus (0.3 km⁻¹, 30 µm) from 11 to 9 km,
/// stratocumulus (8 km⁻¹, 10 µm) from 1.5 to 0.8 km, air elsewhere.
fn column() -> Vec<Step> {
    (0..3400)
        .map(|k| {
            let z = 100e3 - 30.0 * k as f64;
            let (alpha, radius_um) = match z {
                z if (9e3..11e3).contains(&z) => (3e-4, 30.0),
                z if (800.0..1500.0).contains(&z) => (8e-3, 10.0),
                _ => (0.0, 10.0),
            };
            let theta = 532e-9 / (std::f64::consts::PI * radius_um * 1e-6);
            Step {
                width_m: 30.0,
                alpha_particle_per_m: alpha,
                alpha_theta2_per_m: alpha * theta * theta,
                alpha_air_per_m: 1.3e-5 * (-z / 8000.0).exp(),
            }
        })
        .collect()
}

fn caliop(model: &str) -> Scenario {
    let ov = vec![
        format!("multiple_scattering.model=\"{model}\""),
        "instrument.beam_divergence_rad=5e-5".to_string(),
    ];
    Scenario::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/instruments/caliop_532.toml"),
        &ov,
    )
    .expect("config")
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("multiple_scattering");
    g.sample_size(20)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    let steps = column();
    let fp = Footprint {
        divergence_rad: 5e-5,
        fov_half_angle_rad: 65e-6,
    };
    g.bench_function("pvc_3400_gates", |b| {
        b.iter(|| small_angle_ratios(black_box(fp), 705e3 - 100e3, black_box(&steps)))
    });
    // the wide-angle part on its largest grid: a stratocumulus (8 km⁻¹, 10 µm, g 0.85)
    // over the first 25 gates of 30 m, air after
    let gates: Vec<Gate> = (0..MAX_GATES)
        .map(|k| {
            let alpha = if k < 25 { 8e-3 } else { 0.0 };
            let theta = 532e-9 / (std::f64::consts::PI * 10e-6);
            Gate {
                alpha_particle_per_m: alpha,
                alpha_g_per_m: 0.85 * alpha,
                alpha_theta2_per_m: alpha * theta * theta,
                alpha_air_per_m: 1.2e-5,
                scattering_air_per_m: 1.2e-5,
            }
        })
        .collect();
    g.bench_function(format!("tdts_{MAX_GATES}_gates"), |b| {
        b.iter(|| wide_angle_backscatter(black_box(fp), 30.0, 703e3, black_box(&gates), 1.0))
    });
    for model in ["constant", "small_angle", "small_and_wide_angle"] {
        let sc = caliop(model);
        g.bench_function(format!("caliop_expected_{model}"), |b| {
            b.iter(|| black_box(sc.expected().unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
