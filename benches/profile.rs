//! Whole-profile throughput on the paper's scenario 1 (issue 3): one profile of
//! 10 Hz × 100 s (1000 shots), 10 Hz × 1000 s (10,000 shots: issue 11's aggregate
//! against shot case) and 250 Hz × 1000 s (250,000 shots), by the `shot` and
//! `aggregate` methods, plus a low-energy variant (E0 = 1 mJ, every λ ≤ 0.7).
//! Throughput is in shot-bins (shots × bins) per second.
//!
//! `cargo bench --bench profile`

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use lidarsim::scenario::Scenario;
use lidarsim::simulate::{ResolvedMethod, StreamSampler};

fn scenario(overrides: &[&str]) -> Scenario {
    let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scenario::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/paper/scenario1.toml"),
        &ov,
    )
    .expect("config")
}

fn profile_bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("profile");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    let cases = [
        (
            "s1_10Hz_100s",
            vec![
                "instrument.rep_rate_hz=10",
                "acquisition.accumulation_time_s=100",
            ],
        ),
        (
            "s1_10Hz_1000s",
            vec![
                "instrument.rep_rate_hz=10",
                "acquisition.accumulation_time_s=1000",
            ],
        ),
        (
            "s1_250Hz_1000s",
            vec![
                "instrument.rep_rate_hz=250",
                "acquisition.accumulation_time_s=1000",
            ],
        ),
        (
            "s1_1mJ_10Hz_1000s",
            vec![
                "instrument.pulse_energy_j=0.001",
                "instrument.rep_rate_hz=10",
                "acquisition.accumulation_time_s=1000",
            ],
        ),
    ];
    for (name, ov) in cases {
        let sc = scenario(&ov);
        let e = sc.expected().expect("model");
        let shots = sc.shots_per_profile();
        let rest = vec![e.background + e.dark; e.n_bins()];
        g.throughput(Throughput::Elements(shots * e.n_bins() as u64));
        for method in [ResolvedMethod::Shot, ResolvedMethod::Aggregate] {
            let sampler = StreamSampler::new(method, &e.signal, &rest, 0.0);
            let mut acc = vec![0u64; e.n_bins()];
            let mut profile = 0u64;
            g.bench_function(format!("{name}/{}", method.name()), |b| {
                b.iter(|| {
                    profile += 1;
                    sampler.profile_counts(1, profile, shots, black_box(&mut acc));
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, profile_bench);
criterion_main!(benches);
