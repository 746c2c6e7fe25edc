//! The measurements behind the shot sampler's cost model (`lidarsim::sampling::cost`)
//! and the per-bin method switch points (`DENSE_TABLE_MAX`, `DENSE_ALIAS_MAX`), and the
//! per-draw rates that `validation/reports/throughput.md` sets against numpy.
//!
//! For each mean λ, 1000 bins all at λ are drawn by each dense method alone
//! (`PathChoice::Dense`), by the sparse path alone, and by the cost-model choice, one
//! thread, best of `--repeat` runs of `shots` shots; prints ns per shot-bin and the
//! million draws per second.
//!
//! ```text
//! cargo run --release --example sampler_costs -- [--repeat 15] [--bins 1000]
//! ```

use std::hint::black_box;
use std::time::Instant;

use lidarsim::sampling::{DenseMethod, PathChoice, ShotSampler, stream_rng};

/// Means measured, per shot-bin.
const MEANS: [f64; 17] = [
    1e-3, 0.01, 0.05, 0.1, 0.25, 0.5, 1.0, 3.0, 10.0, 30.0, 100.0, 1e3, 1e4, 4e4, 1e5, 1e6, 1e7,
];

fn main() {
    let mut repeat = 15usize;
    let mut bins = 1000usize;
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().and_then(|v| v.parse().ok());
        match a.as_str() {
            "--repeat" => repeat = value().unwrap_or(repeat),
            "--bins" => bins = value().unwrap_or(bins),
            _ => {
                eprintln!("usage: sampler_costs [--repeat N] [--bins N]");
                std::process::exit(2);
            }
        }
    }
    println!("ns per shot-bin, {bins} bins at λ, best of {repeat} (one thread)");
    println!(
        "{:>8} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "λ", "inversion", "alias", "cells", "rejection", "sparse", "auto", "auto M/s"
    );
    for &l in &MEANS {
        let lambda = vec![l; bins];
        // about 2e6 shot-bins and at most ~2e8 counts per run
        let shots = ((2e6 / bins as f64) as u64).clamp(10, 100_000);
        let time = |choice: PathChoice| -> f64 {
            let s = ShotSampler::with_choice(&lambda, choice);
            let mut best = f64::INFINITY;
            for r in 0..repeat {
                let mut acc = vec![0u64; bins];
                let mut rng = stream_rng(7, r as u64, 0);
                let t = Instant::now();
                s.add_shots(&mut rng, shots, black_box(&mut acc));
                best = best.min(t.elapsed().as_secs_f64());
            }
            best * 1e9 / (shots as f64 * bins as f64)
        };
        let cell = |ok: bool, choice: PathChoice| {
            if ok {
                format!("{:10.2}", time(choice))
            } else {
                format!("{:>10}", "-")
            }
        };
        let auto = time(PathChoice::Auto);
        println!(
            "{:>8.0e} {} {} {} {} {} {:10.2} {:10.0}",
            l,
            cell(l <= 600.0, PathChoice::Dense(DenseMethod::Inversion)),
            cell(l <= 1e5, PathChoice::Dense(DenseMethod::Alias)),
            cell(l >= 30.0, PathChoice::Dense(DenseMethod::Cells)),
            cell(true, PathChoice::Dense(DenseMethod::Rejection)),
            cell(l <= 10.0, PathChoice::AllSparse),
            auto,
            1e3 / auto
        );
    }
}
