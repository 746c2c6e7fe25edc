//! Photon-count sampler throughput, in shot-bins per second (one thread).
//!
//! `cargo bench --bench sampler` (add `-- --measurement-time 2` etc. to
//! shorten). Compare with `python benches/numpy_poisson.py`, which times
//! numpy's `Generator.poisson` on the same grid and profile.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use lidarsim::sampling::{PathChoice, ShotSampler, add_aggregate, stream_rng};
use rand_distr::{Distribution, Poisson};

const BINS: usize = 1000;

/// Low-energy space-lidar-like profile: a range-squared and extinction decay
/// from λ = 0.149 down to 1.7e-4, plus a constant background + dark 1e-3
/// (every λ ≤ 0.15; Σλ ≈ 11.9). Same formula in `numpy_poisson.py`.
fn low_energy_profile() -> Vec<f64> {
    (0..BINS)
        .map(|i| {
            let x = i as f64;
            0.149 * (1.0 + x / 100.0).powi(-2) * (-x / 500.0).exp() + 1e-3
        })
        .collect()
}

/// Shots per iteration so that an iteration does ~1e6 shot-bins.
fn shots_for(_lambda: f64) -> u64 {
    1000
}

fn shot_bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("shot");
    let mut cases: Vec<(String, Vec<f64>)> = [1e-4, 1e-2, 1.0, 10.0]
        .iter()
        .map(|&l| (format!("lambda={l:e}"), vec![l; BINS]))
        .collect();
    cases.push(("low_energy".into(), low_energy_profile()));
    for (name, lambda) in &cases {
        let shots = shots_for(lambda[0]);
        g.throughput(Throughput::Elements(shots * BINS as u64));
        let choices = [
            ("auto", PathChoice::Auto),
            ("dense", PathChoice::AllDense),
            ("sparse", PathChoice::AllSparse),
        ];
        for (cname, choice) in choices {
            let s = ShotSampler::with_choice(lambda, choice);
            if cname == "auto" {
                eprintln!("{name}: {}", s.strategy());
            }
            let mut rng = stream_rng(1, 0, 0);
            let mut acc = vec![0u64; BINS];
            g.bench_function(BenchmarkId::new(cname, name), |b| {
                b.iter(|| s.add_shots(&mut rng, shots, black_box(&mut acc)))
            });
        }
        // Baseline: a plain per-bin loop over prebuilt rand_distr::Poisson.
        let pois: Vec<Poisson<f64>> = lambda.iter().map(|&l| Poisson::new(l).unwrap()).collect();
        let mut rng = stream_rng(1, 0, 0);
        let mut acc = vec![0u64; BINS];
        g.bench_function(BenchmarkId::new("rand_distr_loop", name), |b| {
            b.iter(|| {
                for _ in 0..shots {
                    for (a, p) in acc.iter_mut().zip(&pois) {
                        *a += p.sample(&mut rng) as u64;
                    }
                }
                black_box(&mut acc);
            })
        });
    }
    g.finish();
}

fn aggregate_bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("aggregate");
    const SHOTS: u64 = 10_000;
    let mut cases: Vec<(String, Vec<f64>)> = [1e-4, 1e-2, 1.0, 10.0]
        .iter()
        .map(|&l| (format!("lambda={l:e}"), vec![l; BINS]))
        .collect();
    cases.push(("low_energy".into(), low_energy_profile()));
    for (name, lambda) in &cases {
        // Throughput counted as the shot-bins the profile stands for.
        g.throughput(Throughput::Elements(SHOTS * BINS as u64));
        let mut rng = stream_rng(1, 0, 0);
        let mut acc = vec![0u64; BINS];
        g.bench_function(BenchmarkId::new("10k_shots", name), |b| {
            b.iter(|| add_aggregate(&mut rng, black_box(lambda), SHOTS, black_box(&mut acc)))
        });
    }
    g.finish();
}

fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .sample_size(20)
}

criterion_group! {
    name = benches;
    config = config();
    targets = shot_bench, aggregate_bench
}
criterion_main!(benches);
